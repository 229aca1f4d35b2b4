//! The build rules: threshold, depth limit, memory budget, cost guard, presets.

use crate::node::{Entry, entry};
use crate::{MAX_DEPTH, Octree, OctreeParams, ResolutionRule};
use accel_core::{
    Aabb, Accelerator, BruteForce, BuildError, Hit, PrimitiveSet, Ray, Real, Sphere,
    TraversalCounters, TriangleMesh, Vec3,
};
use accel_grid::Grid;
use accel_scenes::{Camera, random_soup, sphere_in_tiled_box, teapot_in_stadium, uv_sphere};

/// A small teapot in a stadium: 5,000 triangles of sphere in a box of side 1e4.
fn stadium() -> TriangleMesh<f64> {
    teapot_in_stadium(5_000, 1.0e4)
}

/// The same sphere in a box whose walls are tiled 20 × 20 and no floor: no
/// triangle is large, so the scene is one part and one root grid must
/// isolate the sphere (built with [`one_root`], which keeps the 800 tiles
/// of a face from being a flat part of their own).
fn tiled_stadium() -> TriangleMesh<f64> {
    sphere_in_tiled_box(5_000, 1.0e4, 20)
}

/// `p` without a flat part ([`OctreeParams::flat_part`]).
fn one_root(p: OctreeParams) -> OctreeParams {
    OctreeParams {
        flat_part: false,
        ..p
    }
}

/// The cells of grid `id` of `o` as (linear index, entry).
fn entries<'o, T: Real, P: PrimitiveSet<T> + ?Sized>(
    o: &'o Octree<'_, T, P>,
    id: usize,
) -> Vec<(usize, Entry<'o>)> {
    let node = &o.nodes[id];
    (0..node.geometry.cell_count())
        .map(|c| (c, entry(o.cells.cell(node.cell_index(c)))))
        .collect()
}

/// Checks a few camera rays and regions against brute force.
fn assert_matches_brute<P: PrimitiveSet<f64> + ?Sized>(o: &Octree<'_, f64, P>, prims: &P) {
    let brute = BruteForce::new(prims).unwrap();
    let b = brute.bounds();
    let camera = Camera::look_at(
        Vec3::new(3.0, -4.0, 2.0),
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 1.0),
        50.0,
    );
    for ray in camera.rays::<f64>(24, 24) {
        let want = brute.intersect(&ray).unwrap();
        assert_eq!(o.intersect(&ray).unwrap(), want, "ray {ray:?}");
        assert_eq!(o.occluded(&ray).unwrap(), want.is_some());
    }
    let c = b.center();
    let region = Aabb::new(c - Vec3::splat(0.5), c + Vec3::new(0.25, 1.0, 0.1));
    assert_eq!(
        o.query_region(&region).unwrap(),
        brute.query_region(&region).unwrap()
    );
}

#[test]
fn cells_at_or_under_the_threshold_stay_leaves() {
    let mesh = uv_sphere(Vec3::new(0.5, -1.0, 2.0), 1.5, 20_000);
    let root_only = Octree::with_params(&mesh, &OctreeParams::default().with_max_depth(0)).unwrap();
    assert_eq!(root_only.grid_count(), 1);
    let before = entries(&root_only, 0);
    assert!(before.iter().all(|(_, e)| e.child.is_none()));
    let most = before.iter().map(|(_, e)| e.prims.len()).max().unwrap();
    assert!(most > 8, "the test needs full cells (most {most})");
    for threshold in [0, 4, most / 2, most - 1, most, usize::MAX] {
        let params = OctreeParams::default()
            .with_max_depth(1)
            .with_split_threshold(threshold);
        let o = Octree::with_params(&mesh, &params).unwrap();
        let after = entries(&o, 0);
        assert_eq!(after.len(), before.len());
        let mut split = 0;
        for ((c, was), (_, now)) in before.iter().zip(&after) {
            if now.child.is_some() {
                assert!(
                    was.prims.len() > threshold,
                    "threshold {threshold}: cell {c} split"
                );
                // What stays in a refined cell is some of what it held.
                assert!(now.prims.iter().all(|p| was.prims.contains(p)));
                split += 1;
            } else {
                assert_eq!(now.prims, was.prims, "threshold {threshold} cell {c}");
            }
        }
        assert_eq!(o.grid_count(), 1 + split);
        assert_eq!(split == 0, threshold >= most, "threshold {threshold}");
        assert_matches_brute(&o, &mesh);
    }
}

