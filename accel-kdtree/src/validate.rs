//! The public invariant checker.

use crate::KdTreeParams;
use crate::build::depth::{Depth, isolates};
use crate::build::{decode_split, inline_splits};
use crate::tree::KdTree;
use accel_core::{Aabb, PrimitiveSet, Real};
use core::borrow::Borrow;

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> KdTree<'_, T, P, S> {
    /// Checks the tree's invariants: every node reached exactly once from the
    /// roots of the parts, one part after the other, in depth-first order (below child next, above child after the
    /// below subtree), empty leaves not stored but marked in their parent
    /// (only an empty root is stored), splits finite and inside their node's box (on a face only for a face cut),
    /// depth within the limit (counting every cut but those narrow enough
    /// to isolate a dense part, see [`crate::KdTreeParams::max_depth`]) and
    /// within the traversal stack, leaf runs tiling the reference array in order,
    /// each leaf's primitives strictly ascending, in range, with bounds
    /// touching the leaf's box, and every primitive in some leaf.
    ///
    /// # Errors
    /// A message naming the first broken invariant.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.primitives().len();
        if self.nodes.is_empty() {
            return Err("no root node".into());
        }
        let mut referenced = vec![false; n];
        let mut next_ref = 0usize;
        let mut next_split = 0usize;
        let mut visited = 0usize;
        // Depth-first, below child first: the order the nodes are stored in.
        // The parts one after the other, each from its root.
        let mut stack: Vec<(usize, Aabb<T>, Depth, u32)> = self
            .parts
            .iter()
            .rev()
            .map(|p| (p.root, p.bounds, Depth::ROOT, p.depth_limit))
            .collect();
        while let Some((i, b, depth, limit)) = stack.pop() {
            if i != visited {
                return Err(format!(
                    "node {i} reached out of depth-first order (expected {visited})"
                ));
            }
            visited += 1;
            check_depth(i, depth, limit)?;
            let node = self.nodes[i];
            if node.is_leaf() {
                let count = node.prim_count() as usize;
                if count == 0 && i > 0 {
                    return Err(format!(
                        "node {i}: an empty leaf stored (its parent marks it)"
                    ));
                }
                if count >= 2 {
                    if node.leaf_payload() as usize != next_ref {
                        return Err(format!(
                            "leaf {i}: run at {} but {next_ref} expected",
                            node.leaf_payload()
                        ));
                    }
                    next_ref += count;
                    if next_ref > self.refs.len() {
                        return Err(format!("leaf {i}: run past the reference array"));
                    }
                }
                let prims = self.leaf_primitives(&node);
                if let Some(w) = prims.windows(2).find(|w| w[0] >= w[1]) {
                    return Err(format!(
                        "leaf {i}: references not strictly ascending at {w:?}"
                    ));
                }
                for &p in prims {
                    let Some(seen) = referenced.get_mut(p as usize) else {
                        return Err(format!(
                            "leaf {i}: reference {p} out of range ({n} primitives)"
                        ));
                    };
                    *seen = true;
                    if !self.primitives().bounds(p as usize).overlaps(&b) {
                        return Err(format!(
                            "leaf {i}: primitive {p} lies outside the leaf's box"
                        ));
                    }
                }
                continue;
            }
            let axis = node.axis();
            if !inline_splits::<T>() {
                if node.split_word() as usize != next_split || next_split >= self.splits.len() {
                    return Err(format!(
                        "node {i}: split index {} out of order",
                        node.split_word()
                    ));
                }
                next_split += 1;
            }
            let s = decode_split(node.split_word(), &self.splits);
            // Inside, or on a face of a node that is not flat there (a face
            // cut, which gives one child no width).
            if !(s.is_finite() && b.min[axis] <= s && s <= b.max[axis] && b.min[axis] < b.max[axis])
            {
                return Err(format!(
                    "node {i}: split {s} on axis {axis} not inside [{}, {}]",
                    b.min[axis], b.max[axis]
                ));
            }
            // Stored children come after the node (the below one next, the
            // above one after the below one's subtree); the depth-first
            // check above catches any that skip a node.
            let [below, above] = node.children(i);
            if below.is_some_and(|b| b >= self.nodes.len())
                || above
                    .is_some_and(|a| a <= i + usize::from(below.is_some()) || a >= self.nodes.len())
            {
                return Err(format!(
                    "node {i}: children {below:?} and {above:?} out of range"
                ));
            }
            let (lo, hi) = b.split_at(axis, s);
            let (w_lo, w_hi) = (s - b.min[axis], b.max[axis] - s);
            let (d_lo, d_hi) = (
                depth.child(isolates(w_lo, w_hi)),
                depth.child(isolates(w_hi, w_lo)),
            );
            // An unstored (empty) child is a leaf at its depth too.
            for (c, d) in [(below, d_lo), (above, d_hi)] {
                if c.is_none() {
                    check_depth(i, d, limit)?;
                }
            }
            stack.extend(above.map(|a| (a, hi, d_hi, limit)));
            stack.extend(below.map(|b| (b, lo, d_lo, limit)));
        }
        if visited != self.nodes.len() {
            return Err(format!(
                "{} of {} nodes reachable",
                visited,
                self.nodes.len()
            ));
        }
        if next_ref != self.refs.len() {
            return Err(format!(
                "leaves use {next_ref} of {} references",
                self.refs.len()
            ));
        }
        if !inline_splits::<T>() && next_split != self.splits.len() {
            return Err(format!(
                "{next_split} of {} split positions used",
                self.splits.len()
            ));
        }
        if let Some(p) = referenced.iter().position(|&r| !r) {
            return Err(format!("primitive {p} is in no leaf"));
        }
        Ok(())
    }
}

