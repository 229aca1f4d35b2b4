//! The tree's shape: real splits, the naive build on a scene large enough to
//! be built in parallel, named edge cases, and typed errors.

use accel_core::{
    Aabb, Accelerator, BruteForce, BuildError, PrimitiveSet, Ray, Sphere, TriangleMesh, Vec3,
};
use accel_kdtree::{KdTree, KdTreeParams};
use accel_scenes::{box_mesh, random_soup, sphere_in_tiled_box, teapot_in_stadium, uv_sphere};

fn assert_same_tree<T: accel_core::Real, P: accel_core::PrimitiveSet<T> + ?Sized>(
    a: &KdTree<'_, T, P>,
    b: &KdTree<'_, T, P>,
) {
    assert_eq!(a.nodes(), b.nodes());
    assert_eq!(a.references(), b.references());
    assert_eq!(a.parts(), b.parts());
    for i in 0..a.nodes().len() {
        assert_eq!(
            a.split_position(i).map(|s| s.to_bits_u64()),
            b.split_position(i).map(|s| s.to_bits_u64())
        );
    }
}

/// A sphere of `dense` triangles in a box of side `stadium` whose faces are
/// tiled 20 × 20: no triangle is large enough for the scene to be built in
/// parts, so one tree must isolate the sphere (built with [`one_tree`], which
/// keeps the 800 tiles of a face from being a flat part of their own).
fn tiled_stadium(dense: usize, stadium: f64) -> TriangleMesh<f64> {
    sphere_in_tiled_box(dense, stadium, 20)
}

/// 3,000 soup triangles (seed `seed`) with a sphere of about `sphere`
/// triangles at their centre: a scene large enough for the top levels to
/// be built in parallel at a threshold of 64.
fn soup_with_sphere(seed: u64, sphere: usize) -> TriangleMesh<f64> {
    let mut mesh = random_soup(3000, seed);
    mesh.append(&uv_sphere(Vec3::new(0.5, 0.5, 0.5), 0.3, sphere))
        .unwrap();
    mesh
}

/// The default parameters without a flat part ([`KdTreeParams::flat_part`]).
fn one_tree() -> KdTreeParams {
    KdTreeParams {
        flat_part: false,
        ..KdTreeParams::default()
    }
}

#[test]
fn sweep_equals_naive_on_a_parallel_build() {
    // 3,000 soup triangles plus a sphere: the top levels are built in parallel
    // (threshold 64), the rest serially; the naive builder is serial throughout.
    let mesh = soup_with_sphere(5, 800);
    // And a sphere in a box 10^4 times wider: with walls tiled finely, one
    // tree whose isolating cuts do not count towards the depth limit (beside
    // a flat part of one face's tiles); with walls of two triangles each,
    // two parts (in either builder).
    for mesh in [
        mesh,
        tiled_stadium(3000, 1.0e4),
        teapot_in_stadium(3000, 1.0e4),
    ] {
        for params in [
            KdTreeParams {
                parallel_threshold: 64,
                // Exact splits throughout: the naive builder has no bins
                // (the tiled stadium has 7,800 triangles).
                binned_above: usize::MAX,
                ..KdTreeParams::default()
            },
            KdTreeParams {
                parallel_threshold: 64,
                ..KdTreeParams::best_traversal()
            },
        ] {
            let tree = KdTree::with_params(&mesh, &params).unwrap();
            let naive = KdTree::with_params_naive(&mesh, &params).unwrap();
            assert!(
                tree.nodes().len() > 1000,
                "{} nodes: the tree must really split",
                tree.nodes().len()
            );
            assert_same_tree(&tree, &naive);
            let m32 = mesh.cast::<f32>().unwrap();
            assert_same_tree(
                &KdTree::with_params(&m32, &params).unwrap(),
                &KdTree::with_params_naive(&m32, &params).unwrap(),
            );
        }
    }
}

