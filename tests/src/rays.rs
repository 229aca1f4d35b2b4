//! Ray descriptions, and how they become concrete rays against a scene
//! ([`RayContext`]).
//!
//! Descriptions are in scene-relative terms (unit coordinates of the frame
//! around the scene, indices of vertices, edges, primitives, probe-grid cells
//! and boundaries, taken modulo their counts), so that any description fits
//! any scene and shrinks to something readable.

use crate::registry::enclosing_region_params;
use crate::{Landmarks, Surface};
use accel_core::{Aabb, PrimitiveSet, Ray, Real, Vec3};
use accel_grid::cells::GridGeometry;
use accel_grid::{Grid, GridParams};

/// The densities of the probe grids whose cell faces, edges and corners the
/// rays aim along (the registry's grid densities).
pub const PROBE_DENSITIES: [f64; 4] = [0.5, 1.0, 2.0, 4.0];

/// What rays are aimed at: the scene's landmarks and the geometry of grids
/// built over it.
#[derive(Clone, Debug)]
pub struct RayContext<T> {
    /// Vertices, edges, surfaces and the frame.
    pub landmarks: Landmarks<T>,
    /// The probe grids' geometries, from [`Grid::parts`]: every part's, per
    /// density of [`PROBE_DENSITIES`], then the enclosing-region grid.
    pub grids: Vec<GridGeometry<T>>,
}

impl<T: Real> RayContext<T> {
    /// Builds the probe grids over `prims`.
    #[must_use]
    pub fn new<P: PrimitiveSet<T> + ?Sized>(prims: &P, landmarks: Landmarks<T>) -> Self {
        let mut params: Vec<GridParams<T>> = PROBE_DENSITIES
            .iter()
            .map(|&m| GridParams::with_density(m))
            .collect();
        params.extend(enclosing_region_params(prims).ok());
        let grids = params
            .iter()
            .filter_map(|p| Grid::with_params(prims, p).ok())
            .flat_map(|g| g.parts().map(|p| p.geometry().clone()).collect::<Vec<_>>())
            .collect();
        Self { landmarks, grids }
    }

    /// Probe grid `i` (modulo the count).
    pub(crate) fn grid(&self, i: usize) -> Option<&GridGeometry<T>> {
        (!self.grids.is_empty()).then(|| &self.grids[i % self.grids.len()])
    }

    /// Boundary `k` (modulo the count) of probe grid `grid` along `axis`.
    fn boundary(&self, grid: usize, axis: usize, k: usize) -> T {
        match self.grid(grid) {
            Some(g) => {
                let b = g.boundaries(axis);
                b[k % b.len()]
            }
            None => self.landmarks.vertex(k)[axis],
        }
    }
}

