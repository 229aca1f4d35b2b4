//! Split-candidate events (Wald & Havran 2006, §4.2).
//!
//! A primitive whose clipped bounds span `[lo, hi]` on an axis makes a
//! *start* event at `lo` and an *end* event at `hi`, or one *planar* event
//! when `lo == hi`. Each axis keeps its events in one list sorted by position
//! and, at equal positions, end < planar < start: the order in which the sweep
//! must count them. The lists are sorted once, at the root; a split
//! partitions them stably (so they stay sorted) and merges in the few freshly
//! clipped events of the primitives that straddle the plane.

use accel_core::{Aabb, Real};
use core::cmp::Ordering;
use rayon::slice::ParallelSliceMut;

/// An end event: the primitive's clipped bounds stop here.
pub(crate) const END: u32 = 0;
/// A planar event: the primitive's clipped bounds are flat here.
pub(crate) const PLANAR: u32 = 1;
/// A start event: the primitive's clipped bounds begin here.
pub(crate) const START: u32 = 2;

/// One event: a position and `local << 2 | kind`, where `local` indexes the
/// node's primitive list (30 bits, so node sizes stay below 2^30).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Event<T> {
    pub(crate) pos: T,
    word: u32,
}

impl<T: Real> Event<T> {
    /// An event of the node's primitive `local`.
    #[inline]
    pub(crate) fn new(pos: T, local: u32, kind: u32) -> Self {
        debug_assert!(local < (1 << 30) && kind <= START);
        Self {
            pos,
            word: (local << 2) | kind,
        }
    }

    /// [`END`], [`PLANAR`] or [`START`].
    #[inline]
    pub(crate) fn kind(self) -> u32 {
        self.word & 3
    }

    /// The primitive's index in its node's list.
    #[inline]
    pub(crate) fn local(self) -> usize {
        (self.word >> 2) as usize
    }

    /// The same event for the primitive's index in a child's list.
    #[inline]
    pub(crate) fn with_local(self, local: u32) -> Self {
        Self {
            pos: self.pos,
            word: (local << 2) | (self.word & 3),
        }
    }
}

/// The three per-axis event lists of a node.
pub(crate) type Events<T> = [Vec<Event<T>>; 3];

/// Appends the events of the node's primitive `local` whose clipped bounds
/// are `b` (not empty). Positions are normalized so that `-0` is `+0`: the
/// sweep groups equal positions, and both zeros must form one plane.
#[inline]
pub(crate) fn push_events<T: Real>(out: &mut Events<T>, local: u32, b: &Aabb<T>) {
    for (a, list) in out.iter_mut().enumerate() {
        push_axis_events(list, a, local, b);
    }
}

/// Appends the events of axis `a` only (see [`push_events`]).
#[inline]
pub(crate) fn push_axis_events<T: Real>(
    list: &mut Vec<Event<T>>,
    a: usize,
    local: u32,
    b: &Aabb<T>,
) {
    let (lo, hi) = (b.min[a] + T::ZERO, b.max[a] + T::ZERO);
    if lo == hi {
        list.push(Event::new(lo, local, PLANAR));
    } else {
        list.push(Event::new(lo, local, START));
        list.push(Event::new(hi, local, END));
    }
}

/// The sweep order: by position, then end < planar < start.
#[inline]
pub(crate) fn order<T: Real>(a: &Event<T>, b: &Event<T>) -> Ordering {
    match a.pos.partial_cmp(&b.pos) {
        Some(Ordering::Equal) | None => a.kind().cmp(&b.kind()),
        Some(o) => o,
    }
}

/// Lists longer than this are sorted in parallel.
const PARALLEL_SORT: usize = 1 << 15;

/// Sorts one list in the sweep order.
pub(crate) fn sort_events<T: Real>(list: &mut [Event<T>]) {
    if list.len() >= PARALLEL_SORT {
        list.par_sort_unstable_by(order);
    } else {
        list.sort_unstable_by(order);
    }
}

/// Merges the sorted `extra` into the sorted `list`, in place from the back.
pub(crate) fn merge_into<T: Real>(list: &mut Vec<Event<T>>, extra: &[Event<T>]) {
    if extra.is_empty() {
        return;
    }
    let old = list.len();
    list.resize(old + extra.len(), extra[0]);
    let (mut i, mut j, mut w) = (old, extra.len(), old + extra.len());
    while j > 0 {
        // Take from `list` while its element comes after extra's last one.
        if i > 0 && order(&list[i - 1], &extra[j - 1]) == Ordering::Greater {
            list[w - 1] = list[i - 1];
            i -= 1;
        } else {
            list[w - 1] = extra[j - 1];
            j -= 1;
        }
        w -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::Vec3;

    #[test]
    fn flat_extents_make_planar_events_and_zeros_merge() {
        let mut ev: Events<f32> = Default::default();
        let b = Aabb::new(Vec3::new(-0.0, 1.0, 2.0), Vec3::new(0.0, 3.0, 2.5));
        push_events(&mut ev, 7, &b);
        assert_eq!(ev[0].len(), 1);
        assert_eq!(ev[0][0].kind(), PLANAR);
        assert!(ev[0][0].pos.is_sign_positive(), "-0 is normalized to +0");
        assert_eq!(
            ev[1].iter().map(|e| (e.pos, e.kind())).collect::<Vec<_>>(),
            [(1.0, START), (3.0, END)]
        );
        assert!(ev[2].iter().all(|e| e.local() == 7));
    }

    #[test]
    fn order_and_merge_keep_end_planar_start_at_equal_positions() {
        let e = |p: f64, k: u32, l: u32| Event::new(p, l, k);
        let mut list = vec![
            e(0.0, START, 0),
            e(1.0, END, 0),
            e(1.0, START, 1),
            e(3.0, END, 1),
        ];
        list.sort_unstable_by(order);
        let extra = [e(1.0, PLANAR, 2), e(1.0, END, 3), e(2.0, START, 4)];
        let mut extra = extra.to_vec();
        extra.sort_unstable_by(order);
        merge_into(&mut list, &extra);
        let got: Vec<(f64, u32)> = list.iter().map(|e| (e.pos, e.kind())).collect();
        assert_eq!(
            got,
            [
                (0.0, START),
                (1.0, END),
                (1.0, END),
                (1.0, PLANAR),
                (1.0, START),
                (2.0, START),
                (3.0, END)
            ]
        );
        assert!(
            list.windows(2)
                .all(|w| order(&w[0], &w[1]) != Ordering::Greater)
        );
    }
}
