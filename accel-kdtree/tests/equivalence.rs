//! The kD-tree answers exactly as brute force, and the event-sweep build
//! equals the naive O(n²) builder node for node: random soups, lattice
//! triangles with many coincident planes (so many primitives lie in split
//! planes), closed meshes, rays at vertices and edges, ±0 components and
//! t windows, several cost settings, in f32 and f64. (The workspace-wide
//! suites in the `tests` crate go further; this one guards the tree itself.)

use accel_core::scenes::{teapot_in_stadium, terrain, torus, uv_sphere};
use accel_core::{Aabb, Accelerator, BruteForce, Ray, Real, TriangleMesh, Vec3};
use accel_kdtree::{KdTree, KdTreeParams};
use proptest::prelude::*;

/// A scene description, kept small so that failures shrink to something readable.
#[derive(Clone, Debug)]
enum SceneSpec {
    /// Triangles with vertices on a coarse lattice (many exact coincidences
    /// with each other's planes, many axis-aligned and flat ones), scaled and
    /// offset.
    Lattice(Vec<[[i8; 3]; 3]>, f64, f64),
    /// Free random triangles in the unit cube.
    Soup(Vec<[[f64; 3]; 3]>),
    /// A closed mesh: 0 sphere, 1 torus, 2 terrain, 3 a sphere in a stadium
    /// (built in two parts, the walls and floor apart); scale and offset.
    Mesh(u8, f64, f64),
}

impl SceneSpec {
    fn mesh(&self) -> TriangleMesh<f64> {
        match self {
            Self::Lattice(tris, scale, offset) => {
                let t: Vec<[Vec3<f64>; 3]> = tris
                    .iter()
                    .map(|t| {
                        t.map(|v| {
                            Vec3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2])) * *scale
                                + Vec3::splat(*offset)
                        })
                    })
                    .collect();
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
                let p = m
                    .positions()
                    .iter()
                    .map(|&p| p * *scale + Vec3::splat(*offset))
                    .collect();
                TriangleMesh::new(p, m.indices().to_vec()).unwrap()
            }
        }
    }
}

fn scene_strategy() -> impl Strategy<Value = SceneSpec> {
    let lattice_vertex = prop::array::uniform3(-4i8..=4);
    // Axis-aligned lattice triangles: one coordinate shared by all three vertices.
    let flat_triangle =
        (prop::array::uniform3(lattice_vertex.clone()), 0usize..3).prop_map(|(mut t, a)| {
            let c = t[0][a];
            for v in &mut t {
                v[a] = c;
            }
            t
        });
    let any_triangle = prop::array::uniform3(lattice_vertex);
    let lattice = (
        prop::collection::vec(prop_oneof![any_triangle, flat_triangle], 1..40),
        prop::sample::select(vec![1.0, 0.25, 1e-3, 1e3]),
        // Far from zero too, where f32's rounding unit dwarfs small scales.
        prop::sample::select(vec![0.0, -3.5, 100.0, 1.0e4]),
    )
        .prop_map(|(t, s, o)| SceneSpec::Lattice(t, s, o));
    let soup = prop::collection::vec(
        prop::array::uniform3(prop::array::uniform3(0.0..1.0f64)),
        1..60,
    )
    .prop_map(SceneSpec::Soup);
    let mesh = (
        0u8..4,
        prop::sample::select(vec![1.0, 0.01, 50.0]),
        prop::sample::select(vec![0.0, 7.0]),
    )
        .prop_map(|(k, s, o)| SceneSpec::Mesh(k, s, o));
    prop_oneof![2 => lattice, 1 => soup, 1 => mesh]
}

/// How a ray is aimed, relative to the scene's bounds and vertices.
#[derive(Clone, Debug)]
enum RaySpec {
    /// Origin in the grown bounds (unit coordinates), any direction, some
    /// components forced to +0 or -0.
    Random([f64; 3], [f64; 3], [u8; 3]),
    /// From a random point toward vertex `v` (index modulo the count), or the
    /// midpoint of an edge when `edge` is set.
    AtVertex([f64; 3], usize, bool),
    /// Starting on a vertex of the scene, in a random direction.
    FromVertex(usize, [f64; 3]),
    /// From a lattice point of the grown bounds along a lattice direction
    /// (axis-parallel rays in the planes of flat triangles, through their
    /// vertices and edges), with ±0 for the zero components.
    Lattice([i8; 3], [i8; 3], bool),
}

fn ray_strategy() -> impl Strategy<Value = RaySpec> {
    let unit3 = prop::array::uniform3(-0.25..1.25f64);
    let dir3 = prop::array::uniform3(-1.0..1.0f64);
    prop_oneof![
        (unit3.clone(), dir3.clone(), prop::array::uniform3(0u8..6))
            .prop_map(|(o, d, z)| RaySpec::Random(o, d, z)),
        (unit3, any::<usize>(), any::<bool>()).prop_map(|(o, v, e)| RaySpec::AtVertex(o, v, e)),
        (any::<usize>(), dir3).prop_map(|(v, d)| RaySpec::FromVertex(v, d)),
        (
            prop::array::uniform3(-5i8..=5),
            prop::array::uniform3(-1i8..=1),
            any::<bool>()
        )
            .prop_map(|(o, d, neg)| RaySpec::Lattice(o, d, neg)),
    ]
}

