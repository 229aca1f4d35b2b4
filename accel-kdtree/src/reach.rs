//! Per node, how far the primitives below it reach: what lets a query narrow
//! its beam inside a small, dense part of a large scene.
//!
//! The beam of [`accel_core::TraversalRay`] is as wide as the rounding of any
//! hit in the whole scene, `gamma(64)` of its farthest corner from the ray
//! origin. Below a node, only the hits of the primitives it references
//! matter, and their rounding is bounded by the node's own size and the
//! distance the ray has travelled to it ([`node_beam`]). A teapot in a
//! stadium is then walked with a beam as thin as if it stood alone, not one
//! as wide as its triangles (the octree narrows its child grids' beams the
//! same way).

use crate::build::decode_split;
use crate::tree::KdTree;
use accel_core::{Aabb, PrimitiveSet, Real, TRAVERSAL_ROUNDINGS};
use core::borrow::Borrow;

/// For each node of `tree` (leaves included, unused there), the largest side
/// of the box holding the node's region and the whole bounds of every
/// primitive referenced below it, rounded up.
pub(crate) fn node_reaches<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>>(
    tree: &KdTree<'_, T, P, S>,
) -> Vec<T> {
    let mut reach = vec![T::ZERO; tree.nodes.len()];
    for part in &tree.parts {
        reach_box(tree, part.root, part.bounds, &mut reach);
    }
    reach
}

/// Whether narrowing the beam per node is worth its cost (a load and a few
/// operations at every inner node, about 10% of a dense scene's traversal,
/// and a pass over the tree at build time): when the thinnest beam any query
/// gets, `gamma(64)` of half the scene's largest side, is at least 1/64 of
/// the median primitive (its bounds' largest side, over up to
/// [`SIZE_SAMPLE`] primitives spread over the set). Then the beam spans a
/// noticeable part of a typical leaf, and rays visit extra ones (a small
/// dense mesh in a large scene); on dense scenes it is thousands of times
/// thinner and narrowing changes no visit.
pub(crate) fn narrowing_pays<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>>(
    tree: &KdTree<'_, T, P, S>,
) -> bool {
    let prims = tree.primitives();
    let n = prims.len();
    if n == 0 || tree.nodes.is_empty() {
        return false;
    }
    let step = n.div_ceil(SIZE_SAMPLE);
    let mut sizes: Vec<T> = (0..n)
        .step_by(step)
        .map(|i| {
            let b = prims.bounds(i);
            (b.max - b.min).max_component()
        })
        .collect();
    let mid = sizes.len() / 2;
    let (_, &mut median, _) = sizes.select_nth_unstable_by(mid, |a, b| {
        a.partial_cmp(b).unwrap_or(core::cmp::Ordering::Equal)
    });
    let scene = (tree.bounds.max - tree.bounds.min).max_component();
    // A set with wide hits is walked with the wide type's beam
    // ([`accel_core::TraversalRay::with_wide_hits`]), already that thin.
    let gamma = if prims.wide_hits() {
        T::from_wide(<T::Wide as Real>::gamma(TRAVERSAL_ROUNDINGS))
    } else {
        T::gamma(TRAVERSAL_ROUNDINGS)
    };
    let thinnest = gamma * scene * T::HALF;
    thinnest * T::from_f64(64.0) >= median
}

/// Primitives whose sizes [`narrowing_pays`] looks at, at most.
const SIZE_SAMPLE: usize = 4096;

/// The box holding node `i`'s `region` and its primitives' bounds; records
/// its largest side in `reach[i]`. Recursion depth is the tree's depth
/// (at most [`crate::KdTreeParams::MAX_DEPTH`]).
fn reach_box<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>>(
    tree: &KdTree<'_, T, P, S>,
    i: usize,
    region: Aabb<T>,
    reach: &mut [T],
) -> Aabb<T> {
    let node = &tree.nodes[i];
    let prims = tree.primitives();
    let held = if node.is_leaf() {
        tree.leaf_primitives(node)
            .iter()
            .fold(region, |b, &p| b.union(&prims.bounds(p as usize)))
    } else {
        let (axis, s) = (node.axis(), decode_split(node.split_word(), &tree.splits));
        let (below, above) = region.split_at(axis, s);
        // An unstored (empty) child holds its region alone.
        let [a, b] = [(0, below), (1, above)]
            .map(|(c, r)| node.children(i)[c].map_or(r, |j| reach_box(tree, j, r, reach)));
        a.union(&b)
    };
    let side = (held.max - held.min).max_component();
    reach[i] = side + side * T::gamma(2);
    held
}

