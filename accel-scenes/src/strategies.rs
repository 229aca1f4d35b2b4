//! Proptest strategies shared by the structure crates' equivalence suites
//! (`accel-grid`, `accel-octree`, `accel-kdtree`: `tests/equivalence.rs`)
//! and the workspace suites of `accel-tests` (feature `proptest`).
//!
//! A suite composes its scene and ray distributions from the blocks here
//! with `prop_oneof!`, keeps its own weights, and resolves what it drew
//! with [`SceneSpec::mesh`] and [`make_ray`]. Descriptions stay small, so
//! a failure shrinks to something readable.

use crate::aimed::{Aim, Target};
use crate::{teapot_in_stadium, terrain, torus, uv_sphere};
use accel_core::{Aabb, Accelerator, Ray, Real, TriangleMesh, Vec3};
use proptest::prelude::*;
use std::ops::Range;

/// Triangles with small integer vertices: `[[x, y, z]; 3]`, each in `-4..=4`.
pub type LatticeTri = [[i8; 3]; 3];

/// A scene description.
#[derive(Clone, Debug)]
pub enum SceneSpec {
    /// Triangles with vertices on a coarse lattice (many exact coincidences
    /// with each other's planes and with cell boundaries), scaled and offset.
    Lattice(Vec<LatticeTri>, f64, f64),
    /// Lattice triangles of two sizes: the second set shrunk by `1/64` into
    /// one corner, a dense cluster among large triangles; offset.
    TwoScales(Vec<LatticeTri>, Vec<LatticeTri>, f64),
    /// Free random triangles in the unit cube.
    Soup(Vec<[[f64; 3]; 3]>),
    /// A generated mesh: 0 sphere, 1 torus, 2 terrain, 3 a sphere in a
    /// stadium (built in two parts, the walls and floor apart); scale and
    /// offset.
    Mesh(u8, f64, f64),
    /// A tessellated sphere of radius 1 with about this many triangles in a
    /// box of the given side with a floor just below it, offset: the teapot
    /// in a stadium.
    Stadium(usize, f64, f64),
}

fn lattice_mesh(tris: &[LatticeTri], scale: f64, offset: Vec3<f64>) -> Vec<[Vec3<f64>; 3]> {
    tris.iter()
        .map(|t| {
            t.map(|v| Vec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2])) * scale + offset)
        })
        .collect()
}

fn moved(m: &TriangleMesh<f64>, scale: f64, offset: f64) -> TriangleMesh<f64> {
    let p = m
        .positions()
        .iter()
        .map(|&p| p * scale + Vec3::splat(offset))
        .collect();
    TriangleMesh::new(p, m.indices().to_vec()).expect("a moved generated mesh is valid")
}

impl SceneSpec {
    /// The mesh, in `f64` (cast it to the precision under test).
    ///
    /// # Panics
    /// Never for what the strategies here draw (finite by construction).
    #[must_use]
    pub fn mesh(&self) -> TriangleMesh<f64> {
        match self {
            Self::Lattice(tris, scale, offset) => {
                TriangleMesh::from_triangles(&lattice_mesh(tris, *scale, Vec3::splat(*offset)))
                    .unwrap()
            }
            Self::TwoScales(big, small, offset) => {
                let mut t = lattice_mesh(big, 1.0, Vec3::splat(*offset));
                t.extend(lattice_mesh(small, 1.0 / 64.0, Vec3::splat(*offset + 1.0)));
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
                    2 => terrain(300, 3),
                    _ => teapot_in_stadium(300, 200.0),
                };
                moved(&m, *scale, *offset)
            }
            Self::Stadium(dense, side, offset) => {
                moved(&teapot_in_stadium(*dense, *side), 1.0, *offset)
            }
        }
    }

    /// The lattice's scale and offset, for [`RaySpec::Lattice`] rays
    /// (`(0.25, 0.0)` for other scenes).
    #[must_use]
    pub fn lattice(&self) -> (f64, f64) {
        match self {
            Self::Lattice(_, s, o) => (*s, *o),
            _ => (0.25, 0.0),
        }
    }
}

/// A lattice vertex, each coordinate in `-4..=4`.
pub fn lattice_vertex() -> impl Strategy<Value = [i8; 3]> + Clone {
    prop::array::uniform3(-4i8..=4)
}

