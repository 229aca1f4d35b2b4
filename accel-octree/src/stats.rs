//! Statistics: per level, and the workspace's common report.

use crate::node::{Entry, LevelStats, Node, entry};
use crate::params::MAX_DEPTH;
use accel_core::{AccelStats, Real};
use accel_grid::csr::CellLists;
use std::time::Duration;

/// The names of the per-level figures in [`AccelStats::extra`].
macro_rules! level_names {
    ($($level:literal),*) => {
        [$((concat!("grids_l", $level), concat!("cells_l", $level))),*]
    };
}

const LEVEL_NAMES: [(&str, &str); MAX_DEPTH as usize + 1] = level_names!(
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24
);

/// The figures of each level, root first.
pub(crate) fn level_stats<T: Real>(nodes: &[Node<T>], cells: &CellLists) -> Vec<LevelStats> {
    let mut levels: Vec<LevelStats> = Vec::new();
    for node in nodes {
        let level = node.level as usize;
        if levels.len() <= level {
            levels.resize(level + 1, LevelStats::default());
        }
        let s = &mut levels[level];
        let count = node.geometry.cell_count();
        s.grids += 1;
        s.cells += count;
        for c in 0..count {
            let Entry { prims, child } = entry(cells.cell(node.cell_index(c)));
            if child.is_none() {
                s.leaves += 1;
                s.empty_leaves += usize::from(prims.is_empty());
            }
            s.references += prims.len();
            s.max_leaf_references = s.max_leaf_references.max(prims.len());
        }
    }
    levels
}

/// The common report of a built octree.
pub(crate) fn accel_stats(
    primitives: usize,
    build_time: Duration,
    bytes: usize,
    levels: &[LevelStats],
    parts: usize,
    root_resolution: [u32; 3],
    capped: bool,
) -> AccelStats {
    let sum = |f: fn(&LevelStats) -> usize| levels.iter().map(f).sum::<usize>();
    let mut extra = vec![
        ("grids", sum(|l| l.grids) as f64),
        ("depth", levels.len().saturating_sub(1) as f64),
        ("parts", parts as f64),
        ("root_nx", f64::from(root_resolution[0])),
        ("root_ny", f64::from(root_resolution[1])),
        ("root_nz", f64::from(root_resolution[2])),
        ("budget_capped", f64::from(u8::from(capped))),
    ];
    for (level, (grids, cells)) in levels.iter().zip(LEVEL_NAMES) {
        extra.push((grids, level.grids as f64));
        extra.push((cells, level.cells as f64));
    }
    AccelStats {
        kind: "octree",
        primitives,
        build_time,
        bytes,
        nodes: sum(|l| l.cells),
        leaves: sum(|l| l.leaves),
        empty_leaves: sum(|l| l.empty_leaves),
        references: sum(|l| l.references),
        max_leaf_references: levels
            .iter()
            .map(|l| l.max_leaf_references)
            .max()
            .unwrap_or(0),
        extra,
    }
}
