//! The fast build ([`crate::KdTreeParams::fast_build`], `binned_above: 0`):
//! the binned SAH at every node, deciding the leaves too, with no event
//! list, sort or sweep anywhere (Wald 2007; Shevtsov, Soupikov & Kapustin
//! 2007, whose kd-tree build bins all the way down as well).
//!
//! A node is a run of [`Item`]s (a primitive's index and its part of the
//! node's box) at the end of one buffer per task, used as a stack. A split
//! partitions the run in place into the primitives above the plane, those
//! straddling it and those below it; each straddler's part of the upper
//! half stays where it was and its part of the lower half is appended, so
//! the below child's run ends the buffer. That child is built first (nodes
//! are stored depth-first, below child first); the buffer is then cut back
//! to the above child's run, which ends it in turn. No list is allocated
//! per node; the buffer grows only by the straddlers along one path.
//!
//! Straddlers are clipped to each half exactly (perfect splits, as the
//! sweep build) in nodes over [`crate::KdTreeParams::clip_above`]
//! primitives; in smaller ones their boxes are cut at the plane, which is
//! as conservative (the primitive's part of a half lies in its box's part)
//! and much cheaper, and in nodes over
//! [`crate::KdTreeParams::tighten_above`] also kept within the triangle's
//! own part of each half (its vertices there and its edges' crossings with
//! the plane), which costs a few crossings and wins back most of what
//! clipping to the node gains. The number of bins falls with the node's
//! size, so that the small nodes near the leaves are not priced at more
//! planes than they have primitive bounds.

use super::binned::{BoxSide, box_side, clip_to_halves};
use super::depth::Depth;
use super::sah::{Sah, Split};
use super::{Ctx, Out, Piece};
use accel_core::triangle::triangle_halves_bounds;
use accel_core::{Aabb, PrimitiveSet, Real, Vec3, parts};
use std::sync::atomic::Ordering;

/// A primitive of a node: its part of the node's box, and its index with
/// [`LARGE`] set when it is large ([`parts::is_large`]).
#[derive(Clone, Copy, Debug)]
struct Item<T> {
    /// The box's corners, as arrays: indexed by a run-time axis without
    /// [`Vec3`]'s match.
    min: [T; 3],
    max: [T; 3],
    prim: u32,
}

/// The flag of a large primitive in [`Item::prim`]: a primitive index has
/// at most 30 bits ([`crate::KdNode::MAX_COUNT`]).
const LARGE: u32 = 1 << 31;

impl<T: Real> Item<T> {
    /// The item of primitive `prim` (with its flag) and box `b`.
    #[inline]
    fn new(prim: u32, b: &Aabb<T>) -> Self {
        Self {
            min: [b.min.x, b.min.y, b.min.z],
            max: [b.max.x, b.max.y, b.max.z],
            prim,
        }
    }

    /// The box.
    #[inline]
    fn bounds(&self) -> Aabb<T> {
        Aabb {
            min: Vec3::new(self.min[0], self.min[1], self.min[2]),
            max: Vec3::new(self.max[0], self.max[1], self.max[2]),
        }
    }

    /// The primitive's index.
    #[inline]
    fn index(&self) -> u32 {
        self.prim & !LARGE
    }
}

/// The fewest bins a node is priced with.
const MIN_BINS: usize = 4;

/// What one task reuses from node to node: the bin counts, a leaf's
/// sorted indices and the straddlers' triangles of a split.
struct Scratch<T> {
    counts: Box<Counts>,
    leaf: Vec<u32>,
    triangles: Vec<Option<[Vec3<T>; 3]>>,
}

impl<T> Default for Scratch<T> {
    fn default() -> Self {
        Self {
            counts: Box::default(),
            leaf: Vec::new(),
            triangles: Vec::new(),
        }
    }
}

/// Builds the tree of one part: `list` (global indices) with bounds
/// `boxes` (in the same order) inside `bounds`.
pub(super) fn build_fast<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    list: &[u32],
    boxes: &[Aabb<T>],
    bounds: Aabb<T>,
) -> Piece<T> {
    let items = list
        .iter()
        .zip(boxes)
        .map(|(&prim, b)| {
            let large = parts::is_large(b, ctx.scene_side);
            Item::new(if large { prim | LARGE } else { prim }, b)
        })
        .collect();
    let node = Node {
        cell: bounds,
        tight: bounds,
        depth: Depth::ROOT,
    };
    build_piece(ctx, items, node)
}

