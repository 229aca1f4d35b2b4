//! The interface every acceleration structure offers, and its reports.

use crate::{Aabb, Hit, PrimitiveSet, QueryError, Ray, Real};
use core::fmt;
use std::time::Duration;

/// Work done by one query: what a heat map shows per pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalCounters {
    /// Cells (grids) or nodes (trees) visited.
    pub nodes: u64,
    /// Primitive intersection or overlap tests run. In a packed layout
    /// ([`crate::packed`]) only the tests its block test could not settle
    /// count: the primitives a block test rejects are not.
    pub prims: u64,
}

impl TraversalCounters {
    /// Adds another query's counts.
    pub fn add(&mut self, o: &Self) {
        self.nodes += o.nodes;
        self.prims += o.prims;
    }
}

/// Counts traversal work, or not: the traversal code is generic over it, and
/// `()` compiles the counting away.
pub trait CostCounter {
    /// One cell or node visited.
    fn node(&mut self);
    /// One primitive tested.
    fn prim(&mut self);
}

impl CostCounter for () {
    #[inline(always)]
    fn node(&mut self) {}
    #[inline(always)]
    fn prim(&mut self) {}
}

impl CostCounter for TraversalCounters {
    #[inline]
    fn node(&mut self) {
        self.nodes += 1;
    }
    #[inline]
    fn prim(&mut self) {
        self.prims += 1;
    }
}

/// Build and shape statistics of an accelerator.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AccelStats {
    /// Short name of the structure ("grid", "octree", "kdtree", "brute").
    pub kind: &'static str,
    /// Number of primitives indexed.
    pub primitives: usize,
    /// Wall-clock build time.
    pub build_time: Duration,
    /// Heap bytes owned by the structure (not counting the primitives).
    pub bytes: usize,
    /// Cells (grids) or nodes (trees), inner ones included.
    pub nodes: usize,
    /// Cells or leaves that can hold references.
    pub leaves: usize,
    /// Of those, the ones holding none.
    pub empty_leaves: usize,
    /// Primitive references stored (a primitive in three cells counts three).
    pub references: usize,
    /// The most references in one cell or leaf.
    pub max_leaf_references: usize,
    /// Structure-specific figures (resolution, depth, SAH cost, ...).
    pub extra: Vec<(&'static str, f64)>,
}

impl AccelStats {
    /// Mean references per non-empty cell or leaf.
    #[must_use]
    pub fn mean_references_per_nonempty_leaf(&self) -> f64 {
        let full = self.leaves - self.empty_leaves;
        if full == 0 {
            0.0
        } else {
            self.references as f64 / full as f64
        }
    }

    /// Bytes per primitive (0 for an empty structure).
    #[must_use]
    pub fn bytes_per_primitive(&self) -> f64 {
        if self.primitives == 0 {
            0.0
        } else {
            self.bytes as f64 / self.primitives as f64
        }
    }

    /// The value of a structure-specific figure.
    #[must_use]
    pub fn extra(&self, name: &str) -> Option<f64> {
        self.extra.iter().find(|(n, _)| *n == name).map(|&(_, v)| v)
    }
}

impl fmt::Display for AccelStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} prims, build {:.2} ms, {:.2} MiB ({:.1} B/prim), {} nodes, {} leaves ({} empty), \
             {} refs (max {}, mean {:.2} per non-empty leaf)",
            self.kind,
            self.primitives,
            self.build_time.as_secs_f64() * 1e3,
            self.bytes as f64 / (1024.0 * 1024.0),
            self.bytes_per_primitive(),
            self.nodes,
            self.leaves,
            self.empty_leaves,
            self.references,
            self.max_leaf_references,
            self.mean_references_per_nonempty_leaf(),
        )?;
        for (name, value) in &self.extra {
            write!(f, ", {name} {value}")?;
        }
        Ok(())
    }
}

