//! Rays aimed at shared edges and vertices of closed parts of a mesh, from
//! outside: the watertightness probe of `render tradeoff`.
//!
//! A target is an edge shared by exactly two triangles with opposite
//! windings (a manifold, consistently oriented edge), or a vertex all of
//! whose edges are such (a closed fan). The ray comes from the side every
//! triangle around the target faces (each normal at least [`MIN_COSINE`]
//! from the approach direction), so the triangles around the target cover a
//! neighbourhood of it as the ray sees them: a watertight test must report
//! one of them, or something nearer. A ray that reaches the target and hits
//! nothing has *leaked*. Works on any scene: parts that are not closed simply
//! provide no targets.

use accel_core::scenes::SplitMix64;
use accel_core::{Ray, TriangleMesh, Vec3};

/// The smallest cosine between the approach and a normal around the target.
pub const MIN_COSINE: f64 = 0.1;

/// A leak ray reaches its target at `t = 1`; it is given this much more.
pub const T_MAX: f64 = 1.0 + 1e-3;

/// Adjacency of the closed parts of a mesh.
struct Closed {
    /// Manifold, consistently oriented edges `(a, b, t1, t2)`.
    edges: Vec<(u32, u32, u32, u32)>,
    /// Vertices whose every edge is in `edges`.
    vertices: Vec<u32>,
    /// Faces around each vertex: `offsets[v]..offsets[v + 1]` into `faces`.
    offsets: Vec<u32>,
    faces: Vec<u32>,
    normals: Vec<Vec3<f64>>,
}

