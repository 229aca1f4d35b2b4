//! The O(n log n) build: root events, the recursion (parallel at the top),
//! and the flattening of the pieces into one depth-first node array.

pub(crate) mod binned;
pub(crate) mod depth;
pub(crate) mod events;
mod fast;
pub(crate) mod sah;
pub(crate) mod spares;
pub(crate) mod split;
mod unstored;

use crate::node::KdNode;
use crate::params::KdTreeParams;
use accel_core::packed::PackedTriangles;
use accel_core::parts;
use accel_core::{Aabb, AccelStats, BuildError, PrimitiveSet, Real, primitive_bounds};
use binned::{BinnedNode, best_binned_split, split_binned};
use depth::Depth;
use events::{Events, push_axis_events, sort_events};
use sah::{Sah, Split, best_split, best_split_of_planes};
use spares::Spares;
use split::{NodeWork, split_node};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Whether split positions fit the node's 32-bit payload (`f32` trees);
/// `f64` trees keep them in a side table.
#[inline]
pub(crate) fn inline_splits<T: Real>() -> bool {
    size_of::<T>() == 4
}

/// The payload word of a split at `pos`, appending to `table` if needed.
pub(crate) fn encode_split<T: Real>(pos: T, table: &mut Vec<T>) -> u32 {
    if inline_splits::<T>() {
        pos.to_bits_u64() as u32
    } else {
        table.push(pos);
        (table.len() - 1) as u32
    }
}

/// The split position stored in `word`.
#[inline]
pub(crate) fn decode_split<T: Real>(word: u32, table: &[T]) -> T {
    if inline_splits::<T>() {
        // Exact: the word holds an f32's bits and T is f32.
        T::from_f64(f64::from(f32::from_bits(word)))
    } else {
        table[word as usize]
    }
}

/// Nodes, references and split table of a tree or of a piece of one, with
/// child indices and leaf offsets relative to its own arrays.
#[derive(Debug)]
pub(crate) struct Out<T> {
    pub(crate) nodes: Vec<KdNode>,
    pub(crate) refs: Vec<u32>,
    pub(crate) splits: Vec<T>,
}

impl<T: Real> Out<T> {
    pub(crate) fn new() -> Self {
        Self {
            nodes: Vec::new(),
            refs: Vec::new(),
            splits: Vec::new(),
        }
    }

    /// Appends a leaf of `prims` (ascending).
    pub(crate) fn push_leaf(&mut self, prims: &[u32]) {
        let node = match prims {
            [] => KdNode::leaf(0, 0),
            [p] => KdNode::leaf(1, *p),
            _ => {
                let at = self.refs.len() as u32;
                self.refs.extend_from_slice(prims);
                KdNode::leaf(prims.len() as u32, at)
            }
        };
        self.nodes.push(node);
    }

    /// Appends an inner node whose above child is not known yet; returns its index.
    pub(crate) fn push_inner(&mut self, axis: usize, pos: T) -> usize {
        let word = encode_split(pos, &mut self.splits);
        self.nodes.push(KdNode::inner(axis, word, 0));
        self.nodes.len() - 1
    }

    /// Marks inner node `at` as having no below child (an empty leaf, not
    /// stored).
    fn unlink_below(&mut self, at: usize) {
        self.nodes[at] = self.nodes[at].without_below();
    }

    /// Sets the above child of inner node `at` to the next node appended.
    pub(crate) fn link_above(&mut self, at: usize) {
        let n = self.nodes[at];
        let above = self.nodes.len().min(KdNode::MAX_NODES as usize) as u32;
        let node = KdNode::inner(n.axis(), n.split_word(), above);
        self.nodes[at] = if n.has_below() {
            node
        } else {
            node.without_below()
        };
    }
}

/// A built subtree: flat arrays, or an inner node over two pieces built in
/// parallel (joined once, at the end, so nothing is copied per level).
enum Piece<T> {
    Flat(Out<T>),
    Inner {
        axis: usize,
        pos: T,
        below: Box<Piece<T>>,
        above: Box<Piece<T>>,
    },
}