#[test]
fn fast_build_on_one_thread_equals_the_build_in_pieces() {
    // On two threads the fast build splits nodes over the threshold into
    // pieces built in parallel and joined afterwards; on one thread it
    // builds the whole tree serially. The trees must be the same.
    let mesh = soup_with_sphere(7, 2000);
    let params = KdTreeParams {
        parallel_threshold: 64,
        ..KdTreeParams::fast_build()
    };
    let pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    };
    for mesh in [mesh, teapot_in_stadium(3000, 1.0e4)] {
        let serial = pool(1).install(|| KdTree::with_params(&mesh, &params).unwrap());
        let pieces = pool(2).install(|| KdTree::with_params(&mesh, &params).unwrap());
        assert!(
            serial.nodes().len() > 1000,
            "{} nodes",
            serial.nodes().len()
        );
        assert_same_tree(&serial, &pieces);
    }
}

#[test]
fn binned_splits_near_the_root_cost_little_and_answer_exactly() {
    // Sweep above 64 primitives replaced by 32 bins: the tree is valid,
    // differs from the exact one, stays within 5% of its SAH cost (the bins
    // only approximate the plane, the sweep still chooses below), and every
    // ray answers as brute force.
    let mesh = soup_with_sphere(5, 800);
    let exact = KdTreeParams {
        binned_above: usize::MAX,
        ..KdTreeParams::default()
    };
    let binned = KdTreeParams {
        binned_above: 64,
        bins: 32,
        parallel_threshold: 256,
        ..KdTreeParams::default()
    };
    let sah = |p: &KdTreeParams| {
        let tree = KdTree::with_params(&mesh, p).unwrap();
        tree.validate().unwrap();
        let cost = tree.stats().extra("sah_cost").unwrap();
        (tree, cost)
    };
    let (exact_tree, exact_cost) = sah(&exact);
    let (binned_tree, binned_cost) = sah(&binned);
    assert_ne!(exact_tree.nodes(), binned_tree.nodes());
    assert!(
        binned_cost <= 1.05 * exact_cost,
        "binned SAH cost {binned_cost} against exact {exact_cost}"
    );
    let brute = BruteForce::new(&mesh).unwrap();
    for ray in accel_scenes::random_rays::<f64>(&mesh.bounds(), 2000, 11) {
        assert_eq!(
            binned_tree.intersect(&ray).unwrap().map(|h| h.bit_key()),
            brute.intersect(&ray).unwrap().map(|h| h.bit_key())
        );
    }
}

#[test]
fn sah_cost_beats_a_single_leaf_and_depth_is_bounded() {
    let mesh = uv_sphere(Vec3::ZERO, 1.0, 20_000);
    let params = KdTreeParams::default();
    let tree = KdTree::with_params(&mesh, &params).unwrap();
    let s = tree.stats();
    let leaf_cost = params.intersect_cost * mesh.triangle_count() as f64;
    let cost = s.extra("sah_cost").unwrap();
    assert!(
        cost < leaf_cost / 100.0,
        "SAH cost {cost} vs one leaf {leaf_cost}"
    );
    // Cuts that isolate a dense part do not count towards the limit; the
    // path's full length stays within the traversal stack.
    assert!(s.extra("depth").unwrap() <= f64::from(KdTreeParams::MAX_DEPTH));
    tree.validate().unwrap();
    assert_eq!(
        tree.depth_limit(),
        params.depth_limit(mesh.triangle_count())
    );
    // Leaves tile the references; each triangle appears at least once.
    assert!(s.references >= mesh.triangle_count());
    assert_eq!(s.nodes, tree.nodes().len());
    assert!(s.bytes >= 8 * s.nodes + 4 * tree.references().len());
}

