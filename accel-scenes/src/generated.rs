//! The workspace's generated scenes and rays, in one place.
//!
//! Benchmarks, tests and `render` share these generators so that a figure
//! quoted for "the 100k soup" means the same triangles everywhere. Everything
//! is deterministic: a seed fixes the output, on every machine and version (the
//! generator is [`SplitMix64`], whose sequence is specified, rather than a
//! crate whose value streams may change between releases).

use crate::camera::{Camera, Z_UP};
use accel_core::{Aabb, Ray, Real, TriangleMesh, Vec3};
use core::f64::consts::{PI, TAU};

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, fully specified generator.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from a seed.
    #[must_use]
    pub const fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    /// A point uniform in the box.
    pub fn point_in(&mut self, b: &Aabb<f64>) -> Vec3<f64> {
        Vec3::new(
            self.range(b.min.x, b.max.x),
            self.range(b.min.y, b.max.y),
            self.range(b.min.z, b.max.z),
        )
    }

    /// A direction uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> Vec3<f64> {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// Builds a mesh from generator output, which is finite by construction.
fn mesh(positions: Vec<Vec3<f64>>, indices: Vec<[u32; 3]>) -> TriangleMesh<f64> {
    TriangleMesh::new(positions, indices).expect("generated meshes are valid")
}

/// A latitude–longitude sphere with shared vertices and about `triangles`
/// triangles (closed: the poles are single vertices).
#[must_use]
pub fn uv_sphere(center: Vec3<f64>, radius: f64, triangles: usize) -> TriangleMesh<f64> {
    // 2·slices·(stacks − 1) triangles with slices = 2·stacks.
    let stacks = ((triangles as f64 / 4.0).sqrt().round() as u32).max(2);
    let slices = 2 * stacks;
    let mut p = vec![center + Vec3::new(0.0, 0.0, radius)];
    for i in 1..stacks {
        let theta = PI * f64::from(i) / f64::from(stacks);
        for j in 0..slices {
            let phi = TAU * f64::from(j) / f64::from(slices);
            p.push(
                center
                    + Vec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    ) * radius,
            );
        }
    }
    let south = p.len() as u32;
    p.push(center - Vec3::new(0.0, 0.0, radius));
    let ring = |i: u32, j: u32| 1 + (i - 1) * slices + j % slices;
    let mut t = Vec::new();
    for j in 0..slices {
        t.push([0, ring(1, j), ring(1, j + 1)]);
        t.push([south, ring(stacks - 1, j + 1), ring(stacks - 1, j)]);
    }
    for i in 1..stacks - 1 {
        for j in 0..slices {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            t.push([a, c, b]);
            t.push([b, c, d]);
        }
    }
    mesh(p, t)
}

/// A torus around the z axis with shared vertices, `rings × sides × 2` triangles.
#[must_use]
pub fn torus(
    center: Vec3<f64>,
    major: f64,
    minor: f64,
    rings: u32,
    sides: u32,
) -> TriangleMesh<f64> {
    let (rings, sides) = (rings.max(3), sides.max(3));
    let mut p = Vec::new();
    for i in 0..rings {
        let u = TAU * f64::from(i) / f64::from(rings);
        for j in 0..sides {
            let v = TAU * f64::from(j) / f64::from(sides);
            let r = major + minor * v.cos();
            p.push(center + Vec3::new(r * u.cos(), r * u.sin(), minor * v.sin()));
        }
    }
    let at = |i: u32, j: u32| (i % rings) * sides + j % sides;
    let mut t = Vec::new();
    for i in 0..rings {
        for j in 0..sides {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
            t.push([a, b, c]);
            t.push([c, b, d]);
        }
    }
    mesh(p, t)
}

