//! The octree answers exactly as brute force: random soups, lattice-snapped
//! triangles, closed meshes and dense clusters in huge sparse boxes (several
//! levels of grids), random and adversarial rays, several thresholds, depths
//! and resolution rules, in f32 and f64. (The workspace-wide suites in the
//! `tests` crate go further; this one guards the octree itself.)
//!
//! `PROPTEST_CASES` sets the number of cases (default 256).

use accel_core::scenes::{teapot_in_stadium, terrain, torus, uv_sphere};
use accel_core::{Aabb, Accelerator, BruteForce, Ray, Real, TraversalCounters, TriangleMesh, Vec3};
use accel_octree::{Octree, OctreeParams, ResolutionRule};
use proptest::prelude::*;

/// A scene description, kept small so that failures shrink to something readable.
#[derive(Clone, Debug)]
enum SceneSpec {
    /// Triangles with vertices on a coarse lattice (many exact coincidences
    /// with cell boundaries at every level), scaled and offset.
    Lattice(Vec<[[i8; 3]; 3]>, f64, f64),
    /// Lattice triangles of two sizes: the second set shrunk by `1/64` into
    /// one corner, a dense cluster among large triangles.
    TwoScales(Vec<[[i8; 3]; 3]>, Vec<[[i8; 3]; 3]>, f64),
    /// Free random triangles in the unit cube.
    Soup(Vec<[[f64; 3]; 3]>),
    /// A closed mesh: 0 sphere, 1 torus, 2 terrain; scale and offset.
    Mesh(u8, f64, f64),
    /// A tessellated sphere of radius 1 in a box of the given side with a
    /// floor just below it, offset: the teapot in a stadium.
    Stadium(usize, f64, f64),
}

fn lattice_mesh(tris: &[[[i8; 3]; 3]], scale: f64, offset: Vec3<f64>) -> Vec<[Vec3<f64>; 3]> {
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
    TriangleMesh::new(p, m.indices().to_vec()).unwrap()
}

impl SceneSpec {
    fn mesh(&self) -> TriangleMesh<f64> {
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
                    _ => terrain(300, 3),
                };
                moved(&m, *scale, *offset)
            }
            Self::Stadium(dense, side, offset) => {
                moved(&teapot_in_stadium(*dense, *side), 1.0, *offset)
            }
        }
    }
}

fn scene_strategy() -> impl Strategy<Value = SceneSpec> {
    let lattice_vertex = prop::array::uniform3(-4i8..=4);
    let lattice_tris = |n: std::ops::Range<usize>| {
        prop::collection::vec(prop::array::uniform3(prop::array::uniform3(-4i8..=4)), n)
    };
    let lattice = (
        prop::collection::vec(prop::array::uniform3(lattice_vertex), 1..24),
        prop::sample::select(vec![1.0, 0.25, 1e-3, 1e3, 1e-20, 1e20]),
        prop::sample::select(vec![0.0, -3.5, 100.0]),
    )
        .prop_map(|(t, s, o)| SceneSpec::Lattice(t, s, o));
    let two_scales = (
        lattice_tris(1..6),
        lattice_tris(8..40),
        prop::sample::select(vec![0.0, -2.5, 1e3]),
    )
        .prop_map(|(b, s, o)| SceneSpec::TwoScales(b, s, o));
    let soup = prop::collection::vec(
        prop::array::uniform3(prop::array::uniform3(0.0..1.0f64)),
        1..40,
    )
    .prop_map(SceneSpec::Soup);
    let mesh = (
        0u8..3,
        prop::sample::select(vec![1.0, 0.01, 50.0]),
        prop::sample::select(vec![0.0, 7.0]),
    )
        .prop_map(|(k, s, o)| SceneSpec::Mesh(k, s, o));
    let stadium = (
        prop::sample::select(vec![60usize, 400]),
        prop::sample::select(vec![8.0, 1e3, 1e5]),
        prop::sample::select(vec![0.0, 3e3]),
    )
        .prop_map(|(d, s, o)| SceneSpec::Stadium(d, s, o));
    prop_oneof![
        3 => lattice,
        2 => two_scales,
        2 => soup,
        2 => mesh,
        2 => stadium,
    ]
}

