//! A uniform grid's part as a packet walks it.

use super::{Answer, Packet, SliceCells};
use crate::blocks::Blocks;
use crate::cells::GridGeometry;
use crate::grid::GridPart;
use accel_core::{PrimitiveSet, QueryError, Ray, Real, TraversalRay};

/// A grid part and its primitives, walked by a packet of queries for the
/// nearest hit (`ANY` false) or for any hit.
pub(super) struct PartCells<'g, T: Real, P: ?Sized, const ANY: bool> {
    pub(super) part: &'g GridPart<T>,
    pub(super) prims: &'g P,
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, const ANY: bool> SliceCells<T>
    for PartCells<'_, T, P, ANY>
{
    fn geometry(&self) -> &GridGeometry<T> {
        &self.part.geometry
    }

    fn blocks(&self) -> Option<&Blocks<T>> {
        self.part.blocks.as_ref()
    }

    #[inline]
    fn holds(&self, cell: usize) -> bool {
        let cells = &self.part.cells;
        if cells.has_occupied_bits() {
            !cells.occupied_cell(cell).1.is_empty()
        } else {
            !cells.cell(cell).is_empty()
        }
    }

    #[inline]
    fn visit(&self, packet: &mut Packet<T>, cell: usize, meeting: u64) {
        let (start, refs) = self.part.cells.cell_at(cell);
        packet.test::<ANY, P>(meeting, self.prims, self.part.packed.as_ref(), start, refs);
    }
}

impl<T: Real> GridPart<T> {
    /// Answers a packet of rays (at most [`super::PACKET`]) as the single
    /// walk answers each ([`Packet::answer`]).
    pub(crate) fn packet<const ANY: bool, P: PrimitiveSet<T> + ?Sized>(
        &self,
        prims: &P,
        rays: &[Ray<T>],
        answer: impl FnMut(usize, Result<Answer<T>, QueryError>),
    ) {
        let cells = PartCells::<T, P, ANY> { part: self, prims };
        Packet::answer::<ANY, _>(&cells, rays, |tr| self.single::<ANY, P>(prims, tr), answer);
    }

    /// One ray's answer by the single walk.
    fn single<const ANY: bool, P: PrimitiveSet<T> + ?Sized>(
        &self,
        prims: &P,
        tr: &TraversalRay<T>,
    ) -> Answer<T> {
        if ANY {
            Answer::Any(self.any(prims, tr, &mut ()))
        } else {
            Answer::Nearest(self.nearest(prims, tr, None, &mut ()))
        }
    }
}
