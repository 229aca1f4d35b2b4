//! The binned SAH for the large nodes near the root (Wald 2007, "On fast
//! construction of SAH-based bounding volume hierarchies"; Shevtsov,
//! Soupikov & Kapustin 2007, "Highly parallel fast kd-tree construction for
//! interactive ray tracing of dynamic scenes").
//!
//! A node over more than [`crate::KdTreeParams::binned_above`] primitives
//! does not need the exact sweep to split well: its cheapest plane is found
//! among `bins − 1` evenly spaced planes per axis, counting each primitive's
//! clipped bounds into the bins of its two ends, in one linear pass without
//! sorting. The node keeps its primitives' clipped boxes instead of event
//! lists (24 bytes per primitive in `f32` instead of 48), the split is
//! classified exactly against the chosen plane, and straddlers are clipped
//! to each child as in the sweep build (perfect splits). Once a node is
//! small enough, its events are made from the boxes and sorted (a small sort
//! per subtree instead of one of the whole scene) and the exact sweep takes
//! over. Where the bins find no split cheaper than a leaf, the exact sweep
//! decides, so leaves are never made by the approximation.

use super::depth::Depth;
use super::events::{Events, push_events, sort_events};
use super::sah::{Sah, Split};
use super::split::NodeWork;
use accel_core::{Aabb, PrimitiveSet, Real};
use rayon::prelude::*;

/// A node of the binned levels: its box, its primitives (global indices,
/// ascending) and their bounds clipped to the box.
#[derive(Debug)]
pub(crate) struct BinnedNode<T> {
    pub(crate) bounds: Aabb<T>,
    pub(crate) prims: Vec<u32>,
    pub(crate) boxes: Vec<Aabb<T>>,
    pub(crate) depth: Depth,
}

/// Nodes with at least this many primitives bin in parallel chunks.
const PARALLEL_BINNING: usize = 1 << 16;

/// Per axis, how many primitives' clipped bounds start and end in each bin:
/// one flat array, the starts of axes 0, 1, 2 and then their ends.
#[derive(Clone, Debug)]
struct Counts {
    bins: usize,
    cells: Vec<u32>,
}

impl Counts {
    fn new(bins: usize) -> Self {
        Self {
            bins,
            cells: vec![0; 6 * bins],
        }
    }

    fn add(mut self, other: &Self) -> Self {
        for (x, y) in self.cells.iter_mut().zip(&other.cells) {
            *x += y;
        }
        self
    }

    /// How many clipped bounds start in bin `i` of axis `a`.
    #[inline]
    fn starts(&self, a: usize, i: usize) -> u32 {
        self.cells[a * self.bins + i]
    }

    /// How many clipped bounds end in bin `i` of axis `a`.
    #[inline]
    fn ends(&self, a: usize, i: usize) -> u32 {
        self.cells[(3 + a) * self.bins + i]
    }
}

/// Maps positions on the three axes of a node to bins.
struct Binning {
    lo: [f64; 3],
    scale: [f64; 3],
    bins: usize,
}

impl Binning {
    fn new<T: Real>(bounds: &Aabb<T>, bins: usize) -> Self {
        let lo = [0, 1, 2].map(|a| bounds.min[a].to_f64());
        let scale = [0, 1, 2].map(|a| {
            let extent = bounds.max[a].to_f64() - lo[a];
            if extent > 0.0 {
                bins as f64 / extent
            } else {
                0.0
            }
        });
        Self { lo, scale, bins }
    }

    /// The bin of `x` on axis `a`, clamped to the node's bins. Written as
    /// plain selects (the positions are finite) and converted from a value
    /// already in range, so it compiles to a few instructions: this runs six
    /// times per primitive and level.
    #[inline]
    fn bin(&self, a: usize, x: f64) -> usize {
        let last = (self.bins - 1) as f64;
        let f = (x - self.lo[a]) * self.scale[a];
        let f = if f > 0.0 { f } else { 0.0 };
        let f = if f < last { f } else { last };
        f as u32 as usize
    }

    fn count<T: Real>(&self, boxes: &[Aabb<T>], mut counts: Counts) -> Counts {
        let bins = self.bins;
        let cells = &mut counts.cells[..6 * bins];
        for b in boxes {
            for a in 0..3 {
                let start = self.bin(a, b.min[a].to_f64());
                let end = self.bin(a, b.max[a].to_f64());
                cells[a * bins + start] += 1;
                cells[(3 + a) * bins + end] += 1;
            }
        }
        counts
    }
}