/// Octree parameters: presets and mixtures of every dial.
fn params_strategy() -> impl Strategy<Value = OctreeParams> {
    let rule = prop::sample::select(vec![
        ResolutionRule::Density(2.0),
        ResolutionRule::Density(0.5),
        ResolutionRule::Nested {
            density: 2.0,
            levels: 1,
        },
        ResolutionRule::Nested {
            density: 1.0,
            levels: 3,
        },
        ResolutionRule::Fixed([2, 2, 2]),
        ResolutionRule::Fixed([3, 1, 2]),
        ResolutionRule::Fixed([1, 1, 1]),
    ]);
    let mixed = (
        rule.clone(),
        rule,
        prop::sample::select(vec![0usize, 1, 4, 8, 32]),
        prop::sample::select(vec![0u32, 1, 2, 3, 8]),
        any::<bool>(),
    )
        .prop_map(
            |(root, children, split_threshold, max_depth, fit_children)| OctreeParams {
                root,
                children,
                split_threshold,
                max_depth,
                fit_children,
                ..OctreeParams::default()
            },
        );
    prop_oneof![
        1 => Just(OctreeParams::default()),
        1 => Just(OctreeParams::classic()),
        1 => Just(OctreeParams::two_level()),
        1 => Just(OctreeParams::grid_root().with_split_threshold(2)),
        4 => mixed,
    ]
}

/// How a ray is aimed, relative to the scene's bounds and vertices.
#[derive(Clone, Debug)]
enum RaySpec {
    /// Origin in the grown bounds (unit coordinates), any direction scaled
    /// by a power of ten (tiny and huge directions), some components forced
    /// to +0 or -0.
    Random([f64; 3], [f64; 3], [u8; 3], f64),
    /// From a random point toward vertex `v` (index modulo the count), or the
    /// midpoint of an edge when `edge` is set.
    AtVertex([f64; 3], usize, bool),
    /// Starting on a vertex of the scene, in a random direction.
    FromVertex(usize, [f64; 3]),
    /// From vertex `a` toward vertex `b`: along edges and across the cluster.
    VertexToVertex(usize, usize),
    /// From a point on the eighths of the bounds along a small integer
    /// direction (zeros included): along the faces, edges and through the
    /// corners of cells at every level where boundaries fall on eighths
    /// (halving grids, lattice scenes).
    Snapped([i8; 3], [i8; 3]),
}

fn ray_strategy() -> impl Strategy<Value = RaySpec> {
    let unit3 = prop::array::uniform3(-0.25..1.25f64);
    let dir3 = prop::array::uniform3(-1.0..1.0f64);
    prop_oneof![
        (
            unit3.clone(),
            dir3.clone(),
            prop::array::uniform3(0u8..6),
            prop::sample::select(vec![1.0, 1.0, 1e-30, 1e-7, 1e25]),
        )
            .prop_map(|(o, d, z, s)| RaySpec::Random(o, d, z, s)),
        (unit3, any::<usize>(), any::<bool>()).prop_map(|(o, v, e)| RaySpec::AtVertex(o, v, e)),
        (any::<usize>(), dir3).prop_map(|(v, d)| RaySpec::FromVertex(v, d)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| RaySpec::VertexToVertex(a, b)),
        (
            prop::array::uniform3(-1i8..=9),
            prop::array::uniform3(-2i8..=2)
        )
            .prop_map(|(o, d)| RaySpec::Snapped(o, d)),
    ]
}

fn make_ray<T: Real>(
    spec: &RaySpec,
    mesh: &TriangleMesh<T>,
    t_window: (f64, f64),
) -> Option<Ray<T>> {
    let b = mesh.bounds();
    let lerp = |u: [f64; 3]| {
        Vec3::new(
            b.min.x + (b.max.x - b.min.x) * T::from_f64(u[0]),
            b.min.y + (b.max.y - b.min.y) * T::from_f64(u[1]),
            b.min.z + (b.max.z - b.min.z) * T::from_f64(u[2]),
        )
    };
    let vertex = |i: usize| mesh.positions()[i % mesh.positions().len()];
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
    };
    let (t_min, t_max) = (T::from_f64(t_window.0), T::from_f64(t_window.1));
    Ray::with_interval(origin, dir, t_min, t_max).ok()
}