/// A node's place: its cell, the box of its items' boxes (inside the cell),
/// and its depth.
#[derive(Clone, Copy, Debug)]
struct Node<T> {
    cell: Aabb<T>,
    tight: Aabb<T>,
    depth: Depth,
}

/// What to do with a node.
enum Step<T> {
    Leaf,
    /// Cut off the empty space beyond `split` (nothing lies there): the
    /// child that keeps every item is below when `keep_below`.
    Empty {
        split: Split<T>,
        keep_below: bool,
    },
    Split(Split<T>),
}

/// Builds a subtree over `items`, the halves of large nodes in parallel.
fn build_piece<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    mut items: Vec<Item<T>>,
    node: Node<T>,
) -> Piece<T> {
    let mut scratch = Scratch::default();
    let mut out = Out::new();
    // On one thread the halves would be built one after the other anyway:
    // the whole subtree goes serially, without splitting the items into
    // vectors of their own and relocating the pieces' nodes afterwards
    // (bunny, one thread: 4% fewer build instructions).
    let small = items.len() < ctx.params.parallel_threshold.max(2);
    if small || rayon::current_num_threads() == 1 {
        if small {
            // Room for the straddlers' copies along a path, and the output
            // (about as many references and nodes as items), without
            // regrowth. A whole tree's worth reserved up front instead
            // faulted in more fresh pages per build than growing does.
            let n = items.len();
            items.reserve(n);
            out.nodes.reserve(n);
            out.refs.reserve(2 * n);
        }
        build_serial(ctx, &mut items, 0, node, &mut out, &mut scratch);
        return Piece::Flat(out);
    }
    let empty = || Box::new(Piece::Flat(empty_leaf()));
    match step(ctx, &items, &node, &mut scratch.counts) {
        Step::Leaf => {
            push_leaf(ctx, &items, &mut out, &mut scratch.leaf);
            Piece::Flat(out)
        }
        Step::Empty {
            split: s,
            keep_below,
        } => {
            ctx.count_inner();
            let kept = empty_child(&node, &s, keep_below, items.len());
            let kept = Box::new(build_piece(ctx, items, kept));
            let (below, above) = if keep_below {
                (kept, empty())
            } else {
                (empty(), kept)
            };
            Piece::Inner {
                axis: s.axis,
                pos: s.pos,
                below,
                above,
            }
        }
        Step::Split(s) => {
            ctx.count_inner();
            let (mid, tight_below, tight_above) =
                split(ctx, &mut items, 0, &node.cell, &s, &mut scratch.triangles);
            let below = items.split_off(mid);
            let (lo, hi) = children(
                &node,
                &s,
                tight_below,
                tight_above,
                below.len(),
                items.len(),
            );
            let (below, above) = rayon::join(
                || build_piece(ctx, below, lo),
                || build_piece(ctx, items, hi),
            );
            Piece::Inner {
                axis: s.axis,
                pos: s.pos,
                below: Box::new(below),
                above: Box::new(above),
            }
        }
    }
}

/// An empty leaf, as a piece's arrays.
fn empty_leaf<T: Real>() -> Out<T> {
    let mut out = Out::new();
    out.push_leaf(&[]);
    out
}

/// The child of an empty-space cut that keeps the node's `n` items.
fn empty_child<T: Real>(node: &Node<T>, s: &Split<T>, keep_below: bool, n: usize) -> Node<T> {
    let (lo, hi) = node.cell.split_at(s.axis, s.pos);
    let (d_lo, d_hi) = if keep_below {
        node.depth.children(&node.cell, s.axis, s.pos, n, 0)
    } else {
        node.depth.children(&node.cell, s.axis, s.pos, 0, n)
    };
    let (cell, depth) = if keep_below { (lo, d_lo) } else { (hi, d_hi) };
    Node {
        cell,
        tight: node.tight,
        depth,
    }
}

/// The two children of a split node, from the boxes of their items.
fn children<T: Real>(
    node: &Node<T>,
    s: &Split<T>,
    tight_below: Aabb<T>,
    tight_above: Aabb<T>,
    n_below: usize,
    n_above: usize,
) -> (Node<T>, Node<T>) {
    let (lo, hi) = node.cell.split_at(s.axis, s.pos);
    let (d_lo, d_hi) = node
        .depth
        .children(&node.cell, s.axis, s.pos, n_below, n_above);
    (
        Node {
            cell: lo,
            tight: tight_below,
            depth: d_lo,
        },
        Node {
            cell: hi,
            tight: tight_above,
            depth: d_hi,
        },
    )
}

