//! The kD-tree: its parts and constructors.

use crate::build::{KdPart, Out, build, decode_split, tree_stats};
use crate::node::KdNode;
use crate::params::KdTreeParams;
use crate::reach::{narrowing_pays, node_reaches};
use accel_core::packed::PackedTriangles;
use accel_core::{Aabb, AccelStats, BuildError, PrimitiveSet, Real};
use core::borrow::Borrow;
use core::marker::PhantomData;
use std::sync::{Arc, OnceLock};
use std::time::Duration;

/// A SAH kD-tree over a primitive set (see the crate docs).
///
/// It stores only `u32` indices into the primitives: 8-byte nodes in
/// depth-first order, one flat reference array for the leaves, and (for
/// `f64` trees) a table of split positions. It holds the primitives as `S`:
/// borrowed (`&'a P`, the default: [`KdTree::new`], [`KdTree::with_params`])
/// or shared ([`Arc<P>`]: [`KdTree::shared`], [`KdTree::shared_with_params`],
/// a [`SharedKdTree`]), which lets an application keep the tree beside its
/// primitives in one struct (accel-core's crate docs, "Embedding").
#[derive(Debug)]
pub struct KdTree<'a, T: Real, P: PrimitiveSet<T> + ?Sized, S = &'a P> {
    pub(crate) prims: S,
    pub(crate) borrows: PhantomData<&'a P>,
    pub(crate) nodes: Vec<KdNode>,
    pub(crate) refs: Vec<u32>,
    pub(crate) splits: Vec<T>,
    /// Per node, how far its primitives reach ([`crate::reach`]); empty
    /// where narrowing the beam would not pay ([`narrowing_pays`]).
    pub(crate) reach: Vec<T>,
    /// The leaves' triangles in packed blocks, when the layout asks for
    /// them and the primitives are watertight triangles.
    pub(crate) packed: Option<PackedTriangles<T>>,
    /// The scene's bounds (every part's box lies inside).
    pub(crate) bounds: Aabb<T>,
    pub(crate) parts: Vec<KdPart<T>>,
    /// `parts[0]`, kept inline: the part a query of a one-part tree walks
    /// (nearly every tree), without a load through the vector.
    pub(crate) first: KdPart<T>,
    /// The parameters the tree was built with, and its build time, for
    /// [`KdTree::shape_stats`].
    params: KdTreeParams,
    build_time: Duration,
    /// The statistics, made on the first request ([`KdTree::shape_stats`]).
    stats: OnceLock<AccelStats>,
}

impl<'a, T: Real, P: PrimitiveSet<T> + ?Sized> KdTree<'a, T, P> {
    /// Builds a tree with the default parameters ([`KdTreeParams::default`]).
    ///
    /// # Errors
    /// [`BuildError`] for non-finite primitives or an exceeded budget.
    pub fn new(prims: &'a P) -> Result<Self, BuildError> {
        Self::with_params(prims, &KdTreeParams::default())
    }

    /// Builds a tree with the given parameters, by the O(n log n) event sweep.
    ///
    /// # Errors
    /// [`BuildError::InvalidParameter`] for a parameter out of range,
    /// [`BuildError::NonFinitePrimitive`] for a NaN or infinite primitive,
    /// [`BuildError::BudgetExceeded`] for more than 2^30 − 1 primitives or
    /// more references than `params.max_references`.
    pub fn with_params(prims: &'a P, params: &KdTreeParams) -> Result<Self, BuildError> {
        Self::assemble(prims, params, false)
    }

    /// Builds the tree with the naive O(n²) SAH builder: the same candidates,
    /// costs and tie-breaks as [`KdTree::with_params`], so the same tree, only
    /// slowly. For tests that check the event sweep against it.
    ///
    /// # Errors
    /// As [`KdTree::with_params`].
    #[doc(hidden)]
    pub fn with_params_naive(prims: &'a P, params: &KdTreeParams) -> Result<Self, BuildError> {
        Self::assemble(prims, params, true)
    }
}

/// A [`KdTree`] that shares its primitives through an [`Arc`].
pub type SharedKdTree<T, P> = KdTree<'static, T, P, Arc<P>>;

