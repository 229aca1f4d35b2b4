//! Splitting a node: classify, partition the sorted lists, re-clip the
//! straddlers (Wald & Havran 2006, §4.3).
//!
//! Against the chosen plane `p` on axis `k`, the events of axis `k` classify
//! each primitive: an end at or before `p` puts it left only, a start at or
//! after `p` right only, a planar event at `p` on the side the SAH chose, and
//! everything else straddles. The three sorted lists are then split by one
//! stable pass each (so both halves stay sorted), with each event's
//! primitive renumbered in its child. A straddling primitive is clipped anew
//! to each child's box (perfect splits), and its few new events are sorted
//! and merged into the child's lists. Nothing is re-sorted: the split is
//! linear in the node's events plus `s log s` for `s` straddlers. A cut of
//! empty space, with every primitive on one side, hands the node's lists to
//! that side as they are, with the planes its sweep recorded (most of a
//! terrain's or a scan's splits: 575,709 of the 1M-triangle terrain's
//! 727,441 inner nodes have an empty child); the sweep's counts say that a
//! split is one, so its events need no classifying.

use super::binned::clip_to_halves;
use super::depth::Depth;
use super::events::{END, Event, Events, PLANAR, push_events, sort_events};
use super::sah::{Kept, Planes, Split};
use super::spares::Spares;
use accel_core::{Aabb, PrimitiveSet, Real};

/// A node under construction: its box, its primitives (global indices,
/// ascending), their events, indexed by position in `prims`, and the
/// planes that a sweep of those events recorded, once one has.
#[derive(Debug)]
pub(crate) struct NodeWork<T> {
    pub(crate) bounds: Aabb<T>,
    pub(crate) prims: Vec<u32>,
    pub(crate) events: Events<T>,
    pub(crate) planes: Option<Planes<T>>,
    pub(crate) depth: Depth,
}

/// Sides in a destination word: one bit each, none for a straddler (whose
/// events the partition drops), so each cursor advances by its bit alone.
const LEFT: u32 = 1;
const RIGHT: u32 = 2;
const BOTH: u32 = 0;
/// Where the side sits in a primitive's destination word.
const SIDE_SHIFT: u32 = 30;
/// The child index below it.
const INDEX_MASK: u32 = (1 << SIDE_SHIFT) - 1;

/// Splits one sorted event list by the primitives' destination words: the
/// left child's events stay in `list` (in place), the right child's go to a
/// new list, both in order and renumbered; straddlers' events are dropped
/// (they are clipped anew). Branch-free: every event is written to both
/// outputs and each cursor advances only on its side, so the unpredictable
/// side costs no mispredicted branch.
fn partition<T: Real>(
    mut list: Vec<Event<T>>,
    dest: &[u32],
    spares: &mut Spares<T>,
) -> (Vec<Event<T>>, Vec<Event<T>>) {
    let len = list.len();
    let mut rights = spares.events();
    rights.reserve(len);
    let slots = &mut rights.spare_capacity_mut()[..len];
    let (mut wl, mut wr) = (0, 0);
    for r in 0..len {
        let e = list[r];
        let d = dest[e.local()];
        let moved = e.with_local(d & INDEX_MASK);
        debug_assert!(wl <= r && wr <= r);
        // SAFETY: `wl` and `wr` each advance at most once per iteration, so
        // both are at most `r < len`, the length of `list` and of `slots`.
        // (The slot `list[wl]` was already read.) Unchecked writes save the
        // two bounds checks of the partition's inner loop, the hottest loop of
        // the build.
        unsafe {
            *list.get_unchecked_mut(wl) = moved;
            slots.get_unchecked_mut(wr).write(moved);
        }
        wl += ((d >> SIDE_SHIFT) & LEFT) as usize;
        wr += (d >> (SIDE_SHIFT + 1)) as usize;
    }
    list.truncate(wl);
    // SAFETY: the loop wrote `slots[..=wr']` for every value `wr'` the cursor
    // took, so the first `wr` elements are initialized (`Event` is `Copy`:
    // nothing to drop), and `wr <= len <= capacity`.
    unsafe { rights.set_len(wr) };
    (list, rights)
}