/// An axis-aligned box surface with shared vertices, each face split into
/// `k × k` quads (`12·k²` triangles).
#[must_use]
pub fn box_mesh(b: &Aabb<f64>, k: u32) -> TriangleMesh<f64> {
    let k = k.max(1);
    let mut p: Vec<Vec3<f64>> = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut vertex = |g: [u32; 3]| -> u32 {
        *index.entry(g).or_insert_with(|| {
            let f = |a: usize| b.min[a] + (b.max[a] - b.min[a]) * f64::from(g[a]) / f64::from(k);
            p.push(Vec3::new(f(0), f(1), f(2)));
            (p.len() - 1) as u32
        })
    };
    let mut t = Vec::new();
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0, k] {
            for i in 0..k {
                for j in 0..k {
                    let g = |di: u32, dj: u32| {
                        let mut c = [0u32; 3];
                        c[axis] = side;
                        c[u] = i + di;
                        c[v] = j + dj;
                        c
                    };
                    let (a, b2, c, d) = (
                        vertex(g(0, 0)),
                        vertex(g(1, 0)),
                        vertex(g(0, 1)),
                        vertex(g(1, 1)),
                    );
                    // Outward winding on both sides.
                    if side == 0 {
                        t.push([a, c, b2]);
                        t.push([b2, c, d]);
                    } else {
                        t.push([a, b2, c]);
                        t.push([b2, d, c]);
                    }
                }
            }
        }
    }
    mesh(p, t)
}

/// Height of the generated terrain at `(x, y)` in `[0, 1]²`: a sum of
/// octaves of smooth waves, range about `[−0.15, 0.15]`.
fn terrain_height(x: f64, y: f64, phases: &[(f64, f64, f64)]) -> f64 {
    let mut h = 0.0;
    let mut amplitude = 0.08;
    let mut frequency = 3.0;
    for &(a, b, c) in phases {
        h += amplitude * ((frequency * x + a) * TAU).sin() * ((frequency * y + b) * TAU).cos();
        h += 0.5 * amplitude * ((frequency * (x + y) + c) * TAU).sin();
        amplitude *= 0.5;
        frequency *= 2.1;
    }
    h
}

/// A heightfield over `[0, 1]²` (z up) with shared vertices and about
/// `triangles` triangles (`2·k²` for a `k × k` grid of quads).
#[must_use]
pub fn terrain(triangles: usize, seed: u64) -> TriangleMesh<f64> {
    let k = ((triangles as f64 / 2.0).sqrt().round() as u32).max(1);
    let mut rng = SplitMix64::new(seed);
    let phases: Vec<(f64, f64, f64)> = (0..6)
        .map(|_| (rng.next_f64(), rng.next_f64(), rng.next_f64()))
        .collect();
    let mut p = Vec::with_capacity(((k + 1) * (k + 1)) as usize);
    for j in 0..=k {
        for i in 0..=k {
            let (x, y) = (f64::from(i) / f64::from(k), f64::from(j) / f64::from(k));
            p.push(Vec3::new(x, y, terrain_height(x, y, &phases)));
        }
    }
    mesh(p, quad_grid_triangles(k, k))
}

/// The triangles of an `nx × ny` grid of quads over `(nx + 1)·(ny + 1)`
/// vertices numbered row by row, two per quad.
fn quad_grid_triangles(nx: u32, ny: u32) -> Vec<[u32; 3]> {
    let at = |i: u32, j: u32| j * (nx + 1) + i;
    let mut t = Vec::with_capacity(2 * (nx * ny) as usize);
    for j in 0..ny {
        for i in 0..nx {
            t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    t
}

/// `n` small random triangles in the unit cube, each of size about the mean
/// spacing `n^(−1/3)`.
#[must_use]
pub fn random_soup(n: usize, seed: u64) -> TriangleMesh<f64> {
    let mut rng = SplitMix64::new(seed);
    let size = 0.5 * (n.max(1) as f64).cbrt().recip();
    let unit = Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0));
    let mut tris = Vec::with_capacity(n);
    for _ in 0..n {
        let c = rng.point_in(&unit);
        tris.push([0, 1, 2].map(|_| c + rng.unit_vector() * size));
    }
    TriangleMesh::from_triangles(&tris).expect("generated meshes are valid")
}

