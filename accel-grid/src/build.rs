//! Building a uniform grid: bounds, resolution, and the two-pass cell lists.

use crate::blocks::Blocks;
use crate::cells::GridGeometry;
use crate::csr::{CellLists, CellVisitor};
use crate::grid::GridPart;
use crate::resolution::resolution;
use accel_core::packed::{Layout, PackedTriangles};
use accel_core::parts::split_surveyed;
use accel_core::triangle::triangle_overlaps_cells;
use accel_core::{Aabb, AccelStats, BuildError, PrimitiveSet, Real, bounds_survey};
use rayon::prelude::*;
use std::time::Instant;

/// Build parameters of a [`crate::Grid`].
#[derive(Clone, Debug, PartialEq)]
pub struct GridParams<T> {
    /// Cells per object along each axis, `m` of the resolution rule: about
    /// `m³·n` cells. Default 2 (the seed's 8 cells per object).
    pub density: f64,
    /// The box to grid instead of the union of the primitives' bounds. Only
    /// primitives that overlap it are referenced, and queries answer for the
    /// part of space inside it: a hit outside the region is found only if the
    /// primitive also lies in a cell the ray crosses, so treat hits outside it
    /// as unspecified. Default: none (the whole scene).
    pub region: Option<Aabb<T>>,
    /// The most cells the build may allocate (4 bytes each, and a bit each
    /// from [`OCCUPIED_BITS_MIN_CELLS`] cells on); more is refused
    /// with [`BuildError::BudgetExceeded`]. Default 2^28 (1 GiB of offsets).
    pub max_cells: u64,
    /// The most primitive references the build may store (4 bytes each).
    /// Default 2^28.
    pub max_references: u64,
    /// Whether a large grid with much empty space keeps [`Blocks`] of cells,
    /// over which its walks pass an empty block at a time
    /// ([`crate::blocks`]; from [`BLOCKS_MIN_CELLS`] cells on, when at least
    /// [`BLOCKS_MIN_EMPTY_SHARE`] of the blocks are empty). They take a byte
    /// per 64 cells. Default true; the answers are the same either way.
    pub skip_empty_blocks: bool,
    /// Whether cells' triangles are also kept in packed blocks, tested
    /// several at once ([`Layout`]). Default [`Layout::Indexed`]: packed
    /// cells take 4.3× the memory on the 100k sphere and traced 0.71–0.77×
    /// as fast on the 100k soup; only the sphere's shadow and diffuse rays
    /// gained (1.1–1.25×). The answers are the same either way.
    pub layout: Layout,
    /// Whether a small dense part of a large sparse scene, or a floor of
    /// many primitives lying flat in one plane, gets a grid of its own
    /// ([`accel_core::parts`], the rule the octree and the kD-tree follow):
    /// one grid over a teapot in a stadium gives the teapot's cell all its
    /// triangles, and rays leaving a floor walk the floor's cells, where
    /// apart they miss its flat box. Queries walk the parts one after the
    /// other. Default true; `false` is the seed's single grid. Ignored with
    /// a [`GridParams::region`].
    pub parts: bool,
}

impl<T: Real> Default for GridParams<T> {
    fn default() -> Self {
        Self {
            density: 2.0,
            region: None,
            max_cells: 1 << 28,
            max_references: 1 << 28,
            skip_empty_blocks: true,
            layout: DEFAULT_LAYOUT,
            parts: true,
        }
    }
}

impl<T: Real> GridParams<T> {
    /// Default parameters with density `m`.
    #[must_use]
    pub fn with_density(density: f64) -> Self {
        Self {
            density,
            ..Self::default()
        }
    }

    /// Default parameters over a user-given region.
    #[must_use]
    pub fn with_region(region: Aabb<T>) -> Self {
        Self {
            region: Some(region),
            ..Self::default()
        }
    }
}

/// What a build produces, before it is wrapped with its primitives.
pub(crate) struct Built<T: Real> {
    /// At least one; the first is the only one of a grid in one part.
    pub(crate) parts: Vec<GridPart<T>>,
    pub(crate) stats: AccelStats,
}

