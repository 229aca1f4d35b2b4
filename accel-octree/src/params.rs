//! Build parameters: how many cells each grid gets, when a cell becomes a
//! grid of its own, and the limits (depth, memory).

use accel_core::packed::Layout;
use accel_core::{Aabb, BuildError, Real};

/// The deepest level below the root that [`OctreeParams::max_depth`] may ask
/// for. Deeper trees only pay on scenes spanning more than `2^24` of their
/// smallest feature, and each level costs a recursion step per ray.
pub const MAX_DEPTH: u32 = 24;

/// How many cells a grid (the root or a child) gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ResolutionRule {
    /// The seed's rule, as the uniform grid uses it
    /// ([`accel_grid::resolution::resolution`]): about `m³·n` roughly cubical
    /// cells for `n` references, `m` the density.
    Density(f64),
    /// The top level of a nested grid after Ize, Shirley & Parker (2007):
    /// about `m³·n^(3/(3+2d))` cells for a structure planned with `d` levels
    /// of grids below it. Coarser than the seed's rule (`d = 0`), because the
    /// levels below refine wherever the objects are. Their analysis assumes
    /// objects gathered on surfaces or in clusters: at the root, a scene that
    /// fills its box instead (more than half of these cells occupied by
    /// primitives that do not span them, unlike walls and floors) gets
    /// the seed's rule with the same density, a uniform grid being the best
    /// structure there.
    Nested {
        /// Cells per object along each axis, `m`.
        density: f64,
        /// Planned levels below this one, `d`.
        levels: u32,
    },
    /// A fixed number of cells per axis: `[2, 2, 2]` is the classic octree.
    /// An axis along which the box has no extent gets one cell.
    Fixed([u32; 3]),
}

impl ResolutionRule {
    /// Cells per axis for `count` references in `bounds`, refusing more than
    /// `max_cells` cells.
    ///
    /// # Errors
    /// [`BuildError::InvalidParameter`] for a density that is not finite and
    /// positive or a fixed resolution with a zero; [`BuildError::BudgetExceeded`]
    /// past `max_cells`.
    pub fn resolution<T: Real>(
        &self,
        bounds: &Aabb<T>,
        count: usize,
        max_cells: u64,
    ) -> Result<[u32; 3], BuildError> {
        self.check("resolution")?;
        match *self {
            Self::Density(m) => accel_grid::resolution::resolution(bounds, count, m, max_cells),
            Self::Nested { density, levels } => {
                // n^(3/(3+2d)) objects' worth of cells, at least one.
                let exponent = 3.0 / (3.0 + 2.0 * f64::from(levels));
                let target = (count as f64).powf(exponent).round().max(1.0) as usize;
                let target = if count == 0 { 0 } else { target };
                accel_grid::resolution::resolution(bounds, target, density, max_cells)
            }
            Self::Fixed(cells) => {
                let d = bounds.diagonal();
                let res: [u32; 3] =
                    core::array::from_fn(|a| if d[a] > T::ZERO { cells[a] } else { 1 });
                let total: u64 = res.iter().map(|&n| u64::from(n)).product();
                if total > max_cells {
                    return Err(BuildError::BudgetExceeded {
                        what: "grid cells",
                        needed: total,
                        budget: max_cells,
                    });
                }
                Ok(res)
            }
        }
    }

    /// Checks the rule's numbers; `name` names the parameter in the error.
    fn check(&self, name: &'static str) -> Result<(), BuildError> {
        let density = match *self {
            Self::Density(m) | Self::Nested { density: m, .. } => m,
            Self::Fixed(cells) => {
                if cells.contains(&0) {
                    return Err(BuildError::InvalidParameter {
                        name,
                        value: format!("Fixed({cells:?})"),
                        expected: "at least one cell per axis",
                    });
                }
                return Ok(());
            }
        };
        if density.is_finite() && density > 0.0 {
            Ok(())
        } else {
            Err(BuildError::InvalidParameter {
                name,
                value: density.to_string(),
                expected: "a finite density above 0",
            })
        }
    }
}

