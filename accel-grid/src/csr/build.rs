//! The two-pass build of [`CellLists`]: a parallel record of each item's
//! cells, bucketed by ranges of cells, then each range counted, scanned and
//! placed in parallel.

use super::{CELLS_PER_CHUNK, CellLists, CellVisitor};
use accel_core::BuildError;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// Items per parallel task in the two passes.
const ITEMS_PER_TASK: usize = 1024;

impl CellLists {
    /// Builds the lists of `cell_count` cells for items `0..item_count`.
    ///
    /// # Errors
    /// [`BuildError::BudgetExceeded`] when the references would number more
    /// than `max_references` (or than `u32` offsets can address).
    pub fn build<V: CellVisitor>(
        cell_count: usize,
        item_count: u32,
        max_references: u64,
        visitor: &V,
    ) -> Result<Self, BuildError> {
        Self::build_with(
            cell_count,
            item_count as usize,
            |i| i as u32,
            true,
            max_references,
            visitor,
        )
    }

    /// Builds the lists of `cell_count` cells for the given items: any ids,
    /// such as the primitives of one cell of a coarser grid (the octree's
    /// child grids). The lists hold the ids themselves, ascending in each
    /// cell, and `visitor` is asked about each id of `items`, which must not
    /// repeat.
    ///
    /// # Errors
    /// [`BuildError::BudgetExceeded`] as [`CellLists::build`].
    pub fn build_items<V: CellVisitor>(
        cell_count: usize,
        items: &[u32],
        max_references: u64,
        visitor: &V,
    ) -> Result<Self, BuildError> {
        Self::build_with(
            cell_count,
            items.len(),
            |i| items[i],
            items.is_sorted(),
            max_references,
            visitor,
        )
    }

    /// [`CellLists::build_items`] for `Some(items)`, [`CellLists::build`]
    /// for every item `0..item_count` when `None`: the lists of a grid over
    /// some of a scene's primitives (a part, an octree's root) or all.
    ///
    /// # Errors
    /// [`BuildError::BudgetExceeded`] as [`CellLists::build`].
    pub fn build_over<V: CellVisitor>(
        cell_count: usize,
        items: Option<&[u32]>,
        item_count: u32,
        max_references: u64,
        visitor: &V,
    ) -> Result<Self, BuildError> {
        match items {
            Some(items) => Self::build_items(cell_count, items, max_references, visitor),
            None => Self::build(cell_count, item_count, max_references, visitor),
        }
    }

    /// The two-pass build over items `id(0) .. id(len - 1)`.
    ///
    /// Pass 1 asks the visitor about each item once and records the item's
    /// cells per task and range of cells; the lists are then counted and
    /// placed from that record, range by range, so the visitor's work (for triangles, the exact triangle-box
    /// tests that dominate the build) is done once, at the cost of a
    /// temporary 4 bytes per reference. Grids with more cells than `u32`
    /// indexes ask the visitor again instead. `ascending` tells whether the
    /// ids ascend with `i` (then the recorded path needs no sort).
    fn build_with<V: CellVisitor>(
        cell_count: usize,
        len: usize,
        id: impl Fn(usize) -> u32 + Sync,
        ascending: bool,
        max_references: u64,
        visitor: &V,
    ) -> Result<Self, BuildError> {
        let budget = max_references.min(u64::from(u32::MAX));
        if u32::try_from(cell_count).is_ok() {
            let ranges = CellRanges::new(cell_count, len, rayon::current_num_threads());
            return match record_cells(len, &id, ranges, budget, visitor) {
                Ok(tasks) => place_recorded(cell_count, &tasks, &id, ranges, ascending, budget),
                // The record stopped the moment it passed the budget; what it
                // had counted by then is the figure (counting the rest would
                // cost the whole enumeration the budget exists to refuse:
                // 200 s for 100,000 copies of one large triangle, issue 32).
                Err(counted) => Err(over_budget(counted, budget)),
            };
        }

        // slots[c + 1] counts cell c in the first pass, holds its start
        // before the second and its end after it; slots[0] stays 0. The
        // array becomes the offsets.
        let slots: Vec<AtomicU32> = written_zeros(cell_count + 1);
        let cells = &slots[1..];
        (0..len)
            .into_par_iter()
            .with_min_len(ITEMS_PER_TASK)
            .for_each(|i| {
                visitor.visit(id(i), |c| {
                    cells[c].fetch_add(1, Ordering::Relaxed);
                });
            });
        let mut slots: Vec<u32> = slots.into_iter().map(AtomicU32::into_inner).collect();
        let running = exclusive_prefix_sum(&mut slots[1..]);
        if running > budget {
            return Err(over_budget(running, budget));
        }
        let total = running as usize;
        let slots: Vec<AtomicU32> = slots.into_iter().map(AtomicU32::new).collect();
        let refs: Vec<AtomicU32> = written_zeros(total);
        let cells = &slots[1..];
        (0..len)
            .into_par_iter()
            .with_min_len(ITEMS_PER_TASK)
            .for_each(|i| {
                let item = id(i);
                visitor.visit(item, |c| {
                    let at = cells[c].fetch_add(1, Ordering::Relaxed);
                    refs[at as usize].store(item, Ordering::Relaxed);
                });
            });
        let offsets: Vec<u32> = slots.into_iter().map(AtomicU32::into_inner).collect();
        let mut refs: Vec<u32> = refs.into_iter().map(AtomicU32::into_inner).collect();
        debug_assert_eq!(offsets[cell_count] as usize, total);
        sort_each_cell(&offsets, &mut refs);
        Ok(Self::with_occupancy(offsets, refs))
    }
}

