//! The byte budget of a build ([`KdTreeParams::max_bytes`]): checked before
//! any work, counted as the build goes, never passed by a tree it returns.

use accel_core::packed::Layout;
use accel_core::{Accelerator, BuildError, Real, TriangleMesh, Vec3};
use accel_kdtree::{KdTree, KdTreeParams};
use accel_scenes::{SplitMix64, random_soup};
use proptest::prelude::*;

fn with_budget(max_bytes: u64, layout: Layout) -> KdTreeParams {
    KdTreeParams {
        max_bytes,
        layout,
        ..KdTreeParams::default()
    }
}

/// `n` long thin slivers through random points of the unit cube: perfect
/// splits copy each into hundreds of leaves.
fn slivers(n: usize) -> TriangleMesh<f32> {
    let mut rng = SplitMix64::new(7);
    let mut p = || Vec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()).map(|x| x as f32);
    let triangles: Vec<[Vec3<f32>; 3]> = (0..n)
        .map(|_| {
            let (a, b) = (p(), p());
            [a, b, a + p() * 1e-3]
        })
        .collect();
    TriangleMesh::from_triangles(&triangles).unwrap()
}

#[test]
fn slivers_stop_at_the_budget_long_before_the_whole_tree() {
    let mesh = slivers(4000);
    let whole = KdTree::new(&mesh).unwrap();
    let whole_bytes = whole.stats().bytes as u64;
    // Premise: the slivers are copied many times over.
    assert!(whole.stats().references > 20 * 4000, "{:?}", whole.stats());
    let budget = whole_bytes / 8;
    match KdTree::with_params(&mesh, &with_budget(budget, Layout::Indexed)) {
        Err(BuildError::BudgetExceeded { what, needed, .. }) => {
            assert!(what.contains("max_bytes"), "{what}");
            assert!(needed > budget);
            // Stopped at the first nodes past the budget, not at the end.
            assert!(needed < budget + budget / 4, "{needed} of {budget}");
        }
        other => panic!("expected the byte budget's error, got {other:?}"),
    }
}

#[test]
fn a_scene_that_cannot_fit_is_refused_before_the_build() {
    // One triangle 1,000 times: no plane separates the copies, so the least
    // tree is one leaf of 1,000 references (4,000 bytes), plus its node
    // (8 bytes) and its value of the reach table (4 bytes in f32).
    let t = [
        Vec3::new(0.0f32, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let mesh = TriangleMesh::from_triangles(&vec![t; 1000]).unwrap();
    for budget in [1, 4011] {
        let err = KdTree::with_params(&mesh, &with_budget(budget, Layout::Indexed)).unwrap_err();
        assert!(
            matches!(err, BuildError::BudgetExceeded { needed: 4012, budget: b, .. } if b == budget),
            "{err:?}"
        );
    }
    let tree = KdTree::with_params(&mesh, &with_budget(4012, Layout::Indexed)).unwrap();
    assert_eq!(tree.stats().leaves, 1);
    assert!(matches!(
        KdTree::with_params(&mesh, &with_budget(0, Layout::Indexed)),
        Err(BuildError::InvalidParameter {
            name: "max_bytes",
            ..
        })
    ));
}

/// Every budget either gives a tree within it or the budget's error, and
/// twice the default tree's size always suffices.
fn budget_is_kept<T: Real>(n: usize, seed: u64, budget: u64, layout: Layout) {
    let mesh: TriangleMesh<T> = random_soup(n, seed).cast().unwrap();
    let full = KdTree::with_params(&mesh, &with_budget(u64::MAX, layout)).unwrap();
    let full_bytes = full.stats().bytes as u64;
    KdTree::with_params(&mesh, &with_budget(2 * full_bytes, layout)).unwrap();
    match KdTree::with_params(&mesh, &with_budget(budget, layout)) {
        Ok(tree) => assert!(
            tree.stats().bytes as u64 <= budget,
            "{} bytes over a budget of {budget}",
            tree.stats().bytes
        ),
        Err(BuildError::BudgetExceeded {
            needed, budget: b, ..
        }) => {
            assert_eq!(b, budget);
            assert!(needed > budget);
        }
        Err(e) => panic!("unexpected {e:?}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn a_returned_tree_is_within_its_budget(
        n in 1usize..400,
        seed in any::<u64>(),
        budget in 1u64..60_000,
        packed in any::<bool>(),
        wide in any::<bool>(),
    ) {
        let layout = if packed { Layout::Packed } else { Layout::Indexed };
        if wide {
            budget_is_kept::<f64>(n, seed, budget, layout);
        } else {
            budget_is_kept::<f32>(n, seed, budget, layout);
        }
    }
}