/// The cheapest of the `bins − 1` evenly spaced planes per axis (ties to the
/// lower axis, then the lower plane), priced by the node's SAH.
pub(crate) fn best_binned_split<T: Real>(
    sah: &Sah,
    bounds: &Aabb<T>,
    boxes: &[Aabb<T>],
    bins: usize,
) -> Option<Split<T>> {
    let binning = Binning::new(bounds, bins);
    let counts = if boxes.len() >= PARALLEL_BINNING {
        boxes
            .par_chunks(PARALLEL_BINNING / 4)
            .map(|chunk| binning.count(chunk, Counts::new(bins)))
            .reduce(|| Counts::new(bins), |a, b| a.add(&b))
    } else {
        binning.count(boxes, Counts::new(bins))
    };
    let n = boxes.len();
    let mut best: Option<Split<T>> = None;
    for k in 0..3 {
        let (lo, hi) = (bounds.min[k].to_f64(), bounds.max[k].to_f64());
        let (mut nl, mut ended) = (0usize, 0usize);
        for i in 1..bins {
            nl += counts.starts(k, i - 1) as usize;
            ended += counts.ends(k, i - 1) as usize;
            // The plane rounded to T, so the split is the one priced.
            let pos = T::from_f64(lo + (hi - lo) * i as f64 / bins as f64);
            let p = pos.to_f64();
            if !sah.is_candidate(k, p) {
                continue;
            }
            let cost = sah.cost(k, p, nl, n - ended);
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis: k,
                    pos,
                    planar_left: true,
                    cost,
                    kept: None,
                });
            }
        }
    }
    best
}

/// Splits a binned node at `split`: each primitive goes by its clipped box,
/// exactly as the sweep build classifies events, and straddlers are clipped
/// anew to each child.
pub(crate) fn split_binned<T: Real, P: PrimitiveSet<T> + ?Sized>(
    node: BinnedNode<T>,
    split: &Split<T>,
    prims: &P,
) -> (BinnedNode<T>, BinnedNode<T>) {
    let (k, p) = (split.axis, split.pos);
    let (left_box, right_box) = node.bounds.split_at(k, p);
    let mut left = child(left_box, node.prims.len() / 2);
    let mut right = child(right_box, node.prims.len() / 2);
    for (&g, b) in node.prims.iter().zip(&node.boxes) {
        match box_side(b, split) {
            BoxSide::Left => left.push(g, *b),
            BoxSide::Right => right.push(g, *b),
            BoxSide::Both => {
                let clipped = clip_to_halves(prims, g, &node.bounds, split);
                for (side, c) in [&mut left, &mut right].into_iter().zip(clipped) {
                    if let Some(c) = c {
                        side.push(g, c);
                    }
                }
            }
        }
    }
    (left.depth, right.depth) =
        node.depth
            .children(&node.bounds, k, p, left.prims.len(), right.prims.len());
    (left, right)
}

/// Where a primitive with clipped bounds `b` goes at `split`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BoxSide {
    Left,
    Right,
    /// Straddles the plane: clipped anew to each child.
    Both,
}

/// The side of `split` a primitive's clipped box belongs to, as the sweep
/// classifies its events: flat in the plane goes to the planar side, ending
/// at or before it left, starting at or after it right.
#[inline]
pub(crate) fn box_side<T: Real>(b: &Aabb<T>, split: &Split<T>) -> BoxSide {
    let (lo, hi) = (b.min[split.axis], b.max[split.axis]);
    let p = split.pos;
    if lo == hi && lo == p {
        if split.planar_left {
            BoxSide::Left
        } else {
            BoxSide::Right
        }
    } else if hi <= p {
        BoxSide::Left
    } else if lo >= p {
        BoxSide::Right
    } else {
        BoxSide::Both
    }
}

/// Primitive `g` clipped to a child's box, `None` where nothing of it lies
/// inside ([`within`]).
#[inline]
pub(crate) fn clip_to_node<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    g: u32,
    child: &Aabb<T>,
) -> Option<Aabb<T>> {
    within(prims.clipped_bounds(g as usize, child), child)
}

/// A clipped box kept inside its child: intersected again, since a user's
/// clipper cannot be trusted not to leak outside the node; `None` when
/// nothing of it is left.
#[inline]
fn within<T: Real>(clipped: Aabb<T>, child: &Aabb<T>) -> Option<Aabb<T>> {
    let c = clipped.intersection(child);
    (!c.is_empty()).then_some(c)
}

