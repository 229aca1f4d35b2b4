//! The settings `studies tradeoff` measures: one point per setting.
//!
//! Two baselines (`f32`, watertight test, error-bound spawn; the grid and the
//! kD-tree), then one dial turned at a time: precision, triangle test and
//! spawn offset on both baselines' structures, the structure-quality
//! presets of each accelerator, and the layout of the grid's cells and the
//! kD-tree's leaves (memory against speed, same answers).

use accel::KdTreeParams;
use accel::{AccelConfig, kdtree_preset, octree_preset};
use accel_core::TriangleTest;
use accel_core::packed::Layout;
use render::cli::Precision;

/// Where secondary rays start, precision-free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spawn {
    /// pbrt-v4's error-bound offset.
    ErrorBound,
    /// A fixed offset in scene units.
    Fixed(f64),
}

impl Spawn {
    /// Short name.
    #[must_use]
    pub fn name(self) -> String {
        match self {
            Self::ErrorBound => "error-bound".to_owned(),
            Self::Fixed(e) => format!("eps {e:e}"),
        }
    }
}

/// One combination of dials.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    /// Short label for tables and plots.
    pub name: String,
    /// Which dial it turns (`baseline`, `precision`, `triangle test`,
    /// `spawn`, `structure`, `layout`).
    pub dial: &'static str,
    /// Precision of geometry and queries.
    pub precision: Precision,
    /// Ray–triangle test.
    pub test: TriangleTest,
    /// Secondary-ray origin.
    pub spawn: Spawn,
    /// Structure and parameters.
    pub config: AccelConfig,
}

fn setting(
    dial: &'static str,
    precision: Precision,
    test: TriangleTest,
    spawn: Spawn,
    config: AccelConfig,
) -> Setting {
    let mut name = config.label();
    if precision != Precision::F32 {
        name += &format!(" {}", precision.name());
    }
    if test != TriangleTest::Watertight {
        name += " MT";
    }
    if let Spawn::Fixed(e) = spawn {
        name += &format!(" eps{e:e}");
    }
    Setting {
        name,
        dial,
        precision,
        test,
        spawn,
        config,
    }
}

/// Every setting, baselines first.
#[must_use]
pub fn all_settings() -> Vec<Setting> {
    use Precision::{F32, F64};
    use TriangleTest::{MollerTrumbore as Mt, Watertight as Wt};
    let grid = |m: f64| AccelConfig::grid(m);
    let kd = |p: &str| AccelConfig::KdTree(kdtree_preset(p).expect("a preset"));
    let oct = |p: &str| AccelConfig::Octree(octree_preset(p).expect("a preset"));
    let eb = Spawn::ErrorBound;
    let mut out = Vec::new();
    for base in [grid(2.0), kd("default")] {
        out.push(setting("baseline", F32, Wt, eb, base));
    }
    for base in [grid(2.0), kd("default")] {
        out.push(setting("precision", F64, Wt, eb, base.clone()));
        out.push(setting("triangle test", F32, Mt, eb, base));
    }
    for eps in [1e-4, 1e-2] {
        out.push(setting("spawn", F32, Wt, Spawn::Fixed(eps), grid(2.0)));
    }
    for m in [1.0, 3.0] {
        out.push(setting("structure", F32, Wt, eb, grid(m)));
    }
    for p in ["default", "classic", "two-level", "grid-root"] {
        out.push(setting("structure", F32, Wt, eb, oct(p)));
    }
    for p in ["fast-build", "pbrt", "best-traversal"] {
        out.push(setting("structure", F32, Wt, eb, kd(p)));
    }
    // The grid and the kD-tree with packed lists: memory per triangle
    // against speed.
    let packed_grid = AccelConfig::Grid {
        density: 2.0,
        layout: Layout::Packed,
        parts: true,
    };
    let packed_kd = AccelConfig::KdTree(KdTreeParams {
        layout: Layout::Packed,
        ..KdTreeParams::default()
    });
    for config in [packed_grid, packed_kd] {
        out.push(setting("layout", F32, Wt, eb, config));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_named_uniquely_and_turn_one_dial_each() {
        let all = all_settings();
        let names: std::collections::HashSet<_> = all.iter().map(|s| s.name.clone()).collect();
        assert_eq!(names.len(), all.len(), "duplicate names");
        for s in &all {
            let turned = usize::from(s.precision != Precision::F32)
                + usize::from(s.test != TriangleTest::Watertight)
                + usize::from(s.spawn != Spawn::ErrorBound);
            assert!(turned <= 1, "{} turns {turned} dials", s.name);
        }
        assert!(names.contains("grid m=2 MT") && names.contains("kdtree f64"));
        assert!(names.contains("grid m=2 eps1e-4"));
        assert!(names.contains("grid m=2 packed") && names.contains("kdtree packed"));
    }
}