#[test]
fn depth_stops_at_the_limit() {
    let mesh = stadium();
    for depth in 0..=4 {
        let params = OctreeParams::classic().with_max_depth(depth);
        let o = Octree::with_params(&mesh, &params).unwrap();
        // The sphere is far smaller than the stadium: every level refines it.
        assert_eq!(o.levels().len() as u32, depth + 1, "max_depth {depth}");
        assert_eq!(o.stats().extra("depth"), Some(f64::from(depth)));
        assert!(o.nodes.iter().all(|n| n.level <= depth));
    }
    let deep = Octree::with_params(&mesh, &OctreeParams::classic()).unwrap();
    assert!(deep.levels().len() > 5);
    assert_matches_brute(&deep, &mesh);
    assert!(matches!(
        Octree::with_params(
            &mesh,
            &OctreeParams::classic().with_max_depth(MAX_DEPTH + 1)
        ),
        Err(BuildError::InvalidParameter {
            name: "max_depth",
            ..
        })
    ));
}

#[test]
fn memory_budget_refuses_the_root_and_caps_the_children() {
    let mesh = stadium();
    let full = Octree::new(&mesh).unwrap();
    let root_only = Octree::with_params(&mesh, &OctreeParams::default().with_max_depth(0)).unwrap();
    assert!(full.grid_count() > 1);
    assert_eq!(full.stats().extra("budget_capped"), Some(0.0));

    // Too small for the root grid: refused with a typed error.
    let tiny = OctreeParams {
        max_bytes: 64,
        ..OctreeParams::default()
    };
    assert!(matches!(
        Octree::with_params(&mesh, &tiny),
        Err(BuildError::BudgetExceeded { budget: 64, .. })
    ));

    // Room for the root and some children, not all of them.
    let (lo, hi) = (root_only.stats().bytes, full.stats().bytes);
    assert!(lo < hi);
    let between = OctreeParams {
        max_bytes: (lo + (hi - lo) / 3) as u64,
        ..OctreeParams::default()
    };
    let capped = Octree::with_params(&mesh, &between).unwrap();
    assert_eq!(capped.stats().extra("budget_capped"), Some(1.0));
    assert!(
        capped.stats().bytes as u64 <= between.max_bytes,
        "{} {} {} {}",
        capped.stats(),
        between.max_bytes,
        lo,
        hi
    );
    assert!(capped.grid_count() < full.grid_count());
    capped.validate().unwrap();
    assert_matches_brute(&capped, &mesh);
}

#[test]
fn cells_that_refining_cannot_help_stay_leaves() {
    // 64 copies of one triangle: every child cell they cross would hold all 64.
    let tri = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.2, 0.1),
        Vec3::new(0.3, 1.0, 0.7),
    ];
    let mesh = TriangleMesh::from_triangles(&vec![tri; 64]).unwrap();
    let params = OctreeParams::default().with_split_threshold(0);
    let o = Octree::with_params(&mesh, &params).unwrap();
    assert_eq!(o.grid_count(), 1);
    assert_matches_brute(&o, &mesh);
    // The same count of distinct small triangles is refined.
    let soup = random_soup(64, 3);
    let o = Octree::with_params(
        &soup,
        &OctreeParams {
            root: ResolutionRule::Fixed([1, 1, 1]),
            ..params
        },
    )
    .unwrap();
    assert!(o.grid_count() > 1);
}