/// Shared by every task of one build.
pub(crate) struct Ctx<'p, T, P: ?Sized> {
    pub(crate) prims: &'p P,
    pub(crate) params: &'p KdTreeParams,
    pub(crate) depth_limit: u32,
    /// The scene's largest side, for [`parts::is_large`].
    scene_side: T,
    refs: AtomicU64,
    /// Bytes of the nodes, references and blocks made so far
    /// ([`KdTreeParams::max_bytes`]).
    bytes: AtomicU64,
    failed: AtomicBool,
    _t: core::marker::PhantomData<T>,
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized> Ctx<'_, T, P> {
    /// True when a node of the primitives `prims` at `depth` is a leaf
    /// without a search. A node of at most [`KdTreeParams::leaf_size`]
    /// primitives is one unless it holds a large primitive: few and crossed
    /// by many rays (a wall, a box's face), those are worth a search however
    /// few they are.
    pub(crate) fn leaf_without_search(
        &self,
        prims: impl ExactSizeIterator<Item = u32>,
        depth: Depth,
    ) -> bool {
        let n = prims.len();
        n == 0
            || (n <= self.params.leaf_size as usize && !self.any_large(prims))
            || depth.exhausted(self.depth_limit)
            || self.failed.load(Ordering::Relaxed)
    }

    /// Whether any of `prims` is large.
    fn any_large(&self, mut prims: impl Iterator<Item = u32>) -> bool {
        prims.any(|p| parts::is_large(&self.prims.bounds(p as usize), self.scene_side))
    }

    /// Counts a leaf's references and bytes against the budgets (an empty
    /// leaf is not stored, and a leaf of one keeps its primitive in the
    /// node).
    fn count_leaf(&self, n: usize) {
        // Past a budget, the open nodes close as leaves uncounted: the
        // error reports the count that passed it.
        if self.failed.load(Ordering::Relaxed) {
            return;
        }
        let total = self.refs.fetch_add(n as u64, Ordering::Relaxed) + n as u64;
        if total > self.params.max_references.min(u64::from(u32::MAX)) {
            self.failed.store(true, Ordering::Relaxed);
        }
        let bytes = match n {
            0 => 0,
            1 => node_bytes::<T>(false),
            _ => {
                node_bytes::<T>(false)
                    + n * size_of::<u32>()
                    + PackedTriangles::<T>::bytes_for_list(self.params.layout, n)
            }
        };
        self.count_bytes(bytes);
    }

    /// Counts an inner node against the byte budget.
    pub(crate) fn count_inner(&self) {
        self.count_bytes(node_bytes::<T>(true));
    }

    /// Adds `n` bytes to the tree's count, failing the build past the budget.
    fn count_bytes(&self, n: usize) {
        let total = self.bytes.fetch_add(n as u64, Ordering::Relaxed) + n as u64;
        if total > self.params.max_bytes {
            self.failed.store(true, Ordering::Relaxed);
        }
    }
}

/// The bytes one stored node takes: the node, its value of the reach table,
/// and an inner node's split position in an `f64` tree's side table.
fn node_bytes<T: Real>(inner: bool) -> usize {
    let split = if inner && !inline_splits::<T>() {
        size_of::<T>()
    } else {
        0
    };
    size_of::<KdNode>() + size_of::<T>() + split
}

/// The split a node should take, or `None` for a leaf (SAH termination).
/// A node whose planes are recorded sweeps those; any other records its
/// planes while it sweeps its events, for a child it may hand them to.
fn choose<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    node: &mut NodeWork<T>,
    spares: &mut Spares<T>,
) -> Option<Split<T>> {
    let n = node.prims.len();
    if ctx.leaf_without_search(node.prims.iter().copied(), node.depth) {
        return None;
    }
    let sah = Sah::new(ctx.params, &node.bounds)?;
    let best = match &node.planes {
        Some(planes) => best_split_of_planes(&sah, planes, n),
        None => {
            let planes = node.planes.insert(spares.planes());
            best_split(&sah, &node.events, n, planes)
        }
    }?;
    let split = (best.cost < sah.leaf_cost(n)).then_some(best);
    if split.is_some() {
        ctx.count_inner();
    }
    split
}