/// Builds the subtree of the node whose items are `buf[start..]` into
/// `out`; `buf` is cut back to `start` items when it returns.
fn build_serial<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    buf: &mut Vec<Item<T>>,
    start: usize,
    mut node: Node<T>,
    out: &mut Out<T>,
    scratch: &mut Scratch<T>,
) {
    loop {
        match step(ctx, &buf[start..], &node, &mut scratch.counts) {
            Step::Leaf => {
                push_leaf(ctx, &buf[start..], out, &mut scratch.leaf);
                buf.truncate(start);
                return;
            }
            Step::Empty {
                split: s,
                keep_below,
            } => {
                // The kept child is the next node either way: the below one
                // is next by position, the above one is linked to it.
                ctx.count_inner();
                let at = out.push_inner(s.axis, s.pos);
                if keep_below {
                    // No above child (index 0): nothing to link.
                } else {
                    out.unlink_below(at);
                    out.link_above(at);
                }
                node = empty_child(&node, &s, keep_below, buf.len() - start);
            }
            Step::Split(s) => {
                ctx.count_inner();
                let at = out.push_inner(s.axis, s.pos);
                let (mid, tight_below, tight_above) =
                    split(ctx, buf, start, &node.cell, &s, &mut scratch.triangles);
                let (lo, hi) = children(
                    &node,
                    &s,
                    tight_below,
                    tight_above,
                    buf.len() - mid,
                    mid - start,
                );
                // An empty child is a leaf that is not stored: its parent
                // says so.
                if buf.len() == mid {
                    out.unlink_below(at);
                } else {
                    build_serial(ctx, buf, mid, lo, out, scratch);
                }
                if mid > start {
                    out.link_above(at);
                    node = hi;
                } else {
                    buf.truncate(start);
                    return;
                }
            }
        }
    }
}

/// Appends the leaf of `items`, their indices ascending.
fn push_leaf<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    items: &[Item<T>],
    out: &mut Out<T>,
    leaf: &mut Vec<u32>,
) {
    leaf.clear();
    leaf.extend(items.iter().map(Item::index));
    if leaf.len() <= RANK_SORT_MAX {
        // Each index placed at its rank, counted without branches (the
        // indices of a leaf differ): a small sort's compares mispredicted
        // about once per index.
        let mut sorted = [0u32; RANK_SORT_MAX];
        for &i in leaf.iter() {
            let rank = leaf.iter().map(|&o| u32::from(o < i)).sum::<u32>();
            sorted[rank as usize] = i;
        }
        let n = leaf.len();
        leaf.copy_from_slice(&sorted[..n]);
        debug_assert!(leaf.is_sorted_by(|a, b| a < b), "a leaf's indices repeat");
    } else {
        leaf.sort_unstable();
    }
    ctx.count_leaf(leaf.len());
    out.push_leaf(leaf);
}

/// The most items of a leaf sorted by ranks ([`push_leaf`]).
const RANK_SORT_MAX: usize = 16;

/// What a node over `items` does: a leaf when it has too few primitives
/// (and none large), reached the depth limit or a failed budget, has no
/// area, or no plane is cheaper than the leaf; a cut of empty space when
/// its items leave at least [`EMPTY_CUT`] of its width empty on a side;
/// else the cheapest binned split.
fn step<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    items: &[Item<T>],
    node: &Node<T>,
    counts: &mut Counts,
) -> Step<T> {
    let n = items.len();
    if n == 0
        || (n <= ctx.params.leaf_size as usize && items.iter().all(|i| i.prim & LARGE == 0))
        || node.depth.exhausted(ctx.depth_limit)
        || ctx.failed.load(Ordering::Relaxed)
    {
        return Step::Leaf;
    }
    let Some(sah) = Sah::new(ctx.params, &node.cell) else {
        return Step::Leaf;
    };
    if let Some(cut) = empty_cut(node) {
        return cut;
    }
    let bins = bins_for(n, ctx.params.bins as usize);
    let mut best = best_split(&sah, &node.cell, items, bins, counts);
    if n <= FACE_CUT_MAX
        && items.iter().any(|i| i.prim & LARGE != 0)
        && let Some(face) = face_cut(&sah, &node.cell, items)
        && best.as_ref().is_none_or(|b| face.cost < b.cost)
    {
        best = Some(face);
    }
    match best {
        Some(s) if s.cost < sah.leaf_cost(n) => Step::Split(s),
        _ => Step::Leaf,
    }
}

