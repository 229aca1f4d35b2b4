//! Compact cell lists: one offset per cell and one reference array (CSR).
//!
//! Built from one parallel pass over the items, which records each item's
//! cells, bucketed by ranges of cells: then each range, in parallel, counts
//! its cells' references from its buckets, turns the counts into offsets
//! and places its references, in item order. An empty
//! cell costs one `u32`. Each cell's references end up sorted ascending, so the
//! build is deterministic whatever the thread count. The items are `0..n`
//! ([`CellLists::build`]) or any list of ids ([`CellLists::build_items`]: the
//! primitives of one cell, refined by a finer grid); [`CellLists::from_cells`]
//! assembles lists a structure has put together itself.

use accel_core::BuildError;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// What the two-pass build asks of the thing being indexed: the cells each
/// item belongs to. `visit` must call `cell` at most once per cell, with the
/// same cells each time it is asked about one item (the build usually asks
/// once and records the answer; very large grids and over-budget builds ask
/// again).
pub trait CellVisitor: Sync {
    /// Calls `cell` with the linear index of every cell that `item` belongs to.
    fn visit<F: FnMut(usize)>(&self, item: u32, cell: F);
}

/// Cell lists in compressed sparse row form: cell `c` holds
/// `refs[offsets[c] .. offsets[c + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CellLists {
    offsets: Vec<u32>,
    refs: Vec<u32>,
    /// The cells with no reference and the most references in one cell,
    /// taken when the offsets are made (a large grid's largest array, which
    /// a pass of its own would read again).
    occupancy: (usize, usize),
    /// A bit per cell, set when the cell holds a reference (cell `c` is bit
    /// `c % 64` of word `c / 64`), once [`CellLists::with_occupied_bits`]
    /// has made them; empty before.
    occupied: Vec<u64>,
}

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

    /// Lists with the given references per cell, in cell order, each kept as
    /// given (a structure that assembles its own cells, such as the octree
    /// joining its grids into one array, or that marks some cells specially).
    ///
    /// # Errors
    /// [`BuildError::BudgetExceeded`] when the references number more than
    /// `u32` offsets can address.
    pub fn from_cells<I, C>(cells: I) -> Result<Self, BuildError>
    where
        I: IntoIterator<Item = C>,
        C: AsRef<[u32]>,
    {
        let cells = cells.into_iter();
        let mut offsets = Vec::with_capacity(cells.size_hint().0 + 1);
        let mut refs = Vec::new();
        offsets.push(0);
        for cell in cells {
            refs.extend_from_slice(cell.as_ref());
            let end = u32::try_from(refs.len()).map_err(|_| BuildError::BudgetExceeded {
                what: "cell references",
                needed: refs.len() as u64,
                budget: u64::from(u32::MAX),
            })?;
            offsets.push(end);
        }
        offsets.shrink_to_fit();
        refs.shrink_to_fit();
        Ok(Self::with_occupancy(offsets, refs))
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

    /// Number of cells.
    #[inline]
    #[must_use]
    pub fn cell_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The references of cell `c`.
    #[inline]
    #[must_use]
    pub fn cell(&self, c: usize) -> &[u32] {
        self.cell_at(c).1
    }

    /// [`CellLists::cell`], with where the list starts in
    /// [`CellLists::refs`].
    #[inline]
    #[must_use]
    pub fn cell_at(&self, c: usize) -> (usize, &[u32]) {
        let (start, end) = (self.offsets[c] as usize, self.offsets[c + 1] as usize);
        (start, &self.refs[start..end])
    }

    /// The offsets array (`cell_count + 1` entries).
    #[inline]
    #[must_use]
    pub fn offsets(&self) -> &[u32] {
        &self.offsets
    }

    /// The reference array.
    #[inline]
    #[must_use]
    pub fn refs(&self) -> &[u32] {
        &self.refs
    }

    /// Total number of references.
    #[inline]
    #[must_use]
    pub fn reference_count(&self) -> usize {
        self.refs.len()
    }

    /// Heap bytes of both arrays.
    #[must_use]
    pub fn bytes(&self) -> usize {
        (self.offsets.capacity() + self.refs.capacity()) * size_of::<u32>()
            + self.occupied.capacity() * size_of::<u64>()
    }

    /// Whether the lists keep a bit per cell
    /// ([`CellLists::with_occupied_bits`]).
    #[inline]
    #[must_use]
    pub fn has_occupied_bits(&self) -> bool {
        !self.occupied.is_empty()
    }

    /// These lists with a bit per cell that says whether the cell holds
    /// anything, for [`CellLists::occupied_cell`]: 1/32 of the offsets'
    /// memory, made in one parallel pass over them.
    #[must_use]
    pub fn with_occupied_bits(mut self) -> Self {
        self.occupied = occupied_bits(&self.offsets);
        self
    }

    /// [`CellLists::cell_at`], reading the cell's occupancy bit first: an empty
    /// cell is answered without touching the offsets, from an array 32 times
    /// smaller. Lists without the bits ([`CellLists::has_occupied_bits`])
    /// take the offsets for every cell.
    #[inline]
    #[must_use]
    pub fn occupied_cell(&self, c: usize) -> (usize, &[u32]) {
        // `get` is `None` when the lists keep no bits (or `c` is out of
        // range, which `cell` then reports).
        if let Some(word) = self.occupied.get(c / 64)
            && word >> (c % 64) & 1 == 0
        {
            return (0, &[]);
        }
        self.cell_at(c)
    }

    /// Whether any of the `len` cells from `start` on holds a reference: two
    /// offsets apart (they never decrease), or a few bits of one or two
    /// words when the lists keep occupancy bits. `len` is at most 64.
    #[inline]
    #[must_use]
    pub fn any_in_run(&self, start: usize, len: usize) -> bool {
        debug_assert!(len <= 64 && start + len <= self.cell_count());
        if self.occupied.is_empty() {
            return self.offsets[start] != self.offsets[start + len];
        }
        let (w, s) = (start / 64, start % 64);
        let mut bits = self.occupied[w] >> s;
        if s + len > 64 {
            bits |= self.occupied[w + 1] << (64 - s);
        }
        let mask = if len == 64 { !0 } else { (1u64 << len) - 1 };
        bits & mask != 0
    }

    /// Cells with no reference.
    #[must_use]
    pub fn empty_cells(&self) -> usize {
        self.occupancy().0
    }

    /// The most references in one cell.
    #[must_use]
    pub fn max_cell_len(&self) -> usize {
        self.occupancy().1
    }

    /// The cells with no reference and the most references in one cell.
    #[must_use]
    pub fn occupancy(&self) -> (usize, usize) {
        self.occupancy
    }

    /// Lists of the given arrays, their occupancy taken in one pass over the
    /// offsets.
    fn with_occupancy(offsets: Vec<u32>, refs: Vec<u32>) -> Self {
        let occupancy = offsets
            .par_windows(2)
            .with_min_len(CELLS_PER_CHUNK)
            .fold(
                || (0, 0),
                |(empty, most), w| {
                    let len = (w[1] - w[0]) as usize;
                    (empty + usize::from(len == 0), most.max(len))
                },
            )
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1.max(b.1)));
        Self::assembled(offsets, refs, occupancy)
    }

    /// Lists of the given arrays and occupancy, without occupancy bits.
    fn assembled(offsets: Vec<u32>, refs: Vec<u32>, occupancy: (usize, usize)) -> Self {
        Self {
            offsets,
            refs,
            occupancy,
            occupied: Vec::new(),
        }
    }
}