/// A structure that answers ray and region queries over a primitive set.
///
/// # The equivalence promise
/// For any finite scene and valid ray, [`Accelerator::intersect`] returns the
/// same hit as [`crate::BruteForce`], bit for bit: the smallest `t`, ties to the
/// lowest primitive index, the same `u`, `v`. [`Accelerator::occluded`] equals
/// `intersect(ray)?.is_some()`, and [`Accelerator::query_region`] returns
/// exactly the primitives whose [`crate::PrimitiveSet::overlaps_box`] accepts the region.
///
/// # Errors
/// Every query refuses a ray that fails [`Ray::validate`] (or a non-finite
/// region) with the [`QueryError`] naming the problem. A ray with an empty
/// interval (`t_min > t_max`) is valid and hits nothing.
pub trait Accelerator<T: Real>: Sync {
    /// Bounds of everything indexed (empty if nothing is).
    fn bounds(&self) -> Aabb<T>;

    /// The nearest hit in `[t_min, t_max]`.
    fn intersect(&self, ray: &Ray<T>) -> Result<Option<Hit<T>>, QueryError>;

    /// Whether any primitive is hit in `[t_min, t_max]`: shadow rays; stops at
    /// the first hit found. By default `intersect(ray)?.is_some()`; a
    /// structure overrides it with a walk that stops at the first hit.
    fn occluded(&self, ray: &Ray<T>) -> Result<bool, QueryError> {
        Ok(self.intersect(ray)?.is_some())
    }

    /// [`Accelerator::intersect`] that also counts the work done. By default
    /// it counts nothing.
    fn intersect_counted(
        &self,
        ray: &Ray<T>,
        counters: &mut TraversalCounters,
    ) -> Result<Option<Hit<T>>, QueryError> {
        let _ = counters;
        self.intersect(ray)
    }

    /// [`Accelerator::occluded`] that also counts the work done. By default
    /// it counts nothing.
    fn occluded_counted(
        &self,
        ray: &Ray<T>,
        counters: &mut TraversalCounters,
    ) -> Result<bool, QueryError> {
        let _ = counters;
        self.occluded(ray)
    }

    /// The nearest hit of every ray of a bundle: `out[i]` becomes
    /// `self.intersect(&rays[i])`, bit for bit, whatever the bundle's size,
    /// coherence or mix of directions. By default one ray at a time; a
    /// structure that traces coherent rays together (a tile of camera rays,
    /// rays to one light) overrides it, and its answers stay those of the
    /// single-ray query ([`check_bundle`] states the promise).
    ///
    /// # Panics
    /// If `out` and `rays` differ in length.
    fn intersect_bundle(&self, rays: &[Ray<T>], out: &mut [Result<Option<Hit<T>>, QueryError>]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray of the bundle");
        for (ray, answer) in rays.iter().zip(out) {
            *answer = self.intersect(ray);
        }
    }

    /// Whether each ray of a bundle hits anything: `out[i]` becomes
    /// `self.occluded(&rays[i])`. By default one ray at a time, as
    /// [`Accelerator::intersect_bundle`].
    ///
    /// # Panics
    /// If `out` and `rays` differ in length.
    fn occluded_bundle(&self, rays: &[Ray<T>], out: &mut [Result<bool, QueryError>]) {
        assert_eq!(rays.len(), out.len(), "one answer per ray of the bundle");
        for (ray, answer) in rays.iter().zip(out) {
            *answer = self.occluded(ray);
        }
    }

    /// Every primitive that overlaps the closed box `region`, ascending and
    /// without repeats (an empty region gives none).
    fn query_region(&self, region: &Aabb<T>) -> Result<Vec<u32>, QueryError>;

    /// Build and shape statistics.
    fn stats(&self) -> AccelStats;
}

/// Where a bundle query's answers differ from the single-ray queries': the
/// first ray (its index) whose nearest hit or occlusion answer differs, with
/// both answers, or `None` when every answer is the same, bit for bit
/// (errors too). The promise of [`Accelerator::intersect_bundle`] and
/// [`Accelerator::occluded_bundle`], for a caller that has no reference
/// answers of its own; the workspace's suites compare bundles with brute
/// force directly.
pub fn check_bundle<T: Real, A: Accelerator<T> + ?Sized>(
    accel: &A,
    rays: &[Ray<T>],
) -> Option<String> {
    let mut nearest = vec![Ok(None); rays.len()];
    accel.intersect_bundle(rays, &mut nearest);
    let mut any = vec![Ok(false); rays.len()];
    accel.occluded_bundle(rays, &mut any);
    let bits = |r: &Result<Option<Hit<T>>, QueryError>| match r {
        Ok(h) => Ok(h.map(|h| h.bit_key())),
        Err(e) => Err(*e),
    };
    for (i, ray) in rays.iter().enumerate() {
        let single = accel.intersect(ray);
        if bits(&nearest[i]) != bits(&single) {
            return Some(format!(
                "ray {i}: bundle nearest {:?}, single {single:?}",
                nearest[i]
            ));
        }
        let occluded = accel.occluded(ray);
        if any[i] != occluded {
            return Some(format!(
                "ray {i}: bundle occluded {:?}, single {occluded:?}",
                any[i]
            ));
        }
    }
    None
}