/// The most items of a node whose face cuts are priced.
const FACE_CUT_MAX: usize = 64;

/// The cheapest face cut of a node with box `cell` (as the sweep build
/// makes them, [`Sah::face_cut`]): the items lying flat in a face of the
/// cell (a wall) cut off from the others, so that rays crossing the node
/// do not all test them. Priced only in small nodes holding a large
/// primitive: walls are few and large.
fn face_cut<T: Real>(sah: &Sah, cell: &Aabb<T>, items: &[Item<T>]) -> Option<Split<T>> {
    let mut best: Option<Split<T>> = None;
    for k in 0..3 {
        for pos in [cell.min[k], cell.max[k]] {
            let planar = items
                .iter()
                .filter(|i| i.min[k] == pos && i.max[k] == pos)
                .count();
            if let Some((cost, planar_left)) = sah.face_cut(k, pos.to_f64(), planar, items.len())
                && best.as_ref().is_none_or(|b| cost < b.cost)
            {
                best = Some(Split {
                    axis: k,
                    pos,
                    planar_left,
                    cost,
                    kept: None,
                });
            }
        }
    }
    best
}

/// The share of a node's width its items must leave empty on one side for
/// that space to be cut off before any binning.
const EMPTY_CUT: f64 = 0.125;

/// The first face of `node`'s cell (axis by axis, lower face first) whose
/// empty gap to the items' box is at least [`EMPTY_CUT`] of the cell's
/// width, as a cut at the items' box.
fn empty_cut<T: Real>(node: &Node<T>) -> Option<Step<T>> {
    let (c, t) = (&node.cell, &node.tight);
    for k in 0..3 {
        let width = (c.max[k] - c.min[k]).to_f64();
        let least = width * EMPTY_CUT;
        if (t.min[k] - c.min[k]).to_f64() >= least && t.min[k] > c.min[k] && t.min[k] < c.max[k] {
            // Everything starts at or above the plane; flat ones in it go
            // above too.
            let split = Split {
                axis: k,
                pos: t.min[k],
                planar_left: false,
                cost: 0.0,
                kept: None,
            };
            return Some(Step::Empty {
                split,
                keep_below: false,
            });
        }
        if (c.max[k] - t.max[k]).to_f64() >= least && t.max[k] < c.max[k] && t.max[k] > c.min[k] {
            let split = Split {
                axis: k,
                pos: t.max[k],
                planar_left: true,
                cost: 0.0,
                kept: None,
            };
            return Some(Step::Empty {
                split,
                keep_below: true,
            });
        }
    }
    None
}

/// The bins a node of `n` primitives is priced with: at most `max` and
/// [`MAX_BINS`], about its primitive count, at least [`MIN_BINS`].
#[inline]
fn bins_for(n: usize, max: usize) -> usize {
    n.clamp(MIN_BINS, max.clamp(MIN_BINS, MAX_BINS))
}

/// The most bins per axis of the fast build.
const MAX_BINS: usize = 256;

/// Per axis, how many items' boxes start and end in each bin, and the
/// sweep's per-plane arrays.
pub(super) struct Counts {
    starts: [[u32; MAX_BINS]; 3],
    ends: [[u32; MAX_BINS]; 3],
    /// Per plane of the axis swept: the items starting below it, those
    /// ending above it, and its cost.
    left: [f32; MAX_BINS],
    right: [f32; MAX_BINS],
    cost: [f32; MAX_BINS],
}

impl Default for Counts {
    fn default() -> Self {
        Self {
            starts: [[0; MAX_BINS]; 3],
            ends: [[0; MAX_BINS]; 3],
            left: [0.0; MAX_BINS],
            right: [0.0; MAX_BINS],
            cost: [0.0; MAX_BINS],
        }
    }
}