/// "Teapot in a stadium": a dense sphere of about `dense` triangles of radius
/// 1 at the origin, inside a huge box (side `stadium`) of 12 triangles and a
/// flat floor of 2 triangles just below the sphere.
#[must_use]
pub fn teapot_in_stadium(dense: usize, stadium: f64) -> TriangleMesh<f64> {
    let mut m = uv_sphere(Vec3::ZERO, 1.0, dense);
    let h = stadium / 2.0;
    m.append(&box_mesh(&Aabb::new(Vec3::splat(-h), Vec3::splat(h)), 1))
        .expect("small mesh");
    let floor = [
        [
            Vec3::new(-h, -h, -1.5),
            Vec3::new(h, -h, -1.5),
            Vec3::new(h, h, -1.5),
        ],
        [
            Vec3::new(-h, -h, -1.5),
            Vec3::new(h, h, -1.5),
            Vec3::new(-h, h, -1.5),
        ],
    ];
    m.append(&TriangleMesh::from_triangles(&floor).expect("valid"))
        .expect("small mesh");
    m
}

/// A sphere of about `dense` triangles of radius 1 at the origin, inside a
/// box of side `stadium` whose faces are tiled `tiles × tiles`: with fine
/// tiles (20 for a box 10⁴ wide) no triangle is large enough for the scene
/// to be built in parts ([`accel_core::parts`]), so one structure must isolate
/// the sphere.
#[must_use]
pub fn sphere_in_tiled_box(dense: usize, stadium: f64, tiles: u32) -> TriangleMesh<f64> {
    let mut m = uv_sphere(Vec3::ZERO, 1.0, dense);
    let h = stadium / 2.0;
    m.append(&box_mesh(
        &Aabb::new(Vec3::splat(-h), Vec3::splat(h)),
        tiles,
    ))
    .expect("small mesh");
    m
}

/// The shape of a [`flat_field`]: a field of quads at `z = 0` and two dense
/// meshes standing on it at its centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlatFieldSpec {
    /// Quads along x and y (two triangles each).
    pub quads: [u32; 2],
    /// The field's extent along x and y, centred on the origin.
    pub extent: [f64; 2],
    /// Triangles of the two dense meshes together (about).
    pub dense: usize,
}

impl FlatFieldSpec {
    /// The benchmark's field: 100 × 60 quads (12,000 triangles) over 80 × 50,
    /// with about 200,000 triangles at its centre, 0.6 and 0.4 high.
    pub const BENCH: Self = Self {
        quads: [100, 60],
        extent: [80.0, 50.0],
        dense: 200_000,
    };
}

/// A perfectly flat field (every vertex at `z = 0`, z up) with two small
/// dense meshes standing on it at its centre: a sphere of diameter 0.6 at
/// `x = −0.45` and a torus 0.4 high (0.9 across) at `x = 0.45`, touching the field. Rays
/// that leave the field (shadow and diffuse rays from most pixels) meet
/// nothing after a few nodes or cells, so a structure's fixed cost per ray
/// dominates their time.
#[must_use]
pub fn flat_field(f: &FlatFieldSpec) -> TriangleMesh<f64> {
    let [nx, ny] = f.quads.map(|q| q.max(1));
    let [ex, ey] = f.extent;
    let mut p = Vec::with_capacity(((nx + 1) * (ny + 1)) as usize);
    for j in 0..=ny {
        for i in 0..=nx {
            p.push(Vec3::new(
                ex * (f64::from(i) / f64::from(nx) - 0.5),
                ey * (f64::from(j) / f64::from(ny) - 0.5),
                0.0,
            ));
        }
    }
    let mut m = mesh(p, quad_grid_triangles(nx, ny));
    let half = f.dense / 2;
    m.append(&uv_sphere(Vec3::new(-0.45, 0.0, 0.3), 0.3, half))
        .expect("generated meshes are small");
    // rings × sides × 2 triangles, rings = 2·sides (a round tube).
    let sides = ((half as f64 / 4.0).sqrt().round() as u32).max(3);
    m.append(&torus(
        Vec3::new(0.45, 0.0, 0.2),
        0.25,
        0.2,
        2 * sides,
        sides,
    ))
    .expect("generated meshes are small");
    m
}