/// Node `i`'s depth (or its empty child's) is within the traversal stack
/// and, counted, within `limit`. The build counts fewer cuts than the width
/// alone lets pass, so this bounds its counted depth.
fn check_depth(i: usize, Depth { counted, levels }: Depth, limit: u32) -> Result<(), String> {
    if levels > KdTreeParams::MAX_DEPTH {
        return Err(format!(
            "node {i}: {levels} levels deep, beyond the traversal stack ({})",
            KdTreeParams::MAX_DEPTH
        ));
    }
    if counted > limit {
        return Err(format!(
            "node {i}: {counted} counted levels deep, beyond the limit {limit}"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::node::KdNode;
    use crate::{KdTree, KdTreeParams};
    use accel_core::{TriangleMesh, Vec3};

    fn mesh() -> TriangleMesh<f64> {
        let tris: Vec<[Vec3<f64>; 3]> = (0..64)
            .map(|i| {
                let (x, y) = (f64::from(i % 8), f64::from(i / 8));
                [
                    Vec3::new(x, y, 0.0),
                    Vec3::new(x + 0.5, y, 0.2),
                    Vec3::new(x, y + 0.5, 0.4),
                ]
            })
            .collect();
        TriangleMesh::from_triangles(&tris).unwrap()
    }

    /// Shallow, so that leaves hold several primitives.
    fn params() -> KdTreeParams {
        KdTreeParams {
            max_depth: Some(3),
            ..KdTreeParams::default()
        }
    }

    #[test]
    fn corruptions_are_reported() {
        let m = mesh();
        let good = KdTree::with_params(&m, &params()).unwrap();
        assert!(good.validate().is_ok());
        let inner = good.nodes.iter().position(|n| !n.is_leaf()).unwrap();
        let leaf = good
            .nodes
            .iter()
            .position(|n| n.is_leaf() && n.prim_count() >= 2)
            .unwrap();

        // A split moved outside its node's box.
        let mut t = KdTree::with_params(&m, &params()).unwrap();
        let n = t.nodes[inner];
        t.splits[n.split_word() as usize] = 1e9;
        assert!(t.validate().unwrap_err().contains("not inside"));

        // A leaf pointing at another leaf's references.
        let mut t = KdTree::with_params(&m, &params()).unwrap();
        let n = t.nodes[leaf];
        t.nodes[leaf] = KdNode::leaf(n.prim_count(), n.leaf_payload() + 1);
        assert!(t.validate().is_err());

        // A primitive dropped from every leaf.
        let mut t = KdTree::with_params(&m, &params()).unwrap();
        let p = t.refs[0];
        for r in t.refs.iter_mut().filter(|r| **r == p) {
            *r = 63 - p;
        }
        for i in 0..t.nodes.len() {
            if t.nodes[i].is_leaf()
                && t.nodes[i].prim_count() == 1
                && t.nodes[i].leaf_payload() == p
            {
                t.nodes[i] = KdNode::leaf(1, 63 - p);
            }
        }
        assert!(t.validate().is_err());

        // An empty leaf stored instead of marked in its parent.
        let mut t = KdTree::with_params(&m, &params()).unwrap();
        let stored = (1..t.nodes.len())
            .find(|&i| t.nodes[i].is_leaf() && t.nodes[i].prim_count() >= 1)
            .unwrap();
        t.nodes[stored] = KdNode::leaf(0, 0);
        assert!(t.validate().unwrap_err().contains("empty leaf stored"));

        // An above child that skips a node.
        let mut t = KdTree::with_params(&m, &params()).unwrap();
        let n = t.nodes[0];
        t.nodes[0] = KdNode::inner(n.axis(), n.split_word(), n.above_child() + 1);
        assert!(t.validate().is_err());
    }
}