#[test]
fn presets_shape_the_tree_as_documented() {
    let mesh = tiled_stadium();
    let n = mesh.len() as f64;

    let classic = Octree::with_params(&mesh, &one_root(OctreeParams::classic())).unwrap();
    assert_eq!(classic.root_geometry().resolution(), [2, 2, 2]);
    for (id, node) in classic.nodes.iter().enumerate() {
        assert_eq!(node.geometry.resolution(), [2, 2, 2], "grid {id}");
        for (c, e) in entries(&classic, id) {
            if let Some(child) = e.child {
                // Not fitted: the child covers its whole cell.
                let cell = node.geometry.cell_bounds(node.geometry.cell_coords(c));
                assert_eq!(*classic.nodes[child].geometry.bounds(), cell);
            }
        }
    }

    let default = Octree::with_params(&mesh, &one_root(OctreeParams::default())).unwrap();
    let root_cells = default.root_geometry().cell_count() as f64;
    let ize = 8.0 * n.powf(0.6);
    assert!(
        (ize..ize * 1.4).contains(&root_cells),
        "{root_cells} root cells, about {ize} expected"
    );
    // Fitted children: the sphere's grid hugs the sphere, not its root cell.
    let sphere_grid = default
        .nodes
        .iter()
        .filter(|g| g.level == 1)
        .max_by_key(|g| g.geometry.cell_count())
        .expect("the sphere's cell is refined");
    let d = sphere_grid.geometry.bounds().diagonal();
    assert!(d.x <= 2.0 + 1e-9 && d.y <= 2.0 + 1e-9, "{d:?}");
    assert_matches_brute(&default, &mesh);

    let two = Octree::with_params(&mesh, &one_root(OctreeParams::two_level())).unwrap();
    assert!(two.levels().len() <= 2);
    assert_eq!(two.root_geometry(), default.root_geometry());

    let grid_root = Octree::with_params(&mesh, &one_root(OctreeParams::grid_root())).unwrap();
    // The seed's single grid (not in parts), as the octree's one root.
    let single = accel_grid::GridParams {
        parts: false,
        ..Default::default()
    };
    let grid = Grid::with_params(&mesh, &single).unwrap();
    assert_eq!(grid_root.root_geometry(), grid.geometry());
    assert!(grid_root.grid_count() > 1);
}

#[test]
fn the_stadium_costs_far_fewer_tests_than_in_a_grid() {
    let mesh = stadium();
    let octree = Octree::new(&mesh).unwrap();
    // Indexed (the default), so that the counters count every reference a
    // cell makes the walk test (a packed grid counts only those its block
    // test keeps); one grid, the seed's, not one per part.
    let indexed = accel_grid::GridParams {
        layout: accel_core::packed::Layout::Indexed,
        parts: false,
        ..Default::default()
    };
    let grid = Grid::with_params(&mesh, &indexed).unwrap();
    let camera = Camera::look_at(
        Vec3::new(3.0, -4.0, 2.0),
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 1.0),
        45.0,
    );
    let (mut in_octree, mut in_grid) = (TraversalCounters::default(), TraversalCounters::default());
    for ray in camera.rays::<f64>(32, 32) {
        let a = octree.intersect_counted(&ray, &mut in_octree).unwrap();
        let b = grid.intersect_counted(&ray, &mut in_grid).unwrap();
        assert_eq!(a, b);
    }
    assert!(
        in_octree.prims * 20 < in_grid.prims,
        "octree {in_octree:?}, grid {in_grid:?}"
    );
}

#[test]
fn level_figures_add_up_to_the_report() {
    let mesh = uv_sphere(Vec3::new(1.0, 2.0, 3.0), 0.5, 20_000);
    let o = Octree::new(&mesh).unwrap();
    let s = o.stats();
    let levels = o.levels();
    assert_eq!(s.kind, "octree");
    assert_eq!(s.primitives, mesh.len());
    assert_eq!(
        levels.iter().map(|l| l.grids).sum::<usize>(),
        o.grid_count()
    );
    assert_eq!(levels[0].grids, 1);
    assert_eq!(levels.iter().map(|l| l.cells).sum::<usize>(), s.nodes);
    assert_eq!(
        levels.iter().map(|l| l.references).sum::<usize>(),
        s.references
    );
    // Every cell is a leaf or a link, and each grid but the root has one link.
    assert_eq!(s.nodes - s.leaves, o.grid_count() - 1);
    assert_eq!(o.cells.reference_count(), s.references + o.grid_count() - 1);
    assert_eq!(s.extra("grids_l0"), Some(1.0));
    assert_eq!(s.extra("cells_l0"), Some(levels[0].cells as f64));
    assert!(s.bytes >= o.cells.bytes());
}

