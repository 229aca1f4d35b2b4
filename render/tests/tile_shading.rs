//! The tile path ([`Shader::tile`], through bundles) against the per-pixel
//! path ([`Shader::pixel`], one ray at a time): the same pixels, tallies
//! and digests, bit for bit, with every accelerator; the bundle queries
//! really used; and the same first refusal.

use accel::{AccelKind, AccelStats, Accelerator};
use accel_core::spawn::SpawnOffset;
use accel_core::{Aabb, Hit, QueryError, Ray, Real, TraversalCounters, TriangleMesh};
use indicatif::ProgressBar;
use render::app::mesh_in;
use render::scene::{Scene, default_scene, generated_scene};
use render::shade::{Pixel, Shader, Tally};
use render::tile_shade::{BLOCK, PixelError};
use render::tiles::{TILE, Tile, for_each_pixel, for_each_tile};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

/// Not multiples of the tile (16) nor of the block (8).
const WIDTH: u32 = 19;
const HEIGHT: u32 = 13;

fn shader<'a, T: Real>(
    accel: &'a dyn Accelerator<T>,
    mesh: &'a TriangleMesh<T>,
    scene: &'a Scene,
    (spp, ao): (u32, u32),
) -> Shader<'a, T> {
    Shader {
        accel,
        mesh,
        scene,
        width: WIDTH,
        height: HEIGHT,
        spp,
        ao,
        count: false,
        spawn: SpawnOffset::default(),
    }
}

/// A pixel's bits: its colour's, its tally (digest included) and its work.
fn bits(p: &Pixel) -> ([u32; 3], Tally, TraversalCounters) {
    (p.rgb.map(f32::to_bits), p.tally, p.primary_work)
}

/// The image by tiles and one pixel at a time.
fn both_paths<T: Real>(shader: &Shader<'_, T>) -> (Vec<Pixel>, Vec<Pixel>) {
    let bar = ProgressBar::hidden();
    let tiles = for_each_tile(WIDTH, HEIGHT, &bar, |t| shader.tile(t, |_, _| true)).unwrap();
    let pixels = for_each_pixel(WIDTH, HEIGHT, &bar, |x, y| shader.pixel(x, y)).unwrap();
    (tiles, pixels)
}

fn same_image_by_tiles_and_by_pixels<T: Real>(scene: &Scene) {
    let mesh = mesh_in::<T>(scene).unwrap();
    for kind in AccelKind::ALL {
        let accel = accel::build(kind, &mesh).unwrap();
        for (spp, ao) in [(3, 2), (1, 0)] {
            let shader = shader(accel.as_dyn(), &mesh, scene, (spp, ao));
            let (tiles, pixels) = both_paths(&shader);
            let what = format!("{} {kind} {} spp {spp} ao {ao}", scene.name, T::NAME);
            for (i, (a, b)) in tiles.iter().zip(&pixels).enumerate() {
                assert_eq!(bits(a), bits(b), "{what}: pixel {i}");
            }
            let mut tally = Tally::default();
            for p in &tiles {
                tally.add(&p.tally);
            }
            // Premises: every kind of ray was traced, and answered both ways.
            let n = u64::from(WIDTH * HEIGHT * spp);
            assert_eq!(tally.primary, n, "{what}");
            assert!(tally.primary_hits > n / 4, "{what}: {tally:?}");
            assert!(tally.shadow_blocked > 0 || ao == 0, "{what}: {tally:?}");
            assert!(tally.ao_blocked > 0 || ao == 0, "{what}: {tally:?}");
            assert!(tally.shadow > tally.shadow_blocked, "{what}: {tally:?}");
        }
    }
}

#[test]
fn the_default_scene_is_the_same_by_tiles_in_f32_and_f64() {
    let scene = default_scene().unwrap();
    same_image_by_tiles_and_by_pixels::<f32>(&scene);
    same_image_by_tiles_and_by_pixels::<f64>(&scene);
}

#[test]
fn the_teapot_in_a_stadium_is_the_same_by_tiles_in_f32_and_f64() {
    let scene = generated_scene(accel::scenes::GeneratedScene::TeapotInStadium);
    same_image_by_tiles_and_by_pixels::<f32>(&scene);
    same_image_by_tiles_and_by_pixels::<f64>(&scene);
}

/// An accelerator that counts the queries it is asked, and refuses (with
/// an error naming the ray's kind) the rays `refuse` picks.
struct Watched<'a, T: Real> {
    inner: &'a dyn Accelerator<T>,
    refuse: fn(&Ray<T>) -> bool,
    singles: AtomicUsize,
    nearest_bundles: AtomicUsize,
    nearest_bundle_rays: AtomicUsize,
    any_bundles: AtomicUsize,
    any_bundle_rays: AtomicUsize,
    largest_nearest_bundle: AtomicUsize,
}

