//! Queries: the beam-walked DDA with mailboxing and robust early termination.

use crate::bundle::{Answer, Reply, answer_bundle};
use crate::dda::{BeamWalk, Step};
use crate::grid::{Grid, GridPart};
use accel_core::packed::for_each_candidate;
use accel_core::parts::part_beam;
use accel_core::{
    Aabb, AccelStats, Accelerator, CostCounter, Hit, Mailbox, PrimitiveSet, QueryError, Ray, Real,
    TraversalRay, nearer, region_matches, region_search_box, validate_region,
};
use core::borrow::Borrow;

impl<T: Real> GridPart<T> {
    /// The references of cell `c`, by its occupancy bit first if `BITS`
    /// (a large grid's, see [`crate::build::OCCUPIED_BITS_MIN_CELLS`]),
    /// with where they start in the reference array.
    #[inline(always)]
    fn cell<const BITS: bool>(&self, c: usize) -> (usize, &[u32]) {
        if BITS {
            self.cells.occupied_cell(c)
        } else {
            self.cells.cell_at(c)
        }
    }

    /// Calls `f` with the reference list (and its start) of every cell a
    /// walk step opened.
    #[inline]
    fn for_step<const BITS: bool>(&self, step: Step, f: impl FnMut((usize, &[u32]))) {
        match step {
            Step::Cell(c) => {
                let mut f = f;
                f(self.cell::<BITS>(self.geometry.linear_index(c)));
            }
            Step::Cells(b) => {
                let mut f = f;
                self.geometry
                    .for_each_cell_index(&b, |c| f(self.cell::<BITS>(c)));
            }
            Step::End => {}
        }
    }