#[test]
fn empty_leaves_are_marked_not_stored_and_still_counted() {
    // The sphere's hollow inside and the stadium's empty space make many
    // empty leaves.
    for mesh in [
        uv_sphere(Vec3::ZERO, 1.0, 20_000),
        teapot_in_stadium(5_000, 1.0e4),
    ] {
        let tree = KdTree::new(&mesh).unwrap();
        let nodes = tree.nodes();
        let inner: Vec<usize> = (0..nodes.len()).filter(|&i| !nodes[i].is_leaf()).collect();
        let unstored = inner
            .iter()
            .flat_map(|&i| nodes[i].children(i))
            .filter(Option::is_none)
            .count();
        assert!(unstored > 100, "premise: {unstored} empty leaves");
        assert!(
            nodes[1..]
                .iter()
                .all(|n| !n.is_leaf() || n.prim_count() > 0),
            "no empty leaf is stored below the root"
        );
        // Each part is a binary tree, and one of `inner` inner nodes has
        // `inner + 1` leaves: the stored ones and the marked ones.
        let parts = tree.parts().len();
        assert_eq!(nodes.len() + unstored, 2 * inner.len() + parts);
        let s = tree.stats();
        assert_eq!(s.nodes, nodes.len());
        assert_eq!(s.leaves, inner.len() + parts);
        assert_eq!(s.empty_leaves, unstored);
        let refs: usize = nodes
            .iter()
            .filter(|n| n.is_leaf())
            .map(|n| n.prim_count() as usize)
            .sum();
        assert_eq!(s.references, refs);
    }
}

#[test]
fn teapot_in_a_stadium_isolates_the_teapot() {
    let mesh = teapot_in_stadium(5_000, 1.0e4);
    let tree = KdTree::new(&mesh).unwrap();
    let brute = BruteForce::new(&mesh).unwrap();
    // A ray from the camera toward the teapot sees few primitives.
    let ray = Ray::new(Vec3::new(3.0, -4.0, 2.0), Vec3::new(-3.0, 4.0, -2.0)).unwrap();
    let mut c = accel_core::TraversalCounters::default();
    let hit = tree.intersect_counted(&ray, &mut c).unwrap();
    assert_eq!(hit, brute.intersect(&ray).unwrap());
    assert!(hit.is_some());
    assert!(c.prims < 100, "{c:?}");
}

#[test]
fn a_small_mesh_among_large_walls_is_built_apart_and_the_walls_cut_off() {
    // The teapot in a stadium: 14 large triangles (walls and floor) around
    // a small sphere. The sphere gets a tree of its own, the large triangles
    // another, whose face cuts send each wall to a flat leaf in its face.
    let mesh = teapot_in_stadium(5_000, 1.0e4);
    let n = mesh.triangle_count();
    let tree = KdTree::new(&mesh).unwrap();
    tree.validate().unwrap();
    let parts = tree.parts();
    assert_eq!(parts.len(), 2);
    assert_eq!(parts[0].root, 0);
    assert!(parts[0].bounds.max.x <= 1.0 && parts[1].bounds.max.x == 5_000.0);
    // Walk each part with node boxes: which primitives each holds, and
    // whether a split lies on its node's face (a face cut).
    let mut held = vec![Vec::new(); 2];
    let mut face_cuts = 0;
    for (k, part) in parts.iter().enumerate() {
        let mut stack = vec![(part.root, part.bounds)];
        while let Some((i, b)) = stack.pop() {
            let node = tree.nodes()[i];
            match tree.split_position(i) {
                None => held[k].extend_from_slice(tree.leaf_primitives(&node)),
                Some(s) => {
                    let a = node.axis();
                    face_cuts += usize::from(s == b.min[a] || s == b.max[a]);
                    let (lo, hi) = b.split_at(a, s);
                    let [below, above] = node.children(i);
                    stack.extend(below.map(|c| (c, lo)));
                    stack.extend(above.map(|c| (c, hi)));
                }
            }
        }
    }
    assert!(held[0].iter().all(|&p| (p as usize) < n - 14));
    assert!(held[1].iter().all(|&p| (p as usize) >= n - 14));
    assert!(face_cuts >= 6, "{face_cuts} face cuts: every wall cut off");
    // Rays from the camera over the scene: every answer brute force's, and
    // a floor ray tests few triangles.
    let brute = BruteForce::new(&mesh).unwrap();
    for i in 0..400 {
        let (u, v) = (f64::from(i % 20) * 0.3 - 3.0, f64::from(i / 20) * 0.3 - 3.0);
        let ray = Ray::new(Vec3::new(3.0, -4.0, 2.0), Vec3::new(u - 3.0, v + 4.0, -3.0)).unwrap();
        assert_eq!(
            tree.intersect(&ray).unwrap().map(|h| h.bit_key()),
            brute.intersect(&ray).unwrap().map(|h| h.bit_key()),
            "ray {i}"
        );
        assert_eq!(tree.occluded(&ray).unwrap(), brute.occluded(&ray).unwrap());
    }
    let floor = Ray::new(Vec3::new(3.0, -4.0, 2.0), Vec3::new(0.0, 1.0, -1.0)).unwrap();
    let mut c = accel_core::TraversalCounters::default();
    let hit = tree.intersect_counted(&floor, &mut c).unwrap().unwrap();
    assert!(hit.prim as usize >= n - 2, "premise: the floor");
    assert!(c.prims <= 4, "{c:?}");
}

