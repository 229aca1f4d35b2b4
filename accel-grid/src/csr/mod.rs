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
//!
//! The two-pass build has a module of its own (`csr/build.rs`); this one
//! holds the lists and what they answer.

mod build;

use accel_core::BuildError;
use rayon::prelude::*;

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

impl CellLists {
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

/// Cells per parallel chunk of the linear passes over cells (the
/// occupancy bits here, the build's counts and scans).
const CELLS_PER_CHUNK: usize = 1 << 16;

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

#[cfg(test)]
mod tests {
    use super::build::{CellRanges, MAX_SHIFT, PARALLEL_ITEMS, exclusive_prefix_sum};
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
