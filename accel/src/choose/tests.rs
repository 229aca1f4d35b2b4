//! The chooser's tests: probes that stop early, the spread-out order,
//! choices that are valid, explained and answer like brute force.

use super::probe::spread_order;
use super::*;
use accel_core::Aabb;
use accel_core::{BruteForce, TriangleMesh, Vec3};
use accel_scenes::{random_rays, random_soup, sphere_in_tiled_box, uv_sphere};

/// Brute force that takes at least a millisecond per ray and counts them.
struct Slow<'a> {
    inner: BruteForce<'a, f64, TriangleMesh<f64>>,
    calls: std::sync::atomic::AtomicUsize,
}

impl Slow<'_> {
    fn wait(&self) {
        self.calls
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        std::thread::sleep(Duration::from_millis(1));
    }
}

impl Accelerator<f64> for Slow<'_> {
    fn bounds(&self) -> Aabb<f64> {
        self.inner.bounds()
    }
    fn intersect(&self, ray: &Ray<f64>) -> Result<Option<accel_core::Hit<f64>>, QueryError> {
        self.wait();
        self.inner.intersect(ray)
    }
    fn occluded(&self, ray: &Ray<f64>) -> Result<bool, QueryError> {
        self.wait();
        self.inner.occluded(ray)
    }
    fn intersect_counted(
        &self,
        ray: &Ray<f64>,
        c: &mut accel_core::TraversalCounters,
    ) -> Result<Option<accel_core::Hit<f64>>, QueryError> {
        self.wait();
        self.inner.intersect_counted(ray, c)
    }
    fn occluded_counted(
        &self,
        ray: &Ray<f64>,
        c: &mut accel_core::TraversalCounters,
    ) -> Result<bool, QueryError> {
        self.wait();
        self.inner.occluded_counted(ray, c)
    }
    fn query_region(&self, region: &Aabb<f64>) -> Result<Vec<u32>, QueryError> {
        self.inner.query_region(region)
    }
    fn stats(&self) -> accel_core::AccelStats {
        self.inner.stats()
    }
}

fn slow(mesh: &TriangleMesh<f64>) -> Slow<'_> {
    Slow {
        inner: BruteForce::new(mesh).unwrap(),
        calls: std::sync::atomic::AtomicUsize::new(0),
    }
}

#[test]
fn a_slow_structure_is_cut_short_at_the_time_cap() {
    // 4096 probe rays at >= 1 ms each would take seconds; with a 10 ms
    // budget the probe stops after its first chunk or two, and still
    // prices the rays at >= 1 ms each (divided by the threads).
    let mesh = uv_sphere(Vec3::ZERO, 1.0, 200);
    let slow = slow(&mesh);
    let rays: Vec<ProbeRay<f64>> = (0..16).flat_map(|_| probe_of(&mesh)).collect();
    assert_eq!(rays.len(), 4096);
    let t = probe_per_ray(&slow, &rays, Duration::from_millis(10), f64::INFINITY).unwrap();
    let calls = slow.calls.into_inner();
    assert_eq!(t.stop, ProbeStop::TimeCap);
    assert_eq!(t.rays, calls);
    // The first chunk overshoots the budget, a second one at most fills it.
    let threads = rayon::current_num_threads();
    assert!(
        calls >= FIRST_CHUNK && calls <= FIRST_CHUNK + 10 * threads,
        "{calls} rays traced"
    );
    assert!(t.per_ray_s >= 1e-3 / threads as f64, "{t:?}");
}

#[test]
fn a_losing_structure_stops_after_its_first_rays() {
    // A generous time budget, but a candidate that needs more than 1 µs
    // per ray to win: it is stopped as losing after its first rays.
    let mesh = uv_sphere(Vec3::ZERO, 1.0, 200);
    let slow = slow(&mesh);
    let rays: Vec<ProbeRay<f64>> = (0..16).flat_map(|_| probe_of(&mesh)).collect();
    let t = probe_per_ray(&slow, &rays, Duration::from_secs(60), 1e-6).unwrap();
    assert_eq!(t.stop, ProbeStop::Loses);
    assert_eq!(slow.calls.into_inner(), t.rays);
    // At 1 ms per ray, LOSE_MIN_TIME is reached after a few chunks.
    let threads = rayon::current_num_threads();
    assert!(t.rays >= LOSE_MIN_RAYS, "{t:?}");
    assert!(t.rays <= LOSE_MIN_RAYS + 128 * threads, "{t:?}");
    assert!(t.per_ray_s >= 1e-3 / threads as f64, "{t:?}");
    // The same structure is not stopped where it may win.
    let few = &rays[..100];
    let slow = self::slow(&mesh);
    let t = probe_per_ray(&slow, few, Duration::from_secs(60), 1.0).unwrap();
    assert_eq!(t.stop, ProbeStop::Complete);
    assert_eq!(t.rays, 100);
    // Every ray, then two to four warm passes.
    let calls = slow.calls.into_inner();
    assert!(
        (300..=500).contains(&calls) && calls.is_multiple_of(100),
        "{calls}"
    );
}