impl<'a, T: Real> Watched<'a, T> {
    fn new(inner: &'a dyn Accelerator<T>, refuse: fn(&Ray<T>) -> bool) -> Self {
        Self {
            inner,
            refuse,
            singles: AtomicUsize::new(0),
            nearest_bundles: AtomicUsize::new(0),
            nearest_bundle_rays: AtomicUsize::new(0),
            any_bundles: AtomicUsize::new(0),
            any_bundle_rays: AtomicUsize::new(0),
            largest_nearest_bundle: AtomicUsize::new(0),
        }
    }

    /// The refusal of a ray `refuse` picks: a camera ray (unbounded), a
    /// shadow ray (up to 1) and an occlusion ray (other bounds) are refused
    /// with different errors, so that a test sees which ray was.
    fn check(&self, ray: &Ray<T>) -> Result<(), QueryError> {
        if !(self.refuse)(ray) {
            Ok(())
        } else if ray.t_max == T::INFINITY {
            Err(QueryError::NonFiniteOrigin)
        } else if ray.t_max == T::ONE {
            Err(QueryError::ZeroDirection)
        } else {
            Err(QueryError::NanInterval)
        }
    }
}

impl<T: Real> Accelerator<T> for Watched<'_, T> {
    fn bounds(&self) -> Aabb<T> {
        self.inner.bounds()
    }

    fn intersect(&self, ray: &Ray<T>) -> Result<Option<Hit<T>>, QueryError> {
        self.singles.fetch_add(1, Relaxed);
        self.check(ray)?;
        self.inner.intersect(ray)
    }

    fn occluded(&self, ray: &Ray<T>) -> Result<bool, QueryError> {
        self.singles.fetch_add(1, Relaxed);
        self.check(ray)?;
        self.inner.occluded(ray)
    }

    fn intersect_counted(
        &self,
        ray: &Ray<T>,
        counters: &mut TraversalCounters,
    ) -> Result<Option<Hit<T>>, QueryError> {
        self.singles.fetch_add(1, Relaxed);
        self.check(ray)?;
        self.inner.intersect_counted(ray, counters)
    }

    fn occluded_counted(
        &self,
        ray: &Ray<T>,
        counters: &mut TraversalCounters,
    ) -> Result<bool, QueryError> {
        self.singles.fetch_add(1, Relaxed);
        self.check(ray)?;
        self.inner.occluded_counted(ray, counters)
    }

    fn intersect_bundle(&self, rays: &[Ray<T>], out: &mut [Result<Option<Hit<T>>, QueryError>]) {
        self.nearest_bundles.fetch_add(1, Relaxed);
        self.nearest_bundle_rays.fetch_add(rays.len(), Relaxed);
        self.largest_nearest_bundle.fetch_max(rays.len(), Relaxed);
        self.inner.intersect_bundle(rays, out);
        for (ray, answer) in rays.iter().zip(out) {
            if let Err(e) = self.check(ray) {
                *answer = Err(e);
            }
        }
    }

    fn occluded_bundle(&self, rays: &[Ray<T>], out: &mut [Result<bool, QueryError>]) {
        self.any_bundles.fetch_add(1, Relaxed);
        self.any_bundle_rays.fetch_add(rays.len(), Relaxed);
        self.inner.occluded_bundle(rays, out);
        for (ray, answer) in rays.iter().zip(out) {
            if let Err(e) = self.check(ray) {
                *answer = Err(e);
            }
        }
    }

    fn query_region(&self, region: &Aabb<T>) -> Result<Vec<u32>, QueryError> {
        self.inner.query_region(region)
    }

    fn stats(&self) -> AccelStats {
        self.inner.stats()
    }
}

/// Refuses nothing.
fn none<T: Real>(_: &Ray<T>) -> bool {
    false
}