/// How a ray is aimed.
#[derive(Clone, Debug, PartialEq)]
pub enum RaySpec {
    /// From a point of the frame in any direction; `zero[a]` = 1 forces the
    /// component to +0 and 2 to −0; the direction is scaled by `2^len_exp`.
    Random {
        /// Origin, unit coordinates of the frame.
        origin: [f64; 3],
        /// Direction.
        dir: [f64; 3],
        /// Forced zero components.
        zero: [u8; 3],
        /// Direction length exponent (base 2).
        len_exp: i32,
    },
    /// Parallel to an axis: ±1 along it, ±0 on the other two.
    Axis {
        /// Origin, unit coordinates of the frame.
        origin: [f64; 3],
        /// The axis.
        axis: usize,
        /// Direction −1 instead of +1.
        negative: bool,
        /// −0 instead of +0 on the other two axes.
        zero_neg: [bool; 2],
    },
    /// In the plane of a cell face: the origin's `axis` coordinate is exactly
    /// boundary `k` of probe grid `grid`, and the direction is ±0 along `axis`.
    CellFace {
        /// Probe grid.
        grid: usize,
        /// The face's normal axis.
        axis: usize,
        /// Boundary index.
        k: usize,
        /// Origin, unit coordinates of the frame (the `axis` one is replaced).
        origin: [f64; 3],
        /// Direction (the `axis` component is replaced by ±0).
        dir: [f64; 3],
        /// −0 instead of +0.
        zero_neg: bool,
    },
    /// Along a grid edge: the line where boundaries `k` of the two axes
    /// other than `axis` meet, walked along `axis`.
    GridEdge {
        /// Probe grid.
        grid: usize,
        /// The edge's direction axis.
        axis: usize,
        /// Boundary indices of the axes `axis + 1` and `axis + 2`.
        k: [usize; 2],
        /// Where the origin sits along `axis`, unit coordinates of the frame.
        along: f64,
        /// Walk toward −axis.
        negative: bool,
        /// −0 instead of +0 on the two other axes.
        zero_neg: [bool; 2],
    },
    /// Through the grid corner where boundaries `k` meet: from a point of the
    /// frame, or starting on the corner in direction `from_corner`.
    CellCorner {
        /// Probe grid.
        grid: usize,
        /// Boundary index per axis.
        k: [usize; 3],
        /// Origin, unit coordinates of the frame.
        origin: [f64; 3],
        /// If set, the ray starts on the corner in this direction.
        from_corner: Option<[f64; 3]>,
    },
    /// From a point of the frame toward a vertex.
    AtVertex {
        /// Origin, unit coordinates of the frame.
        origin: [f64; 3],
        /// Vertex index.
        vertex: usize,
    },
    /// From a point of the frame toward a point of an edge (`s` = 0 and 1
    /// are its ends).
    AtEdge {
        /// Origin, unit coordinates of the frame.
        origin: [f64; 3],
        /// Edge index.
        edge: usize,
        /// Position along the edge.
        s: f64,
    },
    /// Along an edge (edge-on to its triangles), starting `before` edge
    /// lengths ahead of it.
    AlongEdge {
        /// Edge index.
        edge: usize,
        /// Start distance, in edge lengths (0: on the vertex).
        before: f64,
        /// Walk the edge from its other end.
        reverse: bool,
    },
    /// In the axis-aligned plane through a vertex (where a kD-tree puts its
    /// split candidates): ±0 along `axis`.
    VertexPlane {
        /// Vertex index.
        vertex: usize,
        /// The plane's normal axis.
        axis: usize,
        /// Origin, unit coordinates of the frame (the `axis` one is replaced).
        origin: [f64; 3],
        /// Direction (the `axis` component is replaced by ±0).
        dir: [f64; 3],
        /// −0 instead of +0.
        zero_neg: bool,
    },
    /// From a point on a primitive's surface, with `t_min` = `eps` scene sizes
    /// (0 or small).
    OnSurface {
        /// Primitive index.
        prim: usize,
        /// Surface coordinates.
        uv: [f64; 2],
        /// Direction.
        dir: [f64; 3],
        /// `t_min`, in scene sizes along the ray.
        eps: f64,
    },
    /// From a vertex of the scene.
    FromVertex {
        /// Vertex index.
        vertex: usize,
        /// Direction.
        dir: [f64; 3],
    },
    /// From a point inside a primitive's bounds (so inside one of its cells).
    InPrimitiveBox {
        /// Primitive index.
        prim: usize,
        /// Unit coordinates in its bounds.
        at: [f64; 3],
        /// Direction.
        dir: [f64; 3],
    },
    /// From a point inside a cell of a probe grid.
    InCell {
        /// Probe grid.
        grid: usize,
        /// Cell (linear index).
        cell: usize,
        /// Unit coordinates in the cell.
        at: [f64; 3],
        /// Direction.
        dir: [f64; 3],
    },
}

fn lerp_box<T: Real>(b: &Aabb<f64>, u: [f64; 3]) -> Vec3<T> {
    Vec3::new(
        b.min.x + (b.max.x - b.min.x) * u[0],
        b.min.y + (b.max.y - b.min.y) * u[1],
        b.min.z + (b.max.z - b.min.z) * u[2],
    )
    .cast()
}

fn signed_zero<T: Real>(negative: bool) -> T {
    if negative { -T::ZERO } else { T::ZERO }
}

/// A direction that is never the zero vector: `(1, 0, 0)` stands in for one
/// that rounded to zero.
fn nonzero<T: Real>(d: Vec3<T>) -> Vec3<T> {
    if d == Vec3::ZERO {
        Vec3::new(T::ONE, T::ZERO, T::ZERO)
    } else {
        d
    }
}

fn vec<T: Real>(d: [f64; 3]) -> Vec3<T> {
    Vec3::from(d).cast()
}

/// The bounds of a surface, in `f64`.
pub(crate) fn surface_box<T: Real>(s: &Surface<T>) -> Aabb<f64> {
    match *s {
        Surface::Triangle(v) => Aabb::from_points(v.map(|p| p.cast::<f64>())),
        Surface::Sphere(c, r) => {
            let c = c.cast::<f64>();
            let r = Vec3::splat(r.to_f64());
            Aabb::new(c - r, c + r)
        }
    }
}

