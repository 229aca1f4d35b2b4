//! The owning (shared) forms of every accelerator (issue 32, item 6).
//!
//! A structure built over an `Arc` of its primitives (`shared`,
//! `shared_with_params`) is the same structure as one built over a borrow:
//! the same statistics, the same work per ray (nodes and primitive tests
//! counted), and answers bit-identical to its borrowing twin and to brute
//! force, in f32 and f64, on generated meshes and on the user-defined
//! [`accel_tests::Mixed`] primitive. And it can live beside its primitives:
//! a struct holding both is built in a function, returned, sent to another
//! thread and queried there.

use accel_core::packed::Layout;
use accel_core::{
    AccelStats, Accelerator, BruteForce, MollerTrumboreMesh, PrimitiveSet, Ray, Real,
    SharedBruteForce, TraversalCounters, TriangleMesh, Vec3,
};
use accel_grid::{Grid, SharedGrid};
use accel_kdtree::{KdTree, KdTreeParams, SharedKdTree};
use accel_octree::{Octree, SharedOctree};
use accel_tests::assertions::{Expected, check_accelerator};
use accel_tests::config::config;
use accel_tests::registry::{density, fine_octree, with_layout};
use accel_tests::scene::SceneSpec;
use accel_tests::strategies::{boxes, ordinary_placement, rays_and_windows, scene};
use accel_tests::suite::resolve;
use accel_tests::{BoxSpec, Landmarks, RaySpec, Scene, WindowSpec};
use proptest::prelude::*;
use std::sync::Arc;

/// A borrowing accelerator and its shared twin, built with the same
/// parameters over the same primitives.
type Pair<'a, T> = (
    &'static str,
    Box<dyn Accelerator<T> + 'a>,
    Box<dyn Accelerator<T> + 'a>,
);

/// Every structure, by its default constructors and with parameters, each
/// borrowing `prims` and sharing `held` (the same set).
fn pairs<'a, T: Real, P: PrimitiveSet<T> + ?Sized + Send + 'static>(
    prims: &'a P,
    held: &Arc<P>,
) -> Result<Vec<Pair<'a, T>>, String> {
    let arc = || Arc::clone(held);
    let kd_packed = KdTreeParams {
        layout: Layout::Packed,
        ..KdTreeParams::default()
    };
    let grid_packed = with_layout(density(1.0), Layout::Packed);
    let fine = fine_octree();
    let e = |name: &str, e: accel_core::BuildError| format!("{name} ({}): {e}", T::NAME);
    Ok(vec![
        (
            "brute",
            Box::new(BruteForce::new(prims).map_err(|x| e("brute", x))?),
            Box::new(BruteForce::shared(arc()).map_err(|x| e("brute shared", x))?),
        ),
        (
            "grid",
            Box::new(Grid::new(prims).map_err(|x| e("grid", x))?),
            Box::new(Grid::shared(arc()).map_err(|x| e("grid shared", x))?),
        ),
        (
            "grid m=1 packed",
            Box::new(Grid::with_params(prims, &grid_packed).map_err(|x| e("grid", x))?),
            Box::new(
                Grid::shared_with_params(arc(), &grid_packed).map_err(|x| e("grid shared", x))?,
            ),
        ),
        (
            "octree",
            Box::new(Octree::new(prims).map_err(|x| e("octree", x))?),
            Box::new(Octree::shared(arc()).map_err(|x| e("octree shared", x))?),
        ),
        (
            "octree threshold=2 depth=8",
            Box::new(Octree::with_params(prims, &fine).map_err(|x| e("octree", x))?),
            Box::new(Octree::shared_with_params(arc(), &fine).map_err(|x| e("octree shared", x))?),
        ),
        (
            "kdtree",
            Box::new(KdTree::new(prims).map_err(|x| e("kdtree", x))?),
            Box::new(KdTree::shared(arc()).map_err(|x| e("kdtree shared", x))?),
        ),
        (
            "kdtree packed",
            Box::new(KdTree::with_params(prims, &kd_packed).map_err(|x| e("kdtree", x))?),
            Box::new(
                KdTree::shared_with_params(arc(), &kd_packed).map_err(|x| e("kdtree shared", x))?,
            ),
        ),
    ])
}