/// The cells each primitive truly overlaps: the cells its bounds overlap,
/// filtered by the primitive's exact (conservative) box test when the bounds
/// span more than one cell along two or more axes. A row of cells needs no
/// test: a connected primitive whose bounds reach both ends crosses each (a
/// disconnected primitive, or loose bounds, only adds references, which
/// never changes an answer). A triangle over [`BLOCK_TEST_MIN_CELLS`] or
/// more is tested block-wise ([`triangle_overlaps_cells`]), with the same
/// answers.
pub struct PrimitiveCells<'a, T, P: ?Sized> {
    /// The grid.
    pub geometry: &'a GridGeometry<T>,
    /// The primitives.
    pub prims: &'a P,
    /// Their bounds, precomputed, or `None` to ask the primitives (cheap
    /// for triangles, and no array to write).
    pub bounds: Option<&'a [Aabb<T>]>,
    /// Only primitives whose overlap test accepts this box are placed (the
    /// user region), or all when `None`.
    pub region: Option<&'a Aabb<T>>,
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized> CellVisitor for PrimitiveCells<'_, T, P> {
    #[inline]
    fn visit<F: FnMut(usize)>(&self, item: u32, mut cell: F) {
        let i = item as usize;
        if let Some(region) = self.region
            && !self.prims.overlaps_box(i, region)
        {
            return;
        }
        let bounds = match self.bounds {
            Some(boxes) => boxes[i],
            None => self.prims.bounds(i),
        };
        let Some(range) = self.geometry.cells_overlapping(&bounds) else {
            return;
        };
        // A primitive is connected and its bounds reach each extreme, so it
        // crosses every cell of a range that is one cell thick along two
        // axes (a row of cells): only wider ranges need the exact test.
        let wide_axes = (0..3).filter(|&a| range.lo[a] != range.hi[a]).count();
        if wide_axes <= 1 {
            self.geometry.for_each_cell_index(&range, cell);
            return;
        }
        // A triangle over a block of cells: the test shares what the cells
        // of a row or column have in common.
        if range.len() >= BLOCK_TEST_MIN_CELLS
            && let Some(tri) = self.prims.watertight_triangle(i)
        {
            let boundaries = [0, 1, 2].map(|a| {
                &self.geometry.boundaries(a)[range.lo[a] as usize..=range.hi[a] as usize + 1]
            });
            triangle_overlaps_cells(tri, boundaries, |[x, y, z]| {
                cell(self.geometry.linear_index([
                    range.lo[0] + x as u32,
                    range.lo[1] + y as u32,
                    range.lo[2] + z as u32,
                ]));
            });
            return;
        }
        // The cells go to the exact test in batches, so that the primitive
        // prepares it once per batch (a triangle's axes and projections).
        let mut boxes = [Aabb::empty(); CELL_BATCH];
        let mut cells = [0usize; CELL_BATCH];
        let mut meets = [false; CELL_BATCH];
        let mut n = 0;
        let mut test_batch = |boxes: &[Aabb<T>], cells: &[usize], meets: &mut [bool]| {
            self.prims.overlaps_boxes(i, boxes, meets);
            for (&c, &m) in cells.iter().zip(meets.iter()) {
                if m {
                    cell(c);
                }
            }
        };
        self.geometry.for_each_cell_box(&range, |c, b| {
            boxes[n] = b;
            cells[n] = c;
            n += 1;
            if n == CELL_BATCH {
                test_batch(&boxes, &cells, &mut meets);
                n = 0;
            }
        });
        test_batch(&boxes[..n], &cells[..n], &mut meets[..n]);
    }
}

/// Ranges of at least this many cells (of a primitive that is a triangle)
/// are tested as a block ([`triangle_overlaps_cells`]), smaller ones box by
/// box. The same cells either way; blocks pay where triangles cover a few
/// cells along each axis: the soup's grid built in 11% less time (one
/// thread, three alternated rounds), and the scanned meshes, whose
/// triangles rarely cover 12 cells, in the same instructions. From 8 cells
/// on, the sphere's build took 9% more instructions.
pub const BLOCK_TEST_MIN_CELLS: usize = 12;

/// Cells per call of [`PrimitiveSet::overlaps_boxes`]: most triangles of a
/// dense scene cover a handful of cells, and the largest take several calls.
const CELL_BATCH: usize = 32;

/// Grids of at least this many cells (offsets of 8 MiB and more) keep a bit
/// per cell that says whether it holds anything
/// ([`CellLists::with_occupied_bits`]), and their walks read it before the
/// offsets.
///
/// A walk through a large grid visits mostly empty cells (95% of the 1M
/// terrain's 8.1M cells are), and each visit read two offsets from an array
/// too large for the caches: in one pass of the terrain's camera rays, 60%
/// of the walk's samples waited on that load. The bits are 32 times
/// smaller; with them the terrain's camera, shadow and diffuse rays trace
/// about 1.09×, 1.15× and 1.6× as fast. On grids of 0.55M to 0.8M cells
/// (the 69k bunny, the 100k sphere and soup), whose offsets stay in the
/// caches, reading the bits first measured no faster.
pub const OCCUPIED_BITS_MIN_CELLS: usize = 1 << 21;