/// The cheapest of `bins − 1` evenly spaced planes per axis (ties to the
/// lower axis, then the lower plane), counting each item's box into the
/// bins of its two ends. Bins are found in `f32` whatever `T` is: they
/// only price the planes, the split itself is exact in `T`.
fn best_split<T: Real>(
    sah: &Sah,
    bounds: &Aabb<T>,
    items: &[Item<T>],
    bins: usize,
    counts: &mut Counts,
) -> Option<Split<T>> {
    debug_assert!((2..=MAX_BINS).contains(&bins));
    let lo = [0, 1, 2].map(|a| bounds.min[a].to_f64());
    let extent = [0, 1, 2].map(|a| bounds.max[a].to_f64() - lo[a]);
    let scale = extent.map(|e| if e > 0.0 { bins as f64 / e } else { 0.0 });
    let (lo32, scale32) = (lo.map(|x| x as f32), scale.map(|x| x as f32));
    let last = (bins - 1) as u32;
    // The bin of `x` on axis `a`, clamped.
    let bin = |a: usize, x: T| {
        // Saturating: below 0 (or NaN) is 0; then at most the last bin.
        let f = ((x.to_f64() as f32 - lo32[a]) * scale32[a]) as u32;
        (f.min(last) as usize) & (MAX_BINS - 1)
    };
    for a in 0..3 {
        counts.starts[a][..bins].fill(0);
        counts.ends[a][..bins].fill(0);
    }
    // A large node is priced from an even sample of its items: in a
    // mesh's spatial order, a spread over its whole box.
    let stride = items.len().div_ceil(SAMPLE);
    let longest = if extent[0] >= extent[1] && extent[0] >= extent[2] {
        0
    } else if extent[1] >= extent[2] {
        1
    } else {
        2
    };
    let axes = if items.len() > ALL_AXES_ABOVE {
        0..3
    } else {
        longest..longest + 1
    };
    if axes.len() == 3 {
        for it in items.iter().step_by(stride) {
            for a in 0..3 {
                counts.starts[a][bin(a, it.min[a])] += 1;
                counts.ends[a][bin(a, it.max[a])] += 1;
            }
        }
    } else {
        let a = longest;
        for it in items.iter().step_by(stride) {
            counts.starts[a][bin(a, it.min[a])] += 1;
            counts.ends[a][bin(a, it.max[a])] += 1;
        }
    }
    let n = items.len().div_ceil(stride);
    let (mut best_cost, mut best_at) = (f32::INFINITY, (0, 0));
    for k in axes {
        if extent[k] <= 0.0 {
            continue;
        }
        if let Some((cost, i)) = cheapest_plane(sah, k, extent[k], bins, n, counts)
            && cost < best_cost
        {
            (best_cost, best_at) = (cost, (k, i));
        }
    }
    if best_cost == f32::INFINITY {
        return None;
    }
    // The plane rounded to T: a plane that rounds onto the node's face (a
    // node a few ulps wide) is no split. Its cost is priced again exactly.
    let (k, i) = best_at;
    let pos = T::from_f64(lo[k] + extent[k] / bins as f64 * i as f64);
    let p = pos.to_f64();
    let (nl, ended) = (0..i).fold((0, 0), |(l, e), j| {
        (
            l + counts.starts[k][j] as usize,
            e + counts.ends[k][j] as usize,
        )
    });
    // Counts of a sample stand for their share of the node.
    let whole = |c: usize| c * items.len() / n;
    sah.is_candidate(k, p).then(|| Split {
        axis: k,
        pos,
        planar_left: true,
        cost: sah.cost(k, p, whole(nl), whole(n - ended)),
        kept: None,
    })
}

/// The most items binned per node: larger nodes bin every `k`-th item.
const SAMPLE: usize = 2048;

/// Nodes over this many items search the three axes; smaller ones only
/// the longest axis of their box (a third of the binning, and as good a
/// tree on the scanned meshes: cells stay about cubical).
const ALL_AXES_ABOVE: usize = 1024;

/// `0, 1, 2, …` as `f32`: the bins' indices, for the sweep's arithmetic.
const INDICES: [f32; MAX_BINS] = {
    let mut a = [0.0; MAX_BINS];
    let mut i = 0;
    while i < MAX_BINS {
        a[i] = i as f32;
        i += 1;
    }
    a
};