impl Closed {
    fn new(mesh: &TriangleMesh<f64>) -> Self {
        let idx = mesh.indices();
        let nv = mesh.positions().len();
        // (low, high, triangle, forward) for every edge of every triangle.
        let mut all: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(idx.len() * 3);
        for (t, tri) in idx.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                all.push((a.min(b), a.max(b), t as u32, a < b));
            }
        }
        all.sort_unstable();
        let mut bad = vec![false; nv];
        let mut edges = Vec::new();
        let mut i = 0;
        while i < all.len() {
            let mut j = i + 1;
            while j < all.len() && (all[j].0, all[j].1) == (all[i].0, all[i].1) {
                j += 1;
            }
            let (a, b) = (all[i].0, all[i].1);
            if j - i == 2 && all[i].3 != all[i + 1].3 && a != b {
                edges.push((a, b, all[i].2, all[i + 1].2));
            } else {
                bad[a as usize] = true;
                bad[b as usize] = true;
            }
            i = j;
        }
        let mut offsets = vec![0u32; nv + 1];
        for tri in idx {
            for &v in tri {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..nv {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets.clone();
        let mut faces = vec![0u32; offsets[nv] as usize];
        for (t, tri) in idx.iter().enumerate() {
            for &v in tri {
                faces[fill[v as usize] as usize] = t as u32;
                fill[v as usize] += 1;
            }
        }
        let vertices = (0..nv as u32)
            .filter(|&v| !bad[v as usize] && offsets[v as usize + 1] > offsets[v as usize])
            .collect();
        let normals = (0..idx.len())
            .map(|t| {
                let [a, b, c] = mesh.triangle(t);
                let n = (b - a).cross(c - a);
                let len = n.length();
                if len > 0.0 && len.is_finite() {
                    n / len
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        Self {
            edges,
            vertices,
            offsets,
            faces,
            normals,
        }
    }

    /// The approach direction for a target surrounded by `around`, if all
    /// of them face it by the margin.
    fn approach(&self, around: &[u32], jitter: Vec3<f64>) -> Option<Vec3<f64>> {
        let sum = around
            .iter()
            .fold(Vec3::ZERO, |s, &f| s + self.normals[f as usize]);
        if !(sum.length() > 0.0) {
            return None;
        }
        let mean = sum.normalized();
        let faces_all = |d: Vec3<f64>| {
            around
                .iter()
                .all(|&f| self.normals[f as usize].dot(d) >= MIN_COSINE)
        };
        let tilted = (mean + jitter * 0.3).normalized();
        if tilted.is_finite() && faces_all(tilted) {
            Some(tilted)
        } else if faces_all(mean) {
            Some(mean)
        } else {
            None
        }
    }
}

/// Up to `count` leak rays (half at edges, half at vertices), each reaching
/// its target at `t = 1` with `t_max` [`T_MAX`], from 1 to 100 local feature
/// sizes away; deterministic for a seed. Empty when the mesh has no closed
/// part.
#[must_use]
pub fn leak_rays(mesh: &TriangleMesh<f64>, count: usize, seed: u64) -> Vec<Ray<f64>> {
    let closed = Closed::new(mesh);
    let p = mesh.positions();
    let mut rng = SplitMix64::new(seed);
    let mut out = Vec::with_capacity(count);
    let mut attempts = 0;
    while out.len() < count && attempts < 4 * count {
        attempts += 1;
        let jitter = rng.unit_vector();
        let (target, around, size): (Vec3<f64>, Vec<u32>, f64) = if attempts % 2 == 0 {
            if closed.edges.is_empty() {
                continue;
            }
            let e = closed.edges[(rng.next_u64() % closed.edges.len() as u64) as usize];
            let (pa, pb) = (p[e.0 as usize], p[e.1 as usize]);
            let s = rng.range(0.05, 0.95);
            (pa + (pb - pa) * s, vec![e.2, e.3], (pb - pa).length())
        } else {
            if closed.vertices.is_empty() {
                continue;
            }
            let v = closed.vertices[(rng.next_u64() % closed.vertices.len() as u64) as usize];
            let (lo, hi) = (
                closed.offsets[v as usize] as usize,
                closed.offsets[v as usize + 1] as usize,
            );
            let around = closed.faces[lo..hi].to_vec();
            let pv = p[v as usize];
            let size = around
                .iter()
                .flat_map(|&f| mesh.triangle(f as usize))
                .map(|q| (q - pv).length())
                .fold(0.0, f64::max);
            (pv, around, size)
        };
        let Some(approach) = closed.approach(&around, jitter) else {
            continue;
        };
        let distance = size.max(f64::MIN_POSITIVE) * 10f64.powf(rng.range(0.0, 2.0));
        let origin = target + approach * distance;
        if let Ok(ray) = Ray::with_interval(origin, target - origin, 0.0, T_MAX) {
            out.push(ray);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::scenes::{random_soup, uv_sphere};
    use accel_core::{Accelerator, BruteForce, MollerTrumboreMesh};

    #[test]
    fn closed_meshes_give_rays_that_the_watertight_test_never_leaks() {
        let mesh = uv_sphere(Vec3::new(0.3, -0.2, 0.1), 1.0, 2_000);
        let rays = leak_rays(&mesh, 2_000, 5);
        assert!(rays.len() > 1_900, "{} rays", rays.len());
        let brute = BruteForce::new(&mesh).unwrap();
        let f32_mesh = mesh.cast::<f32>().unwrap();
        let brute32 = BruteForce::new(&f32_mesh).unwrap();
        let fast = MollerTrumboreMesh::new(&f32_mesh);
        let mt = BruteForce::new(&fast).unwrap();
        let mut mt_leaks = 0;
        for r in &rays {
            assert!(brute.occluded(r).unwrap(), "f64 leak: {r:?}");
            let r32 = r.cast::<f32>();
            assert!(brute32.occluded(&r32).unwrap(), "f32 leak: {r32:?}");
            mt_leaks += usize::from(!mt.occluded(&r32).unwrap());
        }
        // The premise of the measurement: the non-watertight test leaks here.
        assert!(mt_leaks > 0);
    }

    #[test]
    fn open_soups_have_no_targets() {
        assert!(leak_rays(&random_soup(200, 1), 100, 1).is_empty());
    }
}
