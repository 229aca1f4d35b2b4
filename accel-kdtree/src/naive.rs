//! The naive O(n²) SAH builder: the reference the event sweep must match.
//!
//! Same candidates (every clipped-bounds face strictly inside the node, and
//! the face cuts of [`crate::build::sah`]), same
//! costs ([`Sah`]), same tie-breaks (axis, then position, first strictly
//! cheapest), same clipping policy (only straddlers are clipped anew), but
//! none of the machinery: each node keeps `(primitive, clipped box)` pairs,
//! and each candidate plane counts its sides by scanning them all. Havran
//! shows both builders choose the same planes, so the trees must be equal
//! node for node; `KdTree::with_params_naive` exposes it to the tests.

use crate::build::binned::{BoxSide, box_side, clip_to_node};
use crate::build::depth::Depth;
use crate::build::sah::{Sah, Split, keep_cheaper};
use crate::build::{Ctx, Out};
use accel_core::{Aabb, PrimitiveSet, Real};

/// A primitive in a node and its clipped bounds (zeros normalized to `+0`,
/// as the events are).
#[derive(Clone, Copy, Debug)]
struct Item<T> {
    prim: u32,
    b: Aabb<T>,
}

fn normalized<T: Real>(b: Aabb<T>) -> Aabb<T> {
    Aabb {
        min: b.min.map(|x| x + T::ZERO),
        max: b.max.map(|x| x + T::ZERO),
    }
}

/// Builds the tree of the primitives `list` (bounds `boxes`, in the same
/// order) into `out`.
pub(crate) fn build_naive<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    list: &[u32],
    boxes: &[Aabb<T>],
    bounds: Aabb<T>,
    out: &mut Out<T>,
) {
    let items = list
        .iter()
        .zip(boxes)
        .map(|(&prim, b)| Item {
            prim,
            b: normalized(*b),
        })
        .collect();
    node(ctx, items, bounds, Depth::ROOT, out);
}

/// The cheapest split by brute-force counting, or `None` for a leaf.
fn choose<T: Real>(sah: &Sah, items: &[Item<T>]) -> Option<Split<T>> {
    let mut best = None;
    for k in 0..3 {
        let mut planes: Vec<T> = items
            .iter()
            .flat_map(|it| [it.b.min[k], it.b.max[k]])
            .collect();
        planes.sort_unstable_by(|a, b| a.partial_cmp(b).expect("finite"));
        planes.dedup();
        for &p in &planes {
            let np = items
                .iter()
                .filter(|it| it.b.min[k] == p && it.b.max[k] == p)
                .count();
            let (cost, planar_left) = if sah.is_candidate(k, p.to_f64()) {
                let nl = items.iter().filter(|it| it.b.min[k] < p).count();
                let nr = items.iter().filter(|it| it.b.max[k] > p).count();
                sah.evaluate(k, p.to_f64(), nl, np, nr)
            } else if let Some(face) = sah.face_cut(k, p.to_f64(), np, items.len()) {
                face
            } else {
                continue;
            };
            keep_cheaper(
                &mut best,
                Split {
                    axis: k,
                    pos: p,
                    planar_left,
                    cost,
                    kept: None,
                },
            );
        }
    }
    let best = best?;
    (best.cost < sah.leaf_cost(items.len())).then_some(best)
}

fn node<T: Real, P: PrimitiveSet<T> + ?Sized>(
    ctx: &Ctx<'_, T, P>,
    items: Vec<Item<T>>,
    bounds: Aabb<T>,
    depth: Depth,
    out: &mut Out<T>,
) {
    let split = if ctx.leaf_without_search(items.iter().map(|it| it.prim), depth) {
        None
    } else {
        Sah::new(ctx.params, &bounds).and_then(|sah| choose(&sah, &items))
    };
    let Some(s) = split else {
        let prims: Vec<u32> = items.iter().map(|it| it.prim).collect();
        out.push_leaf(&prims);
        return;
    };
    let (k, p) = (s.axis, s.pos);
    let (below_box, above_box) = bounds.split_at(k, p);
    let (mut below, mut above) = (Vec::new(), Vec::new());
    for it in items {
        match box_side(&it.b, &s) {
            BoxSide::Left => below.push(it),
            BoxSide::Right => above.push(it),
            BoxSide::Both => {
                for (child_box, child) in [(&below_box, &mut below), (&above_box, &mut above)] {
                    if let Some(c) = clip_to_node(ctx.prims, it.prim, child_box) {
                        child.push(Item {
                            prim: it.prim,
                            b: normalized(c),
                        });
                    }
                }
            }
        }
    }
    let (below_depth, above_depth) = depth.children(&bounds, k, p, below.len(), above.len());
    let at = out.push_inner(k, p);
    node(ctx, below, below_box, below_depth, out);
    out.link_above(at);
    node(ctx, above, above_box, above_depth, out);
}