/// The cheapest of the `bins − 1` planes of axis `k` (`extent` wide) by
/// their counts, and its index: the cost up to the SAH's constant terms
/// and factors (the children's areas times their counts, less the empty
/// bonus), in `f32`, in loops the compiler vectorizes.
fn cheapest_plane(
    sah: &Sah,
    k: usize,
    extent: f64,
    bins: usize,
    n: usize,
    counts: &mut Counts,
) -> Option<(f32, usize)> {
    let Counts {
        starts,
        ends,
        left,
        right,
        cost,
    } = counts;
    // Plane i (1 ≤ i < bins) is entry i − 1: the primitives starting
    // before it and those ending after it.
    let m = bins - 1;
    let (left, right, cost) = (&mut left[..m], &mut right[..m], &mut cost[..m]);
    let (mut nl, mut ended) = (0u32, 0u32);
    for (((l, r), s), e) in left
        .iter_mut()
        .zip(right.iter_mut())
        .zip(&starts[k][..m])
        .zip(&ends[k][..m])
    {
        nl += s;
        ended += e;
        *l = nl as f32;
        *r = (n as u32 - ended) as f32;
    }
    // A child's area is linear in the plane's position.
    let (cross, sum) = sah.cross_sum(k);
    let step = (sum * extent / bins as f64) as f32;
    let (base, full) = (cross as f32, (cross + sum * extent) as f32);
    let keep = sah.keep() as f32;
    for (((c, &l), &r), &i) in cost
        .iter_mut()
        .zip(left.iter())
        .zip(right.iter())
        .zip(&INDICES[1..bins])
    {
        let w = if l == 0.0 || r == 0.0 { keep } else { 1.0 };
        let x = i * step;
        *c = w * ((base + x) * l + (full - x) * r);
    }
    let mut best = (f32::INFINITY, 0);
    for (i, &c) in cost.iter().enumerate() {
        if c < best.0 {
            best = (c, i + 1);
        }
    }
    (best.1 > 0).then_some(best)
}

/// Splits the node whose items are `buf[start..]` at `split`: afterwards
/// `buf[start..mid]` holds the above child's items and `buf[mid..]` the
/// below child's; returns `mid` and the boxes of the below and the above
/// child's items.
fn split<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    buf: &mut Vec<Item<T>>,
    start: usize,
    cell: &Aabb<T>,
    split: &Split<T>,
    triangles: &mut Vec<Option<[Vec3<T>; 3]>>,
) -> (usize, Aabb<T>, Aabb<T>) {
    let (k, p) = (split.axis, split.pos);
    debug_assert!(buf[start..].iter().all(|it| {
        let (above, below) = sides(it, k, p, split.planar_left);
        match box_side(&it.bounds(), split) {
            BoxSide::Right => above && !below,
            BoxSide::Left => below && !above,
            BoxSide::Both => !above && !below,
        }
    }));
    let (above, below, mut tight_above, mut tight_below) = match k {
        0 => three_way::<T, 0>(buf, start, p, split.planar_left),
        1 => three_way::<T, 1>(buf, start, p, split.planar_left),
        _ => three_way::<T, 2>(buf, start, p, split.planar_left),
    };
    let end = buf.len();
    // Each straddler's upper part replaces it (packed down over the ones
    // with none), its lower part is appended after the below-only items.
    let clip = ctx.params.clip_above < end - start;
    let tighten = !clip && ctx.params.tighten_above < end - start;
    // The straddlers' triangles fetched first, in a loop of their own: the
    // fetches (cache misses in a large mesh) overlap there, where each
    // waited in turn behind the previous straddler's work before.
    triangles.clear();
    if tighten {
        triangles.extend(
            buf[above..below]
                .iter()
                .map(|it| ctx.prims.watertight_triangle(it.index() as usize)),
        );
    }
    let mut kept = above;
    for j in above..below {
        let it = buf[j];
        let (lo, hi) = if clip {
            let [lo, hi] = clip_to_halves(ctx.prims, it.index(), cell, split);
            (
                lo.map(|b| Item::new(it.prim, &b)),
                hi.map(|b| Item::new(it.prim, &b)),
            )
        } else {
            // The box cut at the plane, within the triangle's own halves
            // (its vertices on each side and its edges' crossings with the
            // plane): each holds the triangle's part of that half of the
            // node, so their common part does too.
            let (mut lo, mut hi) = (it.bounds(), it.bounds());
            lo.max[k] = p;
            hi.min[k] = p;
            if let Some(&Some([a, b, c])) = triangles.get(j - above) {
                let [below_own, above_own] = triangle_halves_bounds(a, b, c, k, p);
                (lo, hi) = (lo.intersection(&below_own), hi.intersection(&above_own));
            }
            (
                (!lo.is_empty()).then(|| Item::new(it.prim, &lo)),
                (!hi.is_empty()).then(|| Item::new(it.prim, &hi)),
            )
        };
        if let Some(hi) = hi {
            tight_above.add(&hi);
            buf[kept] = hi;
            kept += 1;
        }
        if let Some(lo) = lo {
            tight_below.add(&lo);
            buf.push(lo);
        }
    }
    if kept < below {
        buf.copy_within(below.., kept);
        buf.truncate(buf.len() - (below - kept));
    }
    (kept, tight_below.bounds(), tight_above.bounds())
}