/// Statistics without the build time (the one figure two builds may differ in).
fn shape(mut s: AccelStats) -> AccelStats {
    s.build_time = Default::default();
    s
}

/// The shared form of each structure equals brute force (every check of the
/// equivalence suite), and its borrowing twin: statistics, and per ray the
/// nearest hit bit for bit, the any-hit answer and the work counted.
fn check_shared<T: Real, P: PrimitiveSet<T> + ?Sized + Send + 'static>(
    prims: &P,
    held: &Arc<P>,
    rays: &[Ray<T>],
    regions: &[accel_core::Aabb<T>],
) -> Result<(), String> {
    let brute = BruteForce::new(prims).map_err(|e| e.to_string())?;
    let expected = Expected::compute(&brute, rays, regions)?;
    for (name, borrowed, shared) in pairs(prims, held)? {
        let label = format!("{name} shared");
        check_accelerator(&label, &*shared, prims, rays, regions, &expected)?;
        if shape(borrowed.stats()) != shape(shared.stats()) {
            return Err(format!(
                "{label} ({}): stats differ from the borrowing build\n  {:?}\n  {:?}",
                T::NAME,
                shared.stats(),
                borrowed.stats()
            ));
        }
        for ray in rays {
            let (mut cb, mut cs) = (TraversalCounters::default(), TraversalCounters::default());
            let b = borrowed.intersect_counted(ray, &mut cb);
            let s = shared.intersect_counted(ray, &mut cs);
            let key = |h: &Result<Option<accel_core::Hit<T>>, _>| {
                h.as_ref().map(|h| h.map(|h| h.bit_key())).ok()
            };
            let (ob, os) = (
                borrowed.occluded_counted(ray, &mut cb),
                shared.occluded_counted(ray, &mut cs),
            );
            if key(&b) != key(&s) || ob != os || cb != cs {
                return Err(format!(
                    "{label} ({}): differs from the borrowing build on {ray:?}\n  \
                     shared    {s:?} occluded {os:?} work {cs:?}\n  \
                     borrowing {b:?} occluded {ob:?} work {cb:?}",
                    T::NAME
                ));
            }
        }
        for region in regions {
            if borrowed.query_region(region) != shared.query_region(region) {
                return Err(format!(
                    "{label} ({}): region {region:?} differs from the borrowing build",
                    T::NAME
                ));
            }
        }
    }
    Ok(())
}

/// Builds the scene, shares it, resolves the rays, and checks every pair.
fn run<T: Real>(
    spec: &SceneSpec,
    rays: &[(RaySpec, WindowSpec)],
    boxes: &[BoxSpec],
) -> Result<(), TestCaseError> {
    let built = spec.build::<T>();
    let landmarks = Landmarks::of(&built);
    let result = match built {
        Scene::Mesh(m) => {
            let held = Arc::new(m);
            resolve(&*held, landmarks, rays, boxes)
                .and_then(|r| check_shared(&*held, &held, &r.rays, &r.regions))
        }
        Scene::Mixed(v) => {
            let held = Arc::new(v);
            resolve(held.as_slice(), landmarks, rays, boxes)
                .and_then(|r| check_shared(&*held, &held, &r.rays, &r.regions))
        }
    };
    result.map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(config("owning_f32", 500))]
    #[test]
    fn shared_equals_borrowed_and_brute_f32(
        scene in scene(ordinary_placement()),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..4),
    ) {
        run::<f32>(&scene, &rays, &regions)?;
    }
}

proptest! {
    #![proptest_config(config("owning_f64", 500))]
    #[test]
    fn shared_equals_borrowed_and_brute_f64(
        scene in scene(ordinary_placement()),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..4),
    ) {
        run::<f64>(&scene, &rays, &regions)?;
    }
}

/// What an application keeps: its mesh and the structures over it, in one
/// struct, with no borrow between them.
struct World {
    mesh: Arc<TriangleMesh<f32>>,
    brute: SharedBruteForce<f32, TriangleMesh<f32>>,
    grid: SharedGrid<f32, TriangleMesh<f32>>,
    octree: SharedOctree<f32, TriangleMesh<f32>>,
    kdtree: SharedKdTree<f32, TriangleMesh<f32>>,
}

