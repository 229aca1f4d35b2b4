//! The reference: test every primitive.

use crate::accelerator::validate_region;
use crate::{
    Aabb, AccelStats, Accelerator, BuildError, CostCounter, Hit, PreparedRay, PrimitiveSet,
    QueryError, Ray, Real, bounds_union,
};
use core::borrow::Borrow;
use core::marker::PhantomData;
use std::sync::Arc;
use std::time::Instant;

/// Tests every primitive for every query. Slow, obviously right, and the
/// reference that every other accelerator must match bit for bit.
///
/// It holds its primitives as `S`: borrowed (`&'a P`, the default, from
/// [`BruteForce::new`]) or shared (`Arc<P>`, from [`BruteForce::shared`]:
/// a [`SharedBruteForce`], which can live beside its primitives in one
/// struct; see the crate docs, "Embedding").
#[derive(Debug)]
pub struct BruteForce<'a, T: Real, P: PrimitiveSet<T> + ?Sized, S = &'a P> {
    prims: S,
    bounds: Aabb<T>,
    stats: AccelStats,
    borrows: PhantomData<&'a P>,
}

/// A [`BruteForce`] that shares its primitives through an [`Arc`].
pub type SharedBruteForce<T, P> = BruteForce<'static, T, P, Arc<P>>;

impl<'a, T: Real, P: PrimitiveSet<T> + ?Sized> BruteForce<'a, T, P> {
    /// Checks the primitives (finite bounds) and wraps them.
    ///
    /// # Errors
    /// [`BuildError::NonFinitePrimitive`] or [`BuildError::TooManyPrimitives`].
    pub fn new(prims: &'a P) -> Result<Self, BuildError> {
        Self::over(prims)
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized> BruteForce<'static, T, P, Arc<P>> {
    /// [`BruteForce::new`] over primitives it shares: it keeps them alive
    /// itself, so it can be kept beside them in one struct or returned from
    /// the function that loaded them.
    ///
    /// # Errors
    /// As [`BruteForce::new`].
    pub fn shared(prims: Arc<P>) -> Result<Self, BuildError> {
        Self::over(prims)
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> BruteForce<'_, T, P, S> {
    /// Wraps `held` after checking its primitives.
    fn over(held: S) -> Result<Self, BuildError> {
        let start = Instant::now();
        let prims = held.borrow();
        let bounds = bounds_union(prims)?;
        let stats = AccelStats {
            kind: "brute",
            primitives: prims.len(),
            build_time: start.elapsed(),
            leaves: 1,
            nodes: 1,
            empty_leaves: usize::from(prims.is_empty()),
            references: prims.len(),
            max_leaf_references: prims.len(),
            ..AccelStats::default()
        };
        Ok(Self {
            prims: held,
            bounds,
            stats,
            borrows: PhantomData,
        })
    }

    /// The primitives it tests.
    #[inline]
    #[must_use]
    pub fn primitives(&self) -> &P {
        self.prims.borrow()
    }

    fn nearest<C: CostCounter>(
        &self,
        ray: &Ray<T>,
        c: &mut C,
    ) -> Result<Option<Hit<T>>, QueryError> {
        ray.validate()?;
        if ray.is_empty_interval() {
            return Ok(None);
        }
        c.node();
        let pr = PreparedRay::new(*ray);
        let mut best: Option<Hit<T>> = None;
        for i in 0..self.primitives().len() {
            c.prim();
            let t_max = best.map_or(ray.t_max, |b| b.t);
            if let Some(h) = self.primitives().intersect(i, &pr, t_max) {
                let h = Hit::new(i as u32, h);
                // Ascending indices: a tie never replaces the earlier hit.
                if best.is_none_or(|b| h.t < b.t) {
                    best = Some(h);
                }
            }
        }
        Ok(best)
    }

    fn any<C: CostCounter>(&self, ray: &Ray<T>, c: &mut C) -> Result<bool, QueryError> {
        ray.validate()?;
        if ray.is_empty_interval() {
            return Ok(false);
        }
        c.node();
        let pr = PreparedRay::new(*ray);
        for i in 0..self.primitives().len() {
            c.prim();
            if self.primitives().intersect(i, &pr, ray.t_max).is_some() {
                return Ok(true);
            }
        }
        Ok(false)
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P> + Sync> Accelerator<T>
    for BruteForce<'_, T, P, S>
{
    fn bounds(&self) -> Aabb<T> {
        self.bounds
    }

    crate::ray_queries_from_walks!();

    fn query_region(&self, region: &Aabb<T>) -> Result<Vec<u32>, QueryError> {
        validate_region(region)?;
        if region.is_empty() {
            return Ok(Vec::new());
        }
        Ok((0..self.primitives().len())
            .filter(|&i| self.primitives().overlaps_box(i, region))
            .map(|i| i as u32)
            .collect())
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