/// Each primitive's side of `split`, from the events of its axis: one
/// word per primitive with its side in the top two bits (the index in its
/// child goes below, later). `dest` is empty on entry.
fn classify<T: Real>(events: &[Event<T>], split: &Split<T>, n: usize, dest: &mut Vec<u32>) {
    let p = split.pos;
    dest.resize(n, BOTH << SIDE_SHIFT);
    for e in events {
        let d = &mut dest[e.local()];
        match e.kind() {
            END => {
                if e.pos <= p {
                    *d = LEFT << SIDE_SHIFT;
                }
            }
            PLANAR => {
                *d = if e.pos < p || (e.pos == p && split.planar_left) {
                    LEFT << SIDE_SHIFT
                } else {
                    RIGHT << SIDE_SHIFT
                };
            }
            _ => {
                if e.pos >= p {
                    *d = RIGHT << SIDE_SHIFT;
                }
            }
        }
    }
}

/// The child that every primitive goes to, by the sides `dest` gives them;
/// `None` when both children receive some.
fn kept_by(dest: &[u32]) -> Option<Kept> {
    let (n_left, n_right) = dest.iter().fold((0, 0), |(l, r), &d| {
        let side = d >> SIDE_SHIFT;
        (
            l + usize::from(side == LEFT),
            r + usize::from(side == RIGHT),
        )
    });
    if n_left == dest.len() {
        Some(Kept::Below)
    } else if n_right == dest.len() {
        Some(Kept::Above)
    } else {
        None
    }
}