impl RaySpec {
    /// The ray over `[t_min, +∞]` (`t_min` is 0 except for
    /// [`RaySpec::OnSurface`]). Always valid: a direction that rounds to
    /// zero is replaced.
    #[must_use]
    pub fn resolve<T: Real>(&self, ctx: &RayContext<T>) -> Ray<T> {
        let lm = &ctx.landmarks;
        let mut t_min = T::ZERO;
        let (origin, dir): (Vec3<T>, Vec3<T>) = match *self {
            Self::Random {
                origin,
                dir,
                zero,
                len_exp,
            } => {
                let mut d: Vec3<T> = (Vec3::from(dir) * 2f64.powi(len_exp)).cast();
                for a in 0..3 {
                    match zero[a] {
                        1 => d[a] = T::ZERO,
                        2 => d[a] = -T::ZERO,
                        _ => {}
                    }
                }
                (lm.in_frame(origin), d)
            }
            Self::Axis {
                origin,
                axis,
                negative,
                zero_neg,
            } => {
                let axis = axis % 3;
                let mut d = Vec3::ZERO;
                d[axis] = if negative { -T::ONE } else { T::ONE };
                d[(axis + 1) % 3] = signed_zero(zero_neg[0]);
                d[(axis + 2) % 3] = signed_zero(zero_neg[1]);
                (lm.in_frame(origin), d)
            }
            Self::CellFace {
                grid,
                axis,
                k,
                origin,
                dir,
                zero_neg,
            } => {
                let axis = axis % 3;
                let mut o = lm.in_frame(origin);
                o[axis] = ctx.boundary(grid, axis, k);
                let mut d: Vec3<T> = vec(dir);
                d[axis] = signed_zero(zero_neg);
                if d == Vec3::ZERO {
                    d[(axis + 1) % 3] = T::ONE;
                }
                (o, d)
            }
            Self::GridEdge {
                grid,
                axis,
                k,
                along,
                negative,
                zero_neg,
            } => {
                let axis = axis % 3;
                let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
                let mut o = lm.in_frame([along; 3]);
                o[a1] = ctx.boundary(grid, a1, k[0]);
                o[a2] = ctx.boundary(grid, a2, k[1]);
                let mut d = Vec3::ZERO;
                d[axis] = if negative { -T::ONE } else { T::ONE };
                d[a1] = signed_zero(zero_neg[0]);
                d[a2] = signed_zero(zero_neg[1]);
                (o, d)
            }
            Self::CellCorner {
                grid,
                k,
                origin,
                from_corner,
            } => {
                let corner = Vec3::new(
                    ctx.boundary(grid, 0, k[0]),
                    ctx.boundary(grid, 1, k[1]),
                    ctx.boundary(grid, 2, k[2]),
                );
                match from_corner {
                    Some(d) => (corner, vec(d)),
                    None => {
                        let o = lm.in_frame(origin);
                        (o, corner - o)
                    }
                }
            }
            Self::AtVertex { origin, vertex } => {
                let o = lm.in_frame(origin);
                (o, lm.vertex(vertex) - o)
            }
            Self::AtEdge { origin, edge, s } => {
                let [a, b] = lm.edge(edge).map(|p| p.cast::<f64>());
                let target: Vec3<T> = (a + (b - a) * s).cast();
                let o = lm.in_frame(origin);
                (o, target - o)
            }
            Self::AlongEdge {
                edge,
                before,
                reverse,
            } => {
                let [mut a, mut b] = lm.edge(edge);
                if reverse {
                    core::mem::swap(&mut a, &mut b);
                }
                let d = b - a;
                let o = (a.cast::<f64>() - d.cast::<f64>() * before).cast();
                (o, d)
            }
            Self::VertexPlane {
                vertex,
                axis,
                origin,
                dir,
                zero_neg,
            } => {
                let axis = axis % 3;
                let mut o = lm.in_frame(origin);
                o[axis] = lm.vertex(vertex)[axis];
                let mut d: Vec3<T> = vec(dir);
                d[axis] = signed_zero(zero_neg);
                if d == Vec3::ZERO {
                    d[(axis + 1) % 3] = T::ONE;
                }
                (o, d)
            }
            Self::OnSurface { prim, uv, dir, eps } => {
                let o = lm
                    .surface(prim)
                    .map_or_else(|| lm.in_frame([0.5; 3]), |s| s.point(uv));
                let d = nonzero(vec::<T>(dir));
                t_min = T::from_f64(eps * lm.size() / d.cast::<f64>().length());
                (o, d)
            }
            Self::FromVertex { vertex, dir } => (lm.vertex(vertex), vec(dir)),
            Self::InPrimitiveBox { prim, at, dir } => {
                let o = lm
                    .surface(prim)
                    .map_or_else(|| lm.in_frame(at), |s| lerp_box(&surface_box(&s), at));
                (o, vec(dir))
            }
            Self::InCell {
                grid,
                cell,
                at,
                dir,
            } => {
                let o = match ctx.grid(grid) {
                    Some(g) => {
                        let c = g.cell_bounds(g.cell_coords(cell % g.cell_count()));
                        lerp_box(&c.cast(), at)
                    }
                    None => lm.in_frame(at),
                };
                (o, vec(dir))
            }
        };
        Ray {
            origin,
            direction: nonzero(dir),
            t_min,
            t_max: T::INFINITY,
        }
    }
}