/// Primitive `g` clipped to each half of `node` at `split` (below, then
/// above), as [`clip_to_node`] would clip it to each, in one call that
/// shares the two clips' work.
#[inline]
pub(crate) fn clip_to_halves<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    g: u32,
    node: &Aabb<T>,
    split: &Split<T>,
) -> [Option<Aabb<T>>; 2] {
    let (below, above) = node.split_at(split.axis, split.pos);
    let [b, a] = prims.clipped_bounds_split(g as usize, node, split.axis, split.pos);
    [within(b, &below), within(a, &above)]
}

/// An empty child (its depth is set once its primitives are known).
fn child<T: Real>(bounds: Aabb<T>, capacity: usize) -> BinnedNode<T> {
    BinnedNode {
        bounds,
        prims: Vec::with_capacity(capacity),
        boxes: Vec::with_capacity(capacity),
        depth: Depth::ROOT,
    }
}

impl<T: Real> BinnedNode<T> {
    fn push(&mut self, prim: u32, b: Aabb<T>) {
        self.prims.push(prim);
        self.boxes.push(b);
    }

    /// The node with sorted event lists, for the exact sweep.
    pub(crate) fn into_events(self) -> NodeWork<T> {
        let mut events: Events<T> = Default::default();
        for list in &mut events {
            list.reserve(2 * self.boxes.len());
        }
        for (local, b) in self.boxes.iter().enumerate() {
            push_events(&mut events, local as u32, b);
        }
        for list in &mut events {
            sort_events(list);
        }
        NodeWork {
            bounds: self.bounds,
            prims: self.prims,
            events,
            planes: None,
            depth: self.depth,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::KdTreeParams;
    use accel_core::Vec3;

    #[test]
    fn bins_find_the_empty_gap_between_two_clusters() {
        // Ten unit boxes at x in [0, 1] and ten at [3, 4], all spanning the
        // node in y and z: any plane in the gap leaves both sides as cheap as
        // they can be, every other plane cuts a cluster.
        let node = Aabb::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(4.0, 1.0, 1.0));
        let boxes: Vec<Aabb<f32>> = (0..20)
            .map(|i| {
                let x = if i < 10 { 0.0 } else { 3.0 };
                Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0))
            })
            .collect();
        let sah = Sah::new(&KdTreeParams::default(), &node).unwrap();
        let best = best_binned_split(&sah, &node, &boxes, 8).unwrap();
        assert_eq!(best.axis, 0);
        assert!((1.0..=3.0).contains(&best.pos), "{best:?}");
        // Both sides hold ten: the price of the split the sweep would see.
        assert_eq!(best.cost, sah.cost(0, f64::from(best.pos), 10, 10));
    }

    #[test]
    fn a_binned_split_sends_each_box_where_the_sweep_would() {
        use accel_core::TriangleMesh;
        // Left of, right of, flat in, touching, and straddling the plane x = 1.
        let mesh = TriangleMesh::new(
            vec![
                Vec3::new(0.0f64, 0.0, 0.0),
                Vec3::new(0.5, 1.0, 0.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(1.0, 0.0, 0.5),
            ],
            vec![[0, 1, 2], [2, 3, 4], [4, 5, 2], [0, 3, 1]],
        )
        .unwrap();
        let bounds = mesh.bounds();
        let node = BinnedNode {
            bounds,
            prims: vec![0, 1, 2, 3],
            boxes: (0..4).map(|i| PrimitiveSet::bounds(&mesh, i)).collect(),
            depth: Depth::ROOT,
        };
        let split = Split {
            axis: 0,
            pos: 1.0,
            planar_left: false,
            cost: 0.0,
            kept: None,
        };
        let (left, right) = split_binned(node, &split, &mesh);
        // 0 ends at the plane: left. 1 starts there: right. 2 is flat in it:
        // the planar side (right). 3 straddles: both, clipped.
        assert_eq!(left.prims, [0, 3]);
        assert_eq!(right.prims, [1, 2, 3]);
        assert_eq!(left.boxes[1].max.x, 1.0);
        assert_eq!(right.boxes[2].min.x, 1.0);
        assert_eq!((left.depth.counted, right.depth.counted), (1, 1));
        assert_eq!((left.depth.levels, right.depth.levels), (1, 1));
    }
}
