//! The grid answers exactly as brute force: random soups and meshes, random and
//! adversarial rays, several densities, in f32 and f64. (The workspace-wide
//! suites in the `tests` crate go further; this one guards the grid itself.)

use accel_core::scenes::{terrain, torus, uv_sphere};
use accel_core::{Accelerator, BruteForce, Ray, Real, TraversalCounters, TriangleMesh, Vec3};
use accel_grid::{Grid, GridParams};
use proptest::prelude::*;

/// A scene description, kept small so that failures shrink to something readable.
#[derive(Clone, Debug)]
enum SceneSpec {
    /// Triangles with vertices on a coarse lattice (many exact coincidences
    /// with cell boundaries), scaled and offset.
    Lattice(Vec<[[i8; 3]; 3]>, f64, f64),
    /// Free random triangles in the unit cube.
    Soup(Vec<[[f64; 3]; 3]>),
    /// A closed mesh: 0 sphere, 1 torus, 2 terrain; scale and offset.
    Mesh(u8, f64, f64),
}

impl SceneSpec {
    fn mesh(&self) -> TriangleMesh<f64> {
        match self {
            Self::Lattice(tris, scale, offset) => {
                let t: Vec<[Vec3<f64>; 3]> = tris
                    .iter()
                    .map(|t| {
                        t.map(|v| {
                            Vec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2])) * *scale
                                + Vec3::splat(*offset)
                        })
                    })
                    .collect();
                TriangleMesh::from_triangles(&t).unwrap()
            }
            Self::Soup(tris) => {
                let t: Vec<[Vec3<f64>; 3]> = tris.iter().map(|t| t.map(Vec3::from)).collect();
                TriangleMesh::from_triangles(&t).unwrap()
            }
            Self::Mesh(kind, scale, offset) => {
                let m = match kind {
                    0 => uv_sphere(Vec3::ZERO, 1.0, 200),
                    1 => torus(Vec3::ZERO, 1.0, 0.4, 12, 8),
                    _ => terrain(300, 3),
                };
                let p = m
                    .positions()
                    .iter()
                    .map(|&p| p * *scale + Vec3::splat(*offset))
                    .collect();
                TriangleMesh::new(p, m.indices().to_vec()).unwrap()
            }
        }
    }
}

fn scene_strategy() -> impl Strategy<Value = SceneSpec> {
    let lattice_vertex = prop::array::uniform3(-4i8..=4);
    let lattice = (
        prop::collection::vec(prop::array::uniform3(lattice_vertex), 1..24),
        prop::sample::select(vec![1.0, 0.25, 1e-3, 1e3]),
        prop::sample::select(vec![0.0, -3.5, 100.0]),
    )
        .prop_map(|(t, s, o)| SceneSpec::Lattice(t, s, o));
    let soup = prop::collection::vec(
        prop::array::uniform3(prop::array::uniform3(0.0..1.0f64)),
        1..40,
    )
    .prop_map(SceneSpec::Soup);
    let mesh = (
        0u8..3,
        prop::sample::select(vec![1.0, 0.01, 50.0]),
        prop::sample::select(vec![0.0, 7.0]),
    )
        .prop_map(|(k, s, o)| SceneSpec::Mesh(k, s, o));
    prop_oneof![lattice, soup, mesh]
}

/// How a ray is aimed, relative to the scene's bounds and vertices.
#[derive(Clone, Debug)]
enum RaySpec {
    /// Origin in the grown bounds (unit coordinates), any direction, some
    /// components forced to +0 or -0.
    Random([f64; 3], [f64; 3], [u8; 3]),
    /// From a random point toward vertex `v` (index modulo the count), or the
    /// midpoint of an edge when `edge` is set.
    AtVertex([f64; 3], usize, bool),
    /// Starting on a vertex of the scene, in a random direction.
    FromVertex(usize, [f64; 3]),
}