/// Rays that leave the floor of a [`flat_field`] of the extent of `f`:
/// from the points of a 20 × 10 lattice over it, `height` above the floor
/// (about the error-bound spawn offset), up and sideways; the points within
/// a sixteenth of the extent of the centre, whose rays may pass the dense
/// meshes, are left out (191 rays for a field 80 × 50).
#[must_use]
pub fn rays_leaving_the_floor<T: Real>(f: &FlatFieldSpec, height: f64) -> Vec<Ray<T>> {
    let [ex, ey] = f.extent;
    (0..200u32)
        .filter_map(|i| {
            let (a, b) = (f64::from(i % 20), f64::from(i / 20));
            let (x, y) = (ex * (a / 21.6 - 0.4625), ey * (b / 11.6 - 0.42));
            if x.abs() < ex / 16.0 && y.abs() < ey / 10.0 {
                return None;
            }
            let d = Vec3::new(
                0.3 * (f64::from(i % 7) - 3.0),
                0.2 * (f64::from(i % 5) - 2.0),
                1.0,
            );
            Ray::new(Vec3::new(x, y, height).cast(), d.cast()).ok()
        })
        .collect()
}

/// The generated benchmark scenes, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GeneratedScene {
    /// A tessellated sphere of about 100k triangles.
    Sphere100k,
    /// 100k random small triangles in a cube.
    Soup100k,
    /// A heightfield of about 1M triangles.
    Terrain1M,
    /// A 100k-triangle sphere in a box of side 10⁴ with a floor.
    TeapotInStadium,
    /// [`FlatFieldSpec::BENCH`]: a flat field of 12k triangles with 200k at its
    /// centre, where rays leaving the field are all fixed cost.
    FlatField,
}

impl GeneratedScene {
    /// Every generated scene.
    pub const ALL: [Self; 5] = [
        Self::Sphere100k,
        Self::Soup100k,
        Self::Terrain1M,
        Self::TeapotInStadium,
        Self::FlatField,
    ];

    /// The scene called `name` (as [`GeneratedScene::name`] spells it).
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }

    /// A short name for reports.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Sphere100k => "sphere_100k",
            Self::Soup100k => "soup_100k",
            Self::Terrain1M => "terrain_1m",
            Self::TeapotInStadium => "teapot_in_stadium",
            Self::FlatField => "flat_field",
        }
    }

    /// The scene's mesh.
    #[must_use]
    pub fn mesh(self) -> TriangleMesh<f64> {
        match self {
            Self::Sphere100k => uv_sphere(Vec3::ZERO, 1.0, 100_000),
            Self::Soup100k => random_soup(100_000, 0x50_u64),
            Self::Terrain1M => terrain(1_000_000, 0x7E_u64),
            Self::TeapotInStadium => teapot_in_stadium(100_000, 1.0e4),
            Self::FlatField => flat_field(&FlatFieldSpec::BENCH),
        }
    }

    /// A camera that frames the part of the scene worth looking at.
    #[must_use]
    pub fn camera(self) -> Camera {
        match self {
            Self::TeapotInStadium => Camera::look_at(
                Vec3::new(3.0, -4.0, 2.0),
                Vec3::ZERO,
                Vec3::new(0.0, 0.0, 1.0),
                45.0,
            ),
            // Looking down at the dense meshes, the field filling most of
            // the view: most shadow and diffuse rays leave the flat field.
            Self::FlatField => Camera::look_at(
                Vec3::new(-4.0, -6.0, 3.0),
                Vec3::new(0.0, 0.0, 0.2),
                Vec3::new(0.0, 0.0, 1.0),
                60.0,
            ),
            Self::Terrain1M => Camera::look_at(
                Vec3::new(-0.3, -0.3, 0.6),
                Vec3::new(0.5, 0.5, 0.0),
                Vec3::new(0.0, 0.0, 1.0),
                60.0,
            ),
            _ => Camera::frame(&self.mesh_bounds(), Camera::DEFAULT_SIDE, Z_UP),
        }
    }

    fn mesh_bounds(self) -> Aabb<f64> {
        match self {
            Self::Sphere100k => Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)),
            Self::Soup100k => Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0)),
            _ => self.mesh().bounds(),
        }
    }
}