fn make_ray<T: Real>(
    spec: &RaySpec,
    mesh: &TriangleMesh<T>,
    lattice: (f64, f64),
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
    let signed_zero = |neg: bool| if neg { -T::ZERO } else { T::ZERO };
    let (origin, dir) = match spec {
        RaySpec::Random(o, d, zero) => {
            let mut d = Vec3::from(d.map(T::from_f64));
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
    let (t_min, t_max) = (T::from_f64(t_window.0), T::from_f64(t_window.1));
    Ray::with_interval(origin, dir, t_min, t_max).ok()
}

fn window_strategy() -> impl Strategy<Value = (f64, f64)> {
    prop_oneof![
        3 => Just((0.0, f64::INFINITY)),
        1 => (0.0..2.0f64, 0.0..3.0f64),
        1 => Just((1e-4, f64::INFINITY)),
    ]
}

/// The cost settings the suite runs: the defaults, the presets, and two
/// extremes (tiny leaves, very shallow trees).
fn params_strategy() -> impl Strategy<Value = KdTreeParams> {
    prop::sample::select(vec![
        KdTreeParams::default(),
        // Parallel pieces joined at the end: the flattening is checked too.
        KdTreeParams {
            parallel_threshold: 8,
            ..KdTreeParams::best_traversal()
        },
        KdTreeParams::fast_build(),
        KdTreeParams::pbrt(),
        KdTreeParams {
            intersect_cost: 200.0,
            traversal_cost: 0.0,
            empty_bonus: 0.9,
            ..KdTreeParams::default()
        },
        KdTreeParams {
            intersect_cost: 1.0,
            traversal_cost: 3.0,
            empty_bonus: 0.0,
            max_depth: Some(3),
            ..KdTreeParams::default()
        },
        // The binned SAH above four primitives, with few bins: most nodes of
        // these small scenes split by bins, and the sweep finishes them.
        KdTreeParams {
            binned_above: 4,
            bins: 4,
            parallel_threshold: 8,
            ..KdTreeParams::default()
        },
    ])
}

/// A region from two unit-coordinate corners of the scene's grown bounds.
fn region<T: Real>(mesh: &TriangleMesh<T>, a: [f64; 3], b: [f64; 3]) -> Aabb<T> {
    let bb = mesh.bounds();
    let at = |u: [f64; 3]| {
        Vec3::new(
            bb.min.x + (bb.max.x - bb.min.x) * T::from_f64(u[0]),
            bb.min.y + (bb.max.y - bb.min.y) * T::from_f64(u[1]),
            bb.min.z + (bb.max.z - bb.min.z) * T::from_f64(u[2]),
        )
    };
    Aabb::new(at(a), at(b))
}

fn check<T: Real>(
    spec: &SceneSpec,
    rays: &[(RaySpec, (f64, f64))],
    regions: &[([f64; 3], [f64; 3])],
    params: &KdTreeParams,
) -> Result<(), TestCaseError> {
    let Ok(mesh) = spec.mesh().cast::<T>() else {
        return Ok(());
    };
    let lattice = match spec {
        SceneSpec::Lattice(_, s, o) => (*s, *o),
        _ => (0.25, 0.0),
    };
    let brute = BruteForce::new(&mesh).unwrap();
    let tree = KdTree::with_params(&mesh, params).unwrap();
    tree.validate().map_err(TestCaseError::fail)?;
    if params.binned_above < mesh.triangle_count() {
        // Binned splits near the root: no naive reference; brute force below.
        return check_queries(&mesh, &brute, &tree, rays, regions, lattice);
    }
    // The O(n log n) build equals the naive O(n²) one, node for node.
    let naive = KdTree::with_params_naive(&mesh, params).unwrap();
    prop_assert_eq!(
        tree.nodes(),
        naive.nodes(),
        "{} nodes differ from the naive build",
        T::NAME
    );
    prop_assert_eq!(tree.references(), naive.references());
    prop_assert_eq!(tree.parts(), naive.parts());
    for i in 0..tree.nodes().len() {
        prop_assert_eq!(
            tree.split_position(i).map(|s| s.to_bits_u64()),
            naive.split_position(i).map(|s| s.to_bits_u64())
        );
    }
    check_queries(&mesh, &brute, &tree, rays, regions, lattice)
}

/// Every ray and region answers as brute force, bit for bit.
fn check_queries<T: Real>(
    mesh: &TriangleMesh<T>,
    brute: &BruteForce<'_, T, TriangleMesh<T>>,
    tree: &KdTree<'_, T, TriangleMesh<T>>,
    rays: &[(RaySpec, (f64, f64))],
    regions: &[([f64; 3], [f64; 3])],
    lattice: (f64, f64),
) -> Result<(), TestCaseError> {
    for (rs, window) in rays {
        let Some(ray) = make_ray::<T>(rs, mesh, lattice, *window) else {
            continue;
        };
        let want = brute.intersect(&ray).unwrap();
        let got = tree.intersect(&ray).unwrap();
        prop_assert_eq!(
            got.map(|h| h.bit_key()),
            want.map(|h| h.bit_key()),
            "{} ray {:?}: kd-tree {:?} brute {:?}",
            T::NAME,
            ray,
            got,
            want
        );
        prop_assert_eq!(
            tree.occluded(&ray).unwrap(),
            want.is_some(),
            "{} occluded, ray {:?}",
            T::NAME,
            ray
        );
    }
    for (a, b) in regions {
        let r = region(mesh, *a, *b);
        prop_assert_eq!(
            tree.query_region(&r).unwrap(),
            brute.query_region(&r).unwrap(),
            "{} region {:?}",
            T::NAME,
            r
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn kdtree_equals_brute_force_and_the_naive_build(
        scene in scene_strategy(),
        rays in prop::collection::vec((ray_strategy(), window_strategy()), 1..48),
        regions in prop::collection::vec(
            (prop::array::uniform3(-0.1..1.1f64), prop::array::uniform3(-0.1..1.1f64)), 0..4),
        params in params_strategy(),
    ) {
        check::<f32>(&scene, &rays, &regions, &params)?;
        check::<f64>(&scene, &rays, &regions, &params)?;
    }
}
