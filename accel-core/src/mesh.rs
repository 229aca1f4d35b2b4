//! Indexed triangle meshes: shared vertices, triangles as index triples.

use crate::real::{greater, lesser};
use crate::triangle::{
    clip_triangle_bounds, clip_triangle_bounds_split, intersect_triangle, triangle_overlaps_box,
    triangle_overlaps_boxes,
};
use crate::{Aabb, PreparedRay, PrimHit, PrimitiveSet, Real, Vec3};

/// Why a mesh was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {index} has a non-finite coordinate")]
    NonFiniteVertex {
        /// Index of the vertex.
        index: usize,
    },
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} uses vertex {vertex}, but the mesh has {vertex_count} vertices")]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The offending vertex index.
        vertex: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// More triangles than a `u32` index can name.
    #[error("{count} triangles exceed the limit of {} (u32 indices)", u32::MAX)]
    TooManyTriangles {
        /// Number of triangles given.
        count: usize,
    },
}

/// A triangle mesh with shared vertices. Accelerators store triangle indices
/// into it, never copies of its vertices.
///
/// Construction validates every vertex (finite) and index (in range), so the
/// queries need not.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh<T> {
    positions: Vec<Vec3<T>>,
    indices: Vec<[u32; 3]>,
}

impl<T: Real> TriangleMesh<T> {
    /// A mesh from vertex positions and triangles (index triples).
    ///
    /// # Errors
    /// [`MeshError`] naming the first non-finite vertex or out-of-range index.
    pub fn new(positions: Vec<Vec3<T>>, indices: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if indices.len() > u32::MAX as usize {
            return Err(MeshError::TooManyTriangles {
                count: indices.len(),
            });
        }
        if let Some(index) = positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshError::NonFiniteVertex { index });
        }
        let n = positions.len();
        for (triangle, tri) in indices.iter().enumerate() {
            if let Some(&vertex) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    triangle,
                    vertex,
                    vertex_count: n,
                });
            }
        }
        Ok(Self { positions, indices })
    }

    /// A mesh of unconnected triangles (a soup): three vertices each.
    ///
    /// # Errors
    /// [`MeshError`] as [`TriangleMesh::new`].
    pub fn from_triangles(triangles: &[[Vec3<T>; 3]]) -> Result<Self, MeshError> {
        let positions = triangles.iter().flatten().copied().collect();
        let indices = (0..triangles.len() as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        Self::new(positions, indices)
    }

    /// Vertex positions.
    #[inline]
    #[must_use]
    pub fn positions(&self) -> &[Vec3<T>] {
        &self.positions
    }

    /// Triangles as index triples.
    #[inline]
    #[must_use]
    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }

    /// Number of triangles.
    #[inline]
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The three vertices of triangle `i`.
    ///
    /// # Panics
    /// If `i` is out of range.
    #[inline]
    #[must_use]
    pub fn triangle(&self, i: usize) -> [Vec3<T>; 3] {
        let [a, b, c] = self.indices[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Bounds of all vertices (empty for an empty mesh).
    #[must_use]
    pub fn bounds(&self) -> Aabb<T> {
        Aabb::from_points(self.positions.iter().copied())
    }

    /// Appends another mesh, renumbering its indices.
    ///
    /// # Errors
    /// [`MeshError::TooManyTriangles`] if the sum exceeds the `u32` limit.
    pub fn append(&mut self, other: &Self) -> Result<(), MeshError> {
        let count = self.indices.len() + other.indices.len();
        let base = self.positions.len();
        if count > u32::MAX as usize || base + other.positions.len() > u32::MAX as usize {
            return Err(MeshError::TooManyTriangles { count });
        }
        let base = base as u32;
        self.positions.extend_from_slice(&other.positions);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|i| i + base)));
        Ok(())
    }

    /// The same mesh in another precision (rounding to nearest). Rounding
    /// `f64` to `f32` may overflow to infinity, which is refused.
    ///
    /// # Errors
    /// [`MeshError::NonFiniteVertex`] if a coordinate does not fit in `U`.
    pub fn cast<U: Real>(&self) -> Result<TriangleMesh<U>, MeshError> {
        TriangleMesh::new(
            self.positions.iter().map(|p| p.cast()).collect(),
            self.indices.clone(),
        )
    }
}

