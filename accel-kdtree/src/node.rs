//! The 8-byte node, after pbrt's `KdTreeNode`.
//!
//! Two `u32` words. The low two bits of `flags` hold the split axis (0, 1, 2)
//! or 3 for a leaf. A leaf's other 30 bits hold its primitive count. An
//! inner node's bit 2 says that its "below" child is an empty leaf, and the
//! 29 bits above it hold the index of its "above" child, 0 when that child is
//! an empty leaf: empty leaves are not stored (the root, node 0, is no one's
//! child), so a walk skips them without loading a node. A stored below child
//! is the next node (depth-first order). `payload` holds the split position's
//! bits (`f32` trees) or its index in a side table (`f64` trees, whose
//! positions do not fit), and for a leaf the one primitive's index (count 1)
//! or the offset of its run in the flat reference array.

/// A node of a [`crate::KdTree`]: inner (axis, split, children) or leaf
/// (a run of primitive references).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(C)]
pub struct KdNode {
    payload: u32,
    flags: u32,
}

const _: () = assert!(size_of::<KdNode>() == 8);

/// The leaf tag in the low bits of `flags`.
const LEAF: u32 = 3;
/// An inner node's flag: its below child is an empty leaf, not stored.
const BELOW_EMPTY: u32 = 1 << 2;
/// Where an inner node's above child index starts in `flags`.
const ABOVE_SHIFT: u32 = 3;

impl KdNode {
    /// The most primitives in one leaf.
    pub const MAX_COUNT: u32 = (1 << 30) - 1;
    /// The most nodes in one tree (29-bit child indices).
    pub const MAX_NODES: u32 = (1 << 29) - 1;

    /// An inner node splitting `axis` (0..3) at the position stored as
    /// `split_word`, whose below child is the next node and whose above
    /// child is node `above` (0: an empty leaf, not stored).
    #[inline]
    #[must_use]
    pub(crate) const fn inner(axis: usize, split_word: u32, above: u32) -> Self {
        debug_assert!(axis < 3 && above <= Self::MAX_NODES);
        Self {
            payload: split_word,
            flags: (above << ABOVE_SHIFT) | axis as u32,
        }
    }

    /// This inner node with its below child an empty leaf, not stored.
    #[inline]
    #[must_use]
    pub(crate) const fn without_below(self) -> Self {
        debug_assert!(!self.is_leaf());
        Self {
            payload: self.payload,
            flags: self.flags | BELOW_EMPTY,
        }
    }

    /// A leaf of `count` references: `first` is the primitive itself when
    /// `count == 1`, else the offset of the run in the reference array.
    #[inline]
    #[must_use]
    pub(crate) const fn leaf(count: u32, first: u32) -> Self {
        debug_assert!(count <= Self::MAX_COUNT);
        Self {
            payload: first,
            flags: (count << 2) | LEAF,
        }
    }

    /// True for a leaf.
    #[inline]
    #[must_use]
    pub const fn is_leaf(self) -> bool {
        self.flags & 3 == LEAF
    }

    /// The split axis of an inner node.
    #[inline]
    #[must_use]
    pub const fn axis(self) -> usize {
        (self.flags & 3) as usize
    }

    /// The index of an inner node's above child, or 0 when that child is an
    /// empty leaf (not stored).
    #[inline]
    #[must_use]
    pub const fn above_child(self) -> u32 {
        self.flags >> ABOVE_SHIFT
    }

    /// Whether an inner node's below child is stored (as the next node);
    /// `false` when it is an empty leaf.
    #[inline]
    #[must_use]
    pub const fn has_below(self) -> bool {
        self.flags & BELOW_EMPTY == 0
    }

    /// The stored children `[below, above]` of inner node `at` (this node),
    /// `None` for an empty leaf.
    #[inline]
    #[must_use]
    pub const fn children(self, at: usize) -> [Option<usize>; 2] {
        let below = if self.has_below() { Some(at + 1) } else { None };
        let above = match self.above_child() {
            0 => None,
            i => Some(i as usize),
        };
        [below, above]
    }