/// The four ray queries of an [`Accelerator`] impl (`intersect`, `occluded`
/// and their counted twins), for a structure whose inherent methods
/// `nearest(&self, ray, counter)` and `any(&self, ray, counter)` are generic
/// over the [`CostCounter`]: the plain queries pass `()`, which counts
/// nothing and compiles to nothing, the counted ones the
/// [`TraversalCounters`]. Written once here instead of in every structure;
/// use it inside `impl<T: Real, ...> Accelerator<T> for ...` (the impl's
/// float type must be named `T`).
#[macro_export]
macro_rules! ray_queries_from_walks {
    () => {
        fn intersect(
            &self,
            ray: &$crate::Ray<T>,
        ) -> ::core::result::Result<::core::option::Option<$crate::Hit<T>>, $crate::QueryError> {
            self.nearest(ray, &mut ())
        }

        fn occluded(
            &self,
            ray: &$crate::Ray<T>,
        ) -> ::core::result::Result<bool, $crate::QueryError> {
            self.any(ray, &mut ())
        }

        fn intersect_counted(
            &self,
            ray: &$crate::Ray<T>,
            counters: &mut $crate::TraversalCounters,
        ) -> ::core::result::Result<::core::option::Option<$crate::Hit<T>>, $crate::QueryError> {
            self.nearest(ray, counters)
        }

        fn occluded_counted(
            &self,
            ray: &$crate::Ray<T>,
            counters: &mut $crate::TraversalCounters,
        ) -> ::core::result::Result<bool, $crate::QueryError> {
            self.any(ray, counters)
        }
    };
}

/// The box a structure gathers candidates from for a region query:
/// `region` grown by `gamma(1024)` of the largest coordinate in play (the
/// region's and the structure's `bounds`). A primitive's exact overlap test
/// may accept a box up to its own rounding allowance away from the primitive
/// (the triangle–box test allows `gamma(32)` of the magnitudes involved), far
/// less than this margin, so no primitive the exact test accepts lies outside
/// the grown box. Finish with [`region_matches`].
#[must_use]
pub fn region_search_box<T: Real>(region: &Aabb<T>, bounds: &Aabb<T>) -> Aabb<T> {
    let scale = region.max_abs_coordinate().max(bounds.max_abs_coordinate());
    let margin = T::gamma(1024) * scale;
    Aabb {
        min: region.min.map(|x| (x - margin).next_down()),
        max: region.max.map(|x| (x + margin).next_up()),
    }
}

/// The end of a region query: the candidates a structure gathered (from
/// [`region_search_box`]), ascending and without repeats, kept where the
/// primitive's own overlap test accepts `region`.
#[must_use]
pub fn region_matches<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    region: &Aabb<T>,
    mut candidates: Vec<u32>,
) -> Vec<u32> {
    candidates.sort_unstable();
    candidates.dedup();
    candidates.retain(|&p| prims.overlaps_box(p as usize, region));
    candidates
}

