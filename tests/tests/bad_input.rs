//! Bad input: NaN, infinite and zero-direction rays, NaN and infinite
//! region boxes get the typed `QueryError` from every registered
//! accelerator (the one brute force gives, which must name one of the ray's
//! problems), on every kind of scene (empty ones too); non-finite scenes are
//! refused at build with `BuildError::NonFinitePrimitive` naming the first
//! bad primitive.

use accel_core::{Accelerator, BruteForce, BuildError, PrimitiveSet, QueryError, Real};
use accel_tests::bad_input::{
    Bad, Corruption, POISON_VALUES, Poison, bad_region, corrupt, first_non_finite, poisoned,
    problems,
};
use accel_tests::config::config;
use accel_tests::registry::accelerators;
use accel_tests::scene::{Item, SceneSpec};
use accel_tests::strategies::{boxes, mixed_item, ordinary_placement, ray, scene};
use accel_tests::{BoxSpec, RayContext, RaySpec};
use accel_tests::{Landmarks, Scene};
use proptest::prelude::*;

fn bad() -> impl Strategy<Value = Bad> + Clone {
    prop::sample::select(vec![Bad::Nan, Bad::Inf, Bad::NegInf])
}

fn corruption() -> impl Strategy<Value = Corruption> {
    prop_oneof![
        (0usize..3, bad()).prop_map(|(a, b)| Corruption::Origin(a, b)),
        (0usize..3, bad()).prop_map(|(a, b)| Corruption::Direction(a, b)),
        any::<[bool; 3]>().prop_map(Corruption::ZeroDirection),
        Just(Corruption::TMinNan),
        Just(Corruption::TMaxNan),
    ]
}

/// A region corruption: which corner, which axis, what value.
type RegionCorruption = (bool, usize, Bad);

fn check_bad<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    landmarks: Landmarks<T>,
    ray_spec: &RaySpec,
    corruptions: &[Corruption],
    region: (&BoxSpec, RegionCorruption),
) -> Result<(), String> {
    let ctx = RayContext::new(prims, landmarks);
    let ray = corrupt(ray_spec.resolve(&ctx), corruptions);
    let allowed = problems(&ray);
    if allowed.is_empty() {
        return Err(format!(
            "corruptions {corruptions:?} left a valid ray {ray:?}"
        ));
    }
    let brute = BruteForce::new(prims).map_err(|e| e.to_string())?;
    let want = match brute.intersect(&ray) {
        Err(e) => e,
        Ok(h) => {
            return Err(format!(
                "brute force answered {h:?} for invalid ray {ray:?}"
            ));
        }
    };
    let (spec, (upper, axis, value)) = region;
    let bad_box = bad_region(spec.resolve(&ctx), upper, axis, value);
    for entry in accelerators::<T, P>() {
        let acc = (entry.build)(prims).map_err(|e| format!("{}: {e}", entry.name))?;
        accel_tests::assertions::check_refused(entry.name, &*acc, &ray, want, &allowed)?;
        let got = acc.query_region(&bad_box);
        if got != Err(QueryError::NonFiniteRegion) {
            return Err(format!(
                "{} ({}): query_region({bad_box:?}) gave {got:?}, want Err(NonFiniteRegion)",
                entry.name,
                T::NAME
            ));
        }
    }
    Ok(())
}

fn run<T: Real>(
    scene: &SceneSpec,
    ray: &RaySpec,
    corruptions: &[Corruption],
    region: (&BoxSpec, RegionCorruption),
) -> Result<(), TestCaseError> {
    let built = scene.build::<T>();
    let landmarks = Landmarks::of(&built);
    match &built {
        Scene::Mesh(m) => check_bad(m, landmarks, ray, corruptions, region),
        Scene::Mixed(v) => check_bad(v.as_slice(), landmarks, ray, corruptions, region),
    }
    .map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(config("bad_input", 1000))]
    #[test]
    fn invalid_rays_and_regions_get_typed_errors(
        scene in scene(ordinary_placement()),
        ray in ray(),
        corruptions in prop::collection::vec(corruption(), 1..4),
        region in boxes(),
        region_corruption in (any::<bool>(), 0usize..3, bad()),
    ) {
        run::<f32>(&scene, &ray, &corruptions, (&region, region_corruption))?;
        run::<f64>(&scene, &ray, &corruptions, (&region, region_corruption))?;
    }
}

fn check_refused_scene<T: Real>(items: &[Item], poisons: &[(usize, Poison)]) -> Result<(), String> {
    let prims = poisoned::<T>(items, poisons);
    let first = first_non_finite(&prims);
    for entry in accelerators::<T, [accel_tests::Mixed<T>]>() {
        let got = (entry.build)(prims.as_slice()).map(|_| ());
        let ok = match first {
            Some(index) => got == Err(BuildError::NonFinitePrimitive { index }),
            None => got.is_ok(),
        };
        if !ok {
            return Err(format!(
                "{} ({}): build gave {got:?}, want {}",
                entry.name,
                T::NAME,
                first.map_or("Ok".into(), |index| format!(
                    "Err(NonFinitePrimitive {{ index: {index} }})"
                ))
            ));
        }
    }
    Ok(())
}

fn poison() -> impl Strategy<Value = Poison> {
    let value = prop::sample::select(POISON_VALUES.to_vec());
    prop_oneof![
        (0usize..3, 0usize..3, value.clone()).prop_map(|(v, a, x)| Poison::Coordinate(v, a, x)),
        value.prop_map(Poison::Radius),
    ]
}

proptest! {
    #![proptest_config(config("non_finite_scenes", 1000))]
    #[test]
    fn non_finite_scenes_are_refused_at_build(
        items in prop::collection::vec(mixed_item(), 1..12),
        poisons in prop::collection::vec((0usize..12, poison()), 1..3),
    ) {
        check_refused_scene::<f32>(&items, &poisons).map_err(TestCaseError::fail)?;
        check_refused_scene::<f64>(&items, &poisons).map_err(TestCaseError::fail)?;
    }
}

/// A triangle mesh cannot even hold a non-finite vertex (a set of plain
/// `Triangle`s can: see `bug4` in `regressions.rs`), nor can a cast overflow.
#[test]
fn meshes_refuse_non_finite_vertices() {
    use accel_core::{MeshError, TriangleMesh, Vec3};
    let ok = Vec3::new(0.0f32, 0.0, 0.0);
    let nan = Vec3::new(0.0, f32::NAN, 0.0);
    assert_eq!(
        TriangleMesh::new(vec![ok, nan, ok], vec![[0, 1, 2]]),
        Err(MeshError::NonFiniteVertex { index: 1 })
    );
    let big = TriangleMesh::new(vec![Vec3::new(0.0f64, 1e39, 0.0)], vec![]).unwrap();
    assert_eq!(
        big.cast::<f32>(),
        Err(MeshError::NonFiniteVertex { index: 0 })
    );
}
