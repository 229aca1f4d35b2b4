//! Property-based equivalence and numerical-extremes suites for every
//! accelerator of the workspace.
//!
//! The promise checked (`DESIGN.md`, "Equivalence"): for any finite scene and
//! ray, every accelerator returns brute force's nearest hit bit for bit
//! ([`accel_core::Hit::bit_key`]), `occluded` agrees with it, region queries
//! return exactly brute force's set, closed meshes leak no ray, and bad input
//! is refused with a typed error.
//!
//! - [`registry`]: the accelerators under test. **Adding an accelerator or a
//!   configuration is one line** in [`registry::accelerators`].
//! - [`scene`], [`rays`], [`windows`], [`boxes`]: small, readable
//!   descriptions of scenes, rays, windows and boxes ([`SceneSpec`], [`RaySpec`], [`WindowSpec`],
//!   [`BoxSpec`]) and how they resolve against a scene ([`RayContext`]: its
//!   [`Landmarks`] and the geometry of grids built over it).
//! - [`strategies`]: the proptest strategies that generate them.
//! - [`assertions`], [`suite`]: the checks, returning readable messages.
//! - [`watertight`]: rays aimed at shared edges and vertices of closed meshes.
//! - [`bad_input`]: invalid rays and regions, non-finite scenes.
//! - [`limits`]: scenes stretched to the largest finite coordinates.
//! - [`Mixed`]: a user-defined primitive (triangles and spheres in one set).
//!
//! The properties live in `tests/`; `PROPTEST_CASES` sets the number of cases
//! per property (see [`config::config`]).

pub mod assertions;
pub mod bad_input;
pub mod boxes;
pub mod config;
pub mod landmarks;
pub mod limits;
mod mixed;
pub mod rays;
pub mod registry;
pub mod scene;
pub mod strategies;
pub mod suite;
pub mod watertight;
pub mod windows;

pub use boxes::BoxSpec;
pub use landmarks::{Landmarks, Surface};
pub use mixed::Mixed;
pub use rays::{RayContext, RaySpec};
pub use registry::{Entry, accelerators};
pub use scene::{Placement, Scene, SceneSpec};
pub use windows::{HitWindow, WindowSpec};
