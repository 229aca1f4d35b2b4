//! Rays aimed at shared edges and vertices of closed parts of a mesh, from
//! outside: the watertightness probe, one generator for the property suites
//! (`accel-tests`' watertightness suite, through [`Aim`]) and the studies
//! (`studies tradeoff`'s leak rays, [`leak_rays`]).
//!
//! A target is an edge shared by exactly two triangles with opposite
//! windings (a manifold, consistently oriented edge), or a vertex all of
//! whose edges are such (a closed fan). The ray comes from the side every
//! triangle around the target faces (each normal at least [`MIN_COSINE`]
//! from the approach direction), so the triangles around the target cover a
//! neighbourhood of it as the ray sees them: a watertight test must report
//! one of them, or something nearer. A ray that reaches the target and hits
//! nothing has *leaked*. Works on any mesh: parts that are not closed simply
//! provide no targets.

use crate::SplitMix64;
use accel_core::{Ray, Real, TriangleMesh, Vec3};

/// The smallest cosine between the approach and a normal around the target.
pub const MIN_COSINE: f64 = 0.1;

/// A leak ray reaches its target at `t = 1`; it is given this much more.
pub const T_MAX: f64 = 1.0 + 1e-3;

/// What a ray is aimed at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// A vertex (index modulo the vertex count).
    Vertex(usize),
    /// A point of a manifold edge (index modulo their count; `s` = 0 and 1
    /// are its ends).
    Edge(usize, f64),
}

/// A target, and where the ray comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aim {
    /// The target.
    pub target: Target,
    /// Tilt of the approach direction away from the mean normal (each
    /// component −1..1; scaled by 0.3, dropped if it breaks the margin).
    pub jitter: [f64; 3],
    /// The origin is `10^distance_exp` mesh sizes from the target.
    pub distance_exp: i32,
}

/// A triangle mesh with the adjacency of its closed parts, ready to aim
/// rays at.
#[derive(Clone, Debug)]
pub struct ClosedParts<'a, T> {
    mesh: &'a TriangleMesh<T>,
    /// Manifold, consistently oriented edges `(a, b, t1, t2)`, `a < b`,
    /// sorted.
    edges: Vec<(u32, u32, u32, u32)>,
    /// Vertices whose every edge is in `edges` (closed fans).
    vertices: Vec<u32>,
    /// Whether a vertex has an edge outside `edges`.
    open: Vec<bool>,
    /// Faces around each vertex: `offsets[v]..offsets[v + 1]` into `faces`.
    offsets: Vec<u32>,
    faces: Vec<u32>,
    normals: Vec<Vec3<f64>>,
    /// Largest extent of the mesh's bounds (at least the smallest normal).
    size: f64,
}