fn ray_strategy() -> impl Strategy<Value = RaySpec> {
    let unit3 = prop::array::uniform3(-0.25..1.25f64);
    let dir3 = prop::array::uniform3(-1.0..1.0f64);
    prop_oneof![
        (unit3.clone(), dir3.clone(), prop::array::uniform3(0u8..6))
            .prop_map(|(o, d, z)| RaySpec::Random(o, d, z)),
        (unit3, any::<usize>(), any::<bool>()).prop_map(|(o, v, e)| RaySpec::AtVertex(o, v, e)),
        (any::<usize>(), dir3).prop_map(|(v, d)| RaySpec::FromVertex(v, d)),
    ]
}

fn make_ray<T: Real>(
    spec: &RaySpec,
    mesh: &TriangleMesh<T>,
    t_window: (f64, f64),
) -> Option<Ray<T>> {
    let b = mesh.bounds();
    let lerp = |u: [f64; 3]| {
        Vec3::new(
            b.min.x + (b.max.x - b.min.x) * T::from_f64(u[0]),
            b.min.y + (b.max.y - b.min.y) * T::from_f64(u[1]),
            b.min.z + (b.max.z - b.min.z) * T::from_f64(u[2]),
        )
    };
    let vertex = |i: usize| mesh.positions()[i % mesh.positions().len()];
    let (origin, dir) = match spec {
        RaySpec::Random(o, d, zero) => {
            let mut d = Vec3::from(d.map(T::from_f64));
            for a in 0..3 {
                match zero[a] {
                    0 => d[a] = T::ZERO,
                    1 => d[a] = -T::ZERO,
                    _ => {}
                }
            }
            (lerp(*o), d)
        }
        RaySpec::AtVertex(o, v, edge) => {
            let target = if *edge {
                let t = mesh.indices()[v % mesh.indices().len()];
                (mesh.positions()[t[0] as usize] + mesh.positions()[t[1] as usize]) * T::HALF
            } else {
                vertex(*v)
            };
            let origin = lerp(*o);
            (origin, target - origin)
        }
        RaySpec::FromVertex(v, d) => (vertex(*v), Vec3::from(d.map(T::from_f64))),
    };
    let (t_min, t_max) = (T::from_f64(t_window.0), T::from_f64(t_window.1));
    Ray::with_interval(origin, dir, t_min, t_max).ok()
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

fn window_strategy() -> impl Strategy<Value = (f64, f64)> {
    prop_oneof![
        3 => Just((0.0, f64::INFINITY)),
        1 => (0.0..2.0f64, 0.0..3.0f64),
        1 => Just((1e-4, f64::INFINITY)),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn grid_equals_brute_force(
        scene in scene_strategy(),
        rays in prop::collection::vec((ray_strategy(), window_strategy()), 1..48),
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
        rays in prop::collection::vec((ray_strategy(), window_strategy()), 1..64),
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

/// Whether `grid` answers `ray` as `brute` does, nearest and any hit.
fn agrees<T: Real>(
    grid: &Grid<'_, T, TriangleMesh<T>>,
    brute: &BruteForce<'_, T, TriangleMesh<T>>,
    ray: &Ray<T>,
    what: &str,
) -> Result<(), TestCaseError> {
    let want = brute.intersect(ray).unwrap();
    let got = grid.intersect(ray).unwrap();
    prop_assert_eq!(
        got.map(|h| h.bit_key()),
        want.map(|h| h.bit_key()),
        "{} {}: ray {:?}: grid {:?} brute {:?}",
        T::NAME,
        what,
        ray,
        got,
        want
    );
    prop_assert_eq!(
        grid.occluded(ray).unwrap(),
        want.is_some(),
        "{} {} occluded, ray {:?}",
        T::NAME,
        what,
        ray
    );
    Ok(())
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
        rays in prop::collection::vec((ray_strategy(), window_strategy()), 1..64),
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