/// A lattice triangle.
pub fn lattice_tri() -> impl Strategy<Value = LatticeTri> + Clone {
    prop::array::uniform3(lattice_vertex())
}

/// `n` lattice triangles.
pub fn lattice_tris(n: Range<usize>) -> impl Strategy<Value = Vec<LatticeTri>> {
    prop::collection::vec(lattice_tri(), n)
}

/// A lattice triangle, or (as often) one flat in an axis plane: one
/// coordinate shared by all three vertices.
pub fn lattice_or_flat_tri() -> impl Strategy<Value = LatticeTri> {
    let flat_triangle =
        (prop::array::uniform3(lattice_vertex()), 0usize..3).prop_map(|(mut t, a)| {
            let c = t[0][a];
            for v in &mut t {
                v[a] = c;
            }
            t
        });
    prop_oneof![lattice_tri(), flat_triangle]
}

/// [`SceneSpec::Lattice`] of the triangles `tris` draws, under one of
/// `scales` and `offsets`.
pub fn lattice_scene(
    tris: impl Strategy<Value = Vec<LatticeTri>>,
    scales: Vec<f64>,
    offsets: Vec<f64>,
) -> impl Strategy<Value = SceneSpec> {
    (
        tris,
        prop::sample::select(scales),
        prop::sample::select(offsets),
    )
        .prop_map(|(t, s, o)| SceneSpec::Lattice(t, s, o))
}

/// [`SceneSpec::TwoScales`]: 1–5 large and 8–39 small lattice triangles.
pub fn two_scales_scene() -> impl Strategy<Value = SceneSpec> {
    (
        lattice_tris(1..6),
        lattice_tris(8..40),
        prop::sample::select(vec![0.0, -2.5, 1e3]),
    )
        .prop_map(|(b, s, o)| SceneSpec::TwoScales(b, s, o))
}

/// [`SceneSpec::Soup`] of `n` triangles in the unit cube.
pub fn soup_scene(n: Range<usize>) -> impl Strategy<Value = SceneSpec> {
    prop::collection::vec(prop::array::uniform3(prop::array::uniform3(0.0..1.0f64)), n)
        .prop_map(SceneSpec::Soup)
}

/// [`SceneSpec::Mesh`] of the `kinds` (`0..3` without the stadium, `0..4`
/// with it), scaled by 1, 0.01 or 50 and offset by 0 or 7.
pub fn mesh_scene(kinds: Range<u8>) -> impl Strategy<Value = SceneSpec> {
    (
        kinds,
        prop::sample::select(vec![1.0, 0.01, 50.0]),
        prop::sample::select(vec![0.0, 7.0]),
    )
        .prop_map(|(k, s, o)| SceneSpec::Mesh(k, s, o))
}

/// [`SceneSpec::Stadium`]: 60 or 400 triangles in a box of side 8, 1e3 or
/// 1e5, offset by 0 or 3e3.
pub fn stadium_scene() -> impl Strategy<Value = SceneSpec> {
    (
        prop::sample::select(vec![60usize, 400]),
        prop::sample::select(vec![8.0, 1e3, 1e5]),
        prop::sample::select(vec![0.0, 3e3]),
    )
        .prop_map(|(d, s, o)| SceneSpec::Stadium(d, s, o))
}

/// How a ray is aimed, relative to the scene's bounds and vertices.
#[derive(Clone, Debug)]
pub enum RaySpec {
    /// Origin in the grown bounds (unit coordinates), any direction scaled
    /// by the last field (tiny and huge directions), some components forced
    /// to +0 (0) or -0 (1).
    Random([f64; 3], [f64; 3], [u8; 3], f64),
    /// From a random point toward vertex `v` (index modulo the count), or the
    /// midpoint of an edge when `edge` is set.
    AtVertex([f64; 3], usize, bool),
    /// Starting on a vertex of the scene, in a random direction.
    FromVertex(usize, [f64; 3]),
    /// From vertex `a` toward vertex `b`: along edges and across clusters.
    VertexToVertex(usize, usize),
    /// From a point on the eighths of the bounds along a small integer
    /// direction (zeros included): along the faces, edges and through the
    /// corners of cells at every level where boundaries fall on eighths
    /// (halving grids, lattice scenes).
    Snapped([i8; 3], [i8; 3]),
    /// From a lattice point of the grown bounds along a lattice direction
    /// (axis-parallel rays in the planes of flat triangles, through their
    /// vertices and edges), with ±0 for the zero components.
    Lattice([i8; 3], [i8; 3], bool),
}

