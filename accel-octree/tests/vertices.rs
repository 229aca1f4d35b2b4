//! Rays aimed at every vertex and edge midpoint of closed meshes, nested in
//! the octree's grids: where a traversal that loses a cell to rounding would
//! leak. The octree must answer exactly as brute force on each of them, in
//! f32 far from the origin too.

use accel_core::{Aabb, Accelerator, BruteForce, Ray, Real, TriangleMesh, Vec3};
use accel_octree::{Octree, OctreeParams};
use accel_scenes::{box_mesh, teapot_in_stadium, torus, uv_sphere};

/// Every vertex and every edge midpoint of `mesh`'s first `closed` triangles.
fn targets<T: Real>(mesh: &TriangleMesh<T>, closed: usize) -> Vec<Vec3<T>> {
    let p = mesh.positions();
    let mut out = Vec::new();
    for t in &mesh.indices()[..closed] {
        for k in 0..3 {
            let (a, b) = (p[t[k] as usize], p[t[(k + 1) % 3] as usize]);
            out.push(a);
            out.push((a + b) * T::HALF);
        }
    }
    out
}

/// Counts disagreements with brute force for rays from a few origins around
/// `center` toward every target.
fn mismatches<T: Real>(
    mesh: &TriangleMesh<T>,
    closed: usize,
    center: Vec3<f64>,
    reach: f64,
    params: &OctreeParams,
) -> usize {
    let brute = BruteForce::new(mesh).unwrap();
    let octree = Octree::with_params(mesh, params).unwrap();
    octree.validate().unwrap();
    let origins = [
        Vec3::new(2.9, -1.7, 1.3),
        Vec3::new(-3.1, 0.4, -2.2),
        Vec3::new(0.2, 3.3, 0.9),
    ]
    .map(|d| (center + d * reach).cast::<T>());
    let mut bad = 0;
    for target in targets(mesh, closed) {
        for &o in &origins {
            let Ok(ray) = Ray::new(o, target - o) else {
                continue;
            };
            let want = brute.intersect(&ray).unwrap();
            let got = octree.intersect(&ray).unwrap();
            if got.map(|h| h.bit_key()) != want.map(|h| h.bit_key())
                || octree.occluded(&ray).unwrap() != want.is_some()
            {
                bad += 1;
            }
        }
    }
    bad
}

fn presets() -> [OctreeParams; 4] {
    [
        OctreeParams::default(),
        OctreeParams::classic(),
        OctreeParams::grid_root().with_split_threshold(2),
        OctreeParams::default().with_split_threshold(1),
    ]
}

#[test]
fn closed_sphere_far_from_the_origin() {
    let offset = Vec3::new(1.0e3, -2.5e3, 7.0e2);
    let m = uv_sphere(offset, 0.75, 1_200);
    for params in presets() {
        let f32_mesh = m.cast::<f32>().unwrap();
        let n = f32_mesh.triangle_count();
        assert_eq!(
            mismatches(&f32_mesh, n, offset, 1.0, &params),
            0,
            "f32 {params:?}"
        );
        assert_eq!(mismatches(&m, n, offset, 1.0, &params), 0, "f64 {params:?}");
    }
}

#[test]
fn sphere_in_a_stadium_and_a_box_of_quads() {
    let stadium = teapot_in_stadium(2_000, 1.0e4);
    let sphere_tris = uv_sphere(Vec3::ZERO, 1.0, 2_000).triangle_count();
    let boxes = box_mesh(
        &Aabb::new(Vec3::new(-0.5, -0.25, 0.0), Vec3::new(0.5, 0.75, 1.0)),
        8,
    );
    let mut t = torus(Vec3::new(0.3, 0.1, 0.2), 0.6, 0.2, 24, 12);
    t.append(&boxes).unwrap();
    for params in presets() {
        let s32 = stadium.cast::<f32>().unwrap();
        assert_eq!(
            mismatches(&s32, sphere_tris, Vec3::ZERO, 1.5, &params),
            0,
            "{params:?}"
        );
        let t32 = t.cast::<f32>().unwrap();
        let n = t32.triangle_count();
        assert_eq!(
            mismatches(&t32, n, Vec3::ZERO, 2.0, &params),
            0,
            "{params:?}"
        );
    }
}
