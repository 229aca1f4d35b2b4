//! The grid answers exactly as brute force: random soups and meshes, random and
//! adversarial rays, several densities, in f32 and f64. (The workspace-wide
//! suites in the `tests` crate go further; this one guards the grid itself.)

use accel_core::{Accelerator, BruteForce, Ray, Real, TraversalCounters, TriangleMesh, Vec3};
use accel_grid::{Grid, GridParams};
use accel_scenes::strategies::{
    self, RaySpec, SceneSpec, agrees, at_vertex_ray, from_vertex_ray, lattice_scene, lattice_tris,
    mesh_scene, random_ray, soup_scene, window,
};
use accel_scenes::uv_sphere;
use proptest::prelude::*;

fn scene_strategy() -> impl Strategy<Value = SceneSpec> {
    prop_oneof![
        lattice_scene(
            lattice_tris(1..24),
            vec![1.0, 0.25, 1e-3, 1e3],
            vec![0.0, -3.5, 100.0]
        ),
        soup_scene(1..40),
        mesh_scene(0..3),
    ]
}

fn ray_strategy() -> impl Strategy<Value = RaySpec> {
    prop_oneof![random_ray(), at_vertex_ray(), from_vertex_ray()]
}

/// The ray `spec` describes (no lattice rays here).
fn make_ray<T: Real>(spec: &RaySpec, mesh: &TriangleMesh<T>, window: (f64, f64)) -> Option<Ray<T>> {
    strategies::make_ray(spec, mesh, (0.25, 0.0), window)
}

