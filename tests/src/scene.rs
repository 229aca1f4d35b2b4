//! Scene descriptions: small, readable values that proptest generates and
//! shrinks, and the primitive sets they build.
//!
//! Every scene is described in unit-sized `f64` coordinates, placed
//! ([`Placement`]: scaled by a power of ten and moved far from the origin),
//! and only then rounded to the precision under test, so that the same
//! description tests `f32` and `f64` at their own extremes.

use crate::Mixed;
use accel_core::{Aabb, Real, TriangleMesh, Vec3};
use accel_scenes::{
    FlatFieldSpec, box_mesh, flat_field, teapot_in_stadium, terrain, torus, uv_sphere,
};

/// A triangle in unit-sized coordinates.
pub type Tri = [[f64; 3]; 3];

/// The direction along which [`Placement::offset`] moves a scene: oblique,
/// so that no axis is spared.
pub const OFFSET_DIRECTION: [f64; 3] = [1.0, -0.75, 0.5];

/// Where a scene sits: `(p + offset·OFFSET_DIRECTION) · 10^scale_exp`.
///
/// The offset is in units of the scene's size, so `offset = 1e7` puts a
/// unit-sized scene ten million sizes from the origin at every scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// The power of ten the scene is scaled by (−20 ..= 20).
    pub scale_exp: i32,
    /// How far from the origin, in scene sizes.
    pub offset: f64,
}

impl Placement {
    /// Unit scale at the origin.
    pub const IDENTITY: Self = Self {
        scale_exp: 0,
        offset: 0.0,
    };

    /// The scale factor `10^scale_exp`.
    #[must_use]
    pub fn scale(&self) -> f64 {
        10f64.powi(self.scale_exp)
    }

    /// Places a point.
    #[must_use]
    pub fn point(&self, p: [f64; 3]) -> Vec3<f64> {
        let o = Vec3::from(OFFSET_DIRECTION) * self.offset;
        (Vec3::from(p) + o) * self.scale()
    }

    /// Places a length.
    #[must_use]
    pub fn length(&self, r: f64) -> f64 {
        r * self.scale()
    }
}

/// A closed mesh (or, for terrain, a heightfield) with shared vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A latitude–longitude sphere of radius 0.5 with about this many triangles.
    Sphere(usize),
    /// A box with each face split into `k × k` quads, extents given.
    Box(u32, [f64; 3]),
    /// A torus (major radius 0.5, minor 0.2), rings × sides.
    Torus(u32, u32),
    /// A heightfield over the unit square: about this many triangles, seed.
    Terrain(usize, u64),
}

impl Shape {
    /// Whether the mesh is closed (every edge shared by two triangles).
    #[must_use]
    pub fn is_closed(&self) -> bool {
        !matches!(self, Self::Terrain(..))
    }

    /// The unit-sized mesh.
    #[must_use]
    pub fn mesh(&self) -> TriangleMesh<f64> {
        let c = Vec3::new(0.5, 0.5, 0.5);
        match *self {
            Self::Sphere(n) => uv_sphere(c, 0.5, n),
            Self::Box(k, e) => box_mesh(&Aabb::new(Vec3::ZERO, Vec3::from(e)), k),
            Self::Torus(rings, sides) => torus(c, 0.5, 0.2, rings, sides),
            Self::Terrain(n, seed) => terrain(n, seed),
        }
    }
}

/// How a degenerate or nearly degenerate triangle is made from `a`, `b`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DegenerateKind {
    /// `c` a relative `10^eps_exp` off the segment `ab` at `s`: a sliver
    /// (one angle close to 180°).
    Sliver,
    /// `c` a relative `10^eps_exp` from `b`: a needle (one edge tiny).
    Needle,
    /// `c` on the segment `ab` at `s` (zero area up to rounding).
    Collinear,
    /// All three vertices equal.
    Point,
    /// `a, a, b`: two equal vertices.
    Repeated,
}

/// A degenerate or nearly degenerate triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Degenerate {
    /// The construction.
    pub kind: DegenerateKind,
    /// First vertex (unit coordinates).
    pub a: [f64; 3],
    /// Second vertex.
    pub b: [f64; 3],
    /// Position along `ab` (0..1).
    pub s: f64,
    /// The relative size of the small dimension is `10^eps_exp`.
    pub eps_exp: i32,
}

impl Degenerate {
    /// The triangle, unplaced.
    #[must_use]
    pub fn triangle(&self) -> [Vec3<f64>; 3] {
        let (a, b) = (Vec3::from(self.a), Vec3::from(self.b));
        let ab = b - a;
        let len = ab.length();
        let eps = 10f64.powi(self.eps_exp) * len;
        let side = ab.cross(Vec3::new(0.3, 0.5, 0.8));
        let side = if side.length() > 0.0 {
            side.normalized()
        } else {
            Vec3::new(1.0, 0.0, 0.0)
        };
        let on = a + ab * self.s;
        match self.kind {
            DegenerateKind::Sliver => [a, b, on + side * eps],
            DegenerateKind::Needle => [a, b, b + side * eps],
            DegenerateKind::Collinear => [a, b, on],
            DegenerateKind::Point => [a, a, a],
            DegenerateKind::Repeated => [a, a, b],
        }
    }
}