/// Builds a subtree serially into `out`, reusing the lists of `spares`.
fn build_serial<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    mut node: NodeWork<T>,
    out: &mut Out<T>,
    spares: &mut Spares<T>,
) {
    match choose(ctx, &mut node, spares) {
        None => {
            ctx.count_leaf(node.prims.len());
            out.push_leaf(&node.prims);
            spares.recycle(node);
        }
        Some(s) => {
            let at = out.push_inner(s.axis, s.pos);
            let (below, above) = split_node(node, &s, ctx.prims, spares);
            // An empty child is a leaf that is not stored: its parent says
            // so (no below child, or an above index of 0).
            if below.prims.is_empty() {
                out.unlink_below(at);
                spares.recycle(below);
            } else {
                build_serial(ctx, below, out, spares);
            }
            if above.prims.is_empty() {
                spares.recycle(above);
            } else {
                out.link_above(at);
                build_serial(ctx, above, out, spares);
            }
        }
    }
}

/// Builds a subtree, in parallel while it is large.
fn build_piece<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    mut node: NodeWork<T>,
) -> Piece<T> {
    if node.prims.len() < ctx.params.parallel_threshold.max(2) {
        let mut out = Out::new();
        build_serial(ctx, node, &mut out, &mut Spares::default());
        return Piece::Flat(out);
    }
    let mut spares = Spares::default();
    match choose(ctx, &mut node, &mut spares) {
        None => {
            let mut out = Out::new();
            ctx.count_leaf(node.prims.len());
            out.push_leaf(&node.prims);
            Piece::Flat(out)
        }
        Some(s) => {
            let (below, above) = split_node(node, &s, ctx.prims, &mut spares);
            let (below, above) =
                rayon::join(|| build_piece(ctx, below), || build_piece(ctx, above));
            Piece::Inner {
                axis: s.axis,
                pos: s.pos,
                below: Box::new(below),
                above: Box::new(above),
            }
        }
    }
}

/// Builds a subtree whose large nodes split by the binned SAH; the exact
/// sweep takes over at [`KdTreeParams::binned_above`] primitives, and
/// wherever the bins find no split cheaper than a leaf.
fn build_binned<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    node: BinnedNode<T>,
) -> Piece<T> {
    let n = node.prims.len();
    if n <= ctx.params.binned_above
        || ctx.leaf_without_search(node.prims.iter().copied(), node.depth)
    {
        return build_piece(ctx, node.into_events());
    }
    let split = Sah::new(ctx.params, &node.bounds).and_then(|sah| {
        best_binned_split(&sah, &node.bounds, &node.boxes, ctx.params.bins as usize)
            .filter(|s| s.cost < sah.leaf_cost(n))
    });
    let Some(s) = split else {
        return build_piece(ctx, node.into_events());
    };
    ctx.count_inner();
    let (below, above) = split_binned(node, &s, ctx.prims);
    let (below, above) = if n >= ctx.params.parallel_threshold {
        rayon::join(|| build_binned(ctx, below), || build_binned(ctx, above))
    } else {
        (build_binned(ctx, below), build_binned(ctx, above))
    };
    Piece::Inner {
        axis: s.axis,
        pos: s.pos,
        below: Box::new(below),
        above: Box::new(above),
    }
}

impl<T> Piece<T> {
    /// Whether the piece is a single empty leaf (not stored once joined).
    fn is_empty_leaf(&self) -> bool {
        match self {
            Piece::Flat(o) => {
                matches!(o.nodes.as_slice(), [n] if n.is_leaf() && n.prim_count() == 0)
            }
            Piece::Inner { .. } => false,
        }
    }