#[test]
fn the_probe_order_is_a_spread_out_permutation() {
    assert_eq!(spread_order(10, 1), [0, 8, 4, 2, 6, 1, 9, 5, 3, 7]);
    assert_eq!(spread_order(10, 3), [0, 1, 2, 6, 7, 8, 3, 4, 5, 9]);
    assert_eq!(spread_order(5, 16), [0, 1, 2, 3, 4]);
    for block in [1, 16] {
        for n in [0, 1, 2, 3, 1000, 4096] {
            let mut o = spread_order(n, block);
            // The first four blocks land in four different quarters.
            if n >= 4 * block {
                let mut q: Vec<usize> = (0..4).map(|b| 4 * o[b * block] / n).collect();
                q.sort_unstable();
                assert_eq!(q, [0, 1, 2, 3], "n = {n}");
            }
            o.sort_unstable();
            assert_eq!(o, (0..n).collect::<Vec<_>>());
        }
    }
}

fn probe_of(mesh: &TriangleMesh<f64>) -> Vec<ProbeRay<f64>> {
    random_rays(&mesh.bounds(), 256, 3)
        .into_iter()
        .enumerate()
        .map(|(i, ray)| ProbeRay {
            ray,
            any_hit: i % 2 == 1,
        })
        .collect()
}

#[test]
fn tiny_work_gets_brute_force_without_a_probe() {
    let tiny = uv_sphere(Vec3::ZERO, 1.0, 20);
    let n = tiny.triangle_count() as u64;
    let rays = TINY_WORK / n;
    let c = choose_with_probe(&tiny, rays, |_| panic!("no probe for so little work")).unwrap();
    assert_eq!(c.config, AccelConfig::Brute);
    assert!(c.reason.contains("less than a probe"), "{}", c.reason);
    // The same scene with more rays is probed: a grid may pay even here.
    let mut probed = false;
    let c = choose_with_probe(&tiny, rays + 1, |_| {
        probed = true;
        Ok(probe_of(&tiny))
    })
    .unwrap();
    assert!(probed);
    assert_sound(&c, &tiny, &probe_of(&tiny));
}

/// The chosen estimate is probed and the smallest; the structure is the
/// one named and answers like brute force.
fn assert_sound(
    c: &Choice<'_, f64, TriangleMesh<f64>>,
    mesh: &TriangleMesh<f64>,
    probe: &[ProbeRay<f64>],
) {
    assert_eq!(c.accel.stats().kind, c.config.kind().name());
    assert!(!c.reason.contains('\n'));
    let chosen = c
        .estimates
        .iter()
        .find(|e| e.config == c.config)
        .expect("the choice has an estimate");
    assert!(chosen.probed());
    for e in &c.estimates {
        assert!(chosen.total_s <= e.total_s, "{chosen:?} vs {e:?}");
    }
    let brute = BruteForce::new(mesh).unwrap();
    for p in probe {
        assert_eq!(
            c.accel.intersect(&p.ray).unwrap(),
            brute.intersect(&p.ray).unwrap()
        );
        assert_eq!(
            c.accel.occluded(&p.ray).unwrap(),
            brute.occluded(&p.ray).unwrap()
        );
    }
}

#[test]
fn the_choice_is_valid_explained_and_answers_like_brute_force() {
    let mesh = random_soup(3_000, 9);
    for rays in [100, 100_000_000] {
        let c = choose_with_probe(&mesh, rays, |a| {
            // The probe sees a built structure answering queries: the
            // grid, which suits a soup.
            assert_eq!(a.stats().primitives, 3_000);
            assert_eq!(a.stats().kind, "grid");
            Ok(probe_of(&mesh))
        })
        .unwrap();
        assert!(c.reason.contains(&format!("{rays} rays")), "{}", c.reason);
        assert_sound(&c, &mesh, &probe_of(&mesh));
        // Every candidate is accounted for, brute force included (the
        // finer grid too: 3000 primitives is a small scene).
        assert_eq!(c.estimates.len(), candidates().len() + 1);
        assert!(c.estimates.iter().any(|e| e.config == candidates()[1]));
        assert!(c.estimates.iter().all(|e| e.cost_s >= 0.0));
    }
}

