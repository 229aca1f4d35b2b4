//! Predicting a candidate's build time from a build on a subsample.

use crate::{AccelConfig, AccelError, AccelKind, AnyAccelerator, build_config};
use accel_core::{Aabb, PreparedRay, PrimHit, PrimitiveSet, Real, Vec3};
use std::time::Instant;

/// Builds and times one configuration.
pub(super) fn timed_build<'a, T: Real, P: PrimitiveSet<T> + ?Sized>(
    config: &AccelConfig,
    prims: &'a P,
) -> Result<(AnyAccelerator<'a, T, P>, f64), AccelError> {
    let start = Instant::now();
    let accel = build_config(config, prims)?;
    Ok((accel, start.elapsed().as_secs_f64()))
}

/// A random subsample of a primitive set (every primitive with equal
/// probability, deterministic), for predicting build times.
pub(super) struct Subsample<'p, T, P: ?Sized> {
    prims: &'p P,
    index: Vec<usize>,
    _t: core::marker::PhantomData<T>,
}

impl<'p, T: Real, P: PrimitiveSet<T> + ?Sized> Subsample<'p, T, P> {
    pub(super) fn new(prims: &'p P, max: usize) -> Self {
        let n = prims.len();
        let index = if n <= max {
            (0..n).collect()
        } else {
            // Every k-th primitive from a scrambled start: meshes store
            // neighbours together, so a stride samples all parts evenly.
            let mut rng = accel_scenes::SplitMix64::new(0x5A3F);
            let step = n as f64 / max as f64;
            let offset = rng.next_f64() * step;
            (0..max)
                .map(|i| ((offset + i as f64 * step) as usize).min(n - 1))
                .collect()
        };
        Self {
            prims,
            index,
            _t: core::marker::PhantomData,
        }
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized> PrimitiveSet<T> for Subsample<'_, T, P> {
    fn len(&self) -> usize {
        self.index.len()
    }
    fn bounds(&self, i: usize) -> Aabb<T> {
        self.prims.bounds(self.index[i])
    }
    fn intersect(&self, i: usize, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        self.prims.intersect(self.index[i], ray, t_max)
    }
    fn overlaps_box(&self, i: usize, b: &Aabb<T>) -> bool {
        self.prims.overlaps_box(self.index[i], b)
    }
    fn wide_hits(&self) -> bool {
        self.prims.wide_hits()
    }
    fn watertight_triangle(&self, i: usize) -> Option<[Vec3<T>; 3]> {
        self.prims.watertight_triangle(self.index[i])
    }
    fn clipped_bounds(&self, i: usize, b: &Aabb<T>) -> Aabb<T> {
        self.prims.clipped_bounds(self.index[i], b)
    }
    fn clipped_bounds_split(&self, i: usize, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        self.prims.clipped_bounds_split(self.index[i], b, axis, s)
    }
}

/// Predicted full build time from a build on the subsample: scaled by `n`
/// for grids and octrees, by `n log n` for the kD-tree.
pub(super) fn predict_build<T: Real, P: PrimitiveSet<T> + ?Sized>(
    config: &AccelConfig,
    sample: &Subsample<'_, T, P>,
    n: usize,
) -> Result<f64, AccelError> {
    let s = sample.len();
    let (_, t) = timed_build(config, sample)?;
    if s == n || s == 0 {
        return Ok(t);
    }
    let ratio = n as f64 / s as f64;
    Ok(match config.kind() {
        AccelKind::KdTree => t * ratio * (n as f64).ln() / (s as f64).ln(),
        _ => t * ratio,
    })
}
