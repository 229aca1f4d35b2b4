//! The places in a scene worth aiming rays at: vertices, edges, surfaces.

use crate::{Mixed, Scene};
use accel_core::{Aabb, PrimitiveSet, Real, TriangleMesh, Vec3};
use std::collections::BTreeSet;

/// The surface of one primitive, for rays that start on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Surface<T> {
    /// A triangle's vertices.
    Triangle([Vec3<T>; 3]),
    /// A sphere's center and radius.
    Sphere(Vec3<T>, T),
}

impl<T: Real> Surface<T> {
    /// A point of the surface for `uv ∈ [0, 1]²`: barycentric for triangles
    /// (folded into the triangle), longitude and latitude for spheres.
    /// Computed in `f64` and rounded, so it lies on the surface up to rounding.
    #[must_use]
    pub fn point(&self, uv: [f64; 2]) -> Vec3<T> {
        match *self {
            Self::Triangle([a, b, c]) => {
                let (mut u, mut v) = (uv[0], uv[1]);
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                let (a, b, c) = (a.cast::<f64>(), b.cast::<f64>(), c.cast::<f64>());
                (a + (b - a) * u + (c - a) * v).cast()
            }
            Self::Sphere(center, r) => {
                let phi = uv[0] * core::f64::consts::TAU;
                let z = 2.0 * uv[1] - 1.0;
                let s = (1.0 - z * z).max(0.0).sqrt();
                let dir = Vec3::new(s * phi.cos(), s * phi.sin(), z);
                (center.cast::<f64>() + dir * r.to_f64()).cast()
            }
        }
    }
}

/// Vertices, edges and surfaces of a scene, and a frame around it.
#[derive(Clone, Debug)]
pub struct Landmarks<T> {
    /// Union of the primitives' bounds (empty for an empty scene).
    pub bounds: Aabb<T>,
    /// Triangle vertices; sphere centers and their six extreme points.
    pub vertices: Vec<Vec3<T>>,
    /// Triangle edges (shared edges once).
    pub edges: Vec<[Vec3<T>; 2]>,
    /// One surface per primitive, by primitive index.
    pub surfaces: Vec<Surface<T>>,
}

impl<T: Real> Landmarks<T> {
    /// The landmarks of a built scene.
    #[must_use]
    pub fn of(scene: &Scene<T>) -> Self {
        match scene {
            Scene::Mesh(m) => Self::of_mesh(m),
            Scene::Mixed(v) => Self::of_mixed(v),
        }
    }

    /// The landmarks of a triangle mesh: its vertices and its unique edges.
    #[must_use]
    pub fn of_mesh(m: &TriangleMesh<T>) -> Self {
        let mut edge_set = BTreeSet::new();
        for t in m.indices() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edge_set.insert((a.min(b), a.max(b)));
            }
        }
        let p = m.positions();
        Self {
            bounds: union_bounds(m),
            vertices: p.to_vec(),
            edges: edge_set
                .into_iter()
                .map(|(a, b)| [p[a as usize], p[b as usize]])
                .collect(),
            surfaces: (0..m.triangle_count())
                .map(|i| Surface::Triangle(m.triangle(i)))
                .collect(),
        }
    }

    /// The landmarks of a mixed set.
    #[must_use]
    pub fn of_mixed(v: &[Mixed<T>]) -> Self {
        let mut vertices = Vec::new();
        let mut edges = Vec::new();
        let mut surfaces = Vec::new();
        for item in v {
            match item {
                Mixed::Tri(t) => {
                    let [a, b, c] = t.vertices;
                    vertices.extend([a, b, c]);
                    edges.extend([[a, b], [b, c], [c, a]]);
                    surfaces.push(Surface::Triangle(t.vertices));
                }
                Mixed::Ball(s) => {
                    vertices.push(s.center);
                    for axis in 0..3 {
                        for sign in [T::ONE, -T::ONE] {
                            let mut p = s.center;
                            p[axis] += sign * s.radius;
                            vertices.push(p);
                        }
                    }
                    surfaces.push(Surface::Sphere(s.center, s.radius));
                }
            }
        }
        Self {
            bounds: union_bounds(v),
            vertices,
            edges,
            surfaces,
        }
    }

    /// The scene's largest extent; a positive stand-in when it has none (a
    /// point, or nothing).
    #[must_use]
    pub fn size(&self) -> f64 {
        if self.bounds.is_empty() {
            return 1.0;
        }
        let extent = self.bounds.diagonal().max_component().to_f64();
        if extent > 0.0 {
            extent
        } else {
            let at = self.bounds.max_abs_coordinate().to_f64();
            if at > 0.0 { at * 1e-3 } else { 1.0 }
        }
    }

    /// The box ray origins are drawn from: the bounds grown by half the
    /// scene's size on every side (the unit box for an empty scene).
    #[must_use]
    pub fn frame(&self) -> Aabb<f64> {
        if self.bounds.is_empty() {
            return Aabb::new(Vec3::splat(-0.5), Vec3::splat(1.5));
        }
        let b = self.bounds.cast::<f64>();
        b.expanded(0.5 * self.size())
    }

    /// The point at unit coordinates `u` of the frame.
    #[must_use]
    pub fn in_frame(&self, u: [f64; 3]) -> Vec3<T> {
        let f = self.frame();
        Vec3::new(
            f.min.x + (f.max.x - f.min.x) * u[0],
            f.min.y + (f.max.y - f.min.y) * u[1],
            f.min.z + (f.max.z - f.min.z) * u[2],
        )
        .cast()
    }

    /// Vertex `i` (modulo the count); the frame's center when there is none.
    #[must_use]
    pub fn vertex(&self, i: usize) -> Vec3<T> {
        if self.vertices.is_empty() {
            self.frame().center().cast()
        } else {
            self.vertices[i % self.vertices.len()]
        }
    }

    /// Edge `i` (modulo the count); a diagonal of the frame when there is none.
    #[must_use]
    pub fn edge(&self, i: usize) -> [Vec3<T>; 2] {
        if self.edges.is_empty() {
            let f = self.frame();
            [f.min.cast(), f.max.cast()]
        } else {
            self.edges[i % self.edges.len()]
        }
    }

    /// Surface `i` (modulo the count), if the scene has any.
    #[must_use]
    pub fn surface(&self, i: usize) -> Option<Surface<T>> {
        (!self.surfaces.is_empty()).then(|| self.surfaces[i % self.surfaces.len()])
    }
}

/// The union of the primitives' bounds.
fn union_bounds<T: Real, P: PrimitiveSet<T> + ?Sized>(p: &P) -> Aabb<T> {
    (0..p.len()).fold(Aabb::empty(), |b, i| b.union(&p.bounds(i)))
}
