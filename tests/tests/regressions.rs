//! Bugs the suites found, each kept as a named test with the smallest scene
//! and ray that showed it. The property suites replay their own shrunk
//! cases from `proptest-regressions/`; these say what each bug was.

use accel_core::{Accelerator, BruteForce, Ray, Real, TriangleMesh, Vec3};
use accel_tests::registry::accelerators;

/// Every registered accelerator answers `ray` as brute force does.
fn assert_all_agree<T: Real>(mesh: &TriangleMesh<T>, ray: &Ray<T>) {
    let want = BruteForce::new(mesh).unwrap().intersect(ray).unwrap();
    for entry in accelerators::<T, TriangleMesh<T>>() {
        let acc = (entry.build)(mesh).unwrap();
        let got = acc.intersect(ray).unwrap();
        assert_eq!(
            got.map(|h| h.bit_key()),
            want.map(|h| h.bit_key()),
            "{}: intersect",
            entry.name
        );
        assert_eq!(
            acc.occluded(ray).unwrap(),
            want.is_some(),
            "{}: occluded",
            entry.name
        );
    }
}

/// Bug 1 (found by `extremes_f32`): the grid's walk never ended for a ray
/// whose cell-crossing parameters overflow to +∞, as a direction of length
/// 1e-30 gives in a scene 1e20 across in f32. With no hit, the walk's limit
/// (`t_end`, the beam's exit) was +∞ too, so `BeamWalk::advance` accepted a
/// crossing at +∞ (`inf <= inf`) and its trail catch-up loop chased +∞
/// forever: the query hung. Fixed in `accel-grid/src/dda.rs`: a crossing at
/// +∞ ends the walk (no representable hit lies beyond it).
///
/// A regression shows as this test hanging, not failing.
#[test]
fn bug1_grid_walk_ends_when_crossings_overflow_to_infinity() {
    let s = 1e20f32;
    let mesh = TriangleMesh::from_triangles(&[[
        Vec3::new(0.0, 0.0, s),
        Vec3::new(s, 0.0, s),
        Vec3::new(0.0, s, s),
    ]])
    .unwrap();
    // Starts on the triangle; t_min = 1 skips that hit, so nothing is hit.
    let ray = Ray::with_interval(
        Vec3::new(0.25 * s, 0.25 * s, s),
        Vec3::new(1e-30, 0.0, 1e-30),
        1.0,
        f32::INFINITY,
    )
    .unwrap();
    assert_all_agree(&mesh, &ray);
    // From the other side of the plane, the hit at t = 5e49 is beyond f32.
    let ray = Ray::new(
        Vec3::new(0.25 * s, 0.25 * s, 0.5 * s),
        Vec3::new(1e-30, 0.0, 1e-30),
    )
    .unwrap();
    assert_all_agree(&mesh, &ray);
}

/// Bug 2 (found by `equivalence_f64`): in f64, a ray through a zero-area
/// triangle (three collinear vertices) was reported hit at a `t` whose point
/// lay 2e-3 off the triangle, so the grid, which only visits cells near the
/// ray where the triangle is, could not find that hit when the window
/// `[t_min, t_max]` began just before it. Cause: `Real::diff_of_products`
/// for f64 had an exact sign but, when the products cancel, a value that is
/// rounding noise; the triangle test computes `t`, `u`, `v` from those values.
/// (f32 was right: its products are exact in f64.) Fixed in
/// `accel-core/src/real.rs`: cancelling products take the error-free
/// expansion, so the values are accurate and the reported point lies on the
/// triangle as the `Primitive` contract promises.
#[test]
fn bug2_f64_zero_area_triangle_hit_lies_on_the_triangle() {
    let on_line = |x: f64| Vec3::new(x, 0.25, 0.75);
    let mesh = TriangleMesh::from_triangles(&[[
        on_line(0.5699445349624651),
        on_line(0.016532478715710622),
        on_line(0.0),
    ]])
    .unwrap();
    let ray = Ray::new(
        Vec3::new(1.414488630781441, 0.5691189373468835, 0.3075384241047964),
        Vec3::new(
            -1.0383299978107974,
            -0.31911893734688346,
            0.4424615758952036,
        ),
    )
    .unwrap();
    let hit = BruteForce::new(&mesh).unwrap().intersect(&ray).unwrap();
    if let Some(h) = hit {
        let p = ray.at(h.t);
        // The contract: within about gamma(16) of the distance to the ray origin.
        let tolerance = <f64 as Real>::gamma(16) * 2.0;
        assert!(
            (p.y - 0.25).abs() <= tolerance && (p.z - 0.75).abs() <= tolerance,
            "hit point {p:?} is off the triangle's line"
        );
        // The window that exposed it: starting one ulp before the hit.
        let late =
            Ray::with_interval(ray.origin, ray.direction, h.t.next_down(), f64::INFINITY).unwrap();
        assert_all_agree(&mesh, &late);
    }
    assert_all_agree(&mesh, &ray);
}

