//! Watertightness: rays from outside a closed mesh aimed at its shared edges
//! and vertices must hit, in every accelerator. Zero leaks is the only pass.
//!
//! A ray is aimed so that it crosses the surface at the target, not grazes
//! it: it comes from the side that every triangle around the target (around
//! both ends of an edge) faces, by a margin. Then the triangles around the
//! target cover a neighbourhood of it as the ray sees them, and the
//! watertight triangle test must report one of them (or an earlier hit),
//! whatever the rounding of the ray.

use crate::registry::accelerators;
use accel_core::{Accelerator, BruteForce, PrimitiveSet, Ray, Real, TriangleMesh, Vec3};
use std::collections::HashMap;

/// What a ray is aimed at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// A vertex (index modulo the count).
    Vertex(usize),
    /// A point of an edge (index modulo the count; `s` = 0 and 1 are its ends).
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

/// A closed triangle mesh with its adjacency, ready to aim rays at.
#[derive(Clone, Debug)]
pub struct ClosedMesh<'a, T> {
    mesh: &'a TriangleMesh<T>,
    normals: Vec<Vec3<f64>>,
    vertex_faces: Vec<Vec<u32>>,
    edges: Vec<(u32, u32)>,
    size: f64,
}

/// The smallest cosine between the approach direction and the normal of a
/// triangle around the target.
const MIN_COSINE: f64 = 0.1;

impl<'a, T: Real> ClosedMesh<'a, T> {
    /// The mesh with its adjacency, or `None` if it is not closed (some
    /// directed edge is not used exactly once with its twin used once).
    #[must_use]
    pub fn new(mesh: &'a TriangleMesh<T>) -> Option<Self> {
        let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
        for t in mesh.indices() {
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        if mesh.triangle_count() == 0
            || directed
                .iter()
                .any(|(&(a, b), &n)| n != 1 || directed.get(&(b, a)) != Some(&1))
        {
            return None;
        }
        let mut edges: Vec<(u32, u32)> = directed.keys().copied().filter(|&(a, b)| a < b).collect();
        edges.sort_unstable();
        let mut vertex_faces = vec![Vec::new(); mesh.positions().len()];
        let normals = (0..mesh.triangle_count())
            .map(|i| {
                for &v in &mesh.indices()[i] {
                    vertex_faces[v as usize].push(i as u32);
                }
                let [a, b, c] = mesh.triangle(i).map(|p| p.cast::<f64>());
                let n = (b - a).cross(c - a);
                let len = n.length();
                if len > 0.0 && len.is_finite() {
                    n / len
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        let b = mesh.bounds();
        let size = b.diagonal().max_component().to_f64().max(f64::MIN_POSITIVE);
        Some(Self {
            mesh,
            normals,
            vertex_faces,
            edges,
            size,
        })
    }

    /// Number of distinct edges.
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The ray for `aim`, or `None` when the target's triangles do not all
    /// face one side by the margin (a silhouette, a saddle or a degenerate
    /// triangle around it), where a miss would be legitimate.
    #[must_use]
    pub fn ray(&self, aim: &Aim) -> Option<Ray<T>> {
        let p = self.mesh.positions();
        let (target, around): (Vec3<f64>, Vec<u32>) = match aim.target {
            Target::Vertex(i) => {
                let v = i % p.len();
                (p[v].cast(), self.vertex_faces[v].clone())
            }
            Target::Edge(i, s) => {
                let (a, b) = self.edges[i % self.edges.len()];
                let (pa, pb) = (p[a as usize].cast::<f64>(), p[b as usize].cast::<f64>());
                let mut faces = self.vertex_faces[a as usize].clone();
                faces.extend(&self.vertex_faces[b as usize]);
                (pa + (pb - pa) * s, faces)
            }
        };
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
        let tilted = (mean + Vec3::from(aim.jitter) * 0.3).normalized();
        let approach = if tilted.is_finite() && faces_all(tilted) {
            tilted
        } else if faces_all(mean) {
            mean
        } else {
            return None;
        };
        let distance = self.size * 10f64.powi(aim.distance_exp);
        let origin: Vec3<T> = (target + approach * distance).cast();
        let direction = target.cast::<T>() - origin;
        Ray::new(origin, direction).ok()
    }
}

/// Rays (by index) that hit nothing, per accelerator, brute force first.
///
/// # Errors
/// A message if an accelerator cannot be built or refuses a valid ray.
pub fn leaks<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    rays: &[Ray<T>],
) -> Result<Vec<(&'static str, Vec<usize>)>, String> {
    let mut out = Vec::new();
    let brute = BruteForce::new(prims).map_err(|e| e.to_string())?;
    out.push(("brute (reference)", missed(&brute, rays)?));
    for entry in accelerators::<T, P>() {
        let acc = (entry.build)(prims).map_err(|e| format!("{}: {e}", entry.name))?;
        out.push((entry.name, missed(&*acc, rays)?));
    }
    Ok(out)
}

fn missed<T: Real>(acc: &dyn Accelerator<T>, rays: &[Ray<T>]) -> Result<Vec<usize>, String> {
    let mut out = Vec::new();
    for (i, r) in rays.iter().enumerate() {
        if acc.intersect(r).map_err(|e| e.to_string())?.is_none() {
            out.push(i);
        }
    }
    Ok(out)
}

/// Fails with the leaking rays if any accelerator leaks.
///
/// # Errors
/// A message listing, per leaking accelerator, the count and the first rays.
pub fn assert_no_leaks<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    rays: &[Ray<T>],
) -> Result<(), String> {
    let report = leaks(prims, rays)?;
    let leaking: Vec<String> = report
        .iter()
        .filter(|(_, l)| !l.is_empty())
        .map(|(name, l)| {
            let first: Vec<&Ray<T>> = l.iter().take(3).map(|&i| &rays[i]).collect();
            format!(
                "{name} ({}): {} of {} rays leaked, first {first:?}",
                T::NAME,
                l.len(),
                rays.len()
            )
        })
        .collect();
    if leaking.is_empty() {
        Ok(())
    } else {
        Err(leaking.join("\n"))
    }
}