#[test]
fn empty_scenes_and_bad_input() {
    let none: Vec<Sphere<f32>> = Vec::new();
    let o = Octree::new(&none[..]).unwrap();
    let ray = accel_core::Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0)).unwrap();
    assert_eq!(o.intersect(&ray).unwrap(), None);
    assert!(!o.occluded(&ray).unwrap());
    assert!(o.bounds().is_empty());
    let all = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
    assert!(o.query_region(&all).unwrap().is_empty());

    let bad = [
        Sphere::new(Vec3::ZERO, 1.0f32),
        Sphere::new(Vec3::new(f32::NAN, 0.0, 0.0), 1.0),
    ];
    assert_eq!(
        Octree::new(&bad[..]).unwrap_err(),
        BuildError::NonFinitePrimitive { index: 1 }
    );
    let one = [Sphere::new(Vec3::ZERO, 1.0f32)];
    let o = Octree::new(&one[..]).unwrap();
    let bad_ray = accel_core::Ray {
        direction: Vec3::ZERO,
        ..ray
    };
    assert_eq!(
        o.intersect(&bad_ray),
        Err(accel_core::QueryError::ZeroDirection)
    );
    assert_eq!(
        o.occluded(&bad_ray),
        Err(accel_core::QueryError::ZeroDirection)
    );
    let nan_box = Aabb {
        min: Vec3::splat(0.0),
        max: Vec3::new(1.0, f32::NAN, 1.0),
    };
    assert_eq!(
        o.query_region(&nan_box),
        Err(accel_core::QueryError::NonFiniteRegion)
    );
    // The ray starts inside the sphere: the far side is hit.
    assert_eq!(o.intersect(&ray).unwrap().map(|h| h.t), Some(1.0));
}

#[test]
fn a_scene_that_fills_its_box_gets_the_grids_root() {
    // Small triangles all through a cube: the coarse top level would only be
    // refined back into the uniform grid.
    let soup = random_soup(4_000, 5);
    let o = Octree::new(&soup).unwrap();
    assert_eq!(o.root_geometry(), Grid::new(&soup).unwrap().geometry());
    // A surface, and a cluster among walls and a floor, keep Ize's top level.
    for mesh in [uv_sphere(Vec3::ZERO, 1.0, 4_000), stadium()] {
        let o = Octree::new(&mesh).unwrap();
        let want = ResolutionRule::Nested {
            density: 2.0,
            levels: 1,
        }
        .resolution(&mesh.bounds(), mesh.len(), u64::MAX)
        .unwrap();
        assert_eq!(o.root_geometry().resolution(), want);
    }
}

#[test]
fn straddling_primitives_count_by_their_share() {
    let boxes = [
        // Half inside along x, all along y and z: one half.
        Aabb::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0)),
        // Flat in z, a quarter inside: x and y halves.
        Aabb::new(Vec3::new(0.5, 0.5, 0.5), Vec3::new(1.5, 1.5, 0.5)),
        // Wholly inside.
        Aabb::new(Vec3::splat(0.25), Vec3::splat(0.75)),
        // Wholly inside (a point).
        Aabb::from_point(Vec3::splat(0.5)),
    ];
    let cell = Aabb::new(Vec3::splat(0.0), Vec3::splat(1.0));
    // 0.5 + 0.25 + 1 + 1 = 2.75, rounded.
    assert_eq!(super::share(&[0, 1, 2, 3], &boxes, &cell), 3);
    assert_eq!(super::share(&[0, 1], &boxes, &cell), 1);
    assert_eq!(super::share(&[], &boxes, &cell), 1);
}

#[test]
fn child_cells_are_no_finer_than_their_primitives() {
    // Primitives 0.25 wide along x, 0.1 along y, flat in z, in a 2 × 1 × 1 box.
    let boxes: Vec<Aabb<f64>> = (0..8)
        .map(|i| {
            let x = f64::from(i) * 0.25;
            Aabb::new(Vec3::new(x, 0.5, 0.5), Vec3::new(x + 0.25, 0.6, 0.5))
        })
        .collect();
    let b = Aabb::new(Vec3::splat(0.0), Vec3::new(2.0, 1.0, 1.0));
    let prims: Vec<u32> = (0..8).collect();
    // x: 2 / 0.25 = 8 at most; y: 1 / 0.1 = 10; z: no extent, no limit.
    assert_eq!(
        super::no_finer_than_primitives([20, 20, 20], &prims, &boxes, &b),
        [8, 10, 20]
    );
    assert_eq!(
        super::no_finer_than_primitives([3, 4, 5], &prims, &boxes, &b),
        [3, 4, 5]
    );
}