/// The beam half-width that suffices below a node of reach `reach` entered
/// on the parameter interval `[t0, t1]`, never more than the query's own
/// `delta` (for a ray of largest direction component `max_d`).
///
/// A hit's rounding is `gamma(36)` of the farthest vertex of its primitive
/// from the origin, at most (see [`accel_core::TraversalRay`]). Below the
/// node that vertex, and the point of the primitive the hit rounds away
/// from, lie in the node's reach box, of side `reach`; the beam touches the
/// node's region at some parameter `t` of the interval, so that point lies
/// within `reach + delta` of the ray's point `o + t·d`, which is
/// `|t|·max_d` from the origin. So the farthest vertex is within
/// `2·reach + |t|·max_d + delta` of the origin, and `gamma(64)` of that
/// bounds the hit's rounding with room to spare for this sum's own.
#[inline(always)]
pub(crate) fn node_beam<T: Real>(reach: T, t0: T, t1: T, max_d: T, delta: T) -> T {
    let t = if t0.abs() > t1.abs() {
        t0.abs()
    } else {
        t1.abs()
    };
    let narrowed = T::gamma(TRAVERSAL_ROUNDINGS) * ((reach + reach) + t * max_d + delta);
    if narrowed < delta { narrowed } else { delta }
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::Vec3;
    use proptest::prelude::*;

    fn point() -> impl Strategy<Value = Vec3<f64>> {
        (-1e3..1e3f64, -1e3..1e3f64, -1e3..1e3f64).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        /// The narrowed beam covers a hit's rounding allowance, `gamma(36)`
        /// of the primitive's farthest vertex from the origin, for every
        /// triangle in a node's reach and every parameter at which the ray
        /// is in the node's region: the bound's premise, checked against the
        /// distance computed directly.
        #[test]
        fn node_beam_covers_the_rounding_of_every_hit_below_the_node(
            corner in point(),
            size in (0.01..50.0f64, 0.01..50.0f64, 0.01..50.0f64),
            tri in [point(), point(), point()],
            shrink in 1e-4..1.0f64,
            origin in point(),
            towards in (0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64),
        ) {
            let region = Aabb::new(corner, corner + Vec3::new(size.0, size.1, size.2));
            // The triangle near the region: scaled about it towards its corner.
            let tri = tri.map(|v| corner + (v - corner) * shrink);
            let reach_box = tri.iter().fold(region, |b, &v| b.union_point(v));
            let reach = (reach_box.max - reach_box.min).max_component();
            // A ray from `origin` through a point of the region.
            let target = region.min
                + Vec3::new(towards.0 * size.0, towards.1 * size.1, towards.2 * size.2);
            let d = target - origin;
            prop_assume!(d.abs().max_component() > 1e-9);
            let (t0, t1) = region.line_interval(origin, d).expect("the ray meets its target's box");
            // The query's beam over a scene holding everything.
            let scene = reach_box.union_point(origin);
            let far = (scene.min - origin).abs().max((scene.max - origin).abs()).max_component();
            let delta = <f64 as Real>::gamma(TRAVERSAL_ROUNDINGS) * far;
            let beam = node_beam(reach, t0, t1, d.abs().max_component(), delta);
            let farthest = tri
                .iter()
                .map(|&v| (v - origin).abs().max_component())
                .fold(0.0, f64::max);
            prop_assert!(beam >= <f64 as Real>::gamma(36) * farthest, "beam {beam}, farthest vertex {farthest}");
            prop_assert!(beam <= delta);
        }
    }

    #[test]
    fn a_tree_narrows_its_beam_only_where_the_scene_dwarfs_its_primitives() {
        use accel_core::{Triangle, TriangleMesh};
        use accel_scenes::sphere_in_tiled_box;
        // The same dense sphere (triangles about 0.06 across) in a stadium of
        // side 10^4, where the query beam is about 0.02 wide, and of side 10,
        // where it is about 2e-5. The walls are tiled 20 × 20 per face, so
        // no triangle is large enough for the scene to be built in parts
        // (`accel_core::parts`), where each part's beam is its own, and
        // the median triangle is still one of the sphere's.
        // The walls' tiles lie flat in six planes of 800 triangles each, so
        // an indexed mesh (whose hits are wide) would set one face apart
        // (`accel_core::parts::split_flat`); the triangles here, whose
        // hits the set does not declare wide, stay one part and keep `f32`'s
        // beam.
        for (stadium, narrows) in [(1e4, true), (10.0, false)] {
            let mesh: TriangleMesh<f32> = sphere_in_tiled_box(8000, stadium, 20).cast().unwrap();
            let narrow: Vec<NarrowHits> = (0..mesh.len())
                .map(|i| {
                    NarrowHits(Triangle {
                        vertices: mesh.triangle(i),
                    })
                })
                .collect();
            let tree = KdTree::new(&narrow).unwrap();
            assert_eq!(tree.parts().len(), 1, "premise: one part");
            assert_eq!(!tree.reach.is_empty(), narrows, "stadium {stadium}");
            // With wide hits the beam is already thin: no narrowing.
            let tree = KdTree::new(&mesh).unwrap();
            assert!(tree.reach.is_empty(), "stadium {stadium}");
        }
    }

    /// A triangle whose hits are not declared wide.
    struct NarrowHits(accel_core::Triangle<f32>);

    impl accel_core::Primitive<f32> for NarrowHits {
        fn bounds(&self) -> Aabb<f32> {
            self.0.bounds()
        }
        fn intersect(
            &self,
            ray: &accel_core::PreparedRay<f32>,
            t_max: f32,
        ) -> Option<accel_core::PrimHit<f32>> {
            self.0.intersect(ray, t_max)
        }
    }

    #[test]
    fn node_beam_narrows_near_a_small_node_and_caps_at_the_query_beam() {
        let delta = <f64 as Real>::gamma(TRAVERSAL_ROUNDINGS) * 5000.0;
        // A node 0.5 across, entered 1 to 2 units from the origin.
        let near = node_beam(0.5, 1.0, 2.0, 1.0, delta);
        assert!(near < delta / 100.0);
        // A node as large as the scene: the query's beam.
        assert_eq!(node_beam(1e4, 0.0, 1e4, 1.0, delta), delta);
    }
}