/// Bug 3 (found by `extremes_f32`): a torus 1e-20 across in f32 and a ray
/// with a direction of length 1e30 (t of the order 1e-51, below f32's range).
/// A triangle the line meets just *behind* the origin had t ≈ −1e-51, which
/// rounded to −0.0, passed `t ≥ t_min = 0`, and was reported hit at the
/// origin, 1e-21 (a tenth of the scene) away from the triangle; the grid
/// walks forward from the origin and rightly never met it. Causes, both in
/// accel-core: the triangle test scaled the vertex depths (`Sz·a_z`, here
/// 1e-51) in T, where they underflowed to 0, so every triangle the line met
/// got t = ±0; and the primitive tests only refused a parameter that
/// overflowed T, not one that underflowed. Fixed: the depths are scaled in the
/// wide type (`accel-core/src/triangle/mod.rs`), and one rule in
/// `accel-core/src/real.rs` (`Real::hit_parameter`, used by the triangle and
/// sphere tests) refuses a parameter below T's normal range unless it is
/// exactly 0.
#[test]
fn bug3_f32_parameter_that_underflows_is_no_hit() {
    use accel_tests::scene::{Placement, SceneSpec, Shape};
    let scene = SceneSpec::Closed(
        Shape::Torus(3, 5),
        Placement {
            scale_exp: -20,
            offset: 0.0,
        },
    );
    let accel_tests::Scene::Mesh(mesh) = scene.build::<f32>() else {
        unreachable!()
    };
    let ray = Ray::new(
        Vec3::new(1.4563692e-21, 8.217859e-21, 8.716069e-21),
        Vec3::new(-5.495363e29, 0.0, 7.773403e29),
    )
    .unwrap();
    let hit = BruteForce::new(&mesh).unwrap().intersect(&ray).unwrap();
    assert!(
        hit.is_none_or(|h| h.t.abs() >= f32::MIN_POSITIVE),
        "a hit at an underflowed parameter: {hit:?}"
    );
    assert_all_agree(&mesh, &ray);
}

/// Bug 4 (found by `non_finite_scenes_are_refused_at_build`): a set of
/// `Triangle`s (which, unlike `TriangleMesh`, anyone can fill with any
/// vertices) with a NaN coordinate built without complaint in every
/// accelerator: `Triangle::bounds` takes min and max of the vertices, and
/// min/max drop a NaN, so the bounds looked finite. Fixed in
/// `accel-core/src/triangle/mod.rs`: a non-finite vertex gives infinite bounds,
/// as `Sphere::bounds` already did, and every build refuses it.
#[test]
fn bug4_nan_vertex_of_a_plain_triangle_is_refused() {
    use accel_core::{BuildError, Triangle};
    let tri = |v: [[f32; 3]; 3]| Triangle {
        vertices: v.map(Vec3::from),
    };
    let tris = vec![
        tri([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
        tri([[0.0, 0.0, 0.0], [1.0, f32::NAN, 0.0], [0.0, 1.0, 0.0]]),
    ];
    for entry in accelerators::<f32, Vec<Triangle<f32>>>() {
        assert_eq!(
            (entry.build)(&tris).map(|_| ()),
            Err(BuildError::NonFinitePrimitive { index: 1 }),
            "{}",
            entry.name
        );
    }
}

/// Bug 5 (found by the deep run of `extremes_f32`, once in 100,000 cases): a
/// ray over `[−∞, +∞]` with a direction of length 7e-31 starting exactly on a
/// vertex of a scene 1e27 from the origin in f32. Brute force hits the
/// triangle at t = 0; the grid found nothing. The beam's entry into the grid
/// overflowed to −∞, so the walk's start parameter was −∞, and the walk
/// placed the beam at `origin + d·t_start`, where a zero component gives
/// 0·∞ = NaN and the cell lookup lands anywhere. Fixed in
/// `accel-core/src/robust.rs` (`TraversalRay::new`): `t_start` and `t_end`
/// are clamped to finite values (no hit has an infinite parameter), which
/// mends every structure that walks from them.
#[test]
fn bug5_walk_from_an_unbounded_interval_with_a_tiny_direction() {
    use accel_tests::scene::{Placement, SceneSpec};
    let scene = SceneSpec::Soup(
        vec![
            [
                [0.0, 0.0, 0.8599338562336785],
                [0.0, 0.0, 0.9378093153048142],
                [0.0, 0.0, 0.2976264517009592],
            ],
            [
                [0.0, 0.0, 1.0],
                [0.0, 0.749234942994565, 0.5341236431070633],
                [0.9674994892916966, 0.0, 0.9589042903281324],
            ],
        ],
        Placement {
            scale_exp: 20,
            offset: 1e7,
        },
    );
    let accel_tests::Scene::Mesh(mesh) = scene.build::<f32>() else {
        unreachable!()
    };
    let ray = Ray::with_interval(
        Vec3::new(1e27, -7.499999e26, 5.0000007e26),
        Vec3::new(0.0, -6.695094e-31, 0.0),
        f32::NEG_INFINITY,
        f32::INFINITY,
    )
    .unwrap();
    assert!(
        BruteForce::new(&mesh)
            .unwrap()
            .intersect(&ray)
            .unwrap()
            .is_some(),
        "premise"
    );
    assert_all_agree(&mesh, &ray);
}