/// Loads the world: the mesh is made here and leaves with the structures
/// (with borrowing structures, this function could not be written).
fn load() -> World {
    let mesh = accel_scenes::torus(Vec3::new(0.0, 0.0, 0.0), 1.0, 0.25, 24, 12)
        .cast::<f32>()
        .expect("an f32 torus");
    let mesh = Arc::new(mesh);
    World {
        brute: BruteForce::shared(Arc::clone(&mesh)).expect("brute force"),
        grid: Grid::shared(Arc::clone(&mesh)).expect("grid"),
        octree: Octree::shared(Arc::clone(&mesh)).expect("octree"),
        kdtree: KdTree::shared(Arc::clone(&mesh)).expect("kd-tree"),
        mesh,
    }
}

#[test]
fn a_world_holding_mesh_and_structures_is_returned_and_queried_on_another_thread() {
    let world = load();
    // The world's own handle and one per structure.
    assert_eq!(Arc::strong_count(&world.mesh), 5);
    let world = std::thread::spawn(move || {
        // Along x through the ring (radius 1, tube 0.25): the tube's outer
        // side at x = -1.25 is hit first, at t = 0.75.
        let ray = Ray::new(Vec3::new(-2.0f32, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)).unwrap();
        let want = world
            .brute
            .intersect(&ray)
            .unwrap()
            .expect("the ray meets the torus");
        assert!((want.t - 0.75).abs() < 0.01, "t = {}", want.t);
        let accels: [&dyn Accelerator<f32>; 3] = [&world.grid, &world.octree, &world.kdtree];
        for a in accels {
            assert_eq!(
                a.intersect(&ray).unwrap().map(|h| h.bit_key()),
                Some(want.bit_key())
            );
        }
        for s in [world.brute.primitives(), world.grid.primitives()] {
            assert!(std::ptr::eq(s, &*world.mesh));
        }
        assert!(std::ptr::eq(world.octree.primitives(), &*world.mesh));
        assert!(std::ptr::eq(world.kdtree.primitives(), &*world.mesh));
        world
    })
    .join()
    .expect("the query thread");
    // The structures keep the mesh alive after the application lets go.
    let World {
        mesh,
        brute,
        grid,
        octree,
        kdtree,
    } = world;
    drop(mesh);
    assert_eq!(kdtree.primitives().triangle_count(), 24 * 12 * 2);
    let shared = grid.primitives() as *const TriangleMesh<f32>;
    drop((brute, octree, kdtree));
    assert_eq!(grid.primitives() as *const _, shared);
}

/// The fast triangle test's wrapper owns its mesh too, so a structure over
/// it can be kept beside the mesh (issue 32's note: it only borrowed).
type OwnedFast = MollerTrumboreMesh<'static, f32, Arc<TriangleMesh<f32>>>;

/// A mesh and a kD-tree over its Möller–Trumbore wrapper, built and
/// returned together.
fn load_fast() -> (Arc<TriangleMesh<f32>>, SharedKdTree<f32, OwnedFast>) {
    let mesh = accel_scenes::torus(Vec3::new(0.0, 0.0, 0.0), 1.0, 0.25, 24, 12)
        .cast::<f32>()
        .expect("an f32 torus");
    let mesh = Arc::new(mesh);
    let fast = Arc::new(MollerTrumboreMesh::owning(Arc::clone(&mesh)));
    (mesh, KdTree::shared(fast).expect("kd-tree"))
}

#[test]
fn an_owned_fast_test_wrapper_answers_as_the_borrowing_one() {
    let (mesh, tree) = load_fast();
    assert!(std::ptr::eq(tree.primitives().mesh(), &*mesh));
    let borrowed = MollerTrumboreMesh::new(&*mesh);
    let brute = BruteForce::new(&borrowed).unwrap();
    let rays = accel_scenes::random_rays::<f32>(&mesh.bounds().cast(), 2000, 11);
    let mut hits = 0;
    for ray in &rays {
        let want = brute.intersect(ray).unwrap();
        hits += usize::from(want.is_some());
        assert_eq!(
            tree.intersect(ray).unwrap().map(|h| h.bit_key()),
            want.map(|h| h.bit_key()),
            "{ray:?}"
        );
    }
    // Premise: the rays meet the torus often enough to compare hits.
    assert!(hits > 200, "{hits} hits");
}