/// A query box in unit coordinates of the bounds: two corners, or a point.
fn region<T: Real>(corners: &([f64; 3], [f64; 3]), mesh: &TriangleMesh<T>) -> Aabb<T> {
    let b = mesh.bounds();
    let at = |u: [f64; 3]| {
        Vec3::new(
            b.min.x + (b.max.x - b.min.x) * T::from_f64(u[0]),
            b.min.y + (b.max.y - b.min.y) * T::from_f64(u[1]),
            b.min.z + (b.max.z - b.min.z) * T::from_f64(u[2]),
        )
    };
    Aabb::new(at(corners.0), at(corners.1))
}

fn check<T: Real>(
    spec: &SceneSpec,
    params: &OctreeParams,
    rays: &[(RaySpec, (f64, f64))],
    regions: &[([f64; 3], [f64; 3])],
) -> Result<(), TestCaseError> {
    let Ok(mesh) = spec.mesh().cast::<T>() else {
        return Ok(());
    };
    let brute = BruteForce::new(&mesh).unwrap();
    let octree = Octree::with_params(&mesh, params).unwrap();
    octree.validate().map_err(TestCaseError::fail)?;
    for (rs, window) in rays {
        let Some(ray) = make_ray::<T>(rs, &mesh, *window) else {
            continue;
        };
        let want = brute.intersect(&ray).unwrap();
        let got = octree.intersect(&ray).unwrap();
        prop_assert_eq!(
            got.map(|h| h.bit_key()),
            want.map(|h| h.bit_key()),
            "{} ray {:?}: octree {:?} brute {:?} ({} grids)",
            T::NAME,
            ray,
            got,
            want,
            octree.grid_count()
        );
        prop_assert_eq!(
            octree.occluded(&ray).unwrap(),
            want.is_some(),
            "{} occluded, ray {:?}",
            T::NAME,
            ray
        );
        let mut counters = TraversalCounters::default();
        let counted = octree.intersect_counted(&ray, &mut counters).unwrap();
        prop_assert_eq!(counted.map(|h| h.bit_key()), want.map(|h| h.bit_key()));
        prop_assert_eq!(
            octree.occluded_counted(&ray, &mut counters).unwrap(),
            want.is_some()
        );
    }
    for corners in regions {
        let b = region::<T>(corners, &mesh);
        prop_assert_eq!(
            octree.query_region(&b).unwrap(),
            brute.query_region(&b).unwrap(),
            "{} region {:?}",
            T::NAME,
            b
        );
    }
    Ok(())
}

fn window_strategy() -> impl Strategy<Value = (f64, f64)> {
    prop_oneof![
        3 => Just((0.0, f64::INFINITY)),
        1 => (0.0..2.0f64, 0.0..3.0f64),
        1 => Just((1e-4, f64::INFINITY)),
        1 => Just((-1.0, f64::INFINITY)),
    ]
}

fn region_strategy() -> impl Strategy<Value = ([f64; 3], [f64; 3])> {
    let unit3 = prop::array::uniform3(-0.1..1.1f64);
    prop_oneof![
        (unit3.clone(), unit3.clone()),
        unit3.prop_map(|p| (p, p)),
        // Snapped to eighths: corners on shared cell boundaries.
        prop::array::uniform3(0u8..=8).prop_map(|p| {
            let p = p.map(|x| f64::from(x) / 8.0);
            (p, p.map(|x| x + 0.125))
        }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::default())]

    #[test]
    fn octree_equals_brute_force(
        scene in scene_strategy(),
        params in params_strategy(),
        rays in prop::collection::vec((ray_strategy(), window_strategy()), 1..48),
        regions in prop::collection::vec(region_strategy(), 0..4),
    ) {
        check::<f32>(&scene, &params, &rays, &regions)?;
        check::<f64>(&scene, &params, &rays, &regions)?;
    }
}
