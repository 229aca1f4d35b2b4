//! The grid over a user region that covers only part of the scene, against
//! what `GridParams::region` promises: only primitives overlapping the region
//! are referenced and queries answer for the space inside it. So:
//! - a hit brute force finds inside the region (by a margin) is found, bit
//!   for bit;
//! - every hit the grid returns is that primitive's own hit on the ray and is
//!   never before brute force's (hits outside the region are unspecified
//!   only in whether they are found);
//! - `occluded` agrees with the grid's own `intersect`;
//! - a region query inside the region (by a margin) returns exactly brute
//!   force's set, and any region query returns a subset of it.
//!
//! (A region that holds the whole scene is in the registry: exact equivalence.)

use accel_core::{Aabb, Accelerator, BruteForce, BuildError, Hit, PrimitiveSet, Ray, Real, Vec3};
use accel_grid::{Grid, GridParams};
use accel_tests::assertions::own_hit;
use accel_tests::config::config;
use accel_tests::scene::SceneSpec;
use accel_tests::strategies::{boxes, ordinary_placement, rays_and_windows, scene, unit3};
use accel_tests::suite::resolve;
use accel_tests::{BoxSpec, RaySpec, WindowSpec};
use accel_tests::{Landmarks, Scene};
use proptest::prelude::*;

/// Whether brute force's hit point lies inside `r` by a margin that covers
/// the rounding of `o + t·d`.
fn inside<T: Real>(r: &Aabb<T>, ray: &Ray<T>, h: &Hit<T>) -> bool {
    let (o, d, t) = (
        ray.origin.cast::<f64>(),
        ray.direction.cast::<f64>(),
        h.t.to_f64(),
    );
    let p = o + d * t;
    let r = r.cast::<f64>();
    let scale = o.abs().max((d * t).abs()).max_component() + r.max_abs_coordinate();
    let margin = 1e-3 * r.diagonal().max_component() + 64.0 * T::UNIT_ROUNDOFF.to_f64() * scale;
    (0..3).all(|a| p[a] >= r.min[a] + margin && p[a] <= r.max[a] - margin)
}

/// The region shrunk by a margin: a primitive that the overlap test accepts
/// for a box inside it (within the test's rounding allowance) truly reaches
/// into the region, so the grid references it. (One that only touches the
/// region within that allowance, from outside, may lie in no cell.)
fn shrunk<T: Real>(r: &Aabb<T>) -> Aabb<T> {
    let f = r.cast::<f64>();
    let margin = 1e-3 * f.diagonal().max_component()
        + 64.0 * T::UNIT_ROUNDOFF.to_f64() * f.max_abs_coordinate();
    f.expanded(-margin).cast()
}

fn key<T: Real>(h: Option<Hit<T>>) -> Option<(u64, u32, u64, u64)> {
    h.map(|h| h.bit_key())
}

fn check_partial<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    landmarks: Landmarks<T>,
    corners: ([f64; 3], [f64; 3]),
    density: f64,
    rays: &[(RaySpec, WindowSpec)],
    boxes: &[BoxSpec],
) -> Result<(), String> {
    let region = Aabb::new(landmarks.in_frame(corners.0), landmarks.in_frame(corners.1));
    let resolved = resolve(prims, landmarks, rays, boxes)?;
    let params = GridParams {
        region: Some(region),
        ..GridParams::with_density(density)
    };
    let grid = Grid::with_params(prims, &params).map_err(|e| format!("build: {e}"))?;
    grid.validate()?;
    let brute = BruteForce::new(prims).map_err(|e| e.to_string())?;
    let ctx = |ray: &Ray<T>| format!("region {region:?}, density {density}, ray {ray:?}");
    for ray in &resolved.rays {
        let want = brute.intersect(ray).map_err(|e| e.to_string())?;
        let got = grid.intersect(ray).map_err(|e| e.to_string())?;
        if let Some(g) = got {
            let own = own_hit(prims, g.prim, ray);
            if key(own) != key(Some(g)) {
                return Err(format!(
                    "{}: grid hit {g:?} is not the primitive's own {own:?}",
                    ctx(ray)
                ));
            }
            if want.is_none_or(|w| g.is_before(&w)) {
                return Err(format!(
                    "{}: grid hit {g:?} is before brute force's {want:?}",
                    ctx(ray)
                ));
            }
        }
        if let Some(w) = want
            && inside(&region, ray, &w)
            && key(got) != key(want)
        {
            return Err(format!(
                "{}: hit inside the region, grid {got:?}, brute {want:?}",
                ctx(ray)
            ));
        }
        let occluded = grid.occluded(ray).map_err(|e| e.to_string())?;
        if occluded != got.is_some() {
            return Err(format!(
                "{}: occluded {occluded} but intersect {got:?}",
                ctx(ray)
            ));
        }
    }
    for q in &resolved.regions {
        let got = grid.query_region(q).map_err(|e| e.to_string())?;
        let want = brute.query_region(q).map_err(|e| e.to_string())?;
        if let Some(p) = got.iter().find(|p| !want.contains(p)) {
            return Err(format!(
                "region {region:?}: query {q:?} returned {p}, which does not overlap it"
            ));
        }
        let inner = q.intersection(&shrunk(&region));
        if !inner.is_empty() {
            let got = grid.query_region(&inner).map_err(|e| e.to_string())?;
            let want = brute.query_region(&inner).map_err(|e| e.to_string())?;
            if got != want {
                return Err(format!(
                    "region {region:?}: query {inner:?} inside it gave {got:?}, brute force {want:?}"
                ));
            }
        }
    }
    Ok(())
}