/// One primitive of a mixed scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Item {
    /// A triangle.
    Tri(Tri),
    /// A sphere: center and radius (unit coordinates; radius may be 0).
    Ball([f64; 3], f64),
}

/// Which line a [`SceneSpec::Line`] scene lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineKind {
    /// Parallel to x: exactly collinear after rounding.
    AxisX,
    /// Along `(1, 2, 3)`: collinear only up to rounding (near-slivers).
    Oblique,
}

/// A scene, described small enough that a failure shrinks to something readable.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSpec {
    /// No primitives.
    Empty,
    /// Free triangles in the unit cube.
    Soup(Vec<Tri>, Placement),
    /// Triangles with vertices on the lattice `k/4`, `k ∈ −4..=4`: many exact
    /// coincidences with each other and with cell boundaries.
    Lattice(Vec<[[i8; 3]; 3]>, Placement),
    /// A closed mesh or heightfield with shared vertices.
    Closed(Shape, Placement),
    /// A dense sphere (about `dense` triangles, radius 1) in a box of side
    /// `stadium` with a floor: a cluster in empty space. From `dense`
    /// 260 (224 triangles) in a box of side 100 or more, the sphere has
    /// sixteen times as many triangles as the walls and floor (14) and is at
    /// most a sixteenth of the box wide: the kD-tree and the octree build it
    /// apart ([`accel_core::parts`]).
    Teapot {
        /// Triangles of the sphere.
        dense: usize,
        /// Side of the stadium.
        stadium: f64,
        /// Placement.
        place: Placement,
    },
    /// A flat field of `quads × quads` quads over `10 × 10` with two
    /// dense meshes (about `dense` triangles) standing at its centre
    /// ([`accel_scenes::flat_field`]): rays leaving the field.
    FlatField {
        /// Quads along each side of the field.
        quads: u32,
        /// Triangles of the dense meshes.
        dense: usize,
        /// Placement.
        place: Placement,
    },
    /// Every vertex at z = 0 (before placement): a flat scene.
    Flat(Vec<[[f64; 2]; 3]>, Placement),
    /// Every vertex on one line: parameters of the three vertices along it.
    Line(Vec<[f64; 3]>, LineKind, Placement),
    /// A cluster of triangles `10^size_exp` across in a unit scene spanned by
    /// two large triangles from the cluster's corner: every primitive lies in
    /// the cell that holds the corner (and the cluster in that cell alone).
    OneCell {
        /// The cluster's triangles, in the cluster's unit coordinates.
        cluster: Vec<Tri>,
        /// The cluster's size is `10^size_exp` (negative).
        size_exp: i32,
        /// Placement.
        place: Placement,
    },
    /// Copies of a few triangles at several indices (coincident triangles:
    /// the tie rule). A pick `(i, r)` copies `base[i % len]`, rotated `r`
    /// times (`r = 3`: winding reversed).
    Duplicates {
        /// The distinct triangles.
        base: Vec<Tri>,
        /// Which triangle goes at each index.
        picks: Vec<(usize, u8)>,
        /// Placement.
        place: Placement,
    },
    /// Sliver, needle and zero-area triangles.
    Degenerate(Vec<Degenerate>, Placement),
    /// Spheres mixed with triangles (a user-defined primitive type).
    Mixed(Vec<Item>, Placement),
}

/// A built scene: a triangle mesh, or a set of user primitives.
#[derive(Clone, Debug, PartialEq)]
pub enum Scene<T> {
    /// An indexed triangle mesh.
    Mesh(TriangleMesh<T>),
    /// Triangles and spheres.
    Mixed(Vec<Mixed<T>>),
}

impl<T: Real> Scene<T> {
    /// Number of primitives.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Self::Mesh(m) => m.triangle_count(),
            Self::Mixed(v) => v.len(),
        }
    }

    /// True when the scene holds no primitive.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

fn placed_mesh(tris: &[[Vec3<f64>; 3]], place: &Placement) -> TriangleMesh<f64> {
    let t: Vec<[Vec3<f64>; 3]> = tris
        .iter()
        .map(|t| t.map(|p| place.point(p.to_array())))
        .collect();
    TriangleMesh::from_triangles(&t).expect("placed coordinates are finite")
}

/// An indexed mesh placed, its sharing of vertices kept.
fn placed(m: &TriangleMesh<f64>, place: &Placement) -> TriangleMesh<f64> {
    let p = m
        .positions()
        .iter()
        .map(|p| place.point(p.to_array()))
        .collect();
    TriangleMesh::new(p, m.indices().to_vec()).expect("placed coordinates are finite")
}