/// Checks a region for [`Accelerator::query_region`].
///
/// # Errors
/// [`QueryError::NonFiniteRegion`] for a NaN or infinite corner.
#[inline]
pub fn validate_region<T: Real>(region: &Aabb<T>) -> Result<(), QueryError> {
    if region.is_finite() {
        Ok(())
    } else {
        Err(QueryError::NonFiniteRegion)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{BruteForce, TriangleMesh, Vec3};

    /// One triangle over the unit corner at height 1.
    fn one_triangle() -> TriangleMesh<f64> {
        TriangleMesh::new(
            vec![
                Vec3::new(0.0, 0.0, 1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(0.0, 1.0, 1.0),
            ],
            vec![[0, 1, 2]],
        )
        .unwrap()
    }

    /// A user's structure implementing only what the trait requires, over
    /// brute force's nearest hit.
    struct Minimal<'a>(BruteForce<'a, f64, TriangleMesh<f64>>);

    impl Accelerator<f64> for Minimal<'_> {
        fn bounds(&self) -> Aabb<f64> {
            self.0.bounds()
        }
        fn intersect(&self, ray: &Ray<f64>) -> Result<Option<Hit<f64>>, QueryError> {
            self.0.intersect(ray)
        }
        fn query_region(&self, region: &Aabb<f64>) -> Result<Vec<u32>, QueryError> {
            self.0.query_region(region)
        }
        fn stats(&self) -> AccelStats {
            self.0.stats()
        }
    }

    #[test]
    fn the_default_queries_follow_intersect_and_count_nothing() {
        let mesh = one_triangle();
        let minimal = Minimal(BruteForce::new(&mesh).unwrap());
        let brute = BruteForce::new(&mesh).unwrap();
        let up = Vec3::new(0.0, 0.0, 1.0);
        for (origin, hits) in [
            (Vec3::new(0.2, 0.2, 0.0), true),
            (Vec3::new(0.8, 0.8, 0.0), false),
        ] {
            let ray = Ray::new(origin, up).unwrap();
            let mut counters = TraversalCounters::default();
            assert_eq!(minimal.occluded(&ray).unwrap(), hits);
            assert_eq!(minimal.occluded_counted(&ray, &mut counters).unwrap(), hits);
            assert_eq!(
                minimal.intersect_counted(&ray, &mut counters).unwrap(),
                brute.intersect(&ray).unwrap()
            );
            assert_eq!(counters, TraversalCounters::default());
        }
        // A bad ray is refused by the defaults as by `intersect`.
        let bad = Ray {
            origin: Vec3::new(f64::NAN, 0.0, 0.0),
            direction: up,
            t_min: 0.0,
            t_max: 1.0,
        };
        assert!(minimal.occluded(&bad).is_err());
    }

    /// A structure whose bundle query loses every hit after the first ray's.
    struct LossyBundles<'a>(Minimal<'a>);

    impl Accelerator<f64> for LossyBundles<'_> {
        fn bounds(&self) -> Aabb<f64> {
            self.0.bounds()
        }
        fn intersect(&self, ray: &Ray<f64>) -> Result<Option<Hit<f64>>, QueryError> {
            self.0.intersect(ray)
        }
        fn intersect_bundle(
            &self,
            rays: &[Ray<f64>],
            out: &mut [Result<Option<Hit<f64>>, QueryError>],
        ) {
            for (i, (ray, answer)) in rays.iter().zip(out).enumerate() {
                *answer = self.intersect(ray).map(|h| h.filter(|_| i == 0));
            }
        }
        fn query_region(&self, region: &Aabb<f64>) -> Result<Vec<u32>, QueryError> {
            self.0.query_region(region)
        }
        fn stats(&self) -> AccelStats {
            self.0.stats()
        }
    }

    #[test]
    fn bundles_answer_as_single_rays_and_a_lossy_bundle_is_named() {
        let mesh = one_triangle();
        let up = Vec3::new(0.0, 0.0, 1.0);
        let mut rays: Vec<Ray<f64>> = [0.1, 0.2, 0.3, 0.9]
            .iter()
            .map(|&x| Ray::new(Vec3::new(x, 0.1, 0.0), up).unwrap())
            .collect();
        // An invalid ray in the bundle is refused there, as alone.
        rays.push(Ray {
            origin: Vec3::new(f64::NAN, 0.0, 0.0),
            direction: up,
            t_min: 0.0,
            t_max: 1.0,
        });
        let minimal = Minimal(BruteForce::new(&mesh).unwrap());
        assert_eq!(check_bundle(&minimal, &rays), None);
        let mut nearest = vec![Ok(None); rays.len()];
        minimal.intersect_bundle(&rays, &mut nearest);
        assert_eq!(
            nearest.iter().filter(|h| matches!(h, Ok(Some(_)))).count(),
            3
        );
        assert!(nearest[4].is_err());
        let lossy = LossyBundles(Minimal(BruteForce::new(&mesh).unwrap()));
        let report = check_bundle(&lossy, &rays).expect("the lost hit is found");
        assert!(
            report.starts_with("ray 1: bundle nearest Ok(None)"),
            "{report}"
        );
    }
}
