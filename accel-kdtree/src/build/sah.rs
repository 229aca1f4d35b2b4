//! The surface area heuristic and the O(n) sweep over sorted events.
//!
//! For a plane `p` on axis `k`, with `N` primitives in the node, the sweep
//! keeps (Wald & Havran 2006, §4.2): `N_L` = primitives with clipped bounds
//! starting before `p` (`min < p`), `N_R` = those ending after it
//! (`max > p`), and `N_P` = those flat in `p` (`min = max = p`). A primitive
//! that only touches `p` from one side counts on that side only. Planar
//! primitives go to whichever side is cheaper (ties go left): the explicit
//! handling of primitives lying in the split plane.
//!
//! Planes strictly inside the node are candidates (as pbrt). A plane on one
//! of the node's faces is one only where primitives lie flat in that face
//! and others do not: those go to a flat child in the face, the rest to the
//! other child (a *face cut*). A wall lying in a node's face is thus cut
//! away from the space in front of it, where every ray crossing the node
//! would otherwise test it. An empty flat child is never made: the empty
//! bonus would reward cutting it off forever.

use super::events::{Event, Events};
use crate::KdTreeParams;
use accel_core::{Aabb, Real};

/// A chosen split: axis, plane, the side of the planar primitives, and its cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Split<T> {
    pub(crate) axis: usize,
    pub(crate) pos: T,
    pub(crate) planar_left: bool,
    pub(crate) cost: f64,
    /// The child that receives every primitive, when the sweep that chose
    /// the split counted the other side empty (a cut of empty space); `None`
    /// when it is not one, or was not counted (binned splits).
    pub(crate) kept: Option<Kept>,
}

/// The child of a cut of empty space that holds the node's primitives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kept {
    Below,
    Above,
}

/// One candidate plane of an axis, as the sweep over the node's sorted
/// events counts it: the primitives starting before it (`N_L`), lying flat
/// in it (`N_P`) and ending after it (`N_R`).
///
/// The counts depend only on the node's primitives and their clipped
/// bounds, not on its box. A cut of empty space hands its lists to the
/// child that keeps them unchanged, so the child's planes are its parent's,
/// and only their prices change with the box: the child sweeps the planes
/// its parent recorded instead of the events again (40% of the events the
/// terrain's exact levels sweep are in such children, 4.1 per plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Plane<T> {
    pub(crate) pos: T,
    left: u32,
    planar: u32,
    right: u32,
}

/// The planes of a node's three axes, in the order of their events.
pub(crate) type Planes<T> = [Vec<Plane<T>>; 3];

/// The SAH of one node, in `f64` whatever `T` is.
#[derive(Clone, Debug)]
pub(crate) struct Sah {
    traversal: f64,
    intersect: f64,
    /// `1 − empty_bonus`.
    keep: f64,
    min: [f64; 3],
    max: [f64; 3],
    /// Per split axis `k`: the product and the sum of the two other extents.
    cross: [f64; 3],
    sum: [f64; 3],
    inv_half_area: f64,
}

impl Sah {
    /// The SAH of a node with bounds `b`; `None` when the node has no area
    /// (flat in two axes), where no split can be priced.
    pub(crate) fn new<T: Real>(params: &KdTreeParams, b: &Aabb<T>) -> Option<Self> {
        let min = [0, 1, 2].map(|a| b.min[a].to_f64());
        let max = [0, 1, 2].map(|a| b.max[a].to_f64());
        let d = [0, 1, 2].map(|a| max[a] - min[a]);
        let half_area = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
        if !(half_area > 0.0 && half_area.is_finite()) {
            return None;
        }
        let cross = [0, 1, 2].map(|k| d[(k + 1) % 3] * d[(k + 2) % 3]);
        let sum = [0, 1, 2].map(|k| d[(k + 1) % 3] + d[(k + 2) % 3]);
        Some(Self {
            traversal: params.traversal_cost,
            intersect: params.intersect_cost,
            keep: 1.0 - params.empty_bonus,
            min,
            max,
            cross,
            sum,
            inv_half_area: 1.0 / half_area,
        })
    }

    /// Per split axis `k`: the product and the sum of the two other
    /// extents (a child's half area is `product + sum · width`).
    #[inline]
    pub(crate) fn cross_sum(&self, k: usize) -> (f64, f64) {
        (self.cross[k], self.sum[k])
    }