fn check<T: Real>(
    spec: &SceneSpec,
    rays: &[(RaySpec, (f64, f64))],
    density: f64,
) -> Result<(), TestCaseError> {
    let Ok(mesh) = spec.mesh().cast::<T>() else {
        return Ok(());
    };
    let brute = BruteForce::new(&mesh).unwrap();
    let grid = Grid::with_params(&mesh, &GridParams::with_density(density)).unwrap();
    grid.validate().map_err(TestCaseError::fail)?;
    for (rs, window) in rays {
        if let Some(ray) = make_ray::<T>(rs, &mesh, *window) {
            agrees(&grid, &brute, &ray, "scene")?;
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn grid_equals_brute_force(
        scene in scene_strategy(),
        rays in prop::collection::vec((ray_strategy(), window(false)), 1..48),
        density in prop::sample::select(vec![0.5, 1.0, 2.0, 4.0]),
    ) {
        check::<f32>(&scene, &rays, density)?;
        check::<f64>(&scene, &rays, density)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// A grid large enough to keep its occupancy bits
    /// ([`accel_grid::build::OCCUPIED_BITS_MIN_CELLS`]), where the walk reads
    /// a bit, not the offsets, for every cell, answers as brute force too:
    /// the closed meshes under a density that gives about twice that many
    /// cells.
    #[test]
    fn large_grid_with_occupied_bits_equals_brute_force(
        kind in 0u8..2,
        scale in prop::sample::select(vec![1.0, 0.01, 50.0]),
        offset in prop::sample::select(vec![0.0, 7.0]),
        rays in prop::collection::vec((ray_strategy(), window(false)), 1..64),
    ) {
        let scene = SceneSpec::Mesh(kind, scale, offset);
        let mesh = scene.mesh();
        let target = 2.0 * accel_grid::build::OCCUPIED_BITS_MIN_CELLS as f64;
        let density = (target / mesh.triangle_count() as f64).cbrt();
        // The f32 copy has the same bounds up to rounding, so the same
        // resolution, far above the threshold either way.
        let grid = Grid::with_params(&mesh, &GridParams::with_density(density)).unwrap();
        prop_assert!(
            grid.cells().has_occupied_bits(),
            "premise: {} cells",
            grid.cells().cell_count()
        );
        check::<f32>(&scene, &rays, density)?;
        check::<f64>(&scene, &rays, density)?;
    }
}

/// Small spheres at `centres` (unit coordinates) of radius `radius`, and a
/// speck at two opposite corners of the unit cube so that the box stays
/// that cube: a scene that is mostly empty space.
fn scattered_spheres(centres: &[[f64; 3]], radius: f64) -> TriangleMesh<f64> {
    let mut tris: Vec<[Vec3<f64>; 3]> = Vec::new();
    for c in centres {
        let sphere = uv_sphere(Vec3::from(*c), radius, 600);
        tris.extend((0..sphere.triangle_count()).map(|i| sphere.triangle(i)));
    }
    for corner in [Vec3::ZERO, Vec3::splat(1.0)] {
        let e = 1e-3;
        let toward = if corner.x == 0.0 { e } else { -e };
        tris.push([
            corner,
            corner + Vec3::new(toward, 0.0, 0.0),
            corner + Vec3::new(0.0, toward, 0.0),
        ]);
    }
    TriangleMesh::from_triangles(&tris).unwrap()
}

/// A ray whose origin is snapped, on the axes flagged, to a boundary of the
/// grid's blocks (`snap[a]` 1), and that also runs in that boundary plane
/// (`snap[a]` 2: a zero direction component), so that it walks along block
/// faces, edges and through block corners.
fn block_plane_ray<T: Real>(
    grid: &Grid<'_, T, TriangleMesh<T>>,
    origin: [f64; 3],
    pick: usize,
    dir: [f64; 3],
    snap: [u8; 3],
) -> Option<Ray<T>> {
    let blocks = grid.blocks()?.geometry();
    let b = grid.geometry().bounds();
    let mut o = Vec3::ZERO;
    let mut d = Vec3::from(dir.map(T::from_f64));
    for a in 0..3 {
        o[a] = b.min[a] + (b.max[a] - b.min[a]) * T::from_f64(origin[a]);
        if snap[a] >= 1 {
            let planes = blocks.boundaries(a);
            o[a] = planes[(pick >> (8 * a)) % planes.len()];
        }
        if snap[a] >= 2 {
            d[a] = T::ZERO;
        }
    }
    Ray::new(o, d).ok()
}

type SnapSpec = ([f64; 3], usize, [f64; 3], [u8; 3]);

/// [`grid_with_blocks_equals_brute_force`] in precision `T`.
fn check_blocks<T: Real>(
    mesh: &TriangleMesh<f64>,
    rays: &[(RaySpec, (f64, f64))],
    snapped: &[SnapSpec],
) -> Result<(), TestCaseError> {
    let Ok(mesh) = mesh.cast::<T>() else {
        return Ok(());
    };
    let brute = BruteForce::new(&mesh).unwrap();
    let params = GridParams::with_density(4.0);
    let grid = Grid::with_params(&mesh, &params).unwrap();
    grid.validate().map_err(TestCaseError::fail)?;
    prop_assert!(
        grid.blocks().is_some(),
        "premise: blocks kept ({} cells)",
        grid.cells().cell_count()
    );
    for (spec, window) in rays {
        if let Some(ray) = make_ray::<T>(spec, &mesh, *window) {
            agrees(&grid, &brute, &ray, "scattered spheres")?;
        }
    }
    for &(origin, pick, dir, snap) in snapped {
        if let Some(ray) = block_plane_ray(&grid, origin, pick, dir, snap) {
            agrees(&grid, &brute, &ray, "in block planes")?;
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// A grid that skips empty space a block at a time
    /// ([`accel_grid::blocks`]) answers as brute force: small spheres in a
    /// box that is mostly empty, with random rays, rays at their vertices
    /// and edges, and rays starting on block boundaries and running along
    /// block faces and edges.
    #[test]
    fn grid_with_blocks_equals_brute_force(
        centres in prop::collection::vec(prop::array::uniform3(0.05..0.95f64), 1..5),
        radius in prop::sample::select(vec![0.01, 0.04]),
        rays in prop::collection::vec((ray_strategy(), window(false)), 1..64),
        snapped in prop::collection::vec(
            (
                prop::array::uniform3(0.0..1.0f64),
                any::<usize>(),
                prop::array::uniform3(-1.0..1.0f64),
                prop::array::uniform3(0u8..3),
            ),
            0..24,
        ),
    ) {
        let mesh = scattered_spheres(&centres, radius);
        check_blocks::<f32>(&mesh, &rays, &snapped)?;
        check_blocks::<f64>(&mesh, &rays, &snapped)?;
    }
}

/// Skipping empty blocks is what cuts a walk's cells: on a scene that is
/// mostly empty space, the same rays open far fewer cells (counted, not
/// timed) with the blocks than without, and get the same answers.
#[test]
fn blocks_cut_the_cells_a_walk_opens() {
    let mesh = scattered_spheres(&[[0.3, 0.6, 0.5], [0.7, 0.2, 0.4]], 0.04);
    let with = Grid::with_params(&mesh, &GridParams::with_density(4.0)).unwrap();
    let without = Grid::with_params(
        &mesh,
        &GridParams {
            skip_empty_blocks: false,
            ..GridParams::with_density(4.0)
        },
    )
    .unwrap();
    assert!(with.blocks().is_some() && without.blocks().is_none());
    let (mut a, mut b) = (TraversalCounters::default(), TraversalCounters::default());
    let mut hits = 0;
    for i in 0..64 {
        for j in 0..64 {
            // From outside the box, across it toward both spheres.
            let target = Vec3::new(f64::from(i) / 63.0, f64::from(j) / 63.0, 0.5);
            let ray = Ray::new(
                Vec3::new(-1.0, 0.45, 2.0),
                target - Vec3::new(-1.0, 0.45, 2.0),
            )
            .unwrap();
            let got = with.intersect_counted(&ray, &mut a).unwrap();
            assert_eq!(got, without.intersect_counted(&ray, &mut b).unwrap());
            hits += usize::from(got.is_some());
        }
    }
    assert!(hits > 0, "premise: some rays hit a sphere");
    assert!(
        a.nodes * 3 < b.nodes,
        "cells opened: {} with blocks, {} without",
        a.nodes,
        b.nodes
    );
}