#[test]
fn tiles_ask_for_bundles_of_a_block_and_counting_asks_ray_by_ray() {
    let scene = default_scene().unwrap();
    let mesh = mesh_in::<f32>(&scene).unwrap();
    let grid = accel::build(AccelKind::Grid, &mesh).unwrap();
    let (spp, ao) = (2, 3);
    let bar = ProgressBar::hidden();

    let watched = Watched::new(grid.as_dyn(), none);
    let shader = shader(&watched, &mesh, &scene, (spp, ao));
    let image = for_each_tile(WIDTH, HEIGHT, &bar, |t| shader.tile(t, |_, _| true)).unwrap();
    let mut tally = Tally::default();
    for p in &image {
        tally.add(&p.tally);
    }
    // Blocks of 8 × 8 in tiles of 16 × 16: across 19 columns, 8 + 8 + 3
    // (the last tile's one block); down 13 rows, 8 + 5.
    assert_eq!((TILE, BLOCK), (16, 8), "premise of the counts below");
    let blocks = 3 * 2;
    assert_eq!(watched.singles.load(Relaxed), 0, "no ray alone");
    assert_eq!(
        watched.nearest_bundles.load(Relaxed),
        blocks * spp as usize,
        "one camera bundle per block and sample"
    );
    assert_eq!(watched.largest_nearest_bundle.load(Relaxed), 64);
    assert_eq!(
        watched.nearest_bundle_rays.load(Relaxed) as u64,
        tally.primary
    );
    assert_eq!(
        watched.any_bundle_rays.load(Relaxed) as u64,
        tally.shadow + tally.ao
    );
    assert!(tally.shadow > 0 && tally.ao > 0, "{tally:?}");
    // At most a shadow bundle and an occlusion bundle per camera bundle.
    let any = watched.any_bundles.load(Relaxed);
    assert!(any > blocks && any <= 2 * blocks * spp as usize, "{any}");

    // Counting work has no bundle query: the same image, ray by ray.
    let counting = Watched::new(grid.as_dyn(), none);
    let shader = Shader {
        count: true,
        ..shader
    };
    let shader = Shader {
        accel: &counting,
        ..shader
    };
    let counted = for_each_tile(WIDTH, HEIGHT, &bar, |t| shader.tile(t, |_, _| true)).unwrap();
    assert_eq!(counting.nearest_bundles.load(Relaxed), 0);
    assert_eq!(counting.any_bundles.load(Relaxed), 0);
    assert_eq!(counting.singles.load(Relaxed) as u64, tally.rays());
    for (a, b) in counted.iter().zip(&image) {
        assert_eq!(a.rgb.map(f32::to_bits), b.rgb.map(f32::to_bits));
        assert_eq!(a.tally.digest, b.tally.digest);
    }
    assert!(counted.iter().any(|p| p.primary_work.nodes > 0));
}

/// A ray's bits, hashed: a pick of rays that no pattern of pixels or ray
/// kinds explains.
fn hashed<T: Real>(ray: &Ray<T>, one_in: u64) -> bool {
    let mut h = 0u64;
    for v in [ray.origin, ray.direction] {
        for a in 0..3 {
            h = render::shade::mix(h, v[a].to_f64().to_bits());
        }
    }
    h.is_multiple_of(one_in)
}

#[test]
fn a_tile_reports_the_refusal_the_pixels_would_meet_first() {
    let mut scene = default_scene().unwrap();
    // The default occlusion distance is 1, the shadow rays' `t_max`: another
    // tells the two kinds of rays apart (`Watched::check`).
    scene.view.ao_distance = 0.75;
    let mesh = mesh_in::<f64>(&scene).unwrap();
    let kdtree = accel::build(AccelKind::KdTree, &mesh).unwrap();
    let pickers: [fn(&Ray<f64>) -> bool; 6] = [
        // Now and then any ray: most tiles fail, at various rays.
        |r| hashed(r, 97),
        // Rarely any ray: some tiles fail, others not.
        |r| hashed(r, 1500),
        // Secondary rays only, often.
        |r| r.t_max != f64::INFINITY && hashed(r, 7),
        // Half the secondary rays: a pixel's shadow ray and some of its
        // occlusion rays are often refused in the same sample.
        |r| r.t_max != f64::INFINITY && hashed(r, 2),
        // Shadow rays only.
        |r| r.t_max == 1.0 && hashed(r, 5),
        // Camera rays only, now and then.
        |r| r.t_max == f64::INFINITY && hashed(r, 11),
    ];
    let whole = Tile {
        x0: 0,
        y0: 0,
        x1: WIDTH,
        y1: HEIGHT,
    };
    let (mut failed, mut passed) = (0, 0);
    for refuse in pickers {
        let watched = Watched::new(kdtree.as_dyn(), refuse);
        let shader = shader(&watched, &mesh, &scene, (2, 3));
        // Every row, or the odd ones only (as a shard owns bands of rows).
        let wants: [fn(u32, u32) -> bool; 2] = [|_, _| true, |_, y| y % 2 == 1];
        for wanted in wants {
            for tile in whole.parts(TILE) {
                let by_tile = shader.tile(tile, wanted);
                let by_pixel: Result<Vec<Pixel>, PixelError> = tile
                    .pixels()
                    .map(|(x, y)| {
                        if !wanted(x, y) {
                            return Ok(Pixel::default());
                        }
                        shader
                            .pixel(x, y)
                            .map_err(|error| PixelError { x, y, error })
                    })
                    .collect();
                match (&by_tile, &by_pixel) {
                    (Ok(a), Ok(b)) => {
                        passed += 1;
                        assert!(a.iter().zip(b).all(|(a, b)| bits(a) == bits(b)));
                    }
                    (a, b) => {
                        failed += 1;
                        assert_eq!(a.as_ref().err(), b.as_ref().err(), "{tile:?}");
                    }
                }
            }
        }
    }
    // Premises: both outcomes were seen.
    assert!(failed > 3 && passed > 3, "{failed} failed, {passed} passed");
}