/// Build parameters of an [`crate::Octree`].
///
/// The root grid covers the scene's bounds with [`OctreeParams::root`] cells.
/// Level by level, every cell holding more than
/// [`OctreeParams::split_threshold`] references becomes a child grid of
/// [`OctreeParams::children`] cells over the cell (or over the part of it its
/// primitives occupy, with [`OctreeParams::fit_children`]), as long as the
/// child is expected to pay for itself (see the crate docs), the depth stays
/// within [`OctreeParams::max_depth`] and the memory within
/// [`OctreeParams::max_bytes`].
#[derive(Clone, Debug, PartialEq)]
pub struct OctreeParams {
    /// Cells of the root grid. Default: [`ResolutionRule::Nested`] with
    /// density 2 and one planned level below (Ize et al.'s two-level grid),
    /// about `8·n^(3/5)` cells.
    pub root: ResolutionRule,
    /// Cells of each child grid, for the primitives of the cell it refines
    /// (each counted by the share of its bounds inside the child, so that a
    /// primitive straddling cells is not counted in full in each). The
    /// density rules never make cells smaller than those primitives' mean
    /// extent along an axis: finer cells would only copy references. Default:
    /// [`ResolutionRule::Density`] 1.5 (about 3.4 cells per primitive): with
    /// children fitted to their primitives, the benchmark scenes see the
    /// uniform grid's work per ray at density 2, or less, in about its memory.
    pub children: ResolutionRule,
    /// A cell holding more references than this may become a child grid.
    /// Default 12.
    pub split_threshold: usize,
    /// The most levels of child grids below the root (0: a uniform grid; at
    /// most [`MAX_DEPTH`]). Default 6.
    pub max_depth: u32,
    /// A child grid covers only the part of its cell that the cell's
    /// primitives' bounds occupy, instead of the whole cell: a small dense
    /// object in a large cell gets its fine cells at once, and rays that
    /// cross the cell beside it skip it in one box test. Default `true`.
    pub fit_children: bool,
    /// The most heap bytes the octree may take. A root grid over the budget
    /// is refused with [`BuildError::BudgetExceeded`], from a sample of its
    /// primitives' cells before its cell lists are made where the sample
    /// puts it past twice the budget
    /// ([`accel_grid::build::estimate_references`]); child grids are added
    /// level by level in cell order until the next one would exceed it, and
    /// the cells left over stay leaves. Default 2 GiB.
    pub max_bytes: u64,
    /// Whether a scene that stays one part, with many primitives lying flat
    /// in one axis-aligned plane (a floor), gets a root grid of its own for
    /// them ([`accel_core::parts::split_flat`]): with primitives whose hits
    /// are wide ([`accel_core::PrimitiveSet::wide_hits`]), a ray leaving the
    /// floor then misses that root's flat box, tested with the wide type's
    /// thin beam, and walks no cell of it. Default `true`.
    pub flat_part: bool,
    /// Whether cells' triangles are also kept in packed blocks, tested
    /// several at once ([`Layout`]). Default [`Layout::Indexed`]: packed
    /// cells traced 1.00–1.04× as fast on the 100k sphere but 0.84–0.95× on
    /// the teapot in a stadium. The answers are the same either way.
    pub layout: Layout,
}

impl Default for OctreeParams {
    fn default() -> Self {
        Self {
            root: ResolutionRule::Nested {
                density: 2.0,
                levels: 1,
            },
            children: ResolutionRule::Density(1.5),
            split_threshold: 12,
            max_depth: 6,
            fit_children: true,
            max_bytes: 1 << 31,
            flat_part: true,
            layout: Layout::Indexed,
        }
    }
}

impl OctreeParams {
    /// The classic octree: a 2×2×2 root and 2×2×2 children over the whole
    /// cell, split while a cell holds more than 8 references, up to 20
    /// levels deep. Many small grids: slower and larger than the default, and
    /// the structure the literature calls an octree.
    #[must_use]
    pub fn classic() -> Self {
        Self {
            root: ResolutionRule::Fixed([2, 2, 2]),
            children: ResolutionRule::Fixed([2, 2, 2]),
            split_threshold: 8,
            max_depth: 20,
            fit_children: false,
            ..Self::default()
        }
    }

    /// Ize, Shirley & Parker's two-level grid: the default's coarse root and
    /// one level of child grids, no deeper.
    #[must_use]
    pub fn two_level() -> Self {
        Self {
            max_depth: 1,
            ..Self::default()
        }
    }

    /// The uniform grid's own root (density 2, about `8·n` cells: the same
    /// cells as `accel_grid::Grid::new`), refined where a cell is overfull:
    /// the grid's behaviour on evenly filled scenes, the octree's on
    /// clustered ones, at the grid's memory plus the children's.
    #[must_use]
    pub fn grid_root() -> Self {
        Self {
            root: ResolutionRule::Density(2.0),
            ..Self::default()
        }
    }