fn unit3_grown() -> impl Strategy<Value = [f64; 3]> + Clone {
    prop::array::uniform3(-0.25..1.25f64)
}

fn dir3_unit() -> impl Strategy<Value = [f64; 3]> + Clone {
    prop::array::uniform3(-1.0..1.0f64)
}

/// [`RaySpec::Random`] with unit-scale directions.
pub fn random_ray() -> impl Strategy<Value = RaySpec> {
    (unit3_grown(), dir3_unit(), prop::array::uniform3(0u8..6))
        .prop_map(|(o, d, z)| RaySpec::Random(o, d, z, 1.0))
}

/// [`RaySpec::Random`] with directions scaled by 1, 1e-30, 1e-7 or 1e25.
pub fn random_scaled_ray() -> impl Strategy<Value = RaySpec> {
    (
        unit3_grown(),
        dir3_unit(),
        prop::array::uniform3(0u8..6),
        prop::sample::select(vec![1.0, 1.0, 1e-30, 1e-7, 1e25]),
    )
        .prop_map(|(o, d, z, s)| RaySpec::Random(o, d, z, s))
}

/// [`RaySpec::AtVertex`].
pub fn at_vertex_ray() -> impl Strategy<Value = RaySpec> {
    (unit3_grown(), any::<usize>(), any::<bool>()).prop_map(|(o, v, e)| RaySpec::AtVertex(o, v, e))
}

/// [`RaySpec::FromVertex`].
pub fn from_vertex_ray() -> impl Strategy<Value = RaySpec> {
    (any::<usize>(), dir3_unit()).prop_map(|(v, d)| RaySpec::FromVertex(v, d))
}

/// [`RaySpec::VertexToVertex`].
pub fn vertex_to_vertex_ray() -> impl Strategy<Value = RaySpec> {
    (any::<usize>(), any::<usize>()).prop_map(|(a, b)| RaySpec::VertexToVertex(a, b))
}

/// [`RaySpec::Snapped`].
pub fn snapped_ray() -> impl Strategy<Value = RaySpec> {
    (
        prop::array::uniform3(-1i8..=9),
        prop::array::uniform3(-2i8..=2),
    )
        .prop_map(|(o, d)| RaySpec::Snapped(o, d))
}

/// [`RaySpec::Lattice`].
pub fn lattice_ray() -> impl Strategy<Value = RaySpec> {
    (
        prop::array::uniform3(-5i8..=5),
        prop::array::uniform3(-1i8..=1),
        any::<bool>(),
    )
        .prop_map(|(o, d, neg)| RaySpec::Lattice(o, d, neg))
}

/// A ray's `(t_min, t_max)`: mostly `[0, ∞)`, sometimes a random window or
/// `[1e-4, ∞)`, and with `negative_start` also `[-1, ∞)`.
pub fn window(negative_start: bool) -> BoxedStrategy<(f64, f64)> {
    if negative_start {
        prop_oneof![
            3 => Just((0.0, f64::INFINITY)),
            1 => (0.0..2.0f64, 0.0..3.0f64),
            1 => Just((1e-4, f64::INFINITY)),
            1 => Just((-1.0, f64::INFINITY)),
        ]
        .boxed()
    } else {
        prop_oneof![
            3 => Just((0.0, f64::INFINITY)),
            1 => (0.0..2.0f64, 0.0..3.0f64),
            1 => Just((1e-4, f64::INFINITY)),
        ]
        .boxed()
    }
}

/// The point at unit coordinates `u` of `b`.
fn at_unit<T: Real>(b: &Aabb<T>, u: [f64; 3]) -> Vec3<T> {
    Vec3::new(
        b.min.x + (b.max.x - b.min.x) * T::from_f64(u[0]),
        b.min.y + (b.max.y - b.min.y) * T::from_f64(u[1]),
        b.min.z + (b.max.z - b.min.z) * T::from_f64(u[2]),
    )
}