fn run<T: Real>(
    scene: &SceneSpec,
    corners: ([f64; 3], [f64; 3]),
    density: f64,
    rays: &[(RaySpec, WindowSpec)],
    boxes: &[BoxSpec],
) -> Result<(), TestCaseError> {
    let built = scene.build::<T>();
    let lm = Landmarks::of(&built);
    match &built {
        Scene::Mesh(m) => check_partial(m, lm, corners, density, rays, boxes),
        Scene::Mixed(v) => check_partial(v.as_slice(), lm, corners, density, rays, boxes),
    }
    .map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(config("grid_region_f32", 1500))]
    #[test]
    fn grid_partial_region_f32(
        scene in scene(ordinary_placement()),
        corners in (unit3(), unit3()),
        density in prop::sample::select(vec![0.5, 1.0, 2.0, 4.0]),
        rays in rays_and_windows(24),
        queries in prop::collection::vec(boxes(), 0..6),
    ) {
        run::<f32>(&scene, corners, density, &rays, &queries)?;
    }
}

proptest! {
    #![proptest_config(config("grid_region_f64", 1500))]
    #[test]
    fn grid_partial_region_f64(
        scene in scene(ordinary_placement()),
        corners in (unit3(), unit3()),
        density in prop::sample::select(vec![0.5, 1.0, 2.0, 4.0]),
        rays in rays_and_windows(24),
        queries in prop::collection::vec(boxes(), 0..6),
    ) {
        run::<f64>(&scene, corners, density, &rays, &queries)?;
    }
}

#[test]
fn invalid_regions_are_refused_at_build() {
    let mesh = accel_scenes::uv_sphere(Vec3::ZERO, 1.0, 50);
    let nan = Aabb {
        min: Vec3::new(0.0, f64::NAN, 0.0),
        max: Vec3::splat(1.0),
    };
    let inf = Aabb {
        min: Vec3::splat(0.0),
        max: Vec3::new(1.0, 1.0, f64::INFINITY),
    };
    let inverted = Aabb {
        min: Vec3::splat(1.0),
        max: Vec3::splat(0.0),
    };
    for region in [nan, inf, inverted, Aabb::empty()] {
        let err = Grid::with_params(&mesh, &GridParams::with_region(region)).unwrap_err();
        assert_eq!(err, BuildError::InvalidRegion, "{region:?}");
    }
}

#[test]
fn a_region_away_from_the_scene_holds_nothing() {
    let mesh = accel_scenes::uv_sphere(Vec3::ZERO, 1.0, 50);
    let away = Aabb::new(Vec3::splat(5.0), Vec3::splat(6.0));
    let grid = Grid::with_params(&mesh, &GridParams::with_region(away)).unwrap();
    assert_eq!(grid.stats().references, 0);
    assert!(grid.bounds().is_empty());
    let through = Ray::new(Vec3::new(-3.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)).unwrap();
    assert!(
        BruteForce::new(&mesh)
            .unwrap()
            .intersect(&through)
            .unwrap()
            .is_some()
    );
    assert_eq!(grid.intersect(&through).unwrap(), None);
    assert_eq!(grid.query_region(&away).unwrap(), Vec::<u32>::new());
}