    /// The nodes, references and split table entries the piece holds.
    fn sizes(&self) -> [usize; 3] {
        match self {
            Piece::Flat(o) => [o.nodes.len(), o.refs.len(), o.splits.len()],
            Piece::Inner { below, above, .. } => {
                let (b, a) = (below.sizes(), above.sizes());
                // The inner node itself, and its split in an `f64` table.
                [1 + b[0] + a[0], b[1] + a[1], 1 + b[2] + a[2]]
            }
        }
    }
}

/// Joins the pieces of a tree into `out`, its arrays reserved once (a
/// flat piece is appended as it is).
fn join<T: Real>(piece: Piece<T>, out: &mut Out<T>) -> Result<(), BuildError> {
    if let Piece::Inner { .. } = piece {
        let [nodes, refs, splits] = piece.sizes();
        out.nodes.reserve(nodes);
        out.refs.reserve(refs);
        if !inline_splits::<T>() {
            out.splits.reserve(splits);
        }
    }
    flatten(piece, out)
}

/// Appends a piece to `out`, relocating its indices. The empty leaves among
/// an inner piece's children are not stored, as in a serial build.
fn flatten<T: Real>(piece: Piece<T>, out: &mut Out<T>) -> Result<(), BuildError> {
    match piece {
        Piece::Flat(o) => {
            let total = out.nodes.len() + o.nodes.len();
            if total > KdNode::MAX_NODES as usize
                || out.refs.len() + o.refs.len() > u32::MAX as usize
            {
                return Err(BuildError::BudgetExceeded {
                    what: "kd-tree nodes (29-bit indices)",
                    needed: total as u64,
                    budget: u64::from(KdNode::MAX_NODES),
                });
            }
            if out.nodes.is_empty() && out.refs.is_empty() && out.splits.is_empty() {
                // Nothing to relocate by: the piece becomes the output.
                *out = o;
                return Ok(());
            }
            let (nb, rb) = (out.nodes.len() as u32, out.refs.len() as u32);
            let sb = (!inline_splits::<T>()).then_some(out.splits.len() as u32);
            out.nodes
                .extend(o.nodes.iter().map(|n| n.relocated(nb, rb, sb)));
            out.refs.extend_from_slice(&o.refs);
            out.splits.extend_from_slice(&o.splits);
        }
        Piece::Inner {
            axis,
            pos,
            below,
            above,
        } => {
            let at = out.push_inner(axis, pos);
            if below.is_empty_leaf() {
                out.unlink_below(at);
            } else {
                flatten(*below, out)?;
            }
            if !above.is_empty_leaf() {
                out.link_above(at);
                flatten(*above, out)?;
            }
        }
    }
    Ok(())
}

/// One independently built part of a tree: the root of its nodes, the box
/// it covers (its primitives' bounds) and its depth limit. Most trees have
/// one; a small dense part in a large sparse scene makes two
/// ([`parts`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KdPart<T> {
    /// Index of the part's root in [`crate::KdTree::nodes`].
    pub root: usize,
    /// The part's box: the bounds of its primitives.
    pub bounds: Aabb<T>,
    /// The part's depth limit (from its own primitive count).
    pub depth_limit: u32,
}

/// What a build produces before it is wrapped with its primitives.
pub(crate) struct Built<T> {
    pub(crate) out: Out<T>,
    pub(crate) parts: Vec<KdPart<T>>,
    pub(crate) bounds: Aabb<T>,
    pub(crate) build_time: std::time::Duration,
}

/// The primitive count a tree can index: node-local indices have 30 bits.
fn check_count(n: usize) -> Result<(), BuildError> {
    if n > KdNode::MAX_COUNT as usize {
        return Err(BuildError::BudgetExceeded {
            what: "primitives (30-bit kd-tree indices)",
            needed: n as u64,
            budget: u64::from(KdNode::MAX_COUNT),
        });
    }
    Ok(())
}