/// Asserts that the nodes of `x` from `a` on equal those of `y` from `b`.
fn same_nodes_from<P: PrimitiveSet<f64> + ?Sized>(
    x: &KdTree<'_, f64, P>,
    a: usize,
    y: &KdTree<'_, f64, P>,
    b: usize,
) {
    assert_eq!(x.nodes().len() - a, y.nodes().len() - b);
    for (i, j) in (a..x.nodes().len()).zip(b..) {
        let (p, q) = (x.nodes()[i], y.nodes()[j]);
        assert_eq!(p.is_leaf(), q.is_leaf(), "node {i}");
        assert_eq!(x.split_position(i), y.split_position(j), "node {i}");
        if p.is_leaf() {
            assert_eq!(x.leaf_primitives(&p), y.leaf_primitives(&q));
        }
    }
}

#[test]
fn large_primitives_are_searched_whatever_the_leaf_size() {
    // The fast-build preset leaves nodes of up to 4 primitives unsearched,
    // but not nodes holding a large primitive (crossed by most rays). A box
    // of 12 triangles gets the tree of `leaf_size: 0`, each face cut off
    // (with 4 per leaf, rays tested up to 4 faces).
    let searched = KdTreeParams {
        leaf_size: 0,
        ..KdTreeParams::fast_build()
    };
    let cube = box_mesh(&Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)), 1);
    let fast = KdTree::with_params(&cube, &KdTreeParams::fast_build()).unwrap();
    let exact = KdTree::with_params(&cube, &searched).unwrap();
    same_nodes_from(&fast, 0, &exact, 0);
    assert!(fast.nodes().len() > 1);
    // The large part of a teapot in a stadium (14 walls and floor) alike:
    // its walls are still cut off and a floor ray tests few triangles.
    let mesh = teapot_in_stadium(5_000, 1.0e4);
    let fast = KdTree::with_params(&mesh, &KdTreeParams::fast_build()).unwrap();
    let exact = KdTree::with_params(&mesh, &searched).unwrap();
    let (a, b) = (fast.parts()[1].root, exact.parts()[1].root);
    same_nodes_from(&fast, a, &exact, b);
    // The small part keeps the preset: fewer nodes than searched to the end.
    assert!(a < b, "small parts: {a} and {b} nodes");
    let floor = Ray::new(Vec3::new(3.0, -4.0, 2.0), Vec3::new(0.0, 1.0, -1.0)).unwrap();
    let mut c = accel_core::TraversalCounters::default();
    let hit = fast.intersect_counted(&floor, &mut c).unwrap().unwrap();
    assert!(
        hit.prim as usize >= mesh.triangle_count() - 2,
        "premise: the floor"
    );
    assert!(c.prims <= 4, "{c:?}");
}

