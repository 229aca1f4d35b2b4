//! Compact cell lists: one offset per cell and one reference array (CSR).
//!
//! Built in two parallel passes over the items: count the references of each
//! cell, turn the counts into offsets, then place every reference. An empty
//! cell costs one `u32`. Each cell's references end up sorted ascending, so the
//! build is deterministic whatever the thread count. The items are `0..n`
//! ([`CellLists::build`]) or any list of ids ([`CellLists::build_items`]: the
//! primitives of one cell, refined by a finer grid); [`CellLists::from_cells`]
//! assembles lists a structure has put together itself.

use accel_core::BuildError;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// What the two-pass build asks of the thing being indexed: the cells each
/// item belongs to. `visit` must call `cell` at most once per cell, with the
/// same cells both times it is asked about one item.
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
            max_references,
            visitor,
        )
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
        Ok(Self { offsets, refs })
    }

    /// The two-pass build over items `id(0) .. id(len - 1)`.
    fn build_with<V: CellVisitor>(
        cell_count: usize,
        len: usize,
        id: impl Fn(usize) -> u32 + Sync,
        max_references: u64,
        visitor: &V,
    ) -> Result<Self, BuildError> {
        // slots[c + 1] counts cell c in pass 1, holds its start before pass 2 and
        // its end after it; slots[0] stays 0. The array becomes the offsets.
        let slots: Vec<AtomicU32> = (0..=cell_count).map(|_| AtomicU32::new(0)).collect();
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
        let mut running: u64 = 0;
        for slot in &mut slots[1..] {
            let count = u64::from(*slot);
            // Safe to truncate: checked against u32::MAX below before use.
            *slot = running as u32;
            running += count;
        }
        let budget = max_references.min(u64::from(u32::MAX));
        if running > budget {
            return Err(BuildError::BudgetExceeded {
                what: "cell references",
                needed: running,
                budget,
            });
        }
        let total = running as usize;

        let slots: Vec<AtomicU32> = slots.into_iter().map(AtomicU32::new).collect();
        let refs: Vec<AtomicU32> = (0..total).map(|_| AtomicU32::new(0)).collect();
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
        Ok(Self { offsets, refs })
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
        let (start, end) = (self.offsets[c] as usize, self.offsets[c + 1] as usize);
        &self.refs[start..end]
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
    }

    /// Cells with no reference.
    #[must_use]
    pub fn empty_cells(&self) -> usize {
        self.offsets.windows(2).filter(|w| w[0] == w[1]).count()
    }

    /// The most references in one cell.
    #[must_use]
    pub fn max_cell_len(&self) -> usize {
        self.offsets
            .windows(2)
            .map(|w| (w[1] - w[0]) as usize)
            .max()
            .unwrap_or(0)
    }
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
        for c in first..last {
            let (s, e) = (
                (offsets[c] - base) as usize,
                (offsets[c + 1] - base) as usize,
            );
            group[s..e].sort_unstable();
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Item i belongs to cells i % 5 and (i * 3) % 7, once each.
    struct Modular;

    impl CellVisitor for Modular {
        fn visit<F: FnMut(usize)>(&self, item: u32, mut cell: F) {
            let a = item as usize % 5;
            let b = (item as usize * 3) % 7;
            cell(a);
            if b != a {
                cell(b);
            }
        }
    }

    #[test]
    fn lists_match_a_direct_construction() {
        let items = 10_000u32;
        let lists = CellLists::build(7, items, u64::MAX, &Modular).unwrap();
        let mut expected = vec![Vec::new(); 7];
        for i in 0..items {
            Modular.visit(i, |c| expected[c].push(i));
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
        let err = CellLists::build(7, 100, 150, &Modular).unwrap_err();
        assert!(matches!(
            err,
            BuildError::BudgetExceeded { needed, budget: 150, .. } if needed > 150
        ));
    }

    #[test]
    fn item_subsets_hold_their_own_ids() {
        let items = [3u32, 17, 40, 41, 9_999];
        let lists = CellLists::build_items(7, &items, u64::MAX, &Modular).unwrap();
        let mut expected = vec![Vec::new(); 7];
        for &i in &items {
            Modular.visit(i, |c| expected[c].push(i));
        }
        for e in &mut expected {
            e.sort_unstable();
        }
        for (c, want) in expected.iter().enumerate() {
            assert_eq!(lists.cell(c), want.as_slice(), "cell {c}");
        }
        let all = CellLists::build(7, 50, u64::MAX, &Modular).unwrap();
        let every: Vec<u32> = (0..50).collect();
        assert_eq!(
            CellLists::build_items(7, &every, u64::MAX, &Modular).unwrap(),
            all
        );
        let err = CellLists::build_items(7, &items, 3, &Modular).unwrap_err();
        assert!(matches!(err, BuildError::BudgetExceeded { budget: 3, .. }));
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
        let lists = CellLists::build(3, 0, 10, &Modular).unwrap();
        assert_eq!(lists.empty_cells(), 3);
        assert!(lists.cell(2).is_empty());
        assert_eq!(lists.max_cell_len(), 0);
    }
}