/// Builds the tree over `prims` with the event sweep, or with the naive
/// O(n²) reference builder when `naive` is set: one tree per part
/// ([`parts::partition_with_floor`]), appended one after the other.
pub(crate) fn build<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    params: &KdTreeParams,
    naive: bool,
) -> Result<Built<T>, BuildError> {
    let start = Instant::now();
    params.validate()?;
    let (mut boxes, bounds) = primitive_bounds(prims)?;
    check_count(prims.len())?;
    // A floor apart where the walk's beam is thin enough for rays leaving
    // it to miss its flat bounds.
    let groups =
        parts::partition_with_floor(&boxes, &bounds, params.flat_part && prims.wide_hits());
    let whole = groups.len() == 1;
    let mut out = Out::new();
    let mut parts = Vec::with_capacity(groups.len());
    let least = least_bytes::<T>(prims.len(), params);
    if least > params.max_bytes {
        return Err(bytes_exceeded(least, params));
    }
    let (mut references, mut bytes) = (0u64, 0u64);
    let scene_side = (bounds.max - bounds.min).max_component();
    for parts::Group {
        prims: list,
        bounds: part_bounds,
    } in groups
    {
        // A whole scene's part takes the boxes as they are (no copy).
        let part_boxes: Vec<Aabb<T>> = if whole {
            core::mem::take(&mut boxes)
        } else {
            list.iter().map(|&g| boxes[g as usize]).collect()
        };
        let depth_limit = params.depth_limit(list.len());
        let ctx = Ctx {
            prims,
            params,
            depth_limit,
            scene_side,
            refs: AtomicU64::new(references),
            bytes: AtomicU64::new(bytes),
            failed: AtomicBool::new(false),
            _t: core::marker::PhantomData,
        };
        let part = build_part(&ctx, list, part_boxes, part_bounds, naive)?;
        references = ctx.refs.load(Ordering::Relaxed);
        bytes = ctx.bytes.load(Ordering::Relaxed);
        if bytes > params.max_bytes {
            return Err(bytes_exceeded(bytes, params));
        }
        if ctx.failed.load(Ordering::Relaxed) {
            return Err(BuildError::BudgetExceeded {
                what: "kd-tree references",
                needed: references,
                budget: params.max_references.min(u64::from(u32::MAX)),
            });
        }
        let root = out.nodes.len();
        flatten(Piece::Flat(part), &mut out)?;
        parts.push(KdPart {
            root,
            bounds: part_bounds,
            depth_limit,
        });
    }
    out.nodes.shrink_to_fit();
    out.refs.shrink_to_fit();
    out.splits.shrink_to_fit();
    Ok(Built {
        out,
        parts,
        bounds,
        build_time: start.elapsed(),
    })
}

/// The least a tree over `n` primitives takes under `params`: one leaf
/// referencing them all.
fn least_bytes<T: Real>(n: usize, params: &KdTreeParams) -> u64 {
    let refs = if n > 1 {
        n * size_of::<u32>() + PackedTriangles::<T>::bytes_for_list(params.layout, n)
    } else {
        0
    };
    (node_bytes::<T>(false) + refs) as u64
}

/// The error of a tree past [`KdTreeParams::max_bytes`], `needed` being
/// the bytes counted when the build stopped.
fn bytes_exceeded(needed: u64, params: &KdTreeParams) -> BuildError {
    BuildError::BudgetExceeded {
        what: "kd-tree bytes (nodes, references, blocks; KdTreeParams::max_bytes)",
        needed,
        budget: params.max_bytes,
    }
}

