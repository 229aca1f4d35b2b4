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

/// Lists of `f32` events at least this long sort as integer keys.
const KEYED_SORT: usize = 64;

/// Sorts one list in the sweep order. Inlined for the common case of a
/// split's straddler lists, which are mostly empty.
#[inline]
pub(crate) fn sort_events<T: Real>(list: &mut [Event<T>]) {
    if list.len() < 2 {
        return;
    }
    sort_long(list);
}

fn sort_long<T: Real>(list: &mut [Event<T>]) {
    if size_of::<T>() == 4 && list.len() >= KEYED_SORT {
        sort_f32_events(list);
    } else if list.len() >= PARALLEL_SORT {
        list.par_sort_unstable_by(order);
    } else {
        list.sort_unstable_by(order);
    }
}

/// Keyed lists at least this long sort by radix.
const RADIX_SORT: usize = 1024;

/// Sorts keys by their top 34 bits (a position's ordered bits and the
/// kind), least significant digit first, stably: three passes of 11, 11 and
/// 12 bits, each skipped when every key has the same digit there (common in
/// a small node, whose positions share their high bits). About a third of a
/// comparison sort's instructions at the sizes the build meets.
fn radix_sort_keys(keys: &mut Vec<u64>) {
    const DIGITS: [(u32, u32); 3] = [(30, 11), (41, 11), (52, 12)];
    let mut other = vec![0u64; keys.len()];
    let mut counts = vec![0usize; 1 << 12];
    for (shift, width) in DIGITS {
        let mask = (1u64 << width) - 1;
        let counts = &mut counts[..1 << width];
        counts.fill(0);
        for k in keys.iter() {
            counts[((k >> shift) & mask) as usize] += 1;
        }
        if counts.contains(&keys.len()) {
            continue;
        }
        let mut sum = 0;
        for c in counts.iter_mut() {
            (*c, sum) = (sum, sum + *c);
        }
        for &k in keys.iter() {
            let slot = &mut counts[((k >> shift) & mask) as usize];
            other[*slot] = k;
            *slot += 1;
        }
        core::mem::swap(keys, &mut other);
    }
}

/// An `f32`'s bits mapped so that unsigned integer order is the float order
/// (for non-NaN values, with `-0` already normalized to `+0`).
#[inline]
fn ordered_bits(bits: u32) -> u32 {
    if bits >> 31 == 1 {
        !bits
    } else {
        bits | 1 << 31
    }
}

/// The inverse of [`ordered_bits`].
#[inline]
fn float_bits(key: u32) -> u32 {
    if key >> 31 == 1 {
        key & !(1 << 31)
    } else {
        !key
    }
}

/// Sorts `f32` events (`T` is `f32`) by one integer key each: the position's
/// ordered bits, then the kind (the primitive rides in the low bits). Sorting
/// plain `u64`s is about three times cheaper than the comparator, and gives
/// the same sweep order: events equal in position and kind differ only in
/// their primitive, whose order no later step depends on.
fn sort_f32_events<T: Real>(list: &mut [Event<T>]) {
    debug_assert_eq!(size_of::<T>(), 4);
    let mut keys: Vec<u64> = list
        .iter()
        .map(|e| {
            let bits = ordered_bits(e.pos.to_bits_u64() as u32);
            let low = (e.kind() << 30) | e.local() as u32;
            (u64::from(bits) << 32) | u64::from(low)
        })
        .collect();
    if keys.len() >= RADIX_SORT {
        radix_sort_keys(&mut keys);
    } else {
        keys.sort_unstable();
    }
    for (e, k) in list.iter_mut().zip(&keys) {
        let pos = f32::from_bits(float_bits((k >> 32) as u32));
        let low = *k as u32;
        *e = Event::new(
            T::from_f64(f64::from(pos)),
            low & ((1 << 30) - 1),
            low >> 30,
        );
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

    #[test]
    fn keyed_f32_sort_matches_the_comparator_order() {
        // Negative, zero, equal, tiny and extreme positions with every kind,
        // and lists long enough for the keyed sort and for the radix sort
        // (whose passes see both varying and constant digits).
        let fixed = [
            -3.5f32,
            -1e-30,
            0.0,
            1e-30,
            2.0,
            2.0,
            f32::MAX,
            f32::MIN,
            -2.0,
        ];
        for (len, spread) in [(200u32, 0.0f32), (3000, 1e-3), (3000, 1e5)] {
            let mut list: Vec<Event<f32>> = (0..len)
                .map(|i| {
                    let pos = if i % 5 == 0 {
                        fixed[(i as usize * 7) % fixed.len()]
                    } else {
                        1.0 + spread * (i.wrapping_mul(2_654_435_761) % 1000) as f32
                    };
                    Event::new(pos, i, (i * 7) % 3)
                })
                .collect();
            let mut expected = list.clone();
            expected.sort_by(order);
            sort_events(&mut list);
            let key = |e: &Event<f32>| (e.pos.to_bits(), e.kind());
            assert_eq!(
                list.iter().map(key).collect::<Vec<_>>(),
                expected.iter().map(key).collect::<Vec<_>>(),
                "{len} events, spread {spread}"
            );
            // Every event survives, with its primitive and kind.
            let mut locals: Vec<(usize, u32)> =
                list.iter().map(|e| (e.local(), e.kind())).collect();
            locals.sort_unstable();
            assert_eq!(
                locals,
                (0..len)
                    .map(|i| (i as usize, (i * 7) % 3))
                    .collect::<Vec<_>>()
            );
        }
    }
}