    /// The parameters with `max_depth` levels below the root.
    #[must_use]
    pub fn with_max_depth(mut self, max_depth: u32) -> Self {
        self.max_depth = max_depth;
        self
    }

    /// The parameters with split threshold `threshold`.
    #[must_use]
    pub fn with_split_threshold(mut self, threshold: usize) -> Self {
        self.split_threshold = threshold;
        self
    }

    /// Checks every parameter.
    ///
    /// # Errors
    /// [`BuildError::InvalidParameter`] naming the first bad one.
    pub fn validate(&self) -> Result<(), BuildError> {
        self.root.check("root")?;
        self.children.check("children")?;
        if self.max_depth > MAX_DEPTH {
            return Err(BuildError::InvalidParameter {
                name: "max_depth",
                value: self.max_depth.to_string(),
                expected: "at most 24 (MAX_DEPTH)",
            });
        }
        if self.max_bytes == 0 {
            return Err(BuildError::InvalidParameter {
                name: "max_bytes",
                value: "0".into(),
                expected: "a positive number of bytes",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::Vec3;

    fn box123() -> Aabb<f64> {
        Aabb::new(Vec3::new(1.0, -2.0, 0.5), Vec3::new(2.0, 0.0, 3.5))
    }

    #[test]
    fn nested_rule_is_coarser_by_the_ize_exponent() {
        let b = Aabb::new(Vec3::splat(0.0f64), Vec3::splat(1.0));
        let cells = |r: [u32; 3]| r.iter().map(|&n| u64::from(n)).product::<u64>();
        let n = 100_000;
        let seed = ResolutionRule::Density(2.0)
            .resolution(&b, n, u64::MAX)
            .unwrap();
        let nested0 = ResolutionRule::Nested {
            density: 2.0,
            levels: 0,
        };
        assert_eq!(nested0.resolution(&b, n, u64::MAX).unwrap(), seed);
        for (levels, exponent) in [(1u32, 0.6), (2, 3.0 / 7.0)] {
            let rule = ResolutionRule::Nested {
                density: 2.0,
                levels,
            };
            let got = cells(rule.resolution(&b, n, u64::MAX).unwrap()) as f64;
            let want = 8.0 * (n as f64).powf(exponent);
            // The "+1" per axis of the seed's rule adds up to a third.
            assert!(
                (want..want * 1.4).contains(&got),
                "d = {levels}: {got} cells, about {want} expected"
            );
        }
    }

    #[test]
    fn fixed_rule_keeps_flat_axes_to_one_cell() {
        let flat = Aabb::new(Vec3::new(0.0f32, 1.0, 2.0), Vec3::new(3.0, 1.0, 5.0));
        let rule = ResolutionRule::Fixed([2, 3, 4]);
        assert_eq!(rule.resolution(&flat, 10, u64::MAX).unwrap(), [2, 1, 4]);
        assert_eq!(rule.resolution(&box123(), 10, u64::MAX).unwrap(), [2, 3, 4]);
        assert!(matches!(
            rule.resolution(&box123(), 10, 23),
            Err(BuildError::BudgetExceeded {
                needed: 24,
                budget: 23,
                ..
            })
        ));
    }

    #[test]
    fn bad_parameters_are_named() {
        let cases: [(OctreeParams, &str); 5] = [
            (
                OctreeParams {
                    root: ResolutionRule::Density(0.0),
                    ..OctreeParams::default()
                },
                "root",
            ),
            (
                OctreeParams {
                    children: ResolutionRule::Nested {
                        density: f64::NAN,
                        levels: 1,
                    },
                    ..OctreeParams::default()
                },
                "children",
            ),
            (
                OctreeParams {
                    children: ResolutionRule::Fixed([2, 0, 2]),
                    ..OctreeParams::default()
                },
                "children",
            ),
            (
                OctreeParams::default().with_max_depth(MAX_DEPTH + 1),
                "max_depth",
            ),
            (
                OctreeParams {
                    max_bytes: 0,
                    ..OctreeParams::default()
                },
                "max_bytes",
            ),
        ];
        for (params, want) in cases {
            match params.validate() {
                Err(BuildError::InvalidParameter { name, .. }) => assert_eq!(name, want),
                other => panic!("{want}: expected InvalidParameter, got {other:?}"),
            }
        }
        for ok in [
            OctreeParams::default(),
            OctreeParams::classic(),
            OctreeParams::two_level(),
            OctreeParams::grid_root(),
            OctreeParams::default().with_max_depth(MAX_DEPTH),
        ] {
            assert_eq!(ok.validate(), Ok(()));
        }
    }
}