/// The tree of one part: `list` (ascending) with bounds `boxes` (in the same
/// order) inside `bounds`, empty leaves dropped.
fn build_part<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    list: Vec<u32>,
    boxes: Vec<Aabb<T>>,
    bounds: Aabb<T>,
    naive: bool,
) -> Result<Out<T>, BuildError> {
    let mut out = Out::new();
    if naive {
        crate::naive::build_naive(ctx, &list, &boxes, bounds, &mut out);
        unstored::drop_empty_leaves(&mut out);
    } else if ctx.params.binned_above == 0 {
        join(fast::build_fast(ctx, &list, &boxes, bounds), &mut out)?;
    } else if list.len() > ctx.params.binned_above {
        let root = BinnedNode {
            bounds,
            prims: list,
            boxes,
            depth: Depth::ROOT,
        };
        join(build_binned(ctx, root), &mut out)?;
    } else {
        let events = root_events(&boxes);
        drop(boxes);
        let root = NodeWork {
            bounds,
            prims: list,
            events,
            planes: None,
            depth: Depth::ROOT,
        };
        join(build_piece(ctx, root), &mut out)?;
    }
    debug_assert!(
        out.nodes
            .iter()
            .skip(1)
            .all(|n| !n.is_leaf() || n.prim_count() > 0),
        "an empty leaf was stored"
    );
    Ok(out)
}

/// The root's events: each primitive's bounds (its part in the root box),
/// sorted once per axis, the three axes in parallel.
fn root_events<T: Real>(boxes: &[Aabb<T>]) -> Events<T> {
    let make = |a: usize| {
        let mut list = Vec::with_capacity(2 * boxes.len());
        for (i, b) in boxes.iter().enumerate() {
            push_axis_events(&mut list, a, i as u32, b);
        }
        sort_events(&mut list);
        list
    };
    let (x, (y, z)) = rayon::join(|| make(0), || rayon::join(|| make(1), || make(2)));
    [x, y, z]
}

/// Shape statistics of a finished tree, by one walk of each part with node
/// boxes; the SAH cost prices every part against the scene's box `bounds`.
pub(crate) fn tree_stats<T: Real>(
    nodes: &[KdNode],
    splits: &[T],
    parts: &[KdPart<T>],
    bounds: &Aabb<T>,
    params: &KdTreeParams,
    primitives: usize,
) -> AccelStats {
    let mut stats = AccelStats {
        kind: "kdtree",
        primitives,
        nodes: nodes.len(),
        ..AccelStats::default()
    };
    let root_area = bounds.half_area().to_f64();
    let area_ratio = |b: &Aabb<T>| {
        if root_area > 0.0 && root_area.is_finite() {
            b.half_area().to_f64() / root_area
        } else {
            1.0
        }
    };
    let (mut max_depth, mut depth_sum, mut sah_cost) = (0u32, 0u64, 0.0f64);
    // `None` stands for an unstored empty leaf.
    let mut stack: Vec<(Option<usize>, Aabb<T>, u32)> =
        parts.iter().map(|p| (Some(p.root), p.bounds, 0)).collect();
    while let Some((i, b, depth)) = stack.pop() {
        let node = i.map_or(KdNode::leaf(0, 0), |i| nodes[i]);
        if node.is_leaf() {
            let count = node.prim_count() as usize;
            stats.leaves += 1;
            stats.empty_leaves += usize::from(count == 0);
            stats.references += count;
            stats.max_leaf_references = stats.max_leaf_references.max(count);
            max_depth = max_depth.max(depth);
            depth_sum += u64::from(depth);
            sah_cost += params.intersect_cost * count as f64 * area_ratio(&b);
        } else {
            sah_cost += params.traversal_cost * area_ratio(&b);
            let (axis, s) = (node.axis(), decode_split(node.split_word(), splits));
            let (lo, hi) = b.split_at(axis, s);
            // An inner node is always stored: `i` is `Some` here.
            let [below, above] = node.children(i.unwrap_or(0));
            stack.push((below, lo, depth + 1));
            stack.push((above, hi, depth + 1));
        }
    }
    stats.extra = vec![
        ("depth", f64::from(max_depth)),
        (
            "mean_leaf_depth",
            depth_sum as f64 / stats.leaves.max(1) as f64,
        ),
        (
            "depth_limit",
            f64::from(parts.first().map_or(0, |p| p.depth_limit)),
        ),
        ("parts", parts.len() as f64),
        ("sah_cost", sah_cost),
        ("intersect_cost", params.intersect_cost),
        ("traversal_cost", params.traversal_cost),
        ("empty_bonus", params.empty_bonus),
    ];
    stats
}