/// `n` rays with origins uniform in `b` grown by a quarter of its diagonal and
/// directions uniform on the sphere: incoherent, many start inside the scene.
#[must_use]
pub fn random_rays<T: Real>(b: &Aabb<f64>, n: usize, seed: u64) -> Vec<Ray<T>> {
    let mut rng = SplitMix64::new(seed);
    let grown = b.expanded(b.diagonal().length() * 0.25);
    (0..n)
        .map(|_| Ray {
            origin: rng.point_in(&grown).cast(),
            direction: rng.unit_vector().cast(),
            t_min: T::ZERO,
            t_max: T::INFINITY,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::PrimitiveSet;

    #[test]
    fn every_scene_is_found_by_its_name_and_nothing_else_is() {
        for scene in GeneratedScene::ALL {
            assert_eq!(GeneratedScene::from_name(scene.name()), Some(scene));
        }
        for other in ["", "default", "Sphere_100k", "soup_100k ", "teapot"] {
            assert_eq!(GeneratedScene::from_name(other), None, "{other:?}");
        }
    }

    /// Each edge of a closed mesh is used by exactly two triangles, once in each direction.
    fn assert_closed(m: &TriangleMesh<f64>) {
        let mut edges = std::collections::HashMap::new();
        for t in m.indices() {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} used {n} times in one direction");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }

    #[test]
    fn generated_meshes_are_closed_and_sized() {
        let s = uv_sphere(Vec3::ZERO, 1.0, 100_000);
        assert!((95_000..=105_000).contains(&s.triangle_count()));
        assert_closed(&s);
        assert_closed(&torus(Vec3::ZERO, 2.0, 0.5, 24, 12));
        let b = box_mesh(
            &Aabb::new(Vec3::new(0.0, 1.0, 2.0), Vec3::new(1.0, 3.0, 6.0)),
            3,
        );
        assert_eq!(b.triangle_count(), 12 * 9);
        assert_closed(&b);
        let t = terrain(1000, 1);
        assert_eq!(t.triangle_count(), 2 * 22 * 22);
    }

    #[test]
    fn flat_field_is_flat_with_its_meshes_standing_at_the_centre() {
        let f = FlatFieldSpec {
            quads: [10, 6],
            extent: [8.0, 5.0],
            dense: 2000,
        };
        let m = flat_field(&f);
        let field = 2 * 10 * 6;
        assert!((field + 1800..=field + 2200).contains(&m.triangle_count()));
        // The field: every vertex of its triangles at z = 0.
        for i in 0..field {
            assert!(m.triangle(i).iter().all(|p| p.z == 0.0), "triangle {i}");
        }
        let b = m.bounds();
        assert_eq!((b.min.x, b.max.x, b.min.y, b.max.y), (-4.0, 4.0, -2.5, 2.5));
        // The meshes rest on the field (lowest point 0 up to rounding),
        // 0.6 high at most, and within a unit of the centre.
        let dense: Vec<_> = (field..m.len()).flat_map(|i| m.triangle(i)).collect();
        let top = dense.iter().map(|p| p.z).fold(f64::MIN, f64::max);
        let bottom = dense.iter().map(|p| p.z).fold(f64::MAX, f64::min);
        assert!(
            (top - 0.6).abs() < 1e-9 && bottom.abs() < 1e-9,
            "{bottom}..{top}"
        );
        assert!(
            dense
                .iter()
                .all(|p| p.x.abs() <= 0.9 + 1e-9 && p.y.abs() <= 0.45 + 1e-9)
        );
    }

    #[test]
    fn generators_are_deterministic() {
        assert_eq!(random_soup(100, 7), random_soup(100, 7));
        assert_ne!(random_soup(100, 7), random_soup(100, 8));
        // SplitMix64's published first output for seed 0.
        assert_eq!(SplitMix64::new(0).next_u64(), 0xE220_A839_7B1D_CDAF);
    }

    #[test]
    fn box_mesh_faces_point_outward() {
        let b = Aabb::new(Vec3::new(0.0, 1.0, 2.0), Vec3::new(1.0, 3.0, 6.0));
        let m = box_mesh(&b, 2);
        let c = b.center();
        for i in 0..m.len() {
            let [p0, p1, p2] = m.triangle(i);
            let n = (p1 - p0).cross(p2 - p0);
            assert!(n.dot(p0 - c) > 0.0, "triangle {i} faces inward");
        }
    }
}