/// Grids of at least this many cells keep [`Blocks`] for skipping empty
/// space, when at least [`BLOCKS_MIN_EMPTY_SHARE`] of them are empty.
pub const BLOCKS_MIN_CELLS: usize = 1 << 12;

/// The share of empty blocks below which a grid keeps none.
pub const BLOCKS_MIN_EMPTY_SHARE: f64 = 0.5;

/// Blocks of `2^BLOCK_SHIFT` cells per axis.
pub const BLOCK_SHIFT: u32 = 2;

/// The default of [`GridParams::layout`].
pub const DEFAULT_LAYOUT: Layout = Layout::Indexed;

/// Primitives whose cells [`estimate_references`] counts.
pub const REFERENCE_SAMPLE: usize = 256;

/// An estimate of the references a build over `n` items would make, from
/// the cells of [`REFERENCE_SAMPLE`] of them spread evenly over the `n`
/// (every `n / 256`-th; `item(k)` names the `k`-th), scaled to `n`; `None`
/// for up to four samples' worth of items, which the exact build counts
/// quickly enough.
///
/// Counting a sample first is what lets a build refuse a scene over its
/// budget before making its cell lists: 100,000 copies of one triangle
/// across the scene took minutes to be refused by the exact build (issue
/// 32, item 3), the sample takes 256 of them. The octree checks its root
/// grids with it too.
pub fn estimate_references<V: CellVisitor>(
    visitor: &V,
    n: usize,
    item: impl Fn(usize) -> u32 + Sync,
) -> Option<u64> {
    if n <= 4 * REFERENCE_SAMPLE {
        return None;
    }
    let stride = n / REFERENCE_SAMPLE;
    let counted: u64 = (0..REFERENCE_SAMPLE)
        .into_par_iter()
        .map(|k| {
            let mut cells = 0u64;
            // Below n: k·stride + stride/2 < 256·stride <= n.
            visitor.visit(item(k * stride + stride / 2), |_| cells += 1);
            cells
        })
        .sum();
    Some((counted as f64 * (n as f64 / REFERENCE_SAMPLE as f64)) as u64)
}

/// Refuses, before the cell lists are made, a build whose references
/// clearly pass `budget`: an estimate ([`estimate_references`]) of more
/// than twice the budget is refused with it.
///
/// The exact build also stops the moment it passes the budget, but only
/// after enumerating (and testing) every cell of the primitives before that
/// point. A scene the sample leaves out is left to the exact build; between
/// the budget and twice it, so is a scene the sample might overestimate.
///
/// # Errors
/// [`BuildError::BudgetExceeded`] with the estimate.
fn check_reference_estimate<V: CellVisitor>(
    visitor: &V,
    items: Option<&[u32]>,
    n: usize,
    budget: u64,
) -> Result<(), BuildError> {
    match estimate_references(visitor, n, |i| items.map_or(i as u32, |items| items[i])) {
        Some(estimate) if estimate as f64 > 2.0 * budget as f64 => {
            Err(BuildError::BudgetExceeded {
                what: "cell references (estimated from 256 primitives spread over the scene)",
                needed: estimate,
                budget,
            })
        }
        _ => Ok(()),
    }
}

/// Builds the parts of a grid over `prims`: one grid over the whole scene
/// (or the user's region), or, where [`GridParams::parts`] says so and the
/// scene has them, a grid per part ([`accel_core::parts`]) sharing the
/// cell and reference budgets.
pub(crate) fn build<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    params: &GridParams<T>,
) -> Result<Built<T>, BuildError> {
    let start = Instant::now();
    let survey = bounds_survey(prims)?;
    let scene_bounds = survey.bounds;
    let (groups, object_count) = match &params.region {
        Some(region) => {
            if !region.is_finite() || region.is_empty() {
                return Err(BuildError::InvalidRegion);
            }
            accel_core::check_range(region)?;
            // Count what the region holds, for the resolution rule.
            let count = (0..prims.len())
                .filter(|&i| prims.bounds(i).overlaps(region) && prims.overlaps_box(i, region))
                .count();
            (vec![(None, *region)], count)
        }
        None if prims.is_empty() => (vec![(None, Aabb::from_point(accel_core::Vec3::ZERO))], 0),
        None if !params.parts => (vec![(None, scene_bounds)], prims.len()),
        None => {
            let groups = match split_surveyed(
                prims.len(),
                |i| prims.bounds(i),
                &survey,
                prims.wide_hits(),
            ) {
                Some(groups) => groups
                    .into_iter()
                    .map(|g| (Some(g.prims), g.bounds))
                    .collect(),
                None => vec![(None, scene_bounds)],
            };
            (groups, prims.len())
        }
    };
    let mut parts = Vec::with_capacity(groups.len());
    let (mut cells_left, mut refs_left) = (params.max_cells, params.max_references);
    for (items, bounds) in &groups {
        let count = items.as_ref().map_or(object_count, Vec::len);
        let part = build_part(
            prims,
            items.as_deref(),
            bounds,
            count,
            params,
            cells_left,
            refs_left,
        )?;
        cells_left -= part.geometry.cell_count() as u64;
        refs_left -= part.cells.reference_count() as u64;
        parts.push(part);
    }
    let stats = grid_stats(&parts, prims.len(), object_count, params, start);
    Ok(Built { parts, stats })
}

