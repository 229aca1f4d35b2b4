//! Bundles: packets walked slice by slice over the root grid
//! (`accel-grid`'s [`Packet`], the coherent grid traversal of Wald et al.
//! 2006). A root cell under the packet's beams has its own primitives
//! tested against the rays whose rectangles meet it; the grid that refines
//! it is then walked by each of those rays alone, with its single walk's
//! code, beam and stopping rule, its best hit and its mailbox carried in
//! and out. (Walking the nested grids slice by slice too ran 0.89× the
//! single rays on the terrain's camera rays: a nested grid's slices hold
//! few of a packet's rays each, and every ray's rectangle was compared
//! with every full cell. Per ray below the root: 1.15×.) See
//! [`accel_grid::bundle`] for why each ray's answer is its single walk's.
//! Trees in parts, one-level trees of mostly full cells
//! ([`Octree::bundles_by_packets`]), and bundles whose rays head every
//! way go one ray at a time.

use crate::node::{Node, entry};
use crate::octree::Octree;
use accel_core::{PrimitiveSet, QueryError, Ray, Real};
use accel_grid::blocks::Blocks;
use accel_grid::bundle::{Answer, Packet, Reply, SliceCells, answer_bundle};
use accel_grid::cells::GridGeometry;
use core::borrow::Borrow;

/// One grid of an octree, walked by a packet of queries for the nearest hit
/// (`ANY` false) or for any hit.
struct NodeCells<'t, 'a, T: Real, P: PrimitiveSet<T> + ?Sized, S, const ANY: bool> {
    tree: &'t Octree<'a, T, P, S>,
    node: &'t Node<T>,
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>, const ANY: bool> SliceCells<T>
    for NodeCells<'_, '_, T, P, S, ANY>
{
    fn geometry(&self) -> &GridGeometry<T> {
        &self.node.geometry
    }

    fn blocks(&self) -> Option<&Blocks<T>> {
        None
    }

    #[inline]
    fn holds(&self, cell: usize) -> bool {
        !self.tree.cells.cell(self.node.cell_index(cell)).is_empty()
    }

    fn visit(&self, packet: &mut Packet<T>, cell: usize, meeting: u64) {
        let tree = self.tree;
        let (start, refs) = tree.cells.cell_at(self.node.cell_index(cell));
        let cell = entry(refs);
        packet.test::<ANY, P>(
            meeting,
            tree.primitives(),
            tree.packed.as_ref(),
            start,
            cell.prims,
        );
        if let Some(child) = cell.child {
            let child = &tree.nodes[child];
            packet.each_alone::<ANY>(meeting, |tr, best, mailbox| {
                if ANY {
                    tree.any_below(child, tr, mailbox)
                } else {
                    tree.nearest_below(child, tr, best, mailbox);
                    false
                }
            });
        }
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> Octree<'_, T, P, S> {
    /// Whether bundle queries go by packets (the crate docs, "Bundles"): on a tree
    /// of one part, unless it is the seed's uniform grid alone (no nested
    /// grid) with fewer than two thirds of its cells empty, where rays pass
    /// few empty cells a packet could share and packets ran at 0.74× the
    /// single rays (the 100k random soup, 55% empty). Otherwise bundles
    /// are answered one ray at a time, with the same answers.
    #[must_use]
    pub fn bundles_by_packets(&self) -> bool {
        let Some(root) = self.levels.first() else {
            return false;
        };
        !self.empty
            && self.parts == 1
            && (self.levels.len() > 1 || 3 * root.empty_leaves >= 2 * root.cells)
    }

    /// Answers a bundle, `answer(i, …)` for each ray `rays[i]`: its nearest
    /// hit, or (if `ANY`) whether it hits anything. By packets on a tree of
    /// one part, runs of rays that head together
    /// ([`accel_grid::bundle::runs`]); else one ray at a time.
    pub(crate) fn by_packets<const ANY: bool>(
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
        let root = NodeCells::<T, P, S, ANY> {
            tree: self,
            node: &self.nodes[0],
        };
        let alone = |tr: &_| {
            if ANY {
                Answer::Any(self.any_from_root(tr, &mut ()))
            } else {
                Answer::Nearest(self.nearest_from_root(tr, &mut ()))
            }
        };
        let packet = |run: &[Ray<T>], mut reply: Reply<'_, _>| {
            Packet::answer::<ANY, _>(&root, run, alone, |i, a| reply.send(i, a));
        };
        answer_bundle(rays, self.bundles_by_packets(), single, packet, answer);
    }
}
