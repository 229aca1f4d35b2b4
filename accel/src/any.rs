//! [`AnyAccelerator`]: one type for whichever structure was built.

use crate::config::AccelKind;
use accel_core::{
    Aabb, AccelStats, Accelerator, BruteForce, Hit, PrimitiveSet, QueryError, Ray, Real,
    TraversalCounters,
};
use accel_grid::Grid;
use accel_kdtree::KdTree;
use accel_octree::Octree;
use std::borrow::Borrow;

/// One of the workspace's structures over primitives `P`, held through `S`
/// (a borrow by default, as [`crate::build_config`] builds them; an
/// [`Arc`](std::sync::Arc) for the structures' `shared` forms).
///
/// It implements [`Accelerator`] by forwarding every query (the counted
/// and any-hit ones too) to the structure it holds, so it answers exactly
/// as that structure does: bit for bit as brute force. Match on it to reach
/// a structure's own methods.
#[non_exhaustive]
pub enum AnyAccelerator<'a, T: Real, P: PrimitiveSet<T> + ?Sized, S = &'a P> {
    /// The uniform grid.
    Grid(Grid<'a, T, P, S>),
    /// The octree of nested grids.
    Octree(Octree<'a, T, P, S>),
    /// The SAH kD-tree.
    KdTree(KdTree<'a, T, P, S>),
    /// Brute force (the reference).
    Brute(BruteForce<'a, T, P, S>),
}

/// Calls `$body` with `$a` bound to the structure inside `$self`.
macro_rules! each {
    ($self:expr, $a:ident => $body:expr) => {
        match $self {
            AnyAccelerator::Grid($a) => $body,
            AnyAccelerator::Octree($a) => $body,
            AnyAccelerator::KdTree($a) => $body,
            AnyAccelerator::Brute($a) => $body,
        }
    };
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P> + Sync> AnyAccelerator<'_, T, P, S> {
    /// Which structure it is.
    #[must_use]
    pub const fn kind(&self) -> AccelKind {
        match self {
            Self::Grid(_) => AccelKind::Grid,
            Self::Octree(_) => AccelKind::Octree,
            Self::KdTree(_) => AccelKind::KdTree,
            Self::Brute(_) => AccelKind::Brute,
        }
    }

    /// The structure inside, as a trait object: one virtual call per query
    /// straight to the structure's own code, no match on the variant (for
    /// code that takes `&dyn Accelerator`, such as a benchmark loop).
    #[must_use]
    pub fn as_dyn(&self) -> &(dyn Accelerator<T> + '_) {
        each!(self, a => a)
    }

    /// The primitives it indexes.
    #[must_use]
    pub fn primitives(&self) -> &P {
        each!(self, a => a.primitives())
    }

    /// The structure's invariant check (every primitive reachable, indices
    /// in range, children inside their parents); brute force has none.
    ///
    /// # Errors
    /// A message naming the first broken invariant.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Self::Grid(a) => a.validate(),
            Self::Octree(a) => a.validate(),
            Self::KdTree(a) => a.validate(),
            Self::Brute(_) => Ok(()),
        }
    }
}

impl<'a, T, P, S> AnyAccelerator<'a, T, P, S>
where
    T: Real + 'a,
    P: PrimitiveSet<T> + ?Sized + 'a,
    S: Borrow<P> + Sync + 'a,
{
    /// The structure inside, boxed as a trait object ([`Self::as_dyn`],
    /// owned).
    #[must_use]
    pub fn into_dyn(self) -> Box<dyn Accelerator<T> + 'a> {
        each!(self, a => Box::new(a))
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S> std::fmt::Debug for AnyAccelerator<'_, T, P, S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self {
            Self::Grid(_) => AccelKind::Grid,
            Self::Octree(_) => AccelKind::Octree,
            Self::KdTree(_) => AccelKind::KdTree,
            Self::Brute(_) => AccelKind::Brute,
        };
        write!(f, "AnyAccelerator::{kind:?}")
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P> + Sync> Accelerator<T>
    for AnyAccelerator<'_, T, P, S>
{
    #[inline]
    fn bounds(&self) -> Aabb<T> {
        each!(self, a => a.bounds())
    }

    #[inline]
    fn intersect(&self, ray: &Ray<T>) -> Result<Option<Hit<T>>, QueryError> {
        each!(self, a => a.intersect(ray))
    }

    #[inline]
    fn occluded(&self, ray: &Ray<T>) -> Result<bool, QueryError> {
        each!(self, a => a.occluded(ray))
    }

    #[inline]
    fn intersect_counted(
        &self,
        ray: &Ray<T>,
        counters: &mut TraversalCounters,
    ) -> Result<Option<Hit<T>>, QueryError> {
        each!(self, a => a.intersect_counted(ray, counters))
    }

    #[inline]
    fn occluded_counted(
        &self,
        ray: &Ray<T>,
        counters: &mut TraversalCounters,
    ) -> Result<bool, QueryError> {
        each!(self, a => a.occluded_counted(ray, counters))
    }

    #[inline]
    fn intersect_bundle(&self, rays: &[Ray<T>], out: &mut [Result<Option<Hit<T>>, QueryError>]) {
        each!(self, a => a.intersect_bundle(rays, out));
    }

    #[inline]
    fn occluded_bundle(&self, rays: &[Ray<T>], out: &mut [Result<bool, QueryError>]) {
        each!(self, a => a.occluded_bundle(rays, out));
    }

    fn query_region(&self, region: &Aabb<T>) -> Result<Vec<u32>, QueryError> {
        each!(self, a => a.query_region(region))
    }

    fn stats(&self) -> AccelStats {
        each!(self, a => a.stats())
    }
}
