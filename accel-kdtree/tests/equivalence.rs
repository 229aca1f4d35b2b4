//! The kD-tree answers exactly as brute force, and the event-sweep build
//! equals the naive O(n²) builder node for node: random soups, lattice
//! triangles with many coincident planes (so many primitives lie in split
//! planes), closed meshes, rays at vertices and edges, ±0 components and
//! t windows, several cost settings, in f32 and f64. (The workspace-wide
//! suites in the `tests` crate go further; this one guards the tree itself.)

use accel_core::{Accelerator, BruteForce, Real, TriangleMesh};
use accel_kdtree::{KdTree, KdTreeParams};
use accel_scenes::strategies::{
    RaySpec, SceneSpec, at_vertex_ray, from_vertex_ray, lattice_or_flat_tri, lattice_ray,
    lattice_scene, make_ray, mesh_scene, random_ray, region, soup_scene, window,
};
use proptest::prelude::*;

fn scene_strategy() -> impl Strategy<Value = SceneSpec> {
    prop_oneof![
        // Axis-aligned lattice triangles too, and far from zero, where
        // f32's rounding unit dwarfs small scales.
        2 => lattice_scene(
            prop::collection::vec(lattice_or_flat_tri(), 1..40),
            vec![1.0, 0.25, 1e-3, 1e3],
            vec![0.0, -3.5, 100.0, 1.0e4]
        ),
        1 => soup_scene(1..60),
        1 => mesh_scene(0..4),
    ]
}

fn ray_strategy() -> impl Strategy<Value = RaySpec> {
    prop_oneof![
        random_ray(),
        at_vertex_ray(),
        from_vertex_ray(),
        lattice_ray()
    ]
}

/// The cost settings the suite runs: the defaults, the presets, and two
/// extremes (tiny leaves, very shallow trees).
fn params_strategy() -> impl Strategy<Value = KdTreeParams> {
    prop::sample::select(vec![
        KdTreeParams::default(),
        // Parallel pieces joined at the end: the flattening is checked too.
        KdTreeParams {
            parallel_threshold: 8,
            ..KdTreeParams::best_traversal()
        },
        KdTreeParams::fast_build(),
        KdTreeParams::pbrt(),
        KdTreeParams {
            intersect_cost: 200.0,
            traversal_cost: 0.0,
            empty_bonus: 0.9,
            ..KdTreeParams::default()
        },
        KdTreeParams {
            intersect_cost: 1.0,
            traversal_cost: 3.0,
            empty_bonus: 0.0,
            max_depth: Some(3),
            ..KdTreeParams::default()
        },
        // The binned SAH above four primitives, with few bins: most nodes of
        // these small scenes split by bins, and the sweep finishes them.
        KdTreeParams {
            binned_above: 4,
            bins: 4,
            parallel_threshold: 8,
            ..KdTreeParams::default()
        },
    ])
}

fn check<T: Real>(
    spec: &SceneSpec,
    rays: &[(RaySpec, (f64, f64))],
    regions: &[([f64; 3], [f64; 3])],
    params: &KdTreeParams,
) -> Result<(), TestCaseError> {
    let Ok(mesh) = spec.mesh().cast::<T>() else {
        return Ok(());
    };
    let lattice = spec.lattice();
    let brute = BruteForce::new(&mesh).unwrap();
    let tree = KdTree::with_params(&mesh, params).unwrap();
    tree.validate().map_err(TestCaseError::fail)?;
    if params.binned_above < mesh.triangle_count() {
        // Binned splits near the root: no naive reference; brute force below.
        return check_queries(&mesh, &brute, &tree, rays, regions, lattice);
    }
    // The O(n log n) build equals the naive O(n²) one, node for node.
    let naive = KdTree::with_params_naive(&mesh, params).unwrap();
    prop_assert_eq!(
        tree.nodes(),
        naive.nodes(),
        "{} nodes differ from the naive build",
        T::NAME
    );
    prop_assert_eq!(tree.references(), naive.references());
    prop_assert_eq!(tree.parts(), naive.parts());
    for i in 0..tree.nodes().len() {
        prop_assert_eq!(
            tree.split_position(i).map(|s| s.to_bits_u64()),
            naive.split_position(i).map(|s| s.to_bits_u64())
        );
    }
    check_queries(&mesh, &brute, &tree, rays, regions, lattice)
}

/// Every ray and region answers as brute force, bit for bit.
fn check_queries<T: Real>(
    mesh: &TriangleMesh<T>,
    brute: &BruteForce<'_, T, TriangleMesh<T>>,
    tree: &KdTree<'_, T, TriangleMesh<T>>,
    rays: &[(RaySpec, (f64, f64))],
    regions: &[([f64; 3], [f64; 3])],
    lattice: (f64, f64),
) -> Result<(), TestCaseError> {
    for (rs, window) in rays {
        let Some(ray) = make_ray::<T>(rs, mesh, lattice, *window) else {
            continue;
        };
        let want = brute.intersect(&ray).unwrap();
        let got = tree.intersect(&ray).unwrap();
        prop_assert_eq!(
            got.map(|h| h.bit_key()),
            want.map(|h| h.bit_key()),
            "{} ray {:?}: kd-tree {:?} brute {:?}",
            T::NAME,
            ray,
            got,
            want
        );
        prop_assert_eq!(
            tree.occluded(&ray).unwrap(),
            want.is_some(),
            "{} occluded, ray {:?}",
            T::NAME,
            ray
        );
    }
    for (a, b) in regions {
        let r = region(mesh, *a, *b);
        prop_assert_eq!(
            tree.query_region(&r).unwrap(),
            brute.query_region(&r).unwrap(),
            "{} region {:?}",
            T::NAME,
            r
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn kdtree_equals_brute_force_and_the_naive_build(
        scene in scene_strategy(),
        rays in prop::collection::vec((ray_strategy(), window(false)), 1..48),
        regions in prop::collection::vec(
            (prop::array::uniform3(-0.1..1.1f64), prop::array::uniform3(-0.1..1.1f64)), 0..4),
        params in params_strategy(),
    ) {
        check::<f32>(&scene, &rays, &regions, &params)?;
        check::<f64>(&scene, &rays, &regions, &params)?;
    }
}
