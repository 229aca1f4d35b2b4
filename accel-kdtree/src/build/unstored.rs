//! Empty leaves are not stored: every empty leaf but the root is left out
//! and its parent marks the child as empty instead (see [`crate::node`]).
//! The sweep build never stores one (its serial build and its joining of
//! parallel pieces skip them); the naive builder stores them and removes
//! them here. The SAH's empty bonus makes them common (44% of the
//! leaves of the 1M-triangle terrain), and a walk that reached one loaded a
//! node, took the leaf branch and popped the stack for nothing: on camera
//! rays they were 2.65 of the 3.12 leaves a ray visited on the sphere and
//! 4.38 of 5.21 on the terrain.

use super::Out;
use crate::node::KdNode;

/// Removes the empty leaves of a depth-first tree (below child next, above
/// child by index), in place, keeping the depth-first order.
pub(crate) fn drop_empty_leaves<T>(out: &mut Out<T>) {
    let nodes = &mut out.nodes;
    let removed = |n: &KdNode| n.is_leaf() && n.prim_count() == 0;
    // New index of every node: its old index less the removed nodes before
    // it (the root is kept even when it is an empty leaf).
    let mut new_index = Vec::with_capacity(nodes.len());
    let mut gone = 0u32;
    for (i, n) in nodes.iter().enumerate() {
        new_index.push(i as u32 - gone);
        gone += u32::from(i > 0 && removed(n));
    }
    if gone == 0 {
        return;
    }
    let mut kept = 0;
    for i in 0..nodes.len() {
        let n = nodes[i];
        if i > 0 && removed(&n) {
            continue;
        }
        nodes[kept] = if n.is_leaf() {
            n
        } else {
            let [below, above] = n.children(i);
            let above = above
                .filter(|&a| !removed(&nodes[a]))
                .map_or(0, |a| new_index[a]);
            let node = KdNode::inner(n.axis(), n.split_word(), above);
            match below {
                Some(b) if !removed(&nodes[b]) => node,
                _ => node.without_below(),
            }
        };
        kept += 1;
    }
    nodes.truncate(kept);
}
