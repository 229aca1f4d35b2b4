//! A floor as a part of its own: rays that leave it walk none of its cells.

use accel_core::{Accelerator, BruteForce, TraversalCounters, TriangleMesh};
use accel_octree::{Octree, OctreeParams};
use accel_scenes::{FlatFieldSpec, flat_field, rays_leaving_the_floor};

#[test]
fn rays_leaving_a_flat_floor_walk_none_of_its_cells() {
    // A floor of 40 × 25 quads (2,000 triangles) at z = 0 with 4,000
    // triangles standing at its centre, in f32: the floor gets a root grid
    // of its own, whose flat box a ray spawned just above it and going up
    // misses with the thin beam. Without the flat part the same rays walk
    // the cells at their origins.
    let spec = FlatFieldSpec {
        quads: [40, 25],
        extent: [80.0, 50.0],
        dense: 4000,
    };
    let mesh: TriangleMesh<f32> = flat_field(&spec).cast().unwrap();
    let split = Octree::new(&mesh).unwrap();
    let whole = Octree::with_params(
        &mesh,
        &OctreeParams {
            flat_part: false,
            ..OctreeParams::default()
        },
    )
    .unwrap();
    assert_eq!((split.part_roots().len(), whole.part_roots().len()), (2, 1));
    let floor = split.part_roots().nth(1).unwrap().bounds();
    assert_eq!((floor.min.z, floor.max.z), (0.0, 0.0));
    let brute = BruteForce::new(&mesh).unwrap();
    let mut with_part = TraversalCounters::default();
    let mut without = TraversalCounters::default();
    // Points of the floor away from the centre, 1e-5 above it (about the
    // error-bound spawn offset there), rays up and sideways.
    let rays = rays_leaving_the_floor::<f32>(&spec, 1e-5);
    assert_eq!(rays.len(), 191);
    for ray in rays {
        let expected = brute.intersect(&ray).unwrap();
        assert_eq!(
            split.intersect_counted(&ray, &mut with_part).unwrap(),
            expected
        );
        assert_eq!(
            whole.intersect_counted(&ray, &mut without).unwrap(),
            expected
        );
        assert_eq!(split.occluded(&ray).unwrap(), expected.is_some());
    }
    assert_eq!(
        (with_part.nodes, with_part.prims),
        (0, 0),
        "the floor's cells are walked"
    );
    assert!(
        without.nodes >= 190,
        "premise: one root walks {} cells",
        without.nodes
    );
}