#[test]
fn a_small_mesh_in_a_huge_box_is_split_as_finely_as_on_its_own() {
    // A sphere in a box 10^4 times wider whose walls are tiled (so that it
    // is one tree, see `tiled_stadium`). The cuts that isolate the sphere
    // do not count towards the depth limit, so rays
    // at the sphere test about as many triangles as with the sphere alone
    // (before, the limit bound first: 14.1 against 0.9 per camera ray on
    // the 100k-triangle version).
    let stadium = tiled_stadium(20_000, 1.0e4);
    let alone = uv_sphere(Vec3::ZERO, 1.0, 20_000);
    let sphere = alone.triangle_count();
    // Triangle tests per ray over the rays that hit the sphere (its
    // triangles come first in both meshes), and how many do.
    let tests_per_ray = |mesh: &TriangleMesh<f64>| {
        let tree = KdTree::with_params(mesh, &one_tree()).unwrap();
        tree.validate().unwrap();
        let mut c = accel_core::TraversalCounters::default();
        let mut hits = 0;
        for i in 0..400 {
            // Rays from around the sphere at points of a grid on its face.
            let (u, v) = (
                f64::from(i % 20) / 10.0 - 0.95,
                f64::from(i / 20) / 10.0 - 0.95,
            );
            let ray = Ray::new(Vec3::new(u, v, 3.0), Vec3::new(0.0, 0.0, -1.0)).unwrap();
            let mut ray_counts = accel_core::TraversalCounters::default();
            let hit = tree.intersect_counted(&ray, &mut ray_counts).unwrap();
            if hit.is_some_and(|h| (h.prim as usize) < sphere) {
                hits += 1;
                c.add(&ray_counts);
            }
        }
        (c.prims as f64 / f64::from(hits.max(1)), hits)
    };
    let tree = KdTree::with_params(&stadium, &one_tree()).unwrap();
    assert_eq!(tree.parts().len(), 1, "premise: one tree");
    assert!(
        tree.stats().extra("depth").unwrap() > f64::from(tree.depth_limit()),
        "premise: isolating cuts went past the limit"
    );
    let (in_stadium, hits_stadium) = tests_per_ray(&stadium);
    let (on_its_own, hits_alone) = tests_per_ray(&alone);
    // The same rays hit the sphere in both.
    assert_eq!(hits_stadium, hits_alone);
    assert!(
        hits_alone > 250,
        "premise: most rays hit the sphere ({hits_alone})"
    );
    assert!(
        in_stadium <= 2.0 * on_its_own + 1.0,
        "{in_stadium} triangle tests per ray in the stadium, {on_its_own} alone"
    );
}

#[test]
fn planar_primitives_in_a_split_plane_are_found_from_both_sides() {
    // A wall of axis-aligned squares in the plane x = 1, and clutter on both
    // sides, so the SAH splits at x = 1 with the wall on one side only.
    let mut tris = Vec::new();
    for j in 0..8 {
        for k in 0..8 {
            let (y, z) = (f64::from(j), f64::from(k));
            let p = |dy: f64, dz: f64| Vec3::new(1.0, y + dy, z + dz);
            tris.push([p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)]);
            tris.push([p(0.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]);
        }
    }
    for i in 0..64 {
        let (y, z) = (f64::from(i % 8) + 0.25, f64::from(i / 8) + 0.25);
        for x in [0.0, 0.5, 1.5, 2.0] {
            tris.push([
                Vec3::new(x, y, z),
                Vec3::new(x + 0.1, y + 0.5, z),
                Vec3::new(x, y, z + 0.5),
            ]);
        }
    }
    let mesh = TriangleMesh::from_triangles(&tris).unwrap();
    let brute = BruteForce::new(&mesh).unwrap();
    for params in [KdTreeParams::default(), KdTreeParams::best_traversal()] {
        let tree = KdTree::with_params(&mesh, &params).unwrap();
        let splits_at_wall = (0..tree.nodes().len())
            .filter(|&i| {
                !tree.nodes()[i].is_leaf()
                    && tree.nodes()[i].axis() == 0
                    && tree.split_position(i) == Some(1.0)
            })
            .count();
        assert!(
            splits_at_wall > 0,
            "premise: the tree splits in the wall's plane"
        );
        for (ox, dx) in [
            (-1.0, 1.0),
            (3.0, -1.0),
            (1.0, 1.0),
            (1.0, -1.0),
            (0.7, 1.0),
            (1.3, -1.0),
        ] {
            for j in 0..=16 {
                for k in 0..=16 {
                    let (y, z) = (f64::from(j) * 0.5, f64::from(k) * 0.5);
                    let ray = Ray::new(
                        Vec3::new(ox, y + 0.01, z + 0.02),
                        Vec3::new(dx, 0.003, -0.002),
                    )
                    .unwrap();
                    assert_eq!(
                        tree.intersect(&ray).unwrap(),
                        brute.intersect(&ray).unwrap(),
                        "{ray:?}"
                    );
                    // Along the wall (in its plane, ±0 in x): no hit on the wall itself.
                    for zero in [0.0, -0.0] {
                        let ray =
                            Ray::new(Vec3::new(1.0, y, z), Vec3::new(zero, 1.0, 0.5)).unwrap();
                        assert_eq!(
                            tree.intersect(&ray).unwrap(),
                            brute.intersect(&ray).unwrap(),
                            "{ray:?}"
                        );
                        assert_eq!(tree.occluded(&ray).unwrap(), brute.occluded(&ray).unwrap());
                    }
                }
            }
        }
    }
}