    /// The walk's next cells up to `limit`. When the cells it opened last
    /// held nothing: past the empty blocks ahead if the grid keeps blocks
    /// ([`crate::blocks`]) and the walk has settled in an empty one, else
    /// past the empty cells ahead up to one in an empty block
    /// ([`BeamWalk::step_past_empty`], each counted as visited). Else its
    /// next step.
    #[inline(always)]
    fn next_step<'g, const BITS: bool, const BLOCKS: bool, C: CostCounter>(
        &'g self,
        walk: &mut BeamWalk<'g, T>,
        tr: &TraversalRay<T>,
        limit: T,
        opened_empty: bool,
        counter: &mut C,
    ) -> Step {
        if !opened_empty {
            return walk.step(limit);
        }
        if BLOCKS
            && let Some(blocks) = &self.blocks
            && let Some(step) = blocks.pass_empty(walk, &self.geometry, tr, limit)
        {
            return step;
        }
        walk.step_past_empty(limit, |c, at| {
            // A cell of an empty block is opened, not passed: the blocks
            // pass over the rest of it at the next step.
            let passed = self.cell::<BITS>(c).1.is_empty()
                && !(BLOCKS && self.blocks.as_ref().is_some_and(|b| b.is_empty_around(at)));
            if passed {
                counter.node();
            }
            passed
        })
    }

    /// [`GridPart::nearest_with`], reading occupancy bits and skipping
    /// empty blocks where the part keeps them.
    #[inline]
    pub(crate) fn nearest<P: PrimitiveSet<T> + ?Sized, C: CostCounter>(
        &self,
        prims: &P,
        tr: &TraversalRay<T>,
        best: Option<Hit<T>>,
        counter: &mut C,
    ) -> Option<Hit<T>> {
        match (self.cells.has_occupied_bits(), self.blocks.is_some()) {
            (true, true) => self.nearest_with::<true, true, P, C>(prims, tr, best, counter),
            (true, false) => self.nearest_with::<true, false, P, C>(prims, tr, best, counter),
            (false, true) => self.nearest_with::<false, true, P, C>(prims, tr, best, counter),
            (false, false) => self.nearest_with::<false, false, P, C>(prims, tr, best, counter),
        }
    }

    /// [`GridPart::any_with`], reading occupancy bits and skipping empty
    /// blocks where the part keeps them.
    #[inline]
    pub(crate) fn any<P: PrimitiveSet<T> + ?Sized, C: CostCounter>(
        &self,
        prims: &P,
        tr: &TraversalRay<T>,
        counter: &mut C,
    ) -> bool {
        match (self.cells.has_occupied_bits(), self.blocks.is_some()) {
            (true, true) => self.any_with::<true, true, P, C>(prims, tr, counter),
            (true, false) => self.any_with::<true, false, P, C>(prims, tr, counter),
            (false, true) => self.any_with::<false, true, P, C>(prims, tr, counter),
            (false, false) => self.any_with::<false, false, P, C>(prims, tr, counter),
        }
    }

    /// The nearest of `best` and the part's hits: walk front to back, and
    /// stop once the beam's front has passed the best hit by the hit
    /// tolerance (a hit found in one cell may lie beyond it; the seed's
    /// termination trap).
    fn nearest_with<const BITS: bool, const BLOCKS: bool, P, C>(
        &self,
        prims: &P,
        tr: &TraversalRay<T>,
        mut best: Option<Hit<T>>,
        counter: &mut C,
    ) -> Option<Hit<T>>
    where
        P: PrimitiveSet<T> + ?Sized,
        C: CostCounter,
    {
        let ray = tr.ray();
        let mut mailbox = Mailbox::new();
        let mut walk = BeamWalk::unplaced(&self.geometry, tr);
        let first = walk.restart(&self.geometry, tr.t_start);
        let mut cells = Step::Cells(first);
        loop {
            let mut empty = true;
            self.for_step::<BITS>(cells, |(start, refs)| {
                counter.node();
                empty &= refs.is_empty();
                for_each_candidate(self.packed.as_ref(), start, refs, &tr.prepared, |p| {
                    if !mailbox.seen(p) {
                        counter.prim();
                        let t_max = best.map_or(ray.t_max, |b| b.t);
                        if let Some(h) = prims.intersect(p as usize, &tr.prepared, t_max) {
                            best = nearer(best, Hit::new(p, h));
                        }
                    }
                    false
                });
            });
            let limit = match best {
                Some(b) => tr.t_end.min(b.t + tr.t_tol),
                None => tr.t_end,
            };
            cells = self.next_step::<BITS, BLOCKS, C>(&mut walk, tr, limit, empty, counter);
            if cells == Step::End {
                return best;
            }
        }
    }

    /// Any hit in the part: the same walk, returning at the first hit in
    /// `[t_min, t_max]`.
    fn any_with<const BITS: bool, const BLOCKS: bool, P, C>(
        &self,
        prims: &P,
        tr: &TraversalRay<T>,
        counter: &mut C,
    ) -> bool
    where
        P: PrimitiveSet<T> + ?Sized,
        C: CostCounter,
    {
        let ray = tr.ray();
        let mut mailbox = Mailbox::new();
        let mut walk = BeamWalk::unplaced(&self.geometry, tr);
        let first = walk.restart(&self.geometry, tr.t_start);
        let mut cells = Step::Cells(first);
        loop {
            let mut found = false;
            let mut empty = true;
            self.for_step::<BITS>(cells, |(start, refs)| {
                counter.node();
                empty &= refs.is_empty();
                if found {
                    return;
                }
                found = for_each_candidate(self.packed.as_ref(), start, refs, &tr.prepared, |p| {
                    if mailbox.seen(p) {
                        return false;
                    }
                    counter.prim();
                    prims
                        .intersect(p as usize, &tr.prepared, ray.t_max)
                        .is_some()
                });
            });
            if found {
                return true;
            }
            cells = self.next_step::<BITS, BLOCKS, C>(&mut walk, tr, tr.t_end, empty, counter);
            if cells == Step::End {
                return false;
            }
        }
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> Grid<'_, T, P, S> {
    /// The nearest hit, part by part (the later parts with the best hit of
    /// the earlier); a grid of one part, nearly every grid, without the
    /// loop.
    fn nearest<C: CostCounter>(
        &self,
        ray: &Ray<T>,
        counter: &mut C,
    ) -> Result<Option<Hit<T>>, QueryError> {
        ray.validate()?;
        if self.empty {
            return Ok(None);
        }
        if self.rest.is_empty() {
            // Borrowed where it was built: moved, it was copied in loads
            // straddling the stores that had just written it (no store
            // forwarding).
            let entered = TraversalRay::new(ray, self.first.geometry.bounds());
            let Some(tr) = &entered else {
                return Ok(None);
            };
            return Ok(self.first.nearest(self.primitives(), tr, None, counter));
        }
        let wide = self.primitives().wide_hits();
        Ok(self.parts().fold(None, |best, part| {
            match &part_beam(ray, part.geometry.bounds(), wide) {
                Some(tr) => part.nearest(self.primitives(), tr, best, counter),
                None => best,
            }
        }))
    }

    /// Whether bundle queries go by packets ([`crate::bundle`]): on a grid
    /// of one part that keeps empty-space blocks (at least half its blocks
    /// empty), where a packet's slices are mostly empty. A grid of several
    /// parts, or one whose cells are mostly full (the 100k random soup:
    /// packets 0.6× as fast as single rays, each ray's rectangle being
    /// computed in every slice), answers one ray at a time, with the same
    /// answers.
    #[must_use]
    pub fn bundles_by_packets(&self) -> bool {
        !self.empty && self.rest.is_empty() && self.first.blocks.is_some()
    }

    /// Answers a bundle, `answer(i, …)` for each ray `rays[i]`: its nearest
    /// hit, or (if `ANY`) whether it hits anything. By packets
    /// ([`crate::bundle`]) on a grid of one part with empty-space blocks,
    /// else one ray at a time.
    fn by_packets<const ANY: bool>(
        &self,
        rays: &[Ray<T>],
        answer: impl FnMut(usize, Result<Answer<T>, QueryError>),
    ) {
        let single = |ray: &Ray<T>| {
            if ANY {
                self.any(ray, &mut ()).map(Answer::Any)
            } else {
                self.nearest(ray, &mut ()).map(Answer::Nearest)
            }
        };
        let packet = |run: &[Ray<T>], mut reply: Reply<'_, _>| {
            let prims = self.primitives();
            self.first
                .packet::<ANY, P>(prims, run, |i, a| reply.send(i, a));
        };
        answer_bundle(rays, self.bundles_by_packets(), single, packet, answer);
    }

    /// Whether anything is hit, part by part.
    fn any<C: CostCounter>(&self, ray: &Ray<T>, counter: &mut C) -> Result<bool, QueryError> {
        ray.validate()?;
        if self.empty {
            return Ok(false);
        }
        if self.rest.is_empty() {
            // Borrowed where it was built, as in `nearest`.
            let entered = TraversalRay::new(ray, self.first.geometry.bounds());
            let Some(tr) = &entered else {
                return Ok(false);
            };
            return Ok(self.first.any(self.primitives(), tr, counter));
        }
        let wide = self.primitives().wide_hits();
        Ok(self.parts().any(|part| {
            part_beam(ray, part.geometry.bounds(), wide)
                .as_ref()
                .is_some_and(|tr| part.any(self.primitives(), tr, counter))
        }))
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P> + Sync> Accelerator<T>
    for Grid<'_, T, P, S>
{
    fn bounds(&self) -> Aabb<T> {
        if self.empty {
            Aabb::empty()
        } else {
            self.parts()
                .fold(Aabb::empty(), |b, p| b.union(p.geometry.bounds()))
        }
    }

    accel_core::ray_queries_from_walks!();

    crate::bundle_queries_by_packets!();

    /// Gathers the references of every cell near the region (grown by a
    /// rounding allowance, so that a primitive the exact test accepts is never
    /// missed), then keeps those the primitive's own overlap test accepts.
    fn query_region(&self, region: &Aabb<T>) -> Result<Vec<u32>, QueryError> {
        validate_region(region)?;
        if region.is_empty() || self.empty {
            return Ok(Vec::new());
        }
        let mut found: Vec<u32> = Vec::new();
        for part in self.parts() {
            let grown = region_search_box(region, part.geometry.bounds());
            let Some(cells) = part.geometry.cells_overlapping(&grown) else {
                continue;
            };
            part.geometry.for_each_cell_index(&cells, |c| {
                found.extend_from_slice(part.cells.cell(c));
            });
        }
        Ok(region_matches(self.primitives(), region, found))
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
