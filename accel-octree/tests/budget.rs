//! Memory budgets are checked before the memory is spent (issue 32, item 3).

use accel_core::{BuildError, TriangleMesh, Vec3};
use accel_octree::{Octree, OctreeParams};

/// `n` copies of one triangle across the unit cube: every copy crosses
/// hundreds of the root grid's cells.
fn copies(n: usize) -> TriangleMesh<f32> {
    let positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 1.0),
    ];
    TriangleMesh::new(positions, vec![[0, 1, 2]; n]).unwrap()
}

/// The build's refusal, `(what, needed, budget)`; panics on any other outcome.
fn refusal(mesh: &TriangleMesh<f32>, params: &OctreeParams) -> (&'static str, u64, u64) {
    match Octree::with_params(mesh, params).map(|_| ()).unwrap_err() {
        BuildError::BudgetExceeded {
            what,
            needed,
            budget,
        } => (what, needed, budget),
        e => panic!("expected BudgetExceeded, got {e:?}"),
    }
}

/// See: issue 32, item 3 (the octree's part). The uniform grid refuses a
/// scene over its reference budget from a sample before making its cell
/// lists; the octree's root grid now does too, rather than enumerating the
/// cells of every primitive up to the budget first. 100,000 copies of one
/// triangle need some 10^7 root references (tens of MB) against a budget of
/// 4 MiB.
#[test]
fn many_copies_of_a_large_triangle_are_refused_from_a_sample() {
    let mesh = copies(100_000);
    let params = OctreeParams {
        max_bytes: 4 << 20,
        ..OctreeParams::default()
    };
    let (what, needed, budget) = refusal(&mesh, &params);
    assert_eq!(budget, 4 << 20);
    assert!(
        what.contains("root") && what.contains("estimated"),
        "{what}"
    );
    assert!(needed > 2 * budget, "{needed}");
}

/// A scene the sample leaves to the exact build (up to 1,024 primitives) is
/// still refused at the budget, by the exact count.
#[test]
fn a_small_scene_over_the_budget_is_refused_by_the_exact_build() {
    let mesh = copies(1_000);
    let params = OctreeParams {
        max_bytes: 64 << 10,
        ..OctreeParams::default()
    };
    let (what, needed, budget) = refusal(&mesh, &params);
    assert!(!what.contains("estimated"), "{what}");
    // In the budget's own unit, bytes, like every octree refusal.
    assert!(what.starts_with("octree bytes"), "{what}");
    assert_eq!(budget, 64 << 10);
    assert!(needed > budget, "{needed}");
}

/// Under the budget the sample refuses nothing: the same scene builds with
/// the default budget, and answers as brute force does.
#[test]
fn the_same_scene_builds_within_the_default_budget() {
    use accel_core::{Accelerator, BruteForce, Ray};
    let mesh = copies(2_000);
    let octree = Octree::new(&mesh).expect("within the default budget");
    let brute = BruteForce::new(&mesh).unwrap();
    let ray = Ray::new(Vec3::new(0.2, 0.3, -1.0), Vec3::new(0.0, 0.0, 1.0)).unwrap();
    let key = |h: Option<accel_core::Hit<f32>>| h.map(|h| h.bit_key());
    assert_eq!(
        key(octree.intersect(&ray).unwrap()),
        key(brute.intersect(&ray).unwrap())
    );
    assert!(octree.intersect(&ray).unwrap().is_some());
}

/// Whatever stage refuses (the root's resolution, its estimate, its exact
/// cell lists, the nested grids), the refusal is counted in bytes against
/// the `max_bytes` given, never in cells or references against a budget
/// the user did not set.
#[test]
fn every_refusal_is_in_bytes_of_the_budget_given() {
    let mesh = copies(1_000);
    let mut refused = 0;
    for shift in 8..24 {
        let max_bytes = 1u64 << shift;
        let params = OctreeParams {
            max_bytes,
            ..OctreeParams::default()
        };
        match Octree::with_params(&mesh, &params) {
            Ok(_) => {}
            Err(BuildError::BudgetExceeded {
                what,
                needed,
                budget,
            }) => {
                refused += 1;
                assert!(what.starts_with("octree bytes"), "{max_bytes}: {what}");
                assert_eq!(budget, max_bytes);
                assert!(needed > budget, "{what}: {needed} of {budget}");
            }
            Err(e) => panic!("{max_bytes}: {e:?}"),
        }
    }
    // Premise: the small budgets were refused, the large ones were not.
    assert!((1..16).contains(&refused), "{refused} of 16 refused");
}