/// Words of [`CellLists::occupied`] per parallel task, at least.
const WORDS_PER_TASK: usize = 1024;

/// A bit per cell of `offsets` (one more entry than cells), set when the
/// cell holds a reference.
fn occupied_bits(offsets: &[u32]) -> Vec<u64> {
    let cells = offsets.len().saturating_sub(1);
    (0..cells.div_ceil(64))
        .into_par_iter()
        .with_min_len(WORDS_PER_TASK)
        .map(|w| match offsets.get(64 * w..64 * w + 65) {
            Some(window) => word_bits(window.try_into().expect("65 offsets")),
            // The last word, of fewer cells.
            None => offsets[64 * w..]
                .windows(2)
                .enumerate()
                .fold(0, |bits, (b, pair)| {
                    bits | u64::from(pair[1] != pair[0]) << b
                }),
        })
        .collect()
}

/// The occupancy bits of the 64 cells whose offsets are `window` (65
/// entries): the 64 comparisons as bytes (vector compares), packed eight at
/// a time by [`pack_bytes`].
#[inline]
fn word_bits(window: &[u32; 65]) -> u64 {
    let held: [u8; 64] = std::array::from_fn(|b| u8::from(window[b + 1] != window[b]));
    held.chunks_exact(8)
        .enumerate()
        .fold(0, |bits, (k, eight)| {
            bits | pack_bytes(eight.try_into().expect("8 bytes")) << (8 * k)
        })
}