impl<T: Real, P: PrimitiveSet<T> + ?Sized> KdTree<'static, T, P, Arc<P>> {
    /// [`KdTree::new`] over primitives it shares: the tree keeps them alive
    /// itself, so it can be kept beside them in one struct or returned from
    /// the function that loaded them.
    ///
    /// # Errors
    /// As [`KdTree::new`].
    pub fn shared(prims: Arc<P>) -> Result<Self, BuildError> {
        Self::assemble(prims, &KdTreeParams::default(), false)
    }

    /// [`KdTree::with_params`] over primitives it shares (see
    /// [`KdTree::shared`]).
    ///
    /// # Errors
    /// As [`KdTree::with_params`].
    pub fn shared_with_params(prims: Arc<P>, params: &KdTreeParams) -> Result<Self, BuildError> {
        Self::assemble(prims, params, false)
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> KdTree<'_, T, P, S> {
    /// Builds a tree over the primitives `held` holds, and keeps them.
    fn assemble(held: S, params: &KdTreeParams, naive: bool) -> Result<Self, BuildError> {
        let built = build(held.borrow(), params, naive)?;
        let Out {
            nodes,
            refs,
            splits,
        } = built.out;
        let mut tree = Self {
            prims: held,
            borrows: PhantomData,
            nodes,
            refs,
            splits,
            reach: Vec::new(),
            packed: None,
            bounds: built.bounds,
            first: built.parts[0],
            parts: built.parts,
            params: params.clone(),
            build_time: built.build_time,
            stats: OnceLock::new(),
        };
        // A tree in parts has walked each part with a beam as thin as its own
        // bounds allow: the narrowing is for a small dense part left inside
        // one large tree.
        if tree.parts.len() == 1 && narrowing_pays(&tree) {
            tree.reach = node_reaches(&tree);
        }
        tree.packed = PackedTriangles::new(
            params.layout,
            tree.prims.borrow(),
            &tree.refs,
            tree.nodes
                .iter()
                .filter(|n| n.is_leaf() && n.prim_count() > 1)
                .map(|n| (n.leaf_payload() as usize, n.prim_count() as usize)),
        );
        #[cfg(debug_assertions)]
        if let Err(e) = tree.validate() {
            panic!("kd-tree invariant broken after build: {e}");
        }
        Ok(tree)
    }

    /// The tree's statistics: its build time, and its shape (nodes, leaves,
    /// depth, references, bytes, SAH cost) from one walk of the tree with
    /// node boxes. The walk is made on the first request, not by the build:
    /// a tree that is only queried does not pay for it (about 30 ms on the
    /// 1M-triangle terrain's 2M nodes).
    pub(crate) fn shape_stats(&self) -> &AccelStats {
        self.stats.get_or_init(|| {
            let mut stats = tree_stats(
                &self.nodes,
                &self.splits,
                &self.parts,
                &self.bounds,
                &self.params,
                self.primitives().len(),
            );
            stats.build_time = self.build_time;
            stats.bytes = self.nodes.capacity() * size_of::<KdNode>()
                + self.refs.capacity() * size_of::<u32>()
                + self.splits.capacity() * size_of::<T>()
                + self.reach.capacity() * size_of::<T>()
                + self
                    .packed
                    .as_ref()
                    .map_or(0, PackedTriangles::memory_bytes);
            stats
        })
    }

    /// The nodes, depth-first: node 0 is the root (of the first part, see
    /// [`KdTree::parts`]), an inner node's below child follows it, its above
    /// child is at [`KdNode::above_child`]; an empty leaf is not stored but
    /// marked in its parent ([`KdNode::children`]).
    #[must_use]
    pub fn nodes(&self) -> &[KdNode] {
        &self.nodes
    }

    /// The flat reference array that leaves of two or more primitives index.
    #[must_use]
    pub fn references(&self) -> &[u32] {
        &self.refs
    }

    /// The split position of inner node `i` (`None` for a leaf).
    ///
    /// # Panics
    /// If `i` is out of range.
    #[must_use]
    pub fn split_position(&self, i: usize) -> Option<T> {
        let n = self.nodes[i];
        (!n.is_leaf()).then(|| decode_split(n.split_word(), &self.splits))
    }

    /// The primitives of a leaf of this tree, ascending.
    #[inline]
    #[must_use]
    pub fn leaf_primitives<'s>(&'s self, leaf: &'s KdNode) -> &'s [u32] {
        self.leaf_list(leaf).1
    }

    /// [`KdTree::leaf_primitives`], with where they start in
    /// [`KdTree::references`] (0 for a leaf of fewer than two, which holds
    /// its primitive itself).
    #[inline]
    pub(crate) fn leaf_list<'s>(&'s self, leaf: &'s KdNode) -> (usize, &'s [u32]) {
        match leaf.prim_count() {
            0 => (0, &[]),
            1 => (0, core::slice::from_ref(leaf.payload_ref())),
            c => {
                let at = leaf.leaf_payload() as usize;
                (at, &self.refs[at..at + c as usize])
            }
        }
    }

    /// The depth limit the build used (the first part's; see
    /// [`KdTree::parts`]).
    #[must_use]
    pub fn depth_limit(&self) -> u32 {
        self.first.depth_limit
    }

    /// The tree's parts, each a tree of its own in [`KdTree::nodes`]: one,
    /// or two where a small dense part of a large sparse scene is built
    /// apart from the large primitives around it (the small part first).
    /// Every primitive is in exactly one part; queries walk them all.
    #[must_use]
    pub fn parts(&self) -> &[KdPart<T>] {
        &self.parts
    }

    /// The indexed primitives.
    #[inline]
    #[must_use]
    pub fn primitives(&self) -> &P {
        self.prims.borrow()
    }
}