/// The primitives referenced by grid `id` of `o` and every grid below it.
fn referenced_below<T: Real, P: PrimitiveSet<T> + ?Sized>(
    o: &Octree<'_, T, P>,
    id: usize,
    out: &mut Vec<u32>,
) {
    for (_, e) in entries(o, id) {
        out.extend_from_slice(e.prims);
        if let Some(child) = e.child {
            referenced_below(o, child, out);
        }
    }
}

#[test]
fn a_small_mesh_among_large_walls_is_built_apart() {
    let mesh = stadium();
    let n = mesh.len();
    // The sphere's triangles come first, then the 12 wall and 2 floor
    // triangles: each a large primitive.
    let sphere = n - 14;
    let o = Octree::new(&mesh).unwrap();
    o.validate().unwrap();
    assert_eq!(o.stats().extra("parts"), Some(2.0));
    let roots: Vec<_> = o.part_roots().collect();
    assert_eq!(roots.len(), 2);
    // The first part's root covers the sphere alone; the second, the scene.
    let sphere_box = (0..sphere).fold(Aabb::empty(), |b, i| {
        b.union(&PrimitiveSet::bounds(&mesh, i))
    });
    assert_eq!(*roots[0].bounds(), sphere_box);
    assert_eq!(*roots[1].bounds(), o.bounds());
    assert_eq!(o.bounds(), BruteForce::new(&mesh).unwrap().bounds());
    let (mut small, mut large) = (Vec::new(), Vec::new());
    referenced_below(&o, 0, &mut small);
    referenced_below(&o, 1, &mut large);
    assert!(small.iter().all(|&p| (p as usize) < sphere));
    assert!(large.iter().all(|&p| (p as usize) >= sphere));
    small.sort_unstable();
    small.dedup();
    large.sort_unstable();
    large.dedup();
    assert_eq!((small.len(), large.len()), (sphere, 14));
    assert_matches_brute(&o, &mesh);

    // Each part is the octree its primitives alone would get, and a query
    // is theirs in turn, the second with the first's best hit: the same
    // answers and the same work, ray by ray.
    let part = |range: core::ops::Range<usize>| {
        TriangleMesh::new(mesh.positions().to_vec(), mesh.indices()[range].to_vec()).unwrap()
    };
    let (sphere_mesh, walls) = (part(0..sphere), part(sphere..n));
    let (a, b) = (
        Octree::new(&sphere_mesh).unwrap(),
        Octree::new(&walls).unwrap(),
    );
    assert_eq!(o.grid_count(), a.grid_count() + b.grid_count());
    assert_eq!(
        o.stats().references,
        a.stats().references + b.stats().references
    );
    let camera = Camera::look_at(
        Vec3::new(3.0, -4.0, 2.0),
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 1.0),
        60.0,
    );
    let mut hits = [0; 2];
    for ray in camera.rays::<f64>(32, 32) {
        let mut whole = TraversalCounters::default();
        let got = o.intersect_counted(&ray, &mut whole).unwrap();
        let mut apart = TraversalCounters::default();
        let first = a.intersect_counted(&ray, &mut apart).unwrap();
        let rest = first.map_or(ray, |h| {
            Ray::with_interval(ray.origin, ray.direction, ray.t_min, h.t).unwrap()
        });
        let second = b.intersect_counted(&rest, &mut apart).unwrap();
        let want = second
            .map(|h| Hit {
                prim: h.prim + sphere as u32,
                ..h
            })
            .or(first);
        assert_eq!(got, want, "ray {ray:?}");
        assert_eq!(whole, apart, "ray {ray:?}");
        if let Some(h) = got {
            hits[usize::from(h.prim as usize >= sphere)] += 1;
        }
    }
    assert!(
        hits[0] > 50 && hits[1] > 50,
        "rays hit both parts: {hits:?}"
    );
}