/// One part's grid: over the primitives `items` (all when `None`) inside
/// `bounds`, its resolution from their `count`, within the cell and
/// reference budgets left.
fn build_part<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    items: Option<&[u32]>,
    bounds: &Aabb<T>,
    count: usize,
    params: &GridParams<T>,
    max_cells: u64,
    max_references: u64,
) -> Result<GridPart<T>, BuildError> {
    let res = resolution(bounds, count, params.density, max_cells)?;
    let geometry = GridGeometry::new(*bounds, res);
    let visitor = PrimitiveCells {
        geometry: &geometry,
        prims,
        bounds: None,
        region: params.region.as_ref(),
    };
    let n = items.map_or(prims.len(), <[u32]>::len);
    check_reference_estimate(&visitor, items, n, max_references)?;
    let cells = CellLists::build_over(
        geometry.cell_count(),
        items,
        prims.len() as u32,
        max_references,
        &visitor,
    )?;
    let cells = if geometry.cell_count() >= OCCUPIED_BITS_MIN_CELLS {
        cells.with_occupied_bits()
    } else {
        cells
    };
    let blocks = (params.skip_empty_blocks && geometry.cell_count() >= BLOCKS_MIN_CELLS)
        .then(|| Blocks::new(&geometry, &cells, BLOCK_SHIFT))
        .filter(|b| b.empty_share() >= BLOCKS_MIN_EMPTY_SHARE);
    let offsets = cells.offsets();
    let packed = PackedTriangles::new(
        params.layout,
        prims,
        cells.refs(),
        offsets
            .windows(2)
            .map(|w| (w[0] as usize, (w[1] - w[0]) as usize)),
    );
    Ok(GridPart {
        geometry,
        cells,
        blocks,
        packed,
    })
}

/// The statistics of a grid of `parts` over `primitives`, of which
/// `object_count` are gridded (fewer with a region).
fn grid_stats<T: Real>(
    parts: &[GridPart<T>],
    primitives: usize,
    object_count: usize,
    params: &GridParams<T>,
    start: Instant,
) -> AccelStats {
    let bytes = parts
        .iter()
        .map(|p| {
            p.cells.bytes()
                + p.blocks.as_ref().map_or(0, Blocks::bytes)
                + p.packed.as_ref().map_or(0, PackedTriangles::memory_bytes)
                + (0..3)
                    .map(|a| size_of_val(p.geometry.boundaries(a)))
                    .sum::<usize>()
        })
        .sum();
    let cell_count: usize = parts.iter().map(|p| p.geometry.cell_count()).sum();
    let (mut empty_cells, mut max_cell_len) = (0, 0);
    for p in parts {
        let (empty, max) = p.cells.occupancy();
        empty_cells += empty;
        max_cell_len = max_cell_len.max(max);
    }
    let res = parts[0].geometry.resolution();
    AccelStats {
        kind: "grid",
        primitives,
        // Everything the build does, its statistics included.
        build_time: start.elapsed(),
        bytes,
        nodes: cell_count,
        leaves: cell_count,
        empty_leaves: empty_cells,
        references: parts.iter().map(|p| p.cells.reference_count()).sum(),
        max_leaf_references: max_cell_len,
        extra: vec![
            ("nx", f64::from(res[0])),
            ("ny", f64::from(res[1])),
            ("nz", f64::from(res[2])),
            ("density", params.density),
            (
                "cells_per_object",
                cell_count as f64 / object_count.max(1) as f64,
            ),
            ("parts", parts.len() as f64),
        ],
    }
}
