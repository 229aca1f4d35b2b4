//! The depth limit, and the cuts that do not count towards it.
//!
//! pbrt's limit, `8 + 1.3·log2 n`, expects each level of a path to split
//! the primitives near it. A small dense mesh in a large sparse scene (the
//! teapot in a stadium) defeats it: the first levels only cut away the
//! scene's empty space and far walls, keeping every primitive of the mesh,
//! and the limit bound before the mesh itself was split finely (its leaves
//! held 23.7 references on average, against 2.9 for the same sphere alone).
//! So a cut that keeps at most 1/16 of its node's width on the split axis,
//! and at least 16 times as many primitives as it cuts off, does not count
//! for the kept child: it isolates a dense part. Each such cut narrows the
//! kept child 16-fold, so a path has few, and a path's full length stays
//! within [`crate::KdTreeParams::MAX_DEPTH`], the traversal stack's size.

use crate::KdTreeParams;
use accel_core::{Aabb, Real};

/// How much narrower than its node a kept child must be, and how many times
/// as many primitives as the other child it must hold, for the cut not to
/// count: the factor by which a scene's small dense part is built apart.
pub(crate) use accel_core::parts::ISOLATION;

/// A node's place on its path: the levels that count towards the depth
/// limit, and all levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Depth {
    pub(crate) counted: u32,
    pub(crate) levels: u32,
}

impl Depth {
    /// The root's.
    pub(crate) const ROOT: Self = Self {
        counted: 0,
        levels: 0,
    };

    /// True when a node here may not be split: its counted levels reached
    /// `limit`, or its path the traversal stack's size.
    #[inline]
    pub(crate) fn exhausted(self, limit: u32) -> bool {
        self.counted >= limit || self.levels >= KdTreeParams::MAX_DEPTH
    }

    /// The depths of the children of a node here with box `bounds`, split
    /// on `axis` at `pos` into children of `n_below` and `n_above`
    /// primitives.
    #[inline]
    pub(crate) fn children<T: Real>(
        self,
        bounds: &Aabb<T>,
        axis: usize,
        pos: T,
        n_below: usize,
        n_above: usize,
    ) -> (Self, Self) {
        let (below, above) = (pos - bounds.min[axis], bounds.max[axis] - pos);
        let many = |kept: usize, cut: usize| cut.saturating_mul(ISOLATION as usize) <= kept;
        (
            self.child(isolates(below, above) && many(n_below, n_above)),
            self.child(isolates(above, below) && many(n_above, n_below)),
        )
    }

    /// The depth one level down, the cut counting unless `isolated`.
    #[inline]
    pub(crate) fn child(self, isolated: bool) -> Self {
        Self {
            counted: self.counted + u32::from(!isolated),
            levels: self.levels + 1,
        }
    }
}

/// Whether a child `kept` wide, beside a sibling `cut` wide, is narrow
/// enough for its cut not to count (the width half of the rule, which
/// [`crate::KdTree::validate`] can check from the boxes alone).
#[inline]
pub(crate) fn isolates<T: Real>(kept: T, cut: T) -> bool {
    cut >= kept * T::from_f64(f64::from(ISOLATION - 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::Vec3;

    #[test]
    fn only_narrow_dense_cuts_are_free() {
        let node = Aabb::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(16.0, 1.0, 1.0));
        let d = Depth {
            counted: 5,
            levels: 9,
        };
        let counted = |(a, b): (Depth, Depth)| (a.counted, b.counted);
        // Keeps 1/16 of the width below with 16 times the primitives: free.
        assert_eq!(counted(d.children(&node, 0, 1.0, 160, 10)), (5, 6));
        // The same plane, mirrored.
        assert_eq!(counted(d.children(&node, 0, 15.0, 10, 160)), (6, 5));
        // Too wide, or too few primitives kept: both count.
        assert_eq!(counted(d.children(&node, 0, 1.5, 160, 10)), (6, 6));
        assert_eq!(counted(d.children(&node, 0, 1.0, 159, 10)), (6, 6));
        // An empty side: the other is free when narrow enough.
        assert_eq!(counted(d.children(&node, 0, 1.0, 3, 0)), (5, 6));
        // Every level counts in `levels`.
        let (a, b) = d.children(&node, 0, 1.0, 160, 10);
        assert_eq!((a.levels, b.levels), (10, 10));
        assert!(
            Depth {
                counted: 3,
                levels: KdTreeParams::MAX_DEPTH
            }
            .exhausted(10)
        );
        assert!(
            Depth {
                counted: 10,
                levels: 10
            }
            .exhausted(10)
        );
        assert!(
            !Depth {
                counted: 9,
                levels: 40
            }
            .exhausted(10)
        );
    }
}
