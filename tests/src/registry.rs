//! The registry: every accelerator and configuration the suites check.
//!
//! **Adding an accelerator or a configuration is one line** in
//! [`accelerators`]: a name and a builder. Every suite (equivalence,
//! extremes, watertightness, bad input, non-finite scenes, real meshes) runs
//! over every entry, in `f32` and `f64`, for triangle meshes and for the
//! user-defined [`crate::Mixed`] primitive. Each structure is listed in
//! both layouts ([`Layout`]: packed blocks and indexed lists), so that the
//! SIMD block test is held to brute force too.

use accel_core::packed::Layout;
use accel_core::{
    Aabb, Accelerator, BruteForce, BuildError, PrimitiveSet, Real, Vec3, bounds_union,
};
use accel_grid::{Grid, GridParams};
use accel_kdtree::{KdTree, KdTreeParams};
use accel_octree::{Octree, OctreeParams};

/// Builds one accelerator over a primitive set, borrowing it.
pub type Build<T, P> = fn(&P) -> Result<Box<dyn Accelerator<T> + '_>, BuildError>;

/// A named accelerator configuration.
pub struct Entry<T, P: ?Sized> {
    /// Short name, printed in every failure.
    pub name: &'static str,
    /// The builder.
    pub build: Build<T, P>,
}

impl<T, P: ?Sized> core::fmt::Debug for Entry<T, P> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name)
    }
}

/// Every accelerator configuration under test. `BruteForce` itself is the
/// reference the others are compared with; it is listed too, so that its own
/// contract (occluded, region queries, errors) is checked the same way.
#[must_use]
pub fn accelerators<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>() -> Vec<Entry<T, P>> {
    vec![
        entry("brute", |p| boxed(BruteForce::new(p))),
        entry("grid m=0.5", |p| boxed(Grid::with_params(p, &density(0.5)))),
        entry("grid m=1", |p| boxed(Grid::with_params(p, &density(1.0)))),
        entry("grid m=2", |p| boxed(Grid::with_params(p, &density(2.0)))),
        entry("grid m=4", |p| boxed(Grid::with_params(p, &density(4.0)))),
        entry("grid m=2 one-part", |p| {
            let params = GridParams {
                parts: false,
                ..density(2.0)
            };
            boxed(Grid::with_params(p, &params))
        }),
        entry("grid m=1 packed", |p| {
            boxed(Grid::with_params(
                p,
                &with_layout(density(1.0), Layout::Packed),
            ))
        }),
        entry("grid region>scene", |p| boxed(enclosing_region_grid(p))),
        entry("octree", |p| boxed(Octree::new(p))),
        entry("octree classic", |p| {
            boxed(Octree::with_params(p, &OctreeParams::classic()))
        }),
        entry("octree two-level", |p| {
            boxed(Octree::with_params(p, &OctreeParams::two_level()))
        }),
        entry("octree threshold=2 depth=8", |p| {
            boxed(Octree::with_params(p, &fine_octree()))
        }),
        entry("octree threshold=2 depth=8 packed", |p| {
            let params = OctreeParams {
                layout: Layout::Packed,
                ..fine_octree()
            };
            boxed(Octree::with_params(p, &params))
        }),
        entry("kdtree", |p| boxed(KdTree::new(p))),
        entry("kdtree packed", |p| {
            let params = KdTreeParams {
                layout: Layout::Packed,
                ..KdTreeParams::default()
            };
            boxed(KdTree::with_params(p, &params))
        }),
        entry("kdtree fast-build", |p| {
            boxed(KdTree::with_params(p, &KdTreeParams::fast_build()))
        }),
        entry("kdtree best-traversal", |p| {
            boxed(KdTree::with_params(p, &KdTreeParams::best_traversal()))
        }),
        entry("kdtree pbrt", |p| {
            boxed(KdTree::with_params(p, &KdTreeParams::pbrt()))
        }),
        entry("kdtree binned>4", |p| {
            boxed(KdTree::with_params(p, &binned_kdtree()))
        }),
    ]
}

/// A kD-tree that chooses every split above four primitives with the binned
/// SAH (eight bins): on the suites' small scenes most of the tree comes from
/// the binned levels, the exact sweep only finishes it.
#[must_use]
pub fn binned_kdtree() -> KdTreeParams {
    KdTreeParams {
        binned_above: 4,
        bins: 8,
        ..KdTreeParams::default()
    }
}

/// An octree that splits every cell holding more than two references, down
/// to eight levels: many small child grids, so every cell exit between levels
/// is exercised even on the suites' small scenes.
#[must_use]
pub fn fine_octree() -> OctreeParams {
    OctreeParams::default()
        .with_split_threshold(2)
        .with_max_depth(8)
}

/// Grid parameters with density `m` (keeps registry lines short).
#[must_use]
pub fn density<T: Real>(m: f64) -> GridParams<T> {
    GridParams::with_density(m)
}

/// `params` with the cells' triangles kept in `layout`.
#[must_use]
pub fn with_layout<T: Real>(params: GridParams<T>, layout: Layout) -> GridParams<T> {
    GridParams { layout, ..params }
}

/// A registry entry (the closure coerces to a [`Build`] here).
#[must_use]
pub fn entry<T, P: ?Sized>(name: &'static str, build: Build<T, P>) -> Entry<T, P> {
    Entry { name, build }
}

/// Boxes a built accelerator as a trait object.
///
/// # Errors
/// The build's own error.
pub fn boxed<'a, T: Real, A: Accelerator<T> + 'a>(
    built: Result<A, BuildError>,
) -> Result<Box<dyn Accelerator<T> + 'a>, BuildError> {
    Ok(Box::new(built?))
}

/// A grid over [`enclosing_region`].
///
/// # Errors
/// The scene's own [`BuildError`].
pub fn enclosing_region_grid<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
) -> Result<Grid<'_, T, P>, BuildError> {
    Grid::with_params(prims, &enclosing_region_params(prims)?)
}

/// Grid parameters with a user region that strictly contains the whole scene,
/// grown unevenly so that its cell boundaries fall between the scene's own
/// features. With such a region the grid must equal brute force exactly.
///
/// # Errors
/// The scene's own [`BuildError`] (non-finite primitives).
pub fn enclosing_region_params<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
) -> Result<GridParams<T>, BuildError> {
    Ok(GridParams::with_region(enclosing_region(prims)?))
}

/// The box [`enclosing_region_params`] uses: the scene's bounds grown by
/// 13% of their largest extent below and 29% above (a unit box at the origin
/// for an empty scene), clamped into `±T::LIMIT` ([`Real::LIMIT`]).
///
/// # Errors
/// [`BuildError::NonFinitePrimitive`] for a non-finite scene.
pub fn enclosing_region<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
) -> Result<Aabb<T>, BuildError> {
    let b = bounds_union(prims)?;
    if b.is_empty() {
        return Ok(Aabb::new(Vec3::ZERO, Vec3::splat(T::ONE)));
    }
    let extent = b.diagonal().max_component();
    let below = T::from_f64(0.13) * extent;
    let above = T::from_f64(0.29) * extent;
    // Subtracting (adding) a non-negative margin rounds to a value at or below
    // min (at or above max): the region always holds the scene. Clamped into
    // ±T::LIMIT, the range a build accepts (a scene near it gets less margin).
    Ok(Aabb {
        min: (b.min - Vec3::splat(below)).map(|x| x.max(-T::LIMIT)),
        max: (b.max + Vec3::splat(above)).map(|x| x.min(T::LIMIT)),
    })
}
