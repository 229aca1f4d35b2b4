//! Queries: beam-walked grids, front to back through the levels.
//!
//! A query walks the root grid with `accel-grid`'s [`BeamWalk`], exactly as
//! the uniform grid does. In a refined cell, the primitives that span it are
//! tested, and its child grid is walked there and then: from the beam's own
//! entry into the child's box ([`Aabb::beam_interval_inv`]), no earlier than the
//! ray's start, under the same stopping rule as every other walk ("the next
//! cell lies past the best hit plus the hit tolerance"). Each walk therefore
//! visits every one of its cells that the beam touches before the final best
//! hit: the leaves that might hold a nearer hit, or a tie, are never skipped,
//! whichever level they are on. A child's beam is narrowed to the rounding of
//! what the child holds ([`narrowed`]): a dense cluster is walked as finely
//! as if it stood alone. One [`Mailbox`] per query, on its stack, spans all
//! levels. A scene built in parts ([`accel_core::parts`]) is walked part by
//! part, each from its own root on the beam of its root's box, the later
//! parts with the best hit of the earlier.

use crate::node::{Entry, Node, entry};
use crate::octree::Octree;
use accel_core::packed::for_each_candidate;
use accel_core::{
    Aabb, AccelStats, Accelerator, CostCounter, Hit, Mailbox, PreparedRay, PrimitiveSet,
    QueryError, Ray, Real, TRAVERSAL_ROUNDINGS, TraversalRay, nearer, region_matches,
    region_search_box, validate_region,
};
use accel_grid::cells::CellBox;
use accel_grid::dda::{BeamWalk, Step};
use core::borrow::Borrow;

/// The beam for walking `node`: the parent's, narrowed to the rounding of
/// what the node holds.
///
/// [`TraversalRay::new`] sizes the beam's half-width `delta` to the reach of
/// the whole structure from the ray origin, `gamma(64)·max|corner − o|`: the
/// bound on the rounding of any hit and of the walk's crossing parameters.
/// Inside a child grid only the hits of primitives referenced there or below
/// matter (a primitive that spans a refined cell stays in that cell, and is
/// tested on the parent's beam), and those hits and the child's crossings lie
/// in the node's `reach` box: the same bound over that box holds for them. So
/// a small dense cluster far from a large scene's extremes is walked with a
/// beam as thin as if it stood alone, not one that spans several of its cells.
/// The parent's `t_start` and `t_end` (wider) are kept; `delta` never grows.
#[inline]
fn narrowed<T: Real>(tr: &TraversalRay<T>, node: &Node<T>, inv_max_d: T) -> TraversalRay<T> {
    let o = tr.ray().origin;
    let reach = (node.reach.min - o)
        .abs()
        .max((node.reach.max - o).abs())
        .max_component();
    let delta = (T::gamma(TRAVERSAL_ROUNDINGS) * reach).min(tr.delta);
    TraversalRay {
        delta,
        t_tol: (delta * inv_max_d).min(tr.t_tol),
        ..*tr
    }
}

/// `(1 + gamma(2)) / max|d_i|`: turns a beam half-width into the hit
/// tolerance, as [`TraversalRay::new`] does.
#[inline]
fn tolerance_scale<T: Real>(ray: &Ray<T>) -> T {
    (T::ONE + T::gamma(2)) / ray.direction.abs().max_component()
}

/// Where the walk of a child grid starts: the beam's entry into its box, no
/// earlier than the ray's start; `None` when the beam misses the box, leaves
/// it before the start, or enters it only after `limit`.
#[inline]
fn child_start<T: Real>(tr: &TraversalRay<T>, node: &Node<T>, limit: T) -> Option<T> {
    let r = tr.ray();
    let (t0, t1) = node.geometry.bounds().beam_interval_inv(
        r.origin,
        r.direction,
        tr.prepared.inv_dir,
        tr.delta,
    )?;
    let from = t0.max(tr.t_start);
    (from <= t1 && from <= limit).then_some(from)
}

/// What every query of one ray keeps: the tree and its primitives, the
/// prepared ray, the hit tolerance's scale, the mailbox and the work counter.
struct Query<'q, 'a, T: Real, P: PrimitiveSet<T> + ?Sized, S, C> {
    tree: &'q Octree<'a, T, P, S>,
    prims: &'q P,
    prepared: PreparedRay<T>,
    inv_max_d: T,
    mailbox: Mailbox,
    counter: &'q mut C,
}