/// Whether an item lies above only and below only a plane at `p` on axis
/// `k` (neither: it straddles), as [`box_side`] decides: flat in the plane
/// goes to the planar side, ending at or before it below, starting at or
/// after it above.
#[inline(always)]
fn sides<T: Real>(it: &Item<T>, k: usize, p: T, planar_left: bool) -> (bool, bool) {
    let (lo, hi) = (it.min[k], it.max[k]);
    (
        lo > p || (lo == p && (hi > p || !planar_left)),
        hi < p || (hi == p && (lo < p || planar_left)),
    )
}

/// Orders `buf[start..]` above only, straddling, below only (on axis `K`
/// at `p`) in place, by two Hoare partitions: items already on their side
/// stay, which in a mesh's spatial order is most of them. Returns where
/// the straddlers and the items below only begin, and the boxes of the
/// items above only and below only, grown as the partitions place them
/// (not in passes of their own).
fn three_way<T: Real, const K: usize>(
    buf: &mut [Item<T>],
    start: usize,
    p: T,
    planar_left: bool,
) -> (usize, usize, Tight<T>, Tight<T>) {
    let (mut tight_above, mut tight_below) = (Tight::empty(), Tight::empty());
    let above = hoare(
        buf,
        start,
        |it| sides(it, K, p, planar_left).0,
        |it| tight_above.add(it),
        |_| {},
    );
    let below = hoare(
        buf,
        above,
        |it| !sides(it, K, p, planar_left).1,
        |_| {},
        |it| tight_below.add(it),
    );
    (above, below, tight_above, tight_below)
}

/// The box of some items' boxes, grown item by item with plain
/// comparisons (the boxes are finite).
struct Tight<T> {
    min: [T; 3],
    max: [T; 3],
}

impl<T: Real> Tight<T> {
    /// The box of no items.
    fn empty() -> Self {
        Self {
            min: [T::INFINITY; 3],
            max: [T::NEG_INFINITY; 3],
        }
    }

    #[inline(always)]
    fn add(&mut self, it: &Item<T>) {
        for a in 0..3 {
            let (lo, hi) = (it.min[a], it.max[a]);
            self.min[a] = if lo < self.min[a] { lo } else { self.min[a] };
            self.max[a] = if hi > self.max[a] { hi } else { self.max[a] };
        }
    }

    fn bounds(&self) -> Aabb<T> {
        Aabb {
            min: Vec3::new(self.min[0], self.min[1], self.min[2]),
            max: Vec3::new(self.max[0], self.max[1], self.max[2]),
        }
    }
}

/// Moves the items of `buf[start..]` for which `first` holds before the
/// others (swapping only misplaced pairs); returns where the others begin.
/// Each item is shown once to `placed_first` or `placed_other` as it
/// reaches its final place.
#[inline]
fn hoare<T: Real>(
    buf: &mut [Item<T>],
    start: usize,
    first: impl Fn(&Item<T>) -> bool,
    mut placed_first: impl FnMut(&Item<T>),
    mut placed_other: impl FnMut(&Item<T>),
) -> usize {
    let (mut lo, mut hi) = (start, buf.len());
    loop {
        while lo < hi && first(&buf[lo]) {
            placed_first(&buf[lo]);
            lo += 1;
        }
        while lo < hi && !first(&buf[hi - 1]) {
            placed_other(&buf[hi - 1]);
            hi -= 1;
        }
        if lo >= hi {
            return lo;
        }
        buf.swap(lo, hi - 1);
        placed_first(&buf[lo]);
        placed_other(&buf[hi - 1]);
        lo += 1;
        hi -= 1;
    }
}
