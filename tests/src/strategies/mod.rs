//! Proptest strategies for scenes, rays, windows and boxes.
//!
//! Strategies produce the small descriptions of [`crate::scene`] and
//! [`crate::rays`]; they shrink toward fewer primitives, smaller indices and
//! simpler placements, so failures print readably.

mod rays;
mod scenes;
mod watertight;

pub use rays::{
    INDEX_RANGE, boxes, boxes_in, coherent_tile, dir3, ray, ray_in, rays_and_windows, unit, unit3,
    window,
};
pub use scenes::{
    closed_shape, extreme_placement, far_offsets, mixed_item, ordinary_placement, scene, tri,
};
pub use watertight::{aim, aim_in, watertight_placement};