/// Splits `node` at `split` into its two children.
pub(crate) fn split_node<T: Real, P: PrimitiveSet<T> + ?Sized>(
    node: NodeWork<T>,
    split: &Split<T>,
    prims: &P,
    spares: &mut Spares<T>,
) -> (NodeWork<T>, NodeWork<T>) {
    let NodeWork {
        bounds,
        prims: list,
        events,
        planes,
        depth,
    } = node;
    let (k, p) = (split.axis, split.pos);
    let n = list.len();
    let (left_box, right_box) = bounds.split_at(k, p);

    // A cut of empty space (every primitive on one side, so none
    // straddles) hands the node's lists to that side unchanged: the same
    // primitives in the same order, so the same local indices, and the same
    // clipped bounds, since only straddlers are clipped anew; and so the
    // same planes. A split chosen by the sweep says whether it is one; any
    // other, the primitives' sides say.
    let mut dest = spares.words();
    let kept = match split.kept {
        Some(kept) => {
            debug_assert!({
                classify(&events[k], split, n, &mut dest);
                kept_by(&dest) == Some(kept)
            });
            Some(kept)
        }
        None => {
            classify(&events[k], split, n, &mut dest);
            kept_by(&dest)
        }
    };
    if let Some(kept) = kept {
        spares.give_words(dest);
        let (n_below, n_above) = match kept {
            Kept::Below => (n, 0),
            Kept::Above => (0, n),
        };
        let (below_depth, above_depth) = depth.children(&bounds, k, p, n_below, n_above);
        let full = |bounds, depth| NodeWork {
            bounds,
            prims: list,
            events,
            planes,
            depth,
        };
        let empty = |bounds, depth| NodeWork {
            bounds,
            prims: Vec::new(),
            events: Default::default(),
            planes: None,
            depth,
        };
        return match kept {
            Kept::Below => (full(left_box, below_depth), empty(right_box, above_depth)),
            Kept::Above => (empty(left_box, below_depth), full(right_box, above_depth)),
        };
    }
    if let Some(planes) = planes {
        spares.give_planes(planes);
    }

    // Renumber; clip the straddlers to each child (perfect splits).
    let mut left_prims = spares.words();
    left_prims.reserve(n);
    let mut right_prims = spares.words();
    right_prims.reserve(n);
    let mut left_new: Events<T> = [(); 3].map(|()| spares.events());
    let mut right_new: Events<T> = [(); 3].map(|()| spares.events());
    for (d, &g) in dest.iter_mut().zip(&list) {
        match *d >> SIDE_SHIFT {
            LEFT => {
                *d |= left_prims.len() as u32;
                left_prims.push(g);
            }
            RIGHT => {
                *d |= right_prims.len() as u32;
                right_prims.push(g);
            }
            _ => {
                let clipped = clip_to_halves(prims, g, &bounds, split);
                for ((child_prims, new), c) in [
                    (&mut left_prims, &mut left_new),
                    (&mut right_prims, &mut right_new),
                ]
                .into_iter()
                .zip(clipped)
                {
                    if let Some(c) = c {
                        push_events(new, child_prims.len() as u32, &c);
                        child_prims.push(g);
                    }
                }
            }
        }
    }
    spares.give_words(list);

    let n_left = left_prims.len();
    let n_right = right_prims.len();
    let mut left_events: Events<T> = Default::default();
    let mut right_events: Events<T> = Default::default();
    for (a, list) in events.into_iter().enumerate() {
        let (mut lefts, mut rights) = partition(list, &dest, spares);
        for (dst, new) in [
            (&mut lefts, &mut left_new[a]),
            (&mut rights, &mut right_new[a]),
        ] {
            sort_events(new);
            super::events::merge_into(dst, new);
        }
        for new in [&mut left_new[a], &mut right_new[a]] {
            spares.give_events(core::mem::take(new));
        }
        left_events[a] = lefts;
        right_events[a] = rights;
    }
    spares.give_words(dest);
    let (below_depth, above_depth) = depth.children(&bounds, k, p, n_left, n_right);
    debug_assert!(left_events.iter().all(|l| l.len() >= n_left));
    debug_assert!(right_events.iter().all(|l| l.len() >= n_right));
    (
        NodeWork {
            bounds: left_box,
            prims: left_prims,
            events: left_events,
            planes: None,
            depth: below_depth,
        },
        NodeWork {
            bounds: right_box,
            prims: right_prims,
            events: right_events,
            planes: None,
            depth: above_depth,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::sah::{Sah, best_split, best_split_of_planes, sweep_events};
    use accel_core::{TriangleMesh, Vec3};
    use proptest::prelude::*;

    /// Three triangles in x ∈ [0, 1] of a node spanning x ∈ [0, 4].
    fn node_and_mesh() -> (NodeWork<f64>, TriangleMesh<f64>) {
        let tri = |x0: f64, z: f64| {
            [
                Vec3::new(x0, 0.0, z),
                Vec3::new(x0 + 0.5, 0.0, z),
                Vec3::new(x0, 1.0, z + 0.5),
            ]
        };
        let mesh =
            TriangleMesh::from_triangles(&[tri(0.0, 0.0), tri(0.5, 1.0), tri(0.25, 2.0)]).unwrap();
        let bounds = Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(4.0, 1.0, 2.5));
        let mut events: Events<f64> = Default::default();
        for i in 0..3u32 {
            push_events(&mut events, i, &PrimitiveSet::bounds(&mesh, i as usize));
        }
        for list in &mut events {
            sort_events(list);
        }
        let node = NodeWork {
            bounds,
            prims: vec![0, 1, 2],
            events,
            planes: None,
            depth: Depth::ROOT,
        };
        (node, mesh)
    }

    fn cut_at(pos: f64) -> Split<f64> {
        Split {
            axis: 0,
            pos,
            planar_left: true,
            cost: 0.0,
            kept: None,
        }
    }

    #[test]
    fn a_cut_of_empty_space_hands_the_lists_over_unchanged() {
        let (node, mesh) = node_and_mesh();
        let (prims, events) = (node.prims.clone(), node.events.clone());
        let (below, above) = split_node(node, &cut_at(2.0), &mesh, &mut Spares::default());
        assert_eq!((below.prims, below.events), (prims, events));
        assert_eq!(below.bounds.max.x, 2.0);
        assert!(above.prims.is_empty() && above.events.iter().all(Vec::is_empty));
        assert_eq!(above.bounds.min.x, 2.0);
        // Every primitive above a cut at the node's left part: the lists go up.
        let (node, mesh) = node_and_mesh();
        let node = NodeWork {
            bounds: Aabb::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::new(4.0, 1.0, 2.5)),
            ..node
        };
        let (prims, events) = (node.prims.clone(), node.events.clone());
        let (below, above) = split_node(node, &cut_at(-0.5), &mesh, &mut Spares::default());
        assert!(below.prims.is_empty() && below.events.iter().all(Vec::is_empty));
        assert_eq!((above.prims, above.events), (prims, events));
    }

    #[test]
    fn a_cut_through_the_primitives_renumbers_and_clips() {
        let (node, mesh) = node_and_mesh();
        // x = 0.6 ends triangle 0 (x ≤ 0.5) on the left, cuts 1 (0.5..1.0)
        // and 2 (0.25..0.75).
        let (below, above) = split_node(node, &cut_at(0.6), &mesh, &mut Spares::default());
        assert_eq!(below.prims, vec![0, 1, 2]);
        assert_eq!(above.prims, vec![1, 2]);
        for child in [&below, &above] {
            for list in &child.events {
                // Two events per primitive and axis (none is flat), sorted,
                // each pointing at a primitive of the child.
                assert_eq!(list.len(), 2 * child.prims.len());
                assert!(list.windows(2).all(|w| w[0].pos <= w[1].pos));
                assert!(list.iter().all(|e| e.local() < child.prims.len()));
            }
            let xs = &child.events[0];
            assert!(
                xs.iter()
                    .all(|e| child.bounds.min.x <= e.pos && e.pos <= child.bounds.max.x)
            );
        }
    }

    /// Boxes with corners on a small lattice, so that primitives share
    /// planes, touch them from either side and lie flat in them, and a
    /// node box around them that may share their outer planes (face cuts).
    fn lattice_node() -> impl Strategy<Value = (Vec<Aabb<f32>>, Aabb<f32>)> {
        let corner = || (0..6u8, 0..6u8, 0..6u8);
        let boxes = proptest::collection::vec((corner(), corner()), 1..24).prop_map(|pairs| {
            pairs
                .into_iter()
                .map(|((a, b, c), (d, e, f))| {
                    let p = |x, y, z| Vec3::new(f32::from(x), f32::from(y), f32::from(z));
                    Aabb::new(p(a, b, c), p(d, e, f))
                })
                .collect::<Vec<_>>()
        });
        (boxes, 0..2u8, 5..7u8).prop_map(|(boxes, lo, hi)| {
            let (lo, hi) = (-f32::from(lo), f32::from(hi));
            (boxes, Aabb::new(Vec3::splat(lo), Vec3::splat(hi)))
        })
    }

    /// The sorted events of `boxes`.
    fn events_of(boxes: &[Aabb<f32>]) -> Events<f32> {
        let mut events: Events<f32> = Default::default();
        for (i, b) in boxes.iter().enumerate() {
            push_events(&mut events, i as u32, b);
        }
        for list in &mut events {
            sort_events(list);
        }
        events
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        /// A split chosen by the sweep says it cuts off empty space exactly
        /// when the primitives' sides, classified from the events as the
        /// split does, put every one on the same side (empty bonuses up to
        /// 0.9, so that such cuts are often the cheapest).
        #[test]
        fn the_sweep_reports_a_cut_of_empty_space_as_the_sides_do(
            (boxes, node) in lattice_node(),
            bonus in 0.0..0.9f64,
        ) {
            let params = crate::KdTreeParams { empty_bonus: bonus, ..Default::default() };
            let sah = Sah::new(&params, &node).expect("a box with area");
            let events = events_of(&boxes);
            let n = boxes.len();
            let mut planes = Vec::new();
            for (k, list) in events.iter().enumerate() {
                let Some(split) = sweep_events(&sah, k, list, n, &mut planes) else {
                    continue;
                };
                let mut dest = Vec::new();
                classify(list, &split, n, &mut dest);
                prop_assert_eq!(split.kept, kept_by(&dest), "axis {} at {}", k, split.pos);
            }
        }

        /// The child of a cut of empty space, given its parent's events and
        /// planes, chooses from the planes the split that a sweep of the
        /// events would choose in its box: same plane, side, cost and kept
        /// child.
        #[test]
        fn recorded_planes_price_as_a_sweep_of_the_events(
            (boxes, node) in lattice_node(),
            axis in 0..3usize,
            keep_below in any::<bool>(),
        ) {
            let params = crate::KdTreeParams::default();
            let events = events_of(&boxes);
            let n = boxes.len();
            let sah = Sah::new(&params, &node).expect("a box with area");
            let mut planes: Planes<f32> = Default::default();
            let parent = best_split(&sah, &events, n, &mut planes);
            // The child's box: the node cut on `axis` where the primitives
            // end (or start), so that they all stay in it.
            let held = boxes.iter().fold(Aabb::empty(), |b, p| b.union(p));
            let child = if keep_below {
                node.split_at(axis, held.max[axis]).0
            } else {
                node.split_at(axis, held.min[axis]).1
            };
            let Some(sah) = Sah::new(&params, &child) else {
                return Ok(());
            };
            let mut fresh: Planes<f32> = Default::default();
            prop_assert_eq!(
                best_split_of_planes(&sah, &planes, n),
                best_split(&sah, &events, n, &mut fresh),
                "parent's choice {:?}", parent
            );
            prop_assert_eq!(&planes, &fresh);
        }
    }
}