/// `len` zeros (plain or atomic counters), written in parallel rather than
/// allocated zeroed.
///
/// A grid's offsets are its largest array (8 million cells for the 1M
/// terrain), and serial passes over them held back the build's scaling with
/// threads. The counts then increment each entry, and a page of a zeroed
/// allocation that is read first maps the kernel's shared zero page; the
/// write that follows replaces it, which flushes the translation caches of
/// every other thread of the process (an interprocessor interrupt, very
/// costly in a virtual machine). With two threads counting and scanning a
/// fresh zeroed offsets array, the terrain's placement took 55 ms, against
/// 39 ms on one thread and 23 ms on two with the array written first
/// (a page written first faults once, with no flush).
fn written_zeros<Z: Default + Send>(len: usize) -> Vec<Z> {
    (0..len)
        .into_par_iter()
        .with_min_len(CELLS_PER_CHUNK)
        .map(|_| Z::default())
        .collect()
}

/// Replaces each count by the sum of the counts before it and returns the
/// total, in `u64`: chunk totals in parallel, a short serial scan over them,
/// then each chunk's running sums in parallel. Entries are truncated to
/// `u32`; the caller checks the total before using them.
pub(super) fn exclusive_prefix_sum(counts: &mut [u32]) -> u64 {
    let chunk_totals: Vec<u64> = counts
        .par_chunks(CELLS_PER_CHUNK)
        .map(|chunk| chunk.iter().map(|&c| u64::from(c)).sum())
        .collect();
    let mut starts = Vec::with_capacity(chunk_totals.len());
    let mut total = 0u64;
    for t in chunk_totals {
        starts.push(total);
        total += t;
    }
    counts
        .par_chunks_mut(CELLS_PER_CHUNK)
        .zip(starts)
        .for_each(|(chunk, mut running)| {
            for c in chunk {
                let count = u64::from(*c);
                *c = running as u32;
                running += count;
            }
        });
    total
}

/// Sorts every cell's references, in parallel over groups of cells.
fn sort_each_cell(offsets: &[u32], refs: &mut [u32]) {
    const CELLS_PER_TASK: usize = 4096;
    let cell_count = offsets.len() - 1;
    let mut groups: Vec<(usize, &mut [u32])> = Vec::with_capacity(cell_count / CELLS_PER_TASK + 1);
    let mut rest = refs;
    let mut first = 0;
    while first < cell_count {
        let last = (first + CELLS_PER_TASK).min(cell_count);
        let len = (offsets[last] - offsets[first]) as usize;
        let (group, tail) = rest.split_at_mut(len);
        groups.push((first, group));
        rest = tail;
        first = last;
    }
    groups.into_par_iter().for_each(|(first, group)| {
        let base = offsets[first];
        let last = (first + CELLS_PER_TASK).min(cell_count);
        for w in offsets[first..=last].windows(2) {
            if w[1] - w[0] > 1 {
                group[(w[0] - base) as usize..(w[1] - base) as usize].sort_unstable();
            }
        }
    });
}