fn unit_tris(tris: &[Tri]) -> Vec<[Vec3<f64>; 3]> {
    tris.iter().map(|t| t.map(Vec3::from)).collect()
}

/// Rotates a triangle's vertices `r` times; `r = 3` reverses its winding.
#[must_use]
pub fn rotated(t: Tri, r: u8) -> Tri {
    match r % 4 {
        0 => t,
        1 => [t[1], t[2], t[0]],
        2 => [t[2], t[0], t[1]],
        _ => [t[0], t[2], t[1]],
    }
}

impl SceneSpec {
    /// The scene in `f64`, placed.
    #[must_use]
    pub fn build_f64(&self) -> Scene<f64> {
        match self {
            Self::Empty => Scene::Mesh(TriangleMesh::default()),
            Self::Soup(tris, place) => Scene::Mesh(placed_mesh(&unit_tris(tris), place)),
            Self::Lattice(tris, place) => {
                let t: Vec<[Vec3<f64>; 3]> = tris
                    .iter()
                    .map(|t| t.map(|v| Vec3::from(v.map(|k| f64::from(k) * 0.25))))
                    .collect();
                Scene::Mesh(placed_mesh(&t, place))
            }
            Self::Closed(shape, place) => Scene::Mesh(placed(&shape.mesh(), place)),
            Self::Teapot {
                dense,
                stadium,
                place,
            } => Scene::Mesh(placed(&teapot_in_stadium(*dense, *stadium), place)),
            Self::FlatField {
                quads,
                dense,
                place,
            } => Scene::Mesh(placed(
                &flat_field(&FlatFieldSpec {
                    quads: [*quads, *quads],
                    extent: [10.0, 10.0],
                    dense: *dense,
                }),
                place,
            )),
            Self::Flat(tris, place) => {
                let t: Vec<[Vec3<f64>; 3]> = tris
                    .iter()
                    .map(|t| t.map(|[x, y]| Vec3::new(x, y, 0.0)))
                    .collect();
                Scene::Mesh(placed_mesh(&t, place))
            }
            Self::Line(params, kind, place) => {
                let on = |s: f64| match kind {
                    LineKind::AxisX => Vec3::new(s, 0.25, 0.75),
                    LineKind::Oblique => Vec3::new(s, 2.0 * s, 3.0 * s),
                };
                let t: Vec<[Vec3<f64>; 3]> = params.iter().map(|p| p.map(on)).collect();
                Scene::Mesh(placed_mesh(&t, place))
            }
            Self::OneCell {
                cluster,
                size_exp,
                place,
            } => {
                let size = 10f64.powi(*size_exp);
                let corner = Vec3::new(0.41, 0.53, 0.37);
                let mut t: Vec<[Vec3<f64>; 3]> = cluster
                    .iter()
                    .map(|t| t.map(|p| corner + Vec3::from(p) * size))
                    .collect();
                // Two large triangles span the unit cube from the cluster's
                // corner, so every primitive touches the cell holding it.
                t.push([corner, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)]);
                t.push([corner, Vec3::new(0.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 0.0)]);
                Scene::Mesh(placed_mesh(&t, place))
            }
            Self::Duplicates { base, picks, place } => {
                let t: Vec<Tri> = if base.is_empty() {
                    Vec::new()
                } else {
                    picks
                        .iter()
                        .map(|&(i, r)| rotated(base[i % base.len()], r))
                        .collect()
                };
                Scene::Mesh(placed_mesh(&unit_tris(&t), place))
            }
            Self::Degenerate(tris, place) => {
                let t: Vec<[Vec3<f64>; 3]> = tris.iter().map(Degenerate::triangle).collect();
                Scene::Mesh(placed_mesh(&t, place))
            }
            Self::Mixed(items, place) => Scene::Mixed(
                items
                    .iter()
                    .map(|item| match item {
                        Item::Tri(t) => {
                            let [a, b, c] = t.map(|p| place.point(p));
                            Mixed::tri(a, b, c)
                        }
                        Item::Ball(c, r) => Mixed::ball(place.point(*c), place.length(*r)),
                    })
                    .collect(),
            ),
        }
    }

    /// The scene in precision `T` (coordinates rounded to nearest).
    ///
    /// # Panics
    /// If a placed coordinate overflows `T` (the strategies keep them below 1e28).
    #[must_use]
    pub fn build<T: Real>(&self) -> Scene<T> {
        match self.build_f64() {
            Scene::Mesh(m) => Scene::Mesh(m.cast().expect("coordinates fit the precision")),
            Scene::Mixed(v) => Scene::Mixed(v.iter().map(Mixed::cast).collect()),
        }
    }
}