impl<T: Real> PrimitiveSet<T> for TriangleMesh<T> {
    #[inline]
    fn len(&self) -> usize {
        self.indices.len()
    }

    /// By plain selects: the vertices are finite (checked when the mesh was
    /// made), so [`Real::min`]'s NaN rule, several instructions a component,
    /// has nothing to decide.
    #[inline]
    fn bounds(&self, i: usize) -> Aabb<T> {
        let [a, b, c] = self.triangle(i);
        let lo = |x: T, y: T, z: T| lesser(lesser(x, y), z);
        let hi = |x: T, y: T, z: T| greater(greater(x, y), z);
        Aabb {
            min: Vec3::new(lo(a.x, b.x, c.x), lo(a.y, b.y, c.y), lo(a.z, b.z, c.z)),
            max: Vec3::new(hi(a.x, b.x, c.x), hi(a.y, b.y, c.y), hi(a.z, b.z, c.z)),
        }
    }

    #[inline]
    fn intersect(&self, i: usize, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        let [a, b, c] = self.triangle(i);
        intersect_triangle(ray, a, b, c, t_max)
    }

    #[inline]
    fn overlaps_box(&self, i: usize, b: &Aabb<T>) -> bool {
        let [p0, p1, p2] = self.triangle(i);
        triangle_overlaps_box(p0, p1, p2, b)
    }

    /// The watertight test translates and shears in `f64` from the exact
    /// `T` inputs ([`intersect_triangle`]).
    fn wide_hits(&self) -> bool {
        true
    }

    #[inline]
    fn watertight_triangle(&self, i: usize) -> Option<[Vec3<T>; 3]> {
        Some(self.triangle(i))
    }

    fn overlaps_boxes(&self, i: usize, boxes: &[Aabb<T>], out: &mut [bool]) {
        triangle_overlaps_boxes(self.triangle(i), boxes, out);
    }

    #[inline]
    fn clipped_bounds(&self, i: usize, b: &Aabb<T>) -> Aabb<T> {
        let [p0, p1, p2] = self.triangle(i);
        clip_triangle_bounds(p0, p1, p2, b)
    }

    #[inline]
    fn clipped_bounds_split(&self, i: usize, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        let [p0, p1, p2] = self.triangle(i);
        clip_triangle_bounds_split(p0, p1, p2, b, axis, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_bad_vertices_and_indices() {
        let p = vec![
            Vec3::new(0.0f32, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        assert!(TriangleMesh::new(p.clone(), vec![[0, 1, 2]]).is_ok());
        assert_eq!(
            TriangleMesh::new(p.clone(), vec![[0, 1, 3]]),
            Err(MeshError::IndexOutOfRange {
                triangle: 0,
                vertex: 3,
                vertex_count: 3
            })
        );
        let mut bad = p.clone();
        bad[1].y = f32::NAN;
        assert_eq!(
            TriangleMesh::new(bad, vec![]),
            Err(MeshError::NonFiniteVertex { index: 1 })
        );
        let big = TriangleMesh::new(vec![Vec3::new(1e300f64, 0.0, 0.0)], vec![]).unwrap();
        assert_eq!(
            big.cast::<f32>(),
            Err(MeshError::NonFiniteVertex { index: 0 })
        );
    }

    #[test]
    fn append_renumbers() {
        let t = [[
            Vec3::new(0.0f64, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]];
        let mut m = TriangleMesh::from_triangles(&t).unwrap();
        let other = m.clone();
        m.append(&other).unwrap();
        assert_eq!(m.indices(), &[[0, 1, 2], [3, 4, 5]]);
        assert_eq!(m.triangle(1), t[0]);
    }
}