#[test]
fn empty_single_flat_and_sphere_scenes() {
    let empty = TriangleMesh::<f32>::new(vec![], vec![]).unwrap();
    let tree = KdTree::new(&empty).unwrap();
    let ray = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)).unwrap();
    assert_eq!(tree.intersect(&ray).unwrap(), None);
    assert!(!tree.occluded(&ray).unwrap());
    assert!(tree.bounds().is_empty());
    assert_eq!(
        tree.query_region(&Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)))
            .unwrap(),
        Vec::<u32>::new()
    );

    let one = TriangleMesh::from_triangles(&[[
        Vec3::new(0.0f32, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    ]])
    .unwrap();
    let tree = KdTree::new(&one).unwrap();
    let ray = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::new(0.0, 0.0, 1.0)).unwrap();
    assert_eq!(
        tree.intersect(&ray).unwrap().map(|h| (h.t, h.prim)),
        Some((1.0, 0))
    );

    // A flat scene: every triangle in z = 0 (the root box has no depth).
    let mut tris = Vec::new();
    for i in 0..200 {
        let (x, y) = (f64::from(i % 20), f64::from(i / 20));
        tris.push([
            Vec3::new(x, y, 0.0),
            Vec3::new(x + 1.0, y, 0.0),
            Vec3::new(x, y + 1.0, 0.0),
        ]);
    }
    let flat = TriangleMesh::from_triangles(&tris).unwrap();
    let tree = KdTree::new(&flat).unwrap();
    let brute = BruteForce::new(&flat).unwrap();
    assert!(tree.nodes().len() > 1);
    for i in 0..100 {
        let (x, y) = (f64::from(i) * 0.2 + 0.05, f64::from(i) * 0.1 + 0.03);
        for dz in [-1.0, 1.0] {
            let ray = Ray::new(Vec3::new(x, y, -dz), Vec3::new(0.01, 0.02, dz)).unwrap();
            assert_eq!(
                tree.intersect(&ray).unwrap(),
                brute.intersect(&ray).unwrap()
            );
        }
    }

    // Spheres: the default clipped bounds (bounds ∩ box).
    let spheres: Vec<Sphere<f64>> = (0..300)
        .map(|i| {
            Sphere::new(
                Vec3::new(
                    f64::from(i % 10),
                    f64::from(i / 10 % 10),
                    f64::from(i / 100),
                ),
                0.3 + 0.01 * f64::from(i % 7),
            )
        })
        .collect();
    let tree = KdTree::new(spheres.as_slice()).unwrap();
    let brute = BruteForce::new(spheres.as_slice()).unwrap();
    for i in 0..200 {
        let o = Vec3::new(-1.0, f64::from(i % 20) * 0.5, f64::from(i / 20) * 0.3);
        let ray = Ray::new(o, Vec3::new(1.0, 0.05, 0.02)).unwrap();
        assert_eq!(
            tree.intersect(&ray).unwrap().map(|h| h.bit_key()),
            brute.intersect(&ray).unwrap().map(|h| h.bit_key())
        );
    }
    let r = Aabb::new(Vec3::new(2.5, 2.5, 0.5), Vec3::new(4.2, 3.1, 1.0));
    assert_eq!(
        tree.query_region(&r).unwrap(),
        brute.query_region(&r).unwrap()
    );
}