    /// `1 − empty_bonus`: the factor of a split with an empty side.
    #[inline]
    pub(crate) fn keep(&self) -> f64 {
        self.keep
    }

    /// The cost of a leaf of `n` primitives.
    #[inline]
    pub(crate) fn leaf_cost(&self, n: usize) -> f64 {
        self.intersect * n as f64
    }

    /// Whether `pos` may split axis `k` (strictly inside the node).
    #[inline]
    pub(crate) fn is_candidate(&self, k: usize, pos: f64) -> bool {
        self.min[k] < pos && pos < self.max[k]
    }

    /// The SAH cost of splitting axis `k` at `pos` with `nl` and `nr`
    /// primitives on the two sides.
    #[inline]
    pub(crate) fn cost(&self, k: usize, pos: f64, nl: usize, nr: usize) -> f64 {
        let left = self.cross[k] + self.sum[k] * (pos - self.min[k]);
        let right = self.cross[k] + self.sum[k] * (self.max[k] - pos);
        let weight = if nl == 0 || nr == 0 { self.keep } else { 1.0 };
        self.traversal
            + self.intersect * weight * (left * nl as f64 + right * nr as f64) * self.inv_half_area
    }

    /// The cost of a candidate plane with `nl`, `np`, `nr` primitives left,
    /// in and right of it, and whether the planar ones go left.
    #[inline]
    pub(crate) fn evaluate(
        &self,
        k: usize,
        pos: f64,
        nl: usize,
        np: usize,
        nr: usize,
    ) -> (f64, bool) {
        if np == 0 {
            return (self.cost(k, pos, nl, nr), true);
        }
        let to_left = self.cost(k, pos, nl + np, nr);
        let to_right = self.cost(k, pos, nl, np + nr);
        if to_left <= to_right {
            (to_left, true)
        } else {
            (to_right, false)
        }
    }
}

impl Sah {
    /// The cost of a face cut at `pos`, a face of the node on axis `k`, where
    /// `planar` of its `n` primitives lie flat, and whether they go left (to
    /// the flat child at the lower face); `None` where the plane is not a
    /// face, the node is flat on `k`, or the cut would leave a child empty.
    #[inline]
    pub(crate) fn face_cut(
        &self,
        k: usize,
        pos: f64,
        planar: usize,
        n: usize,
    ) -> Option<(f64, bool)> {
        if planar == 0 || planar >= n || !(self.min[k] < self.max[k]) {
            return None;
        }
        if pos == self.min[k] {
            Some((self.cost(k, pos, planar, n - planar), true))
        } else if pos == self.max[k] {
            Some((self.cost(k, pos, n - planar, planar), false))
        } else {
            None
        }
    }
}

/// Keeps the first of the cheapest splits, in the order axis, then position:
/// `candidate` replaces `best` only when strictly cheaper.
#[inline]
pub(crate) fn keep_cheaper<T>(best: &mut Option<Split<T>>, candidate: Split<T>) {
    if best.as_ref().is_none_or(|b| candidate.cost < b.cost) {
        *best = Some(candidate);
    }
}

/// The cheapest plane of one axis seen so far, as plain scalars: the first
/// strictly cheapest wins, as [`keep_cheaper`] (every cost here is finite,
/// so starting from +∞ is the same as starting from none).
struct Cheapest<'s> {
    sah: &'s Sah,
    k: usize,
    /// The node's primitive count, for face cuts.
    n: usize,
    cost: f64,
    /// Index of the cheapest plane in the axis's plane list, or `usize::MAX`.
    at: usize,
    planar_left: bool,
}

impl<'s> Cheapest<'s> {
    fn new(sah: &'s Sah, k: usize, n: usize) -> Self {
        Self {
            sah,
            k,
            n,
            cost: f64::INFINITY,
            at: usize::MAX,
            planar_left: true,
        }
    }

    /// Prices plane `at` of the axis: a candidate strictly inside the node,
    /// or a face cut on one of its faces.
    #[inline(always)]
    fn consider<T: Real>(&mut self, at: usize, plane: &Plane<T>) {
        let (sah, k) = (self.sah, self.k);
        let p = plane.pos.to_f64();
        let (nl, np, nr) = (
            plane.left as usize,
            plane.planar as usize,
            plane.right as usize,
        );
        if sah.min[k] < p && p < sah.max[k] {
            let (cost, planar_left) = sah.evaluate(k, p, nl, np, nr);
            if cost < self.cost {
                (self.cost, self.at, self.planar_left) = (cost, at, planar_left);
            }
        } else if let Some((cost, planar_left)) = sah.face_cut(k, p, np, self.n)
            && cost < self.cost
        {
            (self.cost, self.at, self.planar_left) = (cost, at, planar_left);
        }
    }