impl<'q, 'a, T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>, C> Query<'q, 'a, T, P, S, C> {
    /// A query of `tree` for the prepared ray.
    fn new(tree: &'q Octree<'a, T, P, S>, prepared: PreparedRay<T>, counter: &'q mut C) -> Self {
        Self {
            tree,
            prims: tree.primitives(),
            inv_max_d: tolerance_scale(&prepared.ray),
            prepared,
            mailbox: Mailbox::new(),
            counter,
        }
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>, C: CostCounter> Query<'_, '_, T, P, S, C> {
    /// The walk's next cells up to `limit`: after cells that held nothing,
    /// past the empty ones ahead ([`BeamWalk::step_past_empty`], counted as
    /// visited), else its next step. `None` ends the walk.
    #[inline(always)]
    fn next_cells(
        &mut self,
        walk: &mut BeamWalk<'_, T>,
        node: &Node<T>,
        limit: T,
        opened_empty: bool,
    ) -> Option<CellBox> {
        let step = if opened_empty {
            let (cells, counter) = (&self.tree.cells, &mut *self.counter);
            walk.step_past_empty(limit, |c, _| {
                let empty = node.holds_nothing(cells, c);
                if empty {
                    counter.node();
                }
                empty
            })
        } else {
            walk.step(limit)
        };
        match step {
            Step::End => None,
            Step::Cell(c) => Some(CellBox::single(c)),
            Step::Cells(b) => Some(b),
        }
    }
}

/// The state of one nearest-hit query.
struct Nearest<'q, 'a, T: Real, P: PrimitiveSet<T> + ?Sized, S, C> {
    q: Query<'q, 'a, T, P, S, C>,
    best: Option<Hit<T>>,
}

impl<'q, 'a, T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>, C: CostCounter>
    Nearest<'q, 'a, T, P, S, C>
{
    /// A query of `tree` for the prepared ray, with no hit yet.
    fn new(tree: &'q Octree<'a, T, P, S>, prepared: PreparedRay<T>, counter: &'q mut C) -> Self {
        Self {
            q: Query::new(tree, prepared, counter),
            best: None,
        }
    }

    /// The last parameter a walk on beam `tr` may still reach: the end of
    /// the beam, or the best hit plus the hit tolerance (a hit found in one
    /// cell may lie beyond it: the seed's termination trap).
    #[inline]
    fn limit(&self, tr: &TraversalRay<T>) -> T {
        match self.best {
            Some(b) => tr.t_end.min(b.t + tr.t_tol),
            None => tr.t_end,
        }
    }

    /// Walks grid `node` on beam `tr` from parameter `from` until its next
    /// cell lies past [`Nearest::limit`].
    fn walk(&mut self, node: &Node<T>, tr: &TraversalRay<T>, from: T) {
        let mut walk = BeamWalk::unplaced(&node.geometry, tr);
        let first = walk.restart(&node.geometry, from);
        let mut cells = first;
        loop {
            let mut empty = true;
            node.geometry.for_each_cell_index(&cells, |c| {
                empty &= node.holds_nothing(&self.q.tree.cells, c);
                self.cell(node, tr, c);
            });
            let limit = self.limit(tr);
            match self.q.next_cells(&mut walk, node, limit, empty) {
                Some(next) => cells = next,
                None => return,
            }
        }
    }

    /// Tests the primitives of cell `c` (a linear index in `node`'s grid),
    /// then walks its child grid if it has one.
    #[inline]
    fn cell(&mut self, node: &Node<T>, tr: &TraversalRay<T>, c: usize) {
        self.q.counter.node();
        let (tree, set) = (self.q.tree, self.q.prims);
        let (start, refs) = tree.cells.cell_at(node.cell_index(c));
        let Entry { prims, child } = entry(refs);
        let (q, best) = (&mut self.q, &mut self.best);
        for_each_candidate(tree.packed.as_ref(), start, prims, &q.prepared, |p| {
            if !q.mailbox.seen(p) {
                q.counter.prim();
                let t_max = best.map_or(q.prepared.ray.t_max, |b| b.t);
                if let Some(h) = set.intersect(p as usize, &q.prepared, t_max) {
                    *best = nearer(*best, Hit::new(p, h));
                }
            }
            false
        });
        if let Some(child) = child {
            self.descend(&tree.nodes[child], tr);
        }
    }

    /// Walks the child grid `child` of a cell on the beam `tr`, narrowed
    /// to it, from the beam's entry into its box.
    #[inline]
    fn descend(&mut self, child: &Node<T>, tr: &TraversalRay<T>) {
        let beam = narrowed(tr, child, self.q.inv_max_d);
        if let Some(from) = child_start(&beam, child, self.limit(&beam)) {
            self.walk(child, &beam, from);
        }
    }
}

/// The state of one any-hit query.
struct Any<'q, 'a, T: Real, P: PrimitiveSet<T> + ?Sized, S, C> {
    q: Query<'q, 'a, T, P, S, C>,
}

impl<'q, 'a, T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>, C: CostCounter>
    Any<'q, 'a, T, P, S, C>
{
    /// A query of `tree` for the prepared ray.
    fn new(tree: &'q Octree<'a, T, P, S>, prepared: PreparedRay<T>, counter: &'q mut C) -> Self {
        Self {
            q: Query::new(tree, prepared, counter),
        }
    }

    /// Walks grid `node` on beam `tr` from `from` to the end of the beam;
    /// true at the first hit.
    fn walk(&mut self, node: &Node<T>, tr: &TraversalRay<T>, from: T) -> bool {
        let mut walk = BeamWalk::unplaced(&node.geometry, tr);
        let first = walk.restart(&node.geometry, from);
        let mut cells = first;
        loop {
            let (mut found, mut empty) = (false, true);
            node.geometry.for_each_cell_index(&cells, |c| {
                empty &= node.holds_nothing(&self.q.tree.cells, c);
                found = found || self.cell(node, tr, c);
            });
            if found {
                return true;
            }
            match self.q.next_cells(&mut walk, node, tr.t_end, empty) {
                Some(next) => cells = next,
                None => return false,
            }
        }
    }

    /// Whether a primitive of cell `c` (a linear index in `node`'s grid), or
    /// of its child grid, is hit.
    #[inline]
    fn cell(&mut self, node: &Node<T>, tr: &TraversalRay<T>, c: usize) -> bool {
        self.q.counter.node();
        let (tree, set) = (self.q.tree, self.q.prims);
        let (start, refs) = tree.cells.cell_at(node.cell_index(c));
        let Entry { prims, child } = entry(refs);
        let q = &mut self.q;
        let t_max = q.prepared.ray.t_max;
        if for_each_candidate(tree.packed.as_ref(), start, prims, &q.prepared, |p| {
            if q.mailbox.seen(p) {
                return false;
            }
            q.counter.prim();
            set.intersect(p as usize, &q.prepared, t_max).is_some()
        }) {
            return true;
        }
        child.is_some_and(|child| self.descend(&tree.nodes[child], tr))
    }

    /// Whether anything in the child grid `child` of a cell is hit, on the
    /// beam `tr` narrowed to it.
    #[inline]
    fn descend(&mut self, child: &Node<T>, tr: &TraversalRay<T>) -> bool {
        let beam = narrowed(tr, child, self.q.inv_max_d);
        child_start(&beam, child, beam.t_end).is_some_and(|from| self.walk(child, &beam, from))
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> Octree<'_, T, P, S> {
    /// The nearest hit, counting the work in `counter`: each part's root
    /// walked in turn, on the beam of its own box, the later ones with the
    /// best hit of the earlier. A tree of one part, nearly every tree, takes
    /// a path of its own without the loop; neither prepares anything for a
    /// ray that misses it.
    pub(crate) fn nearest<C: CostCounter>(
        &self,
        ray: &Ray<T>,
        counter: &mut C,
    ) -> Result<Option<Hit<T>>, QueryError> {
        ray.validate()?;
        if self.empty {
            return Ok(None);
        }
        if self.parts == 1 {
            let root = &self.nodes[0];
            // Borrowed where it was built: moved, it was copied in loads
            // straddling the stores that had just written it (no store
            // forwarding).
            let entered = TraversalRay::new(ray, root.geometry.bounds());
            let Some(tr) = &entered else {
                return Ok(None);
            };
            return Ok(self.nearest_from_root(tr, counter));
        }
        // The ray is prepared (its shear takes three divisions) only once
        // a part's box is met: a ray that misses every part prepares nothing.
        // Each beam is borrowed where it was built, as above.
        let roots = &self.nodes[..self.parts];
        for (first, root) in roots.iter().enumerate() {
            let entered = self.part_beam(ray, root);
            let Some(tr) = &entered else {
                continue;
            };
            let mut q = Nearest::new(self, tr.prepared, counter);
            q.walk(root, tr, tr.t_start);
            for root in &roots[first + 1..] {
                if let Some(tr) = &self.part_beam(ray, root) {
                    q.walk(root, tr, tr.t_start);
                }
            }
            return Ok(q.best);
        }
        Ok(None)
    }

    /// Whether anything is hit, counting the work in `counter`, part by part
    /// (a one-part tree as in [`Octree::nearest`]).
    pub(crate) fn any<C: CostCounter>(
        &self,
        ray: &Ray<T>,
        counter: &mut C,
    ) -> Result<bool, QueryError> {
        ray.validate()?;
        if self.empty {
            return Ok(false);
        }
        if self.parts == 1 {
            let root = &self.nodes[0];
            // Borrowed where it was built, as in `nearest`.
            let entered = TraversalRay::new(ray, root.geometry.bounds());
            let Some(tr) = &entered else {
                return Ok(false);
            };
            return Ok(self.any_from_root(tr, counter));
        }
        // Prepared only once a part's box is met, as in `nearest`.
        let roots = &self.nodes[..self.parts];
        for (first, root) in roots.iter().enumerate() {
            let entered = self.part_beam(ray, root);
            let Some(tr) = &entered else {
                continue;
            };
            let mut q = Any::new(self, tr.prepared, counter);
            return Ok(q.walk(root, tr, tr.t_start)
                || roots[first + 1..].iter().any(|root| {
                    self.part_beam(ray, root)
                        .as_ref()
                        .is_some_and(|tr| q.walk(root, tr, tr.t_start))
                }));
        }
        Ok(false)
    }

    /// The nearest hit of a tree of one part, on the beam `tr` through its
    /// root's box.
    #[inline]
    pub(crate) fn nearest_from_root<C: CostCounter>(
        &self,
        tr: &TraversalRay<T>,
        counter: &mut C,
    ) -> Option<Hit<T>> {
        let mut q = Nearest::new(self, tr.prepared, counter);
        q.walk(&self.nodes[0], tr, tr.t_start);
        q.best
    }

    /// Whether anything of a tree of one part is hit, on the beam `tr`
    /// through its root's box.
    #[inline]
    pub(crate) fn any_from_root<C: CostCounter>(
        &self,
        tr: &TraversalRay<T>,
        counter: &mut C,
    ) -> bool {
        Any::new(self, tr.prepared, counter).walk(&self.nodes[0], tr, tr.t_start)
    }

    /// One ray of a packet ([`crate::bundle`]) walking the child grid
    /// `child` alone, as its single walk does from the cell that links it:
    /// on its beam `tr` through the root, with its best hit so far and its
    /// mailbox (both updated).
    pub(crate) fn nearest_below(
        &self,
        child: &Node<T>,
        tr: &TraversalRay<T>,
        best: &mut Option<Hit<T>>,
        mailbox: &mut Mailbox,
    ) {
        let mut uncounted = ();
        let mut q = Nearest::new(self, tr.prepared, &mut uncounted);
        q.best = *best;
        core::mem::swap(&mut q.q.mailbox, mailbox);
        q.descend(child, tr);
        core::mem::swap(&mut q.q.mailbox, mailbox);
        *best = q.best;
    }

    /// As [`Octree::nearest_below`], for an any-hit query: whether anything
    /// below is hit.
    pub(crate) fn any_below(
        &self,
        child: &Node<T>,
        tr: &TraversalRay<T>,
        mailbox: &mut Mailbox,
    ) -> bool {
        let mut uncounted = ();
        let mut q = Any::new(self, tr.prepared, &mut uncounted);
        core::mem::swap(&mut q.q.mailbox, mailbox);
        let found = q.descend(child, tr);
        core::mem::swap(&mut q.q.mailbox, mailbox);
        found
    }

    /// The beam of `ray` through the part whose root is `root`, `None` when
    /// nothing there can be hit ([`accel_core::parts::part_beam`]: a flat
    /// part is first tested with the wide type's thin beam).
    #[inline]
    fn part_beam(&self, ray: &Ray<T>, root: &Node<T>) -> Option<TraversalRay<T>> {
        accel_core::parts::part_beam(ray, root.geometry.bounds(), self.primitives().wide_hits())
    }

    /// Appends the references of every leaf overlapping `region`.
    fn gather(&self, node: &Node<T>, region: &Aabb<T>, out: &mut Vec<u32>) {
        let Some(cells) = node.geometry.cells_overlapping(region) else {
            return;
        };
        node.geometry.for_each_cell_index(&cells, |c| {
            let Entry { prims, child } = entry(self.cells.cell(node.cell_index(c)));
            out.extend_from_slice(prims);
            if let Some(child) = child {
                self.gather(&self.nodes[child], region, out);
            }
        });
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P> + Sync> Accelerator<T>
    for Octree<'_, T, P, S>
{
    fn bounds(&self) -> Aabb<T> {
        if self.empty {
            Aabb::empty()
        } else {
            self.bounds
        }
    }

    accel_core::ray_queries_from_walks!();

    accel_grid::bundle_queries_by_packets!();

    /// Gathers the references of every leaf near the region (grown by a
    /// rounding allowance, so that a primitive the exact test accepts is never
    /// missed), then keeps those the primitive's own overlap test accepts.
    fn query_region(&self, region: &Aabb<T>) -> Result<Vec<u32>, QueryError> {
        validate_region(region)?;
        if region.is_empty() || self.empty {
            return Ok(Vec::new());
        }
        let grown = region_search_box(region, &self.bounds);
        let mut found = Vec::new();
        for root in &self.nodes[..self.parts] {
            self.gather(root, &grown, &mut found);
        }
        Ok(region_matches(self.primitives(), region, found))
    }

    fn stats(&self) -> AccelStats {
        self.stats.clone()
    }
}
