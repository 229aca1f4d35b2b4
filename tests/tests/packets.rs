//! Packets: the grid's, the octree's and the kD-tree's bundle queries
//! ([`Accelerator::intersect_bundle`], [`Accelerator::occluded_bundle`]) on
//! a scene where all three walk bundles by packets (the grid keeps
//! empty-space blocks; the octree is one part with nested grids, which
//! its packets' rays walk alone) answer each ray as brute force does, bit
//! for bit, in f32 and f64: fans of rays from one point (tiles of a camera,
//! mixed direction signs when a fan crosses an axis, ±0 components, rays
//! that start inside the scene and on the surface, some with their own
//! `t` window) and bundles of unrelated rays.

use accel_core::{Accelerator, BruteForce, Hit, QueryError, Ray, Real, TriangleMesh, Vec3};
use accel_grid::Grid;
use accel_kdtree::KdTree;
use accel_octree::Octree;
use accel_scenes::generated::{SplitMix64, torus, uv_sphere};
use proptest::prelude::*;

/// A sphere and a torus apart, so that most of the grid's blocks are empty
/// (the grid keeps blocks, and bundles go by packets) and the octree
/// refines its root cells around them.
fn scene() -> TriangleMesh<f64> {
    let sphere = uv_sphere(Vec3::new(-2.0, 0.0, 0.0), 1.0, 3000);
    let ring = torus(Vec3::new(2.5, 0.5, 0.3), 1.0, 0.25, 40, 24);
    let mut positions = sphere.positions().to_vec();
    let mut indices = sphere.indices().to_vec();
    let base = positions.len() as u32;
    positions.extend_from_slice(ring.positions());
    indices.extend(ring.indices().iter().map(|t| t.map(|i| i + base)));
    TriangleMesh::new(positions, indices).unwrap()
}

/// A bundle: a fan of `w × h` rays from `origin` around `centre`, spread by
/// `spread`, some with a component forced to ±0, or random rays through the
/// scene's box when `fan` is false.
fn bundle(seed: u64, fan: bool, w: usize, h: usize, spread: f64, zero: usize) -> Vec<Ray<f64>> {
    let mut rng = SplitMix64::new(seed);
    let inside = |rng: &mut SplitMix64| {
        Vec3::new(
            rng.range(-3.5, 4.0),
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
        )
    };
    if !fan {
        return (0..w * h)
            .map(|_| {
                let o = inside(&mut rng);
                Ray::new(o, rng.unit_vector()).unwrap()
            })
            .collect();
    }
    let origin = if rng.next_f64() < 0.5 {
        rng.unit_vector() * 9.0
    } else {
        inside(&mut rng)
    };
    let centre = inside(&mut rng) - origin;
    let mut rays = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            let (di, dj) = (i as f64 - w as f64 / 2.0, j as f64 - h as f64 / 2.0);
            let mut d = centre + Vec3::new(spread * di, spread * dj, spread * (di - dj));
            if zero > 0 && (i + j) % zero == 0 {
                let a = (i + 2 * j) % 3;
                d[a] = if (i + j) % 2 == 0 { 0.0 } else { -0.0 };
            }
            // Every fifth ray has a window of its own: starting past the
            // origin, ending before, at or past the fan's centre.
            let ray = if (i + 3 * j) % 5 == 0 {
                let t_min = rng.range(0.0, 0.8);
                Ray::with_interval(origin, d, t_min, t_min + rng.range(0.05, 2.0))
            } else {
                Ray::new(origin, d)
            };
            if let Ok(r) = ray {
                rays.push(r);
            }
        }
    }
    rays
}

/// Every ray of `rays` answered by `accel`'s bundle queries as brute force
/// answers it alone.
fn agrees<T: Real>(
    name: &str,
    accel: &dyn Accelerator<T>,
    brute: &BruteForce<'_, T, TriangleMesh<T>>,
    rays: &[Ray<T>],
) -> Result<(), TestCaseError> {
    let mut nearest: Vec<Result<Option<Hit<T>>, QueryError>> = vec![Ok(None); rays.len()];
    accel.intersect_bundle(rays, &mut nearest);
    let mut any = vec![Ok(false); rays.len()];
    accel.occluded_bundle(rays, &mut any);
    for (i, r) in rays.iter().enumerate() {
        let want = brute.intersect(r).unwrap();
        let got = nearest[i].unwrap();
        prop_assert_eq!(
            got.map(|h| h.bit_key()),
            want.map(|h| h.bit_key()),
            "{}: ray {} of {} ({}): {:?}",
            name,
            i,
            rays.len(),
            T::NAME,
            r
        );
        prop_assert_eq!(
            any[i].unwrap(),
            want.is_some(),
            "{}: occluded, ray {}",
            name,
            i
        );
    }
    Ok(())
}

fn check<T: Real>(mesh: &TriangleMesh<f64>, rays: &[Ray<f64>]) -> Result<(), TestCaseError> {
    let mesh: TriangleMesh<T> = mesh.cast().unwrap();
    let brute = BruteForce::new(&mesh).unwrap();
    let rays: Vec<Ray<T>> = rays.iter().map(Ray::cast).collect();
    let grid = Grid::new(&mesh).unwrap();
    prop_assert!(
        grid.bundles_by_packets(),
        "the grid walks bundles by packets"
    );
    agrees("grid", &grid, &brute, &rays)?;
    let octree = Octree::new(&mesh).unwrap();
    prop_assert!(
        octree.bundles_by_packets(),
        "the octree walks bundles by packets"
    );
    prop_assert!(octree.levels().len() > 1, "the octree has nested grids");
    agrees("octree", &octree, &brute, &rays)?;
    let kdtree = KdTree::new(&mesh).unwrap();
    agrees("kdtree", &kdtree, &brute, &rays)?;
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn packets_answer_as_brute_force(
        seed in any::<u64>(),
        fan in prop::bool::weighted(0.8),
        (w, h) in (4usize..=9, 4usize..=9),
        spread in prop::sample::select(vec![1e-4, 1e-3, 0.01, 0.05, 0.3]),
        zero in 0usize..5,
    ) {
        let mesh = scene();
        let rays = bundle(seed, fan, w, h, spread, zero);
        check::<f32>(&mesh, &rays)?;
        check::<f64>(&mesh, &rays)?;
    }
}