    /// The split at the cheapest plane of `planes`, if any was priced.
    fn split<T: Real>(self, planes: &[Plane<T>]) -> Option<Split<T>> {
        let plane = planes.get(self.at)?;
        // Every primitive is counted on at least one side: it starts before
        // the plane, ends after it, or lies in it.
        let (planar_below, planar_above) = if self.planar_left {
            (plane.planar, 0)
        } else {
            (0, plane.planar)
        };
        let kept = if plane.right + planar_above == 0 {
            Some(Kept::Below)
        } else if plane.left + planar_below == 0 {
            Some(Kept::Above)
        } else {
            None
        };
        Some(Split {
            axis: self.k,
            pos: plane.pos,
            planar_left: self.planar_left,
            cost: self.cost,
            kept,
        })
    }
}

/// The cheapest plane on axis `k` among the node's `n` primitives, by one
/// sweep over its sorted events, recording every plane in `planes`.
pub(crate) fn sweep_events<T: Real>(
    sah: &Sah,
    k: usize,
    events: &[Event<T>],
    n: usize,
    planes: &mut Vec<Plane<T>>,
) -> Option<Split<T>> {
    planes.clear();
    planes.reserve(events.len());
    let mut best = Cheapest::new(sah, k, n);
    let (mut nl, mut nr) = (0usize, n);
    let len = events.len();
    let mut i = 0;
    while i < len {
        let pos = events[i].pos;
        // Count this plane's ends, planars and starts (kinds 0, 1, 2, in
        // that order) from three sums kept in registers: the count, the sum
        // of the kinds (planar + 2·starts) and of their squares (planar +
        // 4·starts). Counters indexed by the kind live in memory, and each
        // increment waited for the last one's store: the build's terrain run
        // took 7% longer that way. Positions compare by their bits: they are
        // never NaN, and zeros are normalized to +0 (see `push_axis_events`),
        // so equal bits are equal positions.
        let bits = pos.to_bits_u64();
        let (mut count, mut kinds, mut squares) = (0usize, 0usize, 0usize);
        for e in &events[i..] {
            if e.pos.to_bits_u64() != bits {
                break;
            }
            let kind = e.kind() as usize;
            count += 1;
            kinds += kind;
            squares += kind * kind;
        }
        i += count;
        let starts = (squares - kinds) / 2;
        let planar = kinds - 2 * starts;
        let ends = count - planar - starts;
        nr -= planar + ends;
        // Counts fit: a node holds fewer than 2^30 primitives.
        let plane = Plane {
            pos,
            left: nl as u32,
            planar: planar as u32,
            right: nr as u32,
        };
        best.consider(planes.len(), &plane);
        planes.push(plane);
        nl += starts + planar;
    }
    best.split(planes)
}

/// [`sweep_events`] over the planes it recorded for the same primitives
/// and events, priced for this node's box.
pub(crate) fn sweep_planes<T: Real>(
    sah: &Sah,
    k: usize,
    planes: &[Plane<T>],
    n: usize,
) -> Option<Split<T>> {
    let mut best = Cheapest::new(sah, k, n);
    for (at, plane) in planes.iter().enumerate() {
        best.consider(at, plane);
    }
    best.split(planes)
}

/// Nodes with at least this many events per axis sweep their axes in parallel.
const PARALLEL_SWEEP: usize = 1 << 14;

/// The cheapest plane over all three axes (ties to the lower axis), by a
/// sweep over the events that records each axis's planes in `planes`.
pub(crate) fn best_split<T: Real>(
    sah: &Sah,
    events: &Events<T>,
    n: usize,
    planes: &mut Planes<T>,
) -> Option<Split<T>> {
    let [px, py, pz] = planes;
    let per_axis: [Option<Split<T>>; 3] = if events[0].len() >= PARALLEL_SWEEP {
        let (x, (y, z)) = rayon::join(
            || sweep_events(sah, 0, &events[0], n, px),
            || {
                rayon::join(
                    || sweep_events(sah, 1, &events[1], n, py),
                    || sweep_events(sah, 2, &events[2], n, pz),
                )
            },
        );
        [x, y, z]
    } else {
        [
            sweep_events(sah, 0, &events[0], n, px),
            sweep_events(sah, 1, &events[1], n, py),
            sweep_events(sah, 2, &events[2], n, pz),
        ]
    };
    cheapest_of(per_axis)
}

