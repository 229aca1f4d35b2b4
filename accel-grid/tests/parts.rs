//! A grid in parts: a small dense part in a large sparse scene, and a floor,
//! each get a uniform grid of their own; the answers stay brute force's.

use accel_core::{Aabb, Accelerator, BruteForce, Real, TraversalCounters, TriangleMesh, Vec3};
use accel_grid::{Grid, GridParams};
use accel_scenes::{
    FlatFieldSpec, flat_field, random_rays, rays_leaving_the_floor, teapot_in_stadium,
};

/// The seed's single grid over the same scene.
fn one_part<T: Real>() -> GridParams<T> {
    GridParams {
        parts: false,
        ..GridParams::default()
    }
}

/// Random rays through the scene's box and through the box around its
/// centre (where the dense part stands) answer as brute force, nearest and
/// any hit.
fn agrees<T: Real>(grid: &Grid<'_, T, TriangleMesh<T>>, mesh: &TriangleMesh<T>, seed: u64) {
    let brute = BruteForce::new(mesh).unwrap();
    let b = brute.bounds();
    let scene = Aabb::new(b.min.cast(), b.max.cast());
    let centre = Aabb::new(Vec3::splat(-1.5), Vec3::splat(1.5));
    let rays = random_rays::<T>(&scene, 1000, seed)
        .into_iter()
        .chain(random_rays::<T>(&centre, 1000, seed + 1));
    for ray in rays {
        let expected = brute.intersect(&ray).unwrap();
        assert_eq!(grid.intersect(&ray).unwrap(), expected, "{ray:?}");
        assert_eq!(grid.occluded(&ray).unwrap(), expected.is_some(), "{ray:?}");
    }
}

#[test]
fn a_dense_part_in_a_large_scene_gets_a_grid_of_its_own() {
    // A sphere of 4,000 triangles of radius 1 in a box 10^4 wide: one grid
    // puts the sphere in one or a few cells, so a ray there tests them all.
    let mesh: TriangleMesh<f32> = teapot_in_stadium(4000, 1e4).cast().unwrap();
    let split = Grid::new(&mesh).unwrap();
    let whole = Grid::with_params(&mesh, &one_part()).unwrap();
    assert_eq!((split.parts().count(), whole.parts().count()), (2, 1));
    // The sphere's part first, its box the sphere's; the walls and floor
    // after it.
    let sphere = split.parts().next().unwrap().geometry().bounds();
    assert!(sphere.max.x <= 1.01 && sphere.min.x >= -1.01, "{sphere:?}");
    let fullest = |g: &Grid<'_, f32, TriangleMesh<f32>>| g.stats().max_leaf_references;
    assert!(
        fullest(&split) * 5 < fullest(&whole),
        "fullest cell: {} in parts, {} in one grid",
        fullest(&split),
        fullest(&whole)
    );
    split.validate().unwrap();
    agrees(&split, &mesh, 7);
    let mesh64: TriangleMesh<f64> = teapot_in_stadium(4000, 1e4);
    let split64 = Grid::new(&mesh64).unwrap();
    assert_eq!(split64.parts().count(), 2);
    agrees(&split64, &mesh64, 8);
}

#[test]
fn rays_leaving_a_flat_floor_open_none_of_its_cells() {
    // A floor of 40 × 25 quads (2,000 triangles) at z = 0 with 4,000
    // triangles standing at its centre: the floor is a grid of its own, with
    // a flat box that a ray spawned just above it and going up misses.
    let spec = FlatFieldSpec {
        quads: [40, 25],
        extent: [80.0, 50.0],
        dense: 4000,
    };
    let mesh: TriangleMesh<f32> = flat_field(&spec).cast().unwrap();
    let split = Grid::new(&mesh).unwrap();
    let whole = Grid::with_params(&mesh, &one_part()).unwrap();
    assert_eq!((split.parts().count(), whole.parts().count()), (2, 1));
    let floor = split.parts().nth(1).unwrap().geometry().bounds();
    assert_eq!((floor.min.z, floor.max.z), (0.0, 0.0));
    let brute = BruteForce::new(&mesh).unwrap();
    let (mut with_parts, mut without) =
        (TraversalCounters::default(), TraversalCounters::default());
    let rays = rays_leaving_the_floor::<f32>(&spec, 1e-5);
    assert_eq!(rays.len(), 191);
    for ray in rays {
        let expected = brute.intersect(&ray).unwrap();
        assert_eq!(
            split.intersect_counted(&ray, &mut with_parts).unwrap(),
            expected
        );
        assert_eq!(
            whole.intersect_counted(&ray, &mut without).unwrap(),
            expected
        );
        assert_eq!(split.occluded(&ray).unwrap(), expected.is_some());
    }
    assert_eq!(
        (with_parts.nodes, with_parts.prims),
        (0, 0),
        "the floor's cells are opened"
    );
    assert!(
        without.prims >= 191,
        "premise: one grid tests the floor's triangles ({})",
        without.prims
    );
    agrees(&split, &mesh, 9);
}

#[test]
fn region_queries_gather_from_every_part() {
    let mesh: TriangleMesh<f32> = teapot_in_stadium(2000, 1e4).cast().unwrap();
    let split = Grid::new(&mesh).unwrap();
    let brute = BruteForce::new(&mesh).unwrap();
    assert_eq!(split.parts().count(), 2);
    // Around the sphere (part one), at a wall (part two), and both.
    for (lo, hi) in [
        (Vec3::splat(-0.5f32), Vec3::splat(0.5)),
        (Vec3::new(4990.0, -1.0, -1.0), Vec3::new(5000.0, 1.0, 1.0)),
        (Vec3::new(-1.0, -1.0, -2.0), Vec3::new(5000.0, 1.0, 0.0)),
    ] {
        let region = Aabb::new(lo, hi);
        assert_eq!(
            split.query_region(&region).unwrap(),
            brute.query_region(&region).unwrap()
        );
    }
}
