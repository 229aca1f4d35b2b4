//! Memory budgets are checked before the memory is spent.

use accel_core::{BuildError, TriangleMesh, Vec3};
use accel_grid::{Grid, GridParams};

/// `n` copies of one triangle across the unit cube: every copy crosses
/// thousands of the grid's cells.
fn copies(n: usize) -> TriangleMesh<f32> {
    let positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 1.0),
    ];
    TriangleMesh::new(positions, vec![[0, 1, 2]; n]).unwrap()
}

/// See: issue 32, item 3. `Grid::new` on 100,000 copies of one triangle ran
/// 200 s and took 1.6 GB before refusing: the build enumerated the cells of
/// every copy up to the budget, then all of them again for the error's
/// figure. Now a sample of the primitives' cells is counted first and the
/// build is refused from its estimate, before the cell lists are made.
#[test]
fn many_copies_of_a_large_triangle_are_refused_at_the_budget() {
    let mesh = copies(100_000);
    let err = Grid::new(&mesh).map(|_| ()).unwrap_err();
    let budget = GridParams::<f32>::default().max_references;
    match err {
        BuildError::BudgetExceeded {
            what,
            needed,
            budget: b,
        } => {
            assert_eq!(b, budget);
            assert!(
                what.contains("references") && what.contains("estimated"),
                "{what}"
            );
            assert!(needed > 2 * budget, "{needed}");
        }
        e => panic!("expected BudgetExceeded, got {e:?}"),
    }
}

/// The exact build still refuses at the budget what the sample leaves to it
/// (here a scene too small to sample), with what it had counted by then.
#[test]
fn the_exact_build_stops_at_the_budget() {
    let mesh = copies(64);
    let params = GridParams::<f32> {
        max_references: 1_000,
        ..GridParams::default()
    };
    match Grid::with_params(&mesh, &params).map(|_| ()).unwrap_err() {
        BuildError::BudgetExceeded {
            what,
            needed,
            budget,
        } => {
            assert_eq!((what, budget), ("cell references", 1_000));
            assert!(needed > budget, "{needed}");
        }
        e => panic!("expected BudgetExceeded, got {e:?}"),
    }
}