/// [`best_split`] of a node whose planes were recorded (by its parent, a
/// cut of empty space that handed it the same events).
pub(crate) fn best_split_of_planes<T: Real>(
    sah: &Sah,
    planes: &Planes<T>,
    n: usize,
) -> Option<Split<T>> {
    cheapest_of([0, 1, 2].map(|k| sweep_planes(sah, k, &planes[k], n)))
}

/// The cheapest of the axes' splits (ties to the lower axis).
fn cheapest_of<T>(per_axis: [Option<Split<T>>; 3]) -> Option<Split<T>> {
    let mut best = None;
    for s in per_axis.into_iter().flatten() {
        keep_cheaper(&mut best, s);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::Vec3;

    fn box123() -> Aabb<f64> {
        Aabb::new(Vec3::new(1.0, -2.0, 0.5), Vec3::new(2.0, 0.0, 3.5))
    }

    #[test]
    fn cost_on_a_1_by_2_by_3_box() {
        // pbrt's costs: intersection 5, traversal 1, empty bonus 0.5.
        let p = KdTreeParams::pbrt();
        let sah = Sah::new(&p, &box123()).unwrap();
        // Split z at 1.5 (1 of the 3 units below): left half-area 1·2 + 3·1 = 5,
        // right 1·2 + 3·2 = 8, of 11.
        let c = sah.cost(2, 1.5, 4, 6);
        assert!(
            (c - (1.0 + 5.0 * (5.0 * 4.0 + 8.0 * 6.0) / 11.0)).abs() < 1e-12,
            "{c}"
        );
        // An empty side earns the bonus.
        let c = sah.cost(0, 1.25, 0, 6);
        let right = 2.0 * 3.0 + 5.0 * 0.75;
        assert!(
            (c - (1.0 + 5.0 * 0.5 * right * 6.0 / 11.0)).abs() < 1e-12,
            "{c}"
        );
        assert_eq!(sah.leaf_cost(3), 15.0);
        assert!(
            sah.is_candidate(1, -1.0) && !sah.is_candidate(1, 0.0) && !sah.is_candidate(1, -2.0)
        );
    }

    #[test]
    fn boxes_without_area_cannot_be_priced() {
        let line = Aabb::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(5.0, 0.0, 0.0));
        assert!(Sah::new(&KdTreeParams::default(), &line).is_none());
        let flat = Aabb::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(5.0, 1.0, 0.0));
        assert!(Sah::new(&KdTreeParams::default(), &flat).is_some());
    }

    #[test]
    fn sweep_counts_touching_and_planar_primitives_on_their_sides() {
        use super::super::events::{push_events, sort_events};
        // Node [0, 4] on x. Prim 0: [0, 1]; prim 1: flat at 1; prim 2: [1, 3].
        let node = Aabb::new(Vec3::new(0.0f64, 0.0, 0.0), Vec3::new(4.0, 1.0, 1.0));
        let spans = [(0.0, 1.0), (1.0, 1.0), (1.0, 3.0)];
        let mut ev: Events<f64> = Default::default();
        for (i, &(lo, hi)) in spans.iter().enumerate() {
            let b = Aabb::new(Vec3::new(lo, 0.0, 0.0), Vec3::new(hi, 1.0, 1.0));
            push_events(&mut ev, i as u32, &b);
        }
        sort_events(&mut ev[0]);
        let sah = Sah::new(&KdTreeParams::default(), &node).unwrap();
        let mut planes = Vec::new();
        // At x = 1: N_L = 1 (prim 0 touches from the left), N_P = 1, N_R = 1.
        let (want, left) = sah.evaluate(0, 1.0, 1, 1, 1);
        // At x = 3: N_L = 3, N_R = 0.
        let at3 = sah.cost(0, 3.0, 3, 0);
        let best = sweep_events(&sah, 0, &ev[0], 3, &mut planes).unwrap();
        let expect = if want < at3 {
            (1.0, want, left)
        } else {
            (3.0, at3, true)
        };
        assert_eq!((best.pos, best.cost, best.planar_left), expect);
    }
}