    /// The stored split word of an inner node (position bits or table index).
    #[inline]
    #[must_use]
    pub const fn split_word(self) -> u32 {
        self.payload
    }

    /// The number of primitives in a leaf.
    #[inline]
    #[must_use]
    pub const fn prim_count(self) -> u32 {
        self.flags >> 2
    }

    /// The payload word by reference (a one-primitive leaf's list).
    #[inline]
    pub(crate) const fn payload_ref(&self) -> &u32 {
        &self.payload
    }

    /// A leaf's payload: its one primitive (count 1) or its run's offset.
    #[inline]
    #[must_use]
    pub const fn leaf_payload(self) -> u32 {
        self.payload
    }

    /// The node with its child index and payload offset by the bases of the
    /// arrays it is appended to (`payload_base` applies to leaves of two or
    /// more primitives, `split_base` to `f64` split indices).
    #[inline]
    #[must_use]
    pub(crate) fn relocated(self, node_base: u32, ref_base: u32, split_base: Option<u32>) -> Self {
        if self.is_leaf() {
            if self.prim_count() >= 2 {
                Self::leaf(self.prim_count(), self.payload + ref_base)
            } else {
                self
            }
        } else {
            let payload = split_base.map_or(self.payload, |b| self.payload + b);
            let above = match self.above_child() {
                0 => 0,
                i => i + node_base,
            };
            let node = Self::inner(self.axis(), payload, above);
            if self.has_below() {
                node
            } else {
                node.without_below()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_round_trip() {
        let n = KdNode::inner(2, 0xDEAD_BEEF, KdNode::MAX_NODES);
        assert!(!n.is_leaf());
        assert_eq!(
            (n.axis(), n.split_word(), n.above_child(), n.has_below()),
            (2, 0xDEAD_BEEF, KdNode::MAX_NODES, true)
        );
        let n = n.without_below();
        assert_eq!(
            (n.axis(), n.split_word(), n.above_child(), n.has_below()),
            (2, 0xDEAD_BEEF, KdNode::MAX_NODES, false)
        );
        assert_eq!(n.children(7), [None, Some(KdNode::MAX_NODES as usize)]);
        assert_eq!(KdNode::inner(0, 0, 0).children(7), [Some(8), None]);
        let l = KdNode::leaf(KdNode::MAX_COUNT, 1);
        assert_eq!(l.prim_count(), KdNode::MAX_COUNT);
        let l = KdNode::leaf(7, 1234);
        assert!(l.is_leaf());
        assert_eq!((l.prim_count(), l.leaf_payload()), (7, 1234));
        let e = KdNode::leaf(0, 0);
        assert!(e.is_leaf() && e.prim_count() == 0);
        for axis in 0..3 {
            assert!(!KdNode::inner(axis, 0, 1).is_leaf());
        }
    }

    #[test]
    fn relocation_moves_indices_only() {
        let n = KdNode::inner(1, 5, 9).relocated(100, 1000, Some(10));
        assert_eq!((n.axis(), n.split_word(), n.above_child()), (1, 15, 109));
        let n = KdNode::inner(0, 5, 9).relocated(100, 1000, None);
        assert_eq!(n.split_word(), 5);
        // Empty children stay empty.
        let n = KdNode::inner(0, 5, 0)
            .without_below()
            .relocated(100, 1000, None);
        assert_eq!(n.children(3), [None, None]);
        assert_eq!(
            KdNode::leaf(3, 4).relocated(100, 1000, None),
            KdNode::leaf(3, 1004)
        );
        // A one-primitive leaf stores the primitive itself.
        assert_eq!(
            KdNode::leaf(1, 4).relocated(100, 1000, None),
            KdNode::leaf(1, 4)
        );
    }
}