impl<'a, T: Real> ClosedParts<'a, T> {
    /// The adjacency of `mesh`'s closed parts (any mesh: open parts give no
    /// targets).
    #[must_use]
    pub fn new(mesh: &'a TriangleMesh<T>) -> Self {
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
        let mut open = vec![false; nv];
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
                open[a as usize] = true;
                open[b as usize] = true;
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
            .filter(|&v| !open[v as usize] && offsets[v as usize + 1] > offsets[v as usize])
            .collect();
        let normals = (0..idx.len())
            .map(|t| {
                let [a, b, c] = mesh.triangle(t).map(|p| p.cast::<f64>());
                let n = (b - a).cross(c - a);
                let len = n.length();
                if len > 0.0 && len.is_finite() {
                    n / len
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        let size = mesh
            .bounds()
            .diagonal()
            .max_component()
            .to_f64()
            .max(f64::MIN_POSITIVE);
        Self {
            mesh,
            edges,
            vertices,
            open,
            offsets,
            faces,
            normals,
            size,
        }
    }

    /// The adjacency, or `None` if the mesh is empty or not closed (some
    /// edge is not shared by exactly two triangles of opposite windings).
    #[must_use]
    pub fn closed(mesh: &'a TriangleMesh<T>) -> Option<Self> {
        let parts = Self::new(mesh);
        (mesh.triangle_count() > 0 && !parts.open.contains(&true)).then_some(parts)
    }

    /// Number of manifold edges (every edge of a closed mesh).
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The faces around vertex `v`.
    fn fan(&self, v: u32) -> &[u32] {
        &self.faces[self.offsets[v as usize] as usize..self.offsets[v as usize + 1] as usize]
    }

    /// The approach direction for a target surrounded by `around`, if all
    /// of them face it by the margin: the mean normal tilted by `jitter`
    /// (×0.3), or the mean normal itself when the tilt breaks the margin.
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

    /// The ray for `aim` (origin `10^distance_exp` mesh sizes from the
    /// target, which it reaches at `t = 1`; `t_max` infinite), or `None`
    /// when the target is not on a closed part, or its triangles (around
    /// both ends, for an edge) do not all face one side by the margin (a
    /// silhouette, a saddle or a degenerate triangle around it), where a
    /// miss would be legitimate.
    #[must_use]
    pub fn ray(&self, aim: &Aim) -> Option<Ray<T>> {
        let p = self.mesh.positions();
        let (target, around): (Vec3<f64>, Vec<u32>) = match aim.target {
            Target::Vertex(i) => {
                let v = i % p.len().max(1);
                if self.open.get(v).is_none_or(|&o| o) {
                    return None;
                }
                (p[v].cast(), self.fan(v as u32).to_vec())
            }
            Target::Edge(i, s) => {
                if self.edges.is_empty() {
                    return None;
                }
                let (a, b, _, _) = self.edges[i % self.edges.len()];
                let (pa, pb) = (p[a as usize].cast::<f64>(), p[b as usize].cast::<f64>());
                let mut faces = self.fan(a).to_vec();
                faces.extend(self.fan(b));
                (pa + (pb - pa) * s, faces)
            }
        };
        let approach = self.approach(&around, Vec3::from(aim.jitter))?;
        let distance = self.size * 10f64.powi(aim.distance_exp);
        let origin: Vec3<T> = (target + approach * distance).cast();
        let direction = target.cast::<T>() - origin;
        Ray::new(origin, direction).ok()
    }

    /// Up to `count` leak rays (half at edge interiors, half at vertices),
    /// each reaching its target at `t = 1` with `t_max` [`T_MAX`], from 1 to
    /// 100 local feature sizes away; deterministic for a seed. Empty when
    /// the mesh has no closed part.
    #[must_use]
    pub fn leak_rays(&self, count: usize, seed: u64) -> Vec<Ray<f64>> {
        let p = self.mesh.positions();
        let mut rng = SplitMix64::new(seed);
        let mut out = Vec::with_capacity(count);
        let mut attempts = 0;
        while out.len() < count && attempts < 4 * count {
            attempts += 1;
            let jitter = rng.unit_vector();
            let (target, around, size): (Vec3<f64>, Vec<u32>, f64) = if attempts % 2 == 0 {
                if self.edges.is_empty() {
                    continue;
                }
                let e = self.edges[(rng.next_u64() % self.edges.len() as u64) as usize];
                let (pa, pb) = (p[e.0 as usize].cast::<f64>(), p[e.1 as usize].cast::<f64>());
                let s = rng.range(0.05, 0.95);
                (pa + (pb - pa) * s, vec![e.2, e.3], (pb - pa).length())
            } else {
                if self.vertices.is_empty() {
                    continue;
                }
                let v = self.vertices[(rng.next_u64() % self.vertices.len() as u64) as usize];
                let around = self.fan(v).to_vec();
                let pv = p[v as usize].cast::<f64>();
                let size = around
                    .iter()
                    .flat_map(|&f| self.mesh.triangle(f as usize))
                    .map(|q| (q.cast::<f64>() - pv).length())
                    .fold(0.0, f64::max);
                (pv, around, size)
            };
            let Some(approach) = self.approach(&around, jitter) else {
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
}

/// Up to `count` leak rays at `mesh`'s closed parts
/// ([`ClosedParts::leak_rays`]).
#[must_use]
pub fn leak_rays(mesh: &TriangleMesh<f64>, count: usize, seed: u64) -> Vec<Ray<f64>> {
    ClosedParts::new(mesh).leak_rays(count, seed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{random_soup, uv_sphere};
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