#[test]
fn a_dense_cell_skips_the_grid_without_probing_it() {
    // 20k triangles in a sphere of radius 1, in a box of side 10^4 whose
    // faces are tiled 20 × 20 (no triangle large enough for the grid to
    // set the sphere apart, `accel_core::parts`): the coarse grid's
    // cells are hundreds of units wide, so the sphere's cell (or cells)
    // hold thousands of references.
    let mesh = sphere_in_tiled_box(20_000, 1.0e4, 20);
    let mut first = "";
    let rays = random_rays(&Aabb::new(Vec3::splat(-2.0), Vec3::splat(2.0)), 512, 5);
    let probe: Vec<ProbeRay<f64>> = rays
        .into_iter()
        .map(|ray| ProbeRay {
            ray,
            any_hit: false,
        })
        .collect();
    for budget in [10_000, 100_000_000] {
        let c = choose_with_probe(&mesh, budget, |a| {
            first = a.stats().kind;
            Ok(probe.clone())
        })
        .unwrap();
        assert_eq!(first, "octree", "the probe is made without the grid");
        let grid = &c.estimates[0];
        assert_eq!(grid.config, AccelConfig::grid(1.0));
        let Status::Skipped(Skip::FullCell(refs)) = grid.status else {
            panic!("{grid:?}");
        };
        assert!(refs > GRID_CELL_LIMIT, "{refs}");
        assert!(
            c.reason.contains(&format!("holds {refs} of")),
            "{}",
            c.reason
        );
        assert_eq!(
            c.estimates[1].config,
            AccelConfig::Octree(OctreeParams::two_level())
        );
        assert!(c.estimates[1].probed());
        assert_sound(&c, &mesh, &probe);
    }
}

#[test]
fn a_refused_probe_ray_is_an_error() {
    let mesh = random_soup(500, 2);
    let bad = Ray {
        origin: Vec3::new(f64::NAN, 0.0, 0.0),
        direction: Vec3::new(1.0, 0.0, 0.0),
        t_min: 0.0,
        t_max: 1.0,
    };
    let err = choose_with_probe(&mesh, 1000, |_| {
        Ok(vec![ProbeRay {
            ray: bad,
            any_hit: false,
        }])
    })
    .unwrap_err();
    assert!(err.to_string().contains("not finite"), "{err}");
}

#[test]
fn probe_primaries_come_in_tiles_of_neighbouring_pixels() {
    let camera = accel_scenes::GeneratedScene::Soup100k.camera();
    let key = |r: &Ray<f64>| r.direction.to_array().map(f64::to_bits);
    // Covering the view: every pixel once (a 10×7 view has partial tiles).
    let mut all: Vec<_> = tiled_primaries::<f64>(&camera, 10, 7, 70)
        .iter()
        .map(key)
        .collect();
    let mut want: Vec<_> = camera.rays::<f64>(10, 7).iter().map(key).collect();
    all.sort_unstable();
    want.sort_unstable();
    assert_eq!(all, want);
    // The chooser's probe of an 800×600 render: about 1,536 rays, in
    // runs of 16 whose directions differ by at most a few pixels.
    let rays = tiled_primaries::<f64>(&camera, 800, 600, PROBE_PRIMARIES);
    assert!((1300..=1800).contains(&rays.len()), "{}", rays.len());
    let pixel = camera.ray_through::<f64>(400.5, 300.5, 800, 600).direction
        - camera.ray_through::<f64>(401.5, 300.5, 800, 600).direction;
    for t in rays.chunks(16) {
        let spread = (t[0].direction - t[15].direction).length();
        assert!(
            spread < 6.0 * pixel.length(),
            "{spread} against {}",
            pixel.length()
        );
    }
    // And the tiles are spread: the first and last are far apart.
    let span = (rays[0].direction - rays[rays.len() - 1].direction).length();
    assert!(span > 300.0 * pixel.length());
}