/// The cells split into ranges of `1 << shift` consecutive cells, the last
/// one shorter: the unit of the record's buckets and of the parallel count,
/// scan and placement.
#[derive(Clone, Copy, Debug)]
pub(super) struct CellRanges {
    pub(super) shift: u32,
    pub(super) count: usize,
}

/// Bits of a recorded entry that hold the item's position in its task.
const POSITION_BITS: u32 = ITEMS_PER_TASK.trailing_zeros();
/// Those bits.
const POSITION_MASK: u32 = (1 << POSITION_BITS) - 1;
/// The longest range is `1 << MAX_SHIFT` cells: a cell's index within its
/// range fits in the entry's remaining bits.
pub(super) const MAX_SHIFT: u32 = u32::BITS - POSITION_BITS;
const _: () = assert!(ITEMS_PER_TASK.is_power_of_two());

impl CellRanges {
    /// Ranges of a power-of-two length (so that a cell's range is a shift,
    /// not a division) of at most `1 << MAX_SHIFT` cells: one range for
    /// small builds or one thread where the cells allow, else `threads` to
    /// `2·threads` ranges (or more, for grids of more than
    /// `threads << MAX_SHIFT` cells).
    pub(super) fn new(cell_count: usize, items: usize, threads: usize) -> Self {
        let shift = if threads <= 1 || items < PARALLEL_ITEMS || cell_count < 2 * threads {
            MAX_SHIFT
        } else {
            // 2^shift <= cell_count / threads < 2^(shift + 1).
            (cell_count / threads).ilog2().min(MAX_SHIFT)
        };
        Self {
            shift,
            count: cell_count.div_ceil(1 << shift).max(1),
        }
    }

    /// The bits of a cell index that give its index within its range; the
    /// bits above them, `c >> shift`, give the range.
    #[inline]
    pub(super) fn mask(self) -> u32 {
        (1 << self.shift) - 1
    }

    /// Cells per range (the last may hold fewer), for chunking a per-cell
    /// array of `cell_count` entries.
    pub(super) fn len(self, cell_count: usize) -> usize {
        (1usize << self.shift).min(cell_count).max(1)
    }
}

/// Builds with fewer items than this record into as few buckets as the
/// cells allow and count, scan and place on one thread.
pub(super) const PARALLEL_ITEMS: usize = 1 << 14;

/// The cells of a run of consecutive items, as pass 1 recorded them: for
/// each range of cells, one entry per reference falling in it, in item
/// order, holding the cell's index within the range (high bits) and the
/// item's position in the run (the low [`POSITION_BITS`]).
struct RecordedTask {
    /// Position of the run's first item.
    first: usize,
    buckets: Vec<Vec<u32>>,
}

/// Pass 1 with a record: each item's cells, kept per run of
/// [`ITEMS_PER_TASK`] items and per range of cells. Stops once the
/// references seen pass `budget`, so an oversized build fails before its
/// record grows past the budget.
fn record_cells<V: CellVisitor>(
    len: usize,
    id: &(impl Fn(usize) -> u32 + Sync),
    ranges: CellRanges,
    budget: u64,
    visitor: &V,
) -> Result<Vec<RecordedTask>, u64> {
    let seen = AtomicU64::new(0);
    (0..len.div_ceil(ITEMS_PER_TASK))
        .into_par_iter()
        .map(|task| {
            let first = task * ITEMS_PER_TASK;
            let last = (first + ITEMS_PER_TASK).min(len);
            let mut buckets = vec![Vec::new(); ranges.count];
            let recorded = if let [only] = buckets.as_mut_slice() {
                // One range: a cell is its own index within it, and the
                // bucket needs no choosing (most of the octree's grids).
                let mut push = |c, position| only.push(c << POSITION_BITS | position);
                record_run(first..last, id, visitor, &seen, budget, &mut push)?
            } else {
                // The shift and mask copied out of `ranges`, so that they
                // stay in registers while the buckets are written (12M more
                // instructions otherwise, about 0.6% of the terrain's
                // one-thread build).
                let (shift, mask) = (ranges.shift, ranges.mask());
                let mut push = |c: u32, position| {
                    buckets[(c >> shift) as usize].push((c & mask) << POSITION_BITS | position);
                };
                record_run(first..last, id, visitor, &seen, budget, &mut push)?
            };
            seen.fetch_add(recorded, Ordering::Relaxed);
            Ok(RecordedTask { first, buckets })
        })
        .collect()
}