#[test]
fn bad_input_gets_typed_errors() {
    let bad = [Sphere::new(Vec3::new(0.0f32, f32::NAN, 0.0), 1.0)];
    assert!(matches!(
        KdTree::new(bad.as_slice()),
        Err(BuildError::NonFinitePrimitive { index: 0 })
    ));
    let mesh = random_soup(10, 1);
    let params = KdTreeParams {
        empty_bonus: -0.5,
        ..KdTreeParams::default()
    };
    assert!(matches!(
        KdTree::with_params(&mesh, &params),
        Err(BuildError::InvalidParameter {
            name: "empty_bonus",
            ..
        })
    ));
    let tiny_budget = KdTreeParams {
        max_references: 5,
        ..KdTreeParams::default()
    };
    assert!(matches!(
        KdTree::with_params(&mesh, &tiny_budget),
        Err(BuildError::BudgetExceeded { .. })
    ));
    let tree = KdTree::new(&mesh).unwrap();
    let nan_ray = Ray {
        origin: Vec3::new(f64::NAN, 0.0, 0.0),
        direction: Vec3::new(1.0, 0.0, 0.0),
        t_min: 0.0,
        t_max: f64::INFINITY,
    };
    assert!(tree.intersect(&nan_ray).is_err());
    assert!(tree.occluded(&nan_ray).is_err());
    let inf_region = Aabb::new(Vec3::splat(0.0), Vec3::new(f64::INFINITY, 1.0, 1.0));
    assert!(tree.query_region(&inf_region).is_err());
}

#[test]
fn rays_leaving_a_flat_floor_walk_none_of_its_nodes() {
    use accel_scenes::{FlatFieldSpec, flat_field, rays_leaving_the_floor};
    // A floor of 40 × 25 quads (2,000 triangles) at z = 0 with 4,000
    // triangles standing at its centre, in f32: the floor is a part of its
    // own, whose flat bounds a ray spawned just above it and going up
    // misses with the thin beam. Without the flat part the same rays walk
    // down to the floor's leaves.
    let spec = FlatFieldSpec {
        quads: [40, 25],
        extent: [80.0, 50.0],
        dense: 4000,
    };
    let mesh: TriangleMesh<f32> = flat_field(&spec).cast().unwrap();
    let tree = KdTree::new(&mesh).unwrap();
    let whole = KdTree::with_params(&mesh, &one_tree()).unwrap();
    assert_eq!((tree.parts().len(), whole.parts().len()), (2, 1));
    let floor = &tree.parts()[1].bounds;
    assert_eq!((floor.min.z, floor.max.z), (0.0, 0.0));
    let brute = BruteForce::new(&mesh).unwrap();
    let mut split = accel_core::TraversalCounters::default();
    let mut one = accel_core::TraversalCounters::default();
    // Points of the floor away from the centre, 1e-5 above it (about the
    // error-bound spawn offset there), rays up and sideways.
    let rays = rays_leaving_the_floor::<f32>(&spec, 1e-5);
    assert_eq!(rays.len(), 191);
    for ray in rays {
        let expected = brute.intersect(&ray).unwrap();
        assert_eq!(tree.intersect_counted(&ray, &mut split).unwrap(), expected);
        assert_eq!(whole.intersect_counted(&ray, &mut one).unwrap(), expected);
        assert_eq!(tree.occluded(&ray).unwrap(), expected.is_some());
    }
    assert_eq!(
        (split.nodes, split.prims),
        (0, 0),
        "the floor's tree is walked"
    );
    assert!(
        one.nodes >= 190 * 5,
        "premise: one tree walks {} nodes",
        one.nodes
    );
}