/// Eight bytes of 0 or 1 as the bits of one byte (byte `i` to bit `i`): the
/// product places byte `i` at bit `56 + i` (the terms `i + j = 7` of
/// `Σ byte_i·2^(8i) · Σ 2^(7j+7)`), lower terms stay below bit 56 without
/// carrying into it, and higher ones overflow away.
#[inline]
fn pack_bytes(eight: [u8; 8]) -> u64 {
    u64::from_le_bytes(eight).wrapping_mul(0x0102_0408_1020_4080) >> 56
}

/// Cells per parallel chunk of the build's linear passes over cells.
const CELLS_PER_CHUNK: usize = 1 << 16;

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
fn exclusive_prefix_sum(counts: &mut [u32]) -> u64 {
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
struct CellRanges {
    shift: u32,
    count: usize,
}

/// Bits of a recorded entry that hold the item's position in its task.
const POSITION_BITS: u32 = ITEMS_PER_TASK.trailing_zeros();
/// Those bits.
const POSITION_MASK: u32 = (1 << POSITION_BITS) - 1;
/// The longest range is `1 << MAX_SHIFT` cells: a cell's index within its
/// range fits in the entry's remaining bits.
const MAX_SHIFT: u32 = u32::BITS - POSITION_BITS;
const _: () = assert!(ITEMS_PER_TASK.is_power_of_two());

impl CellRanges {
    /// Ranges of a power-of-two length (so that a cell's range is a shift,
    /// not a division) of at most `1 << MAX_SHIFT` cells: one range for
    /// small builds or one thread where the cells allow, else `threads` to
    /// `2·threads` ranges (or more, for grids of more than
    /// `threads << MAX_SHIFT` cells).
    fn new(cell_count: usize, items: usize, threads: usize) -> Self {
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
    fn mask(self) -> u32 {
        (1 << self.shift) - 1
    }

    /// Cells per range (the last may hold fewer), for chunking a per-cell
    /// array of `cell_count` entries.
    fn len(self, cell_count: usize) -> usize {
        (1usize << self.shift).min(cell_count).max(1)
    }
}

/// Builds with fewer items than this record into as few buckets as the
/// cells allow and count, scan and place on one thread.
const PARALLEL_ITEMS: usize = 1 << 14;

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

#[cfg(test)]
mod tests {
    use super::*;

    /// Item i belongs to cells `i % first` and `(i * factor) % second`,
    /// once each.
    struct TwoCells {
        first: usize,
        factor: usize,
        second: usize,
    }

    impl CellVisitor for TwoCells {
        fn visit<F: FnMut(usize)>(&self, item: u32, mut cell: F) {
            let a = item as usize % self.first;
            let b = (item as usize * self.factor) % self.second;
            cell(a);
            if b != a {
                cell(b);
            }
        }
    }

    /// Cells i % 5 and (i * 3) % 7 of 7.
    const MODULAR: TwoCells = TwoCells {
        first: 5,
        factor: 3,
        second: 7,
    };

    /// Item `i` belongs to cells `(i · STRIDE) % cells` and, for every
    /// tenth item, the last cell.
    struct Sparse {
        cells: usize,
    }

    impl Sparse {
        const STRIDE: usize = 7919;
    }

    impl CellVisitor for Sparse {
        fn visit<F: FnMut(usize)>(&self, item: u32, mut cell: F) {
            let i = item as usize;
            let a = (i * Self::STRIDE) % self.cells;
            cell(a);
            if i.is_multiple_of(10) && a != self.cells - 1 {
                cell(self.cells - 1);
            }
        }
    }

    #[test]
    fn pack_bytes_maps_byte_i_to_bit_i() {
        for v in 0..=255u8 {
            let bytes = std::array::from_fn(|i| (v >> i) & 1);
            assert_eq!(pack_bytes(bytes), u64::from(v));
        }
    }

    #[test]
    fn a_run_holds_something_exactly_when_one_of_its_cells_does() {
        let cells = 64 * 5 + 21;
        let visitor = Sparse { cells };
        let plain = CellLists::build(cells, 30, u64::MAX, &visitor).unwrap();
        let full = (0..cells).filter(|&c| !plain.cell(c).is_empty()).count();
        assert!(full > 20 && full < 40, "premise: sparse, {full} cells full");
        let bits = plain.clone().with_occupied_bits();
        for start in 0..cells {
            for len in 1..=64.min(cells - start) {
                let want = (start..start + len).any(|c| !plain.cell(c).is_empty());
                assert_eq!(plain.any_in_run(start, len), want, "offsets, {start}+{len}");
                assert_eq!(bits.any_in_run(start, len), want, "bits, {start}+{len}");
            }
        }
    }

    #[test]
    fn occupied_bits_answer_each_cell_as_its_offsets() {
        // Not a whole number of 64-cell words, and mostly empty; the last
        // cell occupied.
        let cells = 64 * 300 + 37;
        let visitor = Sparse { cells };
        let items = 3000u32;
        let mut expected: std::collections::HashMap<usize, Vec<u32>> =
            std::collections::HashMap::new();
        for i in 0..items {
            visitor.visit(i, |c| expected.entry(c).or_default().push(i));
        }
        assert!(expected.contains_key(&(cells - 1)) && expected.len() < cells / 2);
        let built = CellLists::build(cells, items, u64::MAX, &visitor).unwrap();
        let assembled = CellLists::from_cells(
            (0..cells).map(|c| expected.get(&c).cloned().unwrap_or_default()),
        )
        .unwrap();
        for lists in [built, assembled] {
            assert!(!lists.has_occupied_bits());
            let with_bits = lists.clone().with_occupied_bits();
            assert!(with_bits.has_occupied_bits());
            for c in 0..cells {
                let want = expected.get(&c).map_or(&[][..], Vec::as_slice);
                assert_eq!(with_bits.occupied_cell(c).1, want, "cell {c}");
                assert_eq!(lists.occupied_cell(c).1, want, "cell {c} without bits");
            }
            assert_eq!(with_bits.bytes(), lists.bytes() + cells.div_ceil(64) * 8);
        }
    }

    #[test]
    fn lists_match_a_direct_construction() {
        let items = 10_000u32;
        let lists = CellLists::build(7, items, u64::MAX, &MODULAR).unwrap();
        let mut expected = vec![Vec::new(); 7];
        for i in 0..items {
            MODULAR.visit(i, |c| expected[c].push(i));
        }
        for (c, want) in expected.iter().enumerate() {
            assert_eq!(lists.cell(c), want.as_slice(), "cell {c}");
        }
        assert_eq!(
            lists.reference_count(),
            expected.iter().map(Vec::len).sum::<usize>()
        );
        assert_eq!(lists.empty_cells(), 0);
        assert_eq!(lists.offsets()[0], 0);
    }

    #[test]
    fn reference_budget_is_enforced() {
        // The error reports what was counted when the budget was passed: a
        // lower bound of the whole need, past the budget.
        let mut all = 0u64;
        for i in 0..100 {
            MODULAR.visit(i, |_| all += 1);
        }
        let err = CellLists::build(7, 100, 150, &MODULAR).unwrap_err();
        assert!(matches!(
            err,
            BuildError::BudgetExceeded { needed, budget: 150, .. } if needed > 150 && needed <= all
        ));
        assert!(CellLists::build(7, 100, all, &MODULAR).is_ok());
        assert!(CellLists::build(7, 100, all - 1, &MODULAR).is_err());
    }

    #[test]
    fn item_subsets_hold_their_own_ids() {
        let items = [3u32, 17, 40, 41, 9_999];
        let lists = CellLists::build_items(7, &items, u64::MAX, &MODULAR).unwrap();
        let mut expected = vec![Vec::new(); 7];
        for &i in &items {
            MODULAR.visit(i, |c| expected[c].push(i));
        }
        for e in &mut expected {
            e.sort_unstable();
        }
        for (c, want) in expected.iter().enumerate() {
            assert_eq!(lists.cell(c), want.as_slice(), "cell {c}");
        }
        let all = CellLists::build(7, 50, u64::MAX, &MODULAR).unwrap();
        let every: Vec<u32> = (0..50).collect();
        assert_eq!(
            CellLists::build_items(7, &every, u64::MAX, &MODULAR).unwrap(),
            all
        );
        let err = CellLists::build_items(7, &items, 3, &MODULAR).unwrap_err();
        assert!(matches!(err, BuildError::BudgetExceeded { budget: 3, .. }));
    }

    /// Cells i % 1009 and (i * 7) % 1013 of 1013: many cells, so that
    /// threads count ranges of them.
    const WIDE: TwoCells = TwoCells {
        first: 1009,
        factor: 7,
        second: 1013,
    };

    #[test]
    fn ranges_counted_by_several_threads_give_the_same_lists() {
        // Past PARALLEL_ITEMS items, on three threads (six ranges of 256
        // cells, the last one shorter), and on one (one range); the cells
        // past 1013 stay empty.
        const CELLS: usize = 1500;
        let items = 50_000u32;
        let build = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| CellLists::build(CELLS, items, u64::MAX, &WIDE).unwrap())
        };
        let three = build(3);
        assert!(items as usize >= PARALLEL_ITEMS);
        assert_eq!(CellRanges::new(CELLS, items as usize, 3).count, 6);
        let mut expected = vec![Vec::new(); CELLS];
        for i in 0..items {
            WIDE.visit(i, |c| expected[c].push(i));
        }
        for (c, want) in expected.iter().enumerate() {
            assert_eq!(three.cell(c), want.as_slice(), "cell {c}");
        }
        // The occupancy taken range by range, against the lists themselves.
        let empty = expected.iter().filter(|l| l.is_empty()).count();
        let most = expected.iter().map(Vec::len).max().unwrap();
        assert_eq!(three.occupancy(), (empty, most));
        assert!(empty >= CELLS - 1013);
        assert_eq!(build(1), three);
    }

    #[test]
    fn cell_ranges_cover_every_cell_with_a_range_per_thread_or_two() {
        let max_len = 1usize << MAX_SHIFT;
        for (cells, threads) in [
            (1013, 3),
            (8_000_000, 2),
            (4_300_000, 2),
            (64, 32),
            (7, 4),
            (1 << 20, 1),
            (10_000_000, 1),
            (u32::MAX as usize, 2),
        ] {
            let r = CellRanges::new(cells, 1 << 20, threads);
            let len = r.len(cells);
            assert!(len <= max_len);
            assert_eq!(
                r.count,
                cells.div_ceil(len),
                "{cells} cells, {threads} threads"
            );
            if threads > 1 && cells >= 2 * threads && cells / threads <= max_len {
                assert!(
                    (threads..=2 * threads).contains(&r.count),
                    "{cells} cells: {r:?}"
                );
            } else {
                assert_eq!(r.count, cells.div_ceil(max_len), "{cells} cells: {r:?}");
            }
            for c in [0, len - 1, len, cells / 2, cells - 1] {
                let c = c.min(cells - 1);
                let (range, within) = (c >> r.shift, c as u32 & r.mask());
                assert_eq!(range * len + within as usize, c, "cell {c} of {cells}");
                assert!((within as usize) < len && range < r.count);
            }
        }
        // A small build or one thread: one range while the cells allow.
        assert_eq!(CellRanges::new(1013, 100, 8).count, 1);
        assert_eq!(CellRanges::new(max_len, 1 << 20, 1).count, 1);
    }

    #[test]
    fn items_in_any_order_end_up_ascending_in_each_cell() {
        let items: Vec<u32> = (0..2_000u32).rev().map(|i| i * 3 + 1).collect();
        let lists = CellLists::build_items(7, &items, u64::MAX, &MODULAR).unwrap();
        let mut expected = vec![Vec::new(); 7];
        for &i in &items {
            MODULAR.visit(i, |c| expected[c].push(i));
        }
        for (c, want) in expected.iter_mut().enumerate() {
            want.sort_unstable();
            assert_eq!(lists.cell(c), want.as_slice(), "cell {c}");
        }
    }

    #[test]
    fn lists_from_given_cells_keep_them_in_order() {
        let given: Vec<Vec<u32>> = vec![vec![5, 1], vec![], vec![7], vec![], vec![2, 3, 4]];
        let lists = CellLists::from_cells(&given).unwrap();
        assert_eq!(lists.cell_count(), 5);
        for (c, want) in given.iter().enumerate() {
            assert_eq!(lists.cell(c), want.as_slice(), "cell {c}");
        }
        assert_eq!(lists.offsets(), &[0, 2, 2, 3, 3, 6]);
        assert_eq!(lists.empty_cells(), 2);
        assert_eq!(lists.max_cell_len(), 3);
        let none = CellLists::from_cells(Vec::<[u32; 0]>::new()).unwrap();
        assert_eq!((none.cell_count(), none.reference_count()), (0, 0));
    }

    #[test]
    fn no_items_gives_empty_cells() {
        let lists = CellLists::build(3, 0, 10, &MODULAR).unwrap();
        assert_eq!(lists.empty_cells(), 3);
        assert!(lists.cell(2).is_empty());
        assert_eq!(lists.max_cell_len(), 0);
    }

    #[test]
    fn prefix_sum_across_chunks_matches_a_serial_scan() {
        // Several chunks, a partial last one, and a total past u32::MAX.
        let len = 3 * CELLS_PER_CHUNK + 17;
        let counts: Vec<u32> = (0..len)
            .map(|i| if i == 5 { u32::MAX } else { (i % 7) as u32 })
            .collect();
        let mut got = counts.clone();
        let total = exclusive_prefix_sum(&mut got);
        let mut running = 0u64;
        for (i, &c) in counts.iter().enumerate() {
            assert_eq!(got[i], running as u32, "entry {i}");
            running += u64::from(c);
        }
        assert_eq!(total, running);
        assert!(total > u64::from(u32::MAX));
    }
}