/// Records the cells of the items at positions `items` through
/// `push(cell, position in the run)`, checking after each item that the
/// references seen by every task stay within `budget`; the references
/// recorded, or `Err` with the references seen by then, once past the
/// budget.
#[inline(always)]
fn record_run<V: CellVisitor>(
    items: std::ops::Range<usize>,
    id: &(impl Fn(usize) -> u32 + Sync),
    visitor: &V,
    seen: &AtomicU64,
    budget: u64,
    push: &mut impl FnMut(u32, u32),
) -> Result<u64, u64> {
    let mut recorded = 0u64;
    let first = items.start;
    for i in items {
        let position = (i - first) as u32;
        // The caller checked that every cell index fits.
        visitor.visit(id(i), |c| {
            push(c as u32, position);
            recorded += 1;
        });
        let total = seen.load(Ordering::Relaxed) + recorded;
        if total > budget {
            return Err(total);
        }
    }
    Ok(recorded)
}

/// Counts and places the recorded references without atomics, each range
/// of cells by one task.
///
/// A range's task reads only its own buckets (in task order, so in item
/// order), counts its cells, turns the counts into starts from the range's
/// base (the references of the ranges before it, known from the buckets'
/// lengths), then places its references into its own part of the
/// reference array. Each cell therefore receives its items in order: its
/// list is ascending when the ids are (`ascending`), and sorted afterwards
/// otherwise.
fn place_recorded(
    cell_count: usize,
    tasks: &[RecordedTask],
    id: &(impl Fn(usize) -> u32 + Sync),
    ranges: CellRanges,
    ascending: bool,
    budget: u64,
) -> Result<CellLists, BuildError> {
    let per_range: Vec<u64> = (0..ranges.count)
        .map(|r| tasks.iter().map(|t| t.buckets[r].len() as u64).sum())
        .collect();
    let total: u64 = per_range.iter().sum();
    if total > budget {
        return Err(over_budget(total, budget));
    }
    // Fits: total <= budget <= u32::MAX.
    let bases: Vec<u32> = per_range
        .iter()
        .scan(0u64, |running, &n| {
            let base = *running as u32;
            *running += n;
            Some(base)
        })
        .collect();

    let mut refs = vec![0u32; total as usize];
    let mut parts: Vec<&mut [u32]> = Vec::with_capacity(ranges.count);
    let mut rest = refs.as_mut_slice();
    for &n in &per_range {
        let (part, tail) = rest.split_at_mut(n as usize);
        parts.push(part);
        rest = tail;
    }

    // offsets[c + 1] counts cell c, then holds its start, then its end.
    let mut offsets: Vec<u32> = written_zeros(cell_count + 1);
    let range_len = ranges.len(cell_count);
    let occupancy = offsets[1..]
        .par_chunks_mut(range_len)
        .zip(parts)
        .enumerate()
        .map(|(r, (cursors, part))| {
            for task in tasks {
                for &entry in &task.buckets[r] {
                    cursors[(entry >> POSITION_BITS) as usize] += 1;
                }
            }
            let mut running = bases[r];
            let (mut empty, mut most) = (0, 0);
            for c in cursors.iter_mut() {
                let count = *c;
                *c = running;
                running += count;
                empty += usize::from(count == 0);
                most = most.max(count);
            }
            for task in tasks {
                for &entry in &task.buckets[r] {
                    let item = id(task.first + (entry & POSITION_MASK) as usize);
                    let at = &mut cursors[(entry >> POSITION_BITS) as usize];
                    part[(*at - bases[r]) as usize] = item;
                    *at += 1;
                }
            }
            (empty, most as usize)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1.max(b.1)));
    debug_assert_eq!(u64::from(offsets[cell_count]), total);
    if !ascending {
        sort_each_cell(&offsets, &mut refs);
    }
    Ok(CellLists::assembled(offsets, refs, occupancy))
}

/// The error of a build that needs `needed` references.
fn over_budget(needed: u64, budget: u64) -> BuildError {
    BuildError::BudgetExceeded {
        what: "cell references",
        needed,
        budget,
    }
}