/// The ray `spec` describes in `mesh` (with the lattice's scale and offset
/// `lattice` for [`RaySpec::Lattice`], see [`SceneSpec::lattice`]) over
/// `window`, or `None` when it is not a valid ray (a zero direction).
#[must_use]
pub fn make_ray<T: Real>(
    spec: &RaySpec,
    mesh: &TriangleMesh<T>,
    lattice: (f64, f64),
    window: (f64, f64),
) -> Option<Ray<T>> {
    let b = mesh.bounds();
    let lerp = |u: [f64; 3]| at_unit(&b, u);
    let vertex = |i: usize| mesh.positions()[i % mesh.positions().len()];
    let signed_zero = |neg: bool| if neg { -T::ZERO } else { T::ZERO };
    let (origin, dir) = match spec {
        RaySpec::Random(o, d, zero, scale) => {
            let mut d = Vec3::from(d.map(|x| T::from_f64(x * scale)));
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
        RaySpec::VertexToVertex(a, c) => (vertex(*a), vertex(*c) - vertex(*a)),
        RaySpec::Snapped(o, d) => (
            lerp(o.map(|x| f64::from(x) / 8.0)),
            Vec3::from(d.map(|x| T::from_f64(f64::from(x)))),
        ),
        RaySpec::Lattice(o, d, neg) => {
            let (scale, offset) = lattice;
            let origin = Vec3::from(o.map(|c| T::from_f64(f64::from(c) * scale + offset)));
            let dir = Vec3::from(d.map(|c| {
                if c == 0 {
                    signed_zero(*neg)
                } else {
                    T::from_f64(f64::from(c))
                }
            }));
            (origin, dir)
        }
    };
    let (t_min, t_max) = (T::from_f64(window.0), T::from_f64(window.1));
    Ray::with_interval(origin, dir, t_min, t_max).ok()
}

/// A query box from two unit-coordinate corners of `mesh`'s bounds.
#[must_use]
pub fn region<T: Real>(mesh: &TriangleMesh<T>, a: [f64; 3], b: [f64; 3]) -> Aabb<T> {
    let bb = mesh.bounds();
    Aabb::new(at_unit(&bb, a), at_unit(&bb, b))
}

/// Fails unless `accel` answers `ray` as `reference` does: the nearest hit
/// bit for bit ([`accel_core::Hit::bit_key`]) and the any-hit query.
/// `what` names the accelerator and the case in the message.
///
/// # Errors
/// A [`TestCaseError`] naming the ray and both answers.
///
/// # Panics
/// If either refuses the ray (the suites make valid rays only).
pub fn agrees<T, A, B>(
    accel: &A,
    reference: &B,
    ray: &Ray<T>,
    what: &str,
) -> Result<(), TestCaseError>
where
    T: Real,
    A: Accelerator<T> + ?Sized,
    B: Accelerator<T> + ?Sized,
{
    let want = reference.intersect(ray).unwrap();
    let got = accel.intersect(ray).unwrap();
    prop_assert_eq!(
        got.map(|h| h.bit_key()),
        want.map(|h| h.bit_key()),
        "{} {}: ray {:?}: got {:?}, brute force {:?}",
        T::NAME,
        what,
        ray,
        got,
        want
    );
    prop_assert_eq!(
        accel.occluded(ray).unwrap(),
        want.is_some(),
        "{} {} occluded, ray {:?}",
        T::NAME,
        what,
        ray
    );
    Ok(())
}

/// A unit coordinate: mostly uniform, sometimes exactly 0, ¼, ½, ¾ or 1.
pub fn unit() -> impl Strategy<Value = f64> + Clone {
    prop_oneof![
        6 => 0.0..=1.0f64,
        1 => prop::sample::select(vec![0.0, 0.25, 0.5, 0.75, 1.0]),
    ]
}

/// A ray aimed at a vertex or at a point of an edge (its ends included), for
/// [`crate::aimed::ClosedParts::ray`], with vertex and edge indices drawn
/// from `0..max_index`.
pub fn aim_in(max_index: usize) -> BoxedStrategy<Aim> {
    let target = prop_oneof![
        (0..max_index).prop_map(Target::Vertex),
        (
            0..max_index,
            prop_oneof![4 => unit(), 1 => prop::sample::select(vec![0.0, 1.0])]
        )
            .prop_map(|(e, s)| Target::Edge(e, s)),
    ];
    (
        target,
        [-1.0..=1.0f64, -1.0..=1.0f64, -1.0..=1.0f64],
        prop::sample::select(vec![-1, 0, 1, 3]),
    )
        .prop_map(|(target, jitter, distance_exp)| Aim {
            target,
            jitter,
            distance_exp,
        })
        .boxed()
}
