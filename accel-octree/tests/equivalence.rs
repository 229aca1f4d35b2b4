//! The octree answers exactly as brute force: random soups, lattice-snapped
//! triangles, closed meshes and dense clusters in huge sparse boxes (several
//! levels of grids), random and adversarial rays, several thresholds, depths
//! and resolution rules, in f32 and f64. (The workspace-wide suites in the
//! `tests` crate go further; this one guards the octree itself.)
//!
//! `PROPTEST_CASES` sets the number of cases (default 256).

use accel_core::{Accelerator, BruteForce, Real, TraversalCounters};
use accel_octree::{Octree, OctreeParams, ResolutionRule};
use accel_scenes::strategies::{
    RaySpec, SceneSpec, at_vertex_ray, from_vertex_ray, lattice_scene, lattice_tris, make_ray,
    mesh_scene, random_scaled_ray, region, snapped_ray, soup_scene, stadium_scene,
    two_scales_scene, vertex_to_vertex_ray, window,
};
use proptest::prelude::*;

fn scene_strategy() -> impl Strategy<Value = SceneSpec> {
    prop_oneof![
        3 => lattice_scene(
            lattice_tris(1..24),
            vec![1.0, 0.25, 1e-3, 1e3, 1e-20, 1e20],
            vec![0.0, -3.5, 100.0]
        ),
        2 => two_scales_scene(),
        2 => soup_scene(1..40),
        2 => mesh_scene(0..3),
        2 => stadium_scene(),
    ]
}

/// Octree parameters: presets and mixtures of every dial.
fn params_strategy() -> impl Strategy<Value = OctreeParams> {
    let rule = prop::sample::select(vec![
        ResolutionRule::Density(2.0),
        ResolutionRule::Density(0.5),
        ResolutionRule::Nested {
            density: 2.0,
            levels: 1,
        },
        ResolutionRule::Nested {
            density: 1.0,
            levels: 3,
        },
        ResolutionRule::Fixed([2, 2, 2]),
        ResolutionRule::Fixed([3, 1, 2]),
        ResolutionRule::Fixed([1, 1, 1]),
    ]);
    let mixed = (
        rule.clone(),
        rule,
        prop::sample::select(vec![0usize, 1, 4, 8, 32]),
        prop::sample::select(vec![0u32, 1, 2, 3, 8]),
        any::<bool>(),
    )
        .prop_map(
            |(root, children, split_threshold, max_depth, fit_children)| OctreeParams {
                root,
                children,
                split_threshold,
                max_depth,
                fit_children,
                ..OctreeParams::default()
            },
        );
    prop_oneof![
        1 => Just(OctreeParams::default()),
        1 => Just(OctreeParams::classic()),
        1 => Just(OctreeParams::two_level()),
        1 => Just(OctreeParams::grid_root().with_split_threshold(2)),
        4 => mixed,
    ]
}

fn ray_strategy() -> impl Strategy<Value = RaySpec> {
    prop_oneof![
        random_scaled_ray(),
        at_vertex_ray(),
        from_vertex_ray(),
        vertex_to_vertex_ray(),
        snapped_ray(),
    ]
}

fn check<T: Real>(
    spec: &SceneSpec,
    params: &OctreeParams,
    rays: &[(RaySpec, (f64, f64))],
    regions: &[([f64; 3], [f64; 3])],
) -> Result<(), TestCaseError> {
    let Ok(mesh) = spec.mesh().cast::<T>() else {
        return Ok(());
    };
    let brute = BruteForce::new(&mesh).unwrap();
    let octree = Octree::with_params(&mesh, params).unwrap();
    octree.validate().map_err(TestCaseError::fail)?;
    for (rs, window) in rays {
        let Some(ray) = make_ray::<T>(rs, &mesh, (0.25, 0.0), *window) else {
            continue;
        };
        let want = brute.intersect(&ray).unwrap();
        let got = octree.intersect(&ray).unwrap();
        prop_assert_eq!(
            got.map(|h| h.bit_key()),
            want.map(|h| h.bit_key()),
            "{} ray {:?}: octree {:?} brute {:?} ({} grids)",
            T::NAME,
            ray,
            got,
            want,
            octree.grid_count()
        );
        prop_assert_eq!(
            octree.occluded(&ray).unwrap(),
            want.is_some(),
            "{} occluded, ray {:?}",
            T::NAME,
            ray
        );
        let mut counters = TraversalCounters::default();
        let counted = octree.intersect_counted(&ray, &mut counters).unwrap();
        prop_assert_eq!(counted.map(|h| h.bit_key()), want.map(|h| h.bit_key()));
        prop_assert_eq!(
            octree.occluded_counted(&ray, &mut counters).unwrap(),
            want.is_some()
        );
    }
    for corners in regions {
        let b = region::<T>(&mesh, corners.0, corners.1);
        prop_assert_eq!(
            octree.query_region(&b).unwrap(),
            brute.query_region(&b).unwrap(),
            "{} region {:?}",
            T::NAME,
            b
        );
    }
    Ok(())
}

fn region_strategy() -> impl Strategy<Value = ([f64; 3], [f64; 3])> {
    let unit3 = prop::array::uniform3(-0.1..1.1f64);
    prop_oneof![
        (unit3.clone(), unit3.clone()),
        unit3.prop_map(|p| (p, p)),
        // Snapped to eighths: corners on shared cell boundaries.
        prop::array::uniform3(0u8..=8).prop_map(|p| {
            let p = p.map(|x| f64::from(x) / 8.0);
            (p, p.map(|x| x + 0.125))
        }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::default())]

    #[test]
    fn octree_equals_brute_force(
        scene in scene_strategy(),
        params in params_strategy(),
        rays in prop::collection::vec((ray_strategy(), window(true)), 1..48),
        regions in prop::collection::vec(region_strategy(), 0..4),
    ) {
        check::<f32>(&scene, &params, &rays, &regions)?;
        check::<f64>(&scene, &params, &rays, &regions)?;
    }
}
