//! Building the octree: the root grid, then child grids level by level.
//!
//! Each grid's cell lists come from `accel-grid`'s two-pass CSR build
//! ([`CellLists::build`] for the root, [`CellLists::build_items`] over the
//! primitives of the cell being refined) with its [`PrimitiveCells`] visitor,
//! so a primitive is placed in a cell exactly when the grid would place it
//! there. A level's children are built in parallel, then accepted in cell
//! order (deterministic whatever the thread count) while they pay for
//! themselves and fit the memory budget. Finally all grids' cells are joined
//! into one cell array, each refined cell holding the primitives that span it
//! and a link to its child.

use crate::node::{CHILD, MAX_PRIMITIVES, Node};
use crate::params::{OctreeParams, ResolutionRule};
use accel_core::parts::{Group, partition_with_floor};
use accel_core::{Aabb, BuildError, PrimitiveSet, Real, Vec3, primitive_bounds};
use accel_grid::build::{PrimitiveCells, estimate_references};
use accel_grid::cells::GridGeometry;
use accel_grid::csr::CellLists;
use rayon::prelude::*;

/// The share of occupied cells above which a [`ResolutionRule::Nested`] root
/// gives way to the seed's rule (see [`root`]).
const FILLED: f64 = 0.5;
/// The estimated cost of entering a child grid, in primitive tests: its box
/// test, the narrowing of the beam and the start of its walk. Set high on
/// purpose, since every grid also costs a node's memory: on the benchmark
/// scenes, 10 rather than 4 leaves a fifth to a third fewer small grids and
/// the work per ray (cells visited, primitives tested) within a few percent.
const ENTER_COST: f64 = 10.0;
/// The estimated cost of one cell step of a walk, in primitive tests.
const CELL_COST: f64 = 1.0;
/// The most references a child grid's non-empty cells may hold on average,
/// as a fraction of the references it takes over: a child must separate
/// primitives...
const SEPARATION: f64 = 0.5;
/// ...or at least not multiply their references by more than `1 + SPREAD`
/// (a small object in a corner of a cell, refined toward it).
const SPREAD: f64 = 0.125;

/// The built structure, before it is wrapped with its primitives.
pub(crate) struct Built<T> {
    pub(crate) nodes: Vec<Node<T>>,
    /// How many parts: the first `parts` nodes are their root grids.
    pub(crate) parts: usize,
    pub(crate) cells: CellLists,
    /// True when subdivision stopped at the memory budget.
    pub(crate) capped: bool,
}

/// A grid under construction, its cells still listing their primitives.
struct Draft<T> {
    geometry: GridGeometry<T>,
    lists: CellLists,
    level: u32,
    /// `(cell, final entry)` for each refined cell, by cell: the primitives
    /// that stay in the cell and the link to its child.
    links: Vec<(u32, Vec<u32>)>,
}

/// Where and how fine a child grid would be.
struct Plan<T> {
    /// The cell it refines.
    cell_box: Aabb<T>,
    /// Its box: the cell, or the part of it its primitives occupy.
    bounds: Aabb<T>,
    resolution: [u32; 3],
    /// The cell's primitives that span it: they stay in the cell.
    stay: Vec<u32>,
    /// The others: the child grid's.
    go: Vec<u32>,
}

/// The heap bytes of one grid apart from its references: its node, its
/// boundaries and one offset per cell.
fn grid_bytes<T>(resolution: [u32; 3]) -> u64 {
    let cells: u64 = resolution.iter().map(|&n| u64::from(n)).product();
    let boundaries: u64 = resolution.iter().map(|&n| u64::from(n) + 1).sum();
    size_of::<Node<T>>() as u64 + boundaries * size_of::<T>() as u64 + cells * 4
}

/// Builds the octree's grids and joined cell lists over `prims`.
pub(crate) fn build<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    params: &OctreeParams,
) -> Result<Built<T>, BuildError> {
    params.validate()?;
    let (boxes, scene) = primitive_bounds(prims)?;
    let n = prims.len();
    if n > MAX_PRIMITIVES {
        return Err(BuildError::BudgetExceeded {
            what: "primitives (octree indices keep one bit for child links)",
            needed: n as u64,
            budget: MAX_PRIMITIVES as u64,
        });
    }
    let budget = params.max_bytes;
    // A small dense part of a large sparse scene gets a root grid of its
    // own, apart from the large primitives around it.
    let groups = if n == 0 {
        vec![Group {
            prims: Vec::new(),
            bounds: Aabb::from_point(Vec3::ZERO),
        }]
    } else {
        partition_with_floor(&boxes, &scene, params.flat_part && prims.wide_hits())
    };
    let whole = groups.len() == 1;
    let parts = groups.len();
    let mut used = 0u64;
    let mut drafts = Vec::with_capacity(parts);
    for group in &groups {
        let items = (!whole).then_some(group.prims.as_slice());
        let (geometry, lists) = root(
            prims,
            &boxes,
            items,
            group.bounds,
            &params.root,
            budget.saturating_sub(used),
        )?;
        used += grid_bytes::<T>(geometry.resolution()) + lists.reference_count() as u64 * 4;
        drafts.push(Draft {
            geometry,
            lists,
            level: 0,
            links: Vec::new(),
        });
    }

    let mut capped = false;
    let mut level_start = 0;
    for _ in 0..params.max_depth {
        let level_end = drafts.len();
        let candidates: Vec<(u32, u32)> = (level_start..level_end)
            .flat_map(|g| {
                let lists = &drafts[g].lists;
                (0..lists.cell_count())
                    .filter(|&c| lists.cell(c).len() > params.split_threshold)
                    .map(move |c| (g as u32, c as u32))
            })
            .collect();
        level_start = level_end;
        if candidates.is_empty() {
            break;
        }
        let left = budget - used;
        let plans: Vec<Result<Plan<T>, BuildError>> = candidates
            .par_iter()
            .map(|&(g, c)| plan(&drafts[g as usize], c, &boxes, params, left / 4))
            .collect();
        // The candidates whose grids fit what is left; the first that does
        // not ends subdivision.
        let mut planned = 0u64;
        let mut count = 0;
        for p in &plans {
            match p {
                Ok(p) if planned + grid_bytes::<T>(p.resolution) <= left => {
                    planned += grid_bytes::<T>(p.resolution);
                    count += 1;
                }
                Ok(_) | Err(BuildError::BudgetExceeded { .. }) => {
                    capped = true;
                    break;
                }
                Err(e) => return Err(e.clone()),
            }
        }
        let children: Vec<Result<Option<Draft<T>>, BuildError>> = (0..count)
            .into_par_iter()
            .map(|i| {
                let (g, _) = candidates[i];
                let Ok(plan) = &plans[i] else {
                    unreachable!("only planned candidates are built")
                };
                refine(&drafts[g as usize], plan, prims, &boxes, left / 4)
            })
            .collect();
        for (i, child) in children.into_iter().enumerate() {
            let (g, c) = candidates[i];
            let child = match child {
                Ok(Some(child)) => child,
                Ok(None) => continue,
                Err(BuildError::BudgetExceeded { .. }) => {
                    capped = true;
                    break;
                }
                Err(e) => return Err(e),
            };
            // The child's grid, its references and a link replace the
            // references of the primitives that moved down.
            let Ok(plan) = &plans[i] else {
                unreachable!("only planned candidates are built")
            };
            let grown = used
                + grid_bytes::<T>(child.geometry.resolution())
                + (child.lists.reference_count() as u64 + 1) * 4;
            let after = grown - plan.go.len() as u64 * 4;
            if after > budget {
                capped = true;
                break;
            }
            used = after;
            let mut entry = plan.stay.clone();
            entry.push(CHILD | drafts.len() as u32);
            drafts[g as usize].links.push((c, entry));
            drafts.push(child);
        }
        if capped {
            break;
        }
    }
    assemble(drafts, parts, &boxes, capped)
}

/// The root grid by `rule` over `bounds`, within `budget` bytes, holding
/// `items` (every primitive when `None`).
///
/// A [`ResolutionRule::Nested`] root whose cells are mostly occupied
/// ([`FILLED`]: holding a primitive that does not span them, see [`spans`]) is
/// rebuilt by the seed's rule. Ize et al.'s coarse top level assumes
/// primitives gathered on surfaces or in clusters (about `M^(2/3)` of `M`
/// cells occupied); a scene that fills its box evenly is served best by a
/// uniform grid, which the levels below would only imitate at a cost.
fn root<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    boxes: &[Aabb<T>],
    items: Option<&[u32]>,
    bounds: Aabb<T>,
    rule: &ResolutionRule,
    budget: u64,
) -> Result<(GridGeometry<T>, CellLists), BuildError> {
    let over_budget = |e| match e {
        BuildError::BudgetExceeded { needed, .. } => BuildError::BudgetExceeded {
            what: "octree bytes",
            needed: needed.saturating_mul(4),
            budget,
        },
        e => e,
    };
    let grid = |rule: &ResolutionRule| -> Result<(GridGeometry<T>, CellLists), BuildError> {
        let count = items.map_or(prims.len(), <[u32]>::len);
        let resolution = rule
            .resolution(&bounds, count, budget / 4)
            .map_err(over_budget)?;
        let bytes = grid_bytes::<T>(resolution);
        if bytes > budget {
            return Err(BuildError::BudgetExceeded {
                what: "octree bytes",
                needed: bytes,
                budget,
            });
        }
        let geometry = GridGeometry::new(bounds, resolution);
        let visitor = PrimitiveCells {
            geometry: &geometry,
            prims,
            bounds: Some(boxes),
            region: None,
        };
        let max_references = (budget - bytes) / 4;
        // Refused from a sample before the cell lists are made, as the
        // uniform grid is: the exact build below stops at the budget only
        // after enumerating the cells of every primitive before that point.
        let estimate = estimate_references(&visitor, count, |k| {
            items.map_or(k as u32, |items| items[k])
        });
        if let Some(estimate) = estimate.filter(|&e| e as f64 > 2.0 * max_references as f64) {
            return Err(BuildError::BudgetExceeded {
                what: "octree bytes (the root grid's references estimated from 256 primitives spread over the scene)",
                needed: bytes.saturating_add(estimate.saturating_mul(4)),
                budget,
            });
        }
        let lists = CellLists::build_over(
            geometry.cell_count(),
            items,
            prims.len() as u32,
            max_references,
            &visitor,
        )
        .map_err(|e| match e {
            // In the unit of the octree's budget, bytes, as every other
            // refusal of the octree's build.
            BuildError::BudgetExceeded { needed, .. } => BuildError::BudgetExceeded {
                what: "octree bytes (the root grid's cell references)",
                needed: bytes.saturating_add(needed.saturating_mul(4)),
                budget,
            },
            e => e,
        })?;
        Ok((geometry, lists))
    };
    let (geometry, lists) = grid(rule)?;
    if let ResolutionRule::Nested { density, .. } = *rule {
        // Walls and floors span their cells: they occupy no volume.
        let occupied = (0..lists.cell_count())
            .into_par_iter()
            .filter(|&c| {
                let cell = geometry.cell_bounds(geometry.cell_coords(c));
                lists
                    .cell(c)
                    .iter()
                    .any(|&p| !spans(&boxes[p as usize], &cell))
            })
            .count();
        if occupied as f64 > FILLED * lists.cell_count() as f64 && lists.cell_count() > 1 {
            return grid(&ResolutionRule::Density(density));
        }
    }
    Ok((geometry, lists))
}

/// The box and resolution of a child grid for cell `cell` of `parent`.
fn plan<T: Real>(
    parent: &Draft<T>,
    cell: u32,
    boxes: &[Aabb<T>],
    params: &OctreeParams,
    max_cells: u64,
) -> Result<Plan<T>, BuildError> {
    let g = &parent.geometry;
    let cell_box = g.cell_bounds(g.cell_coords(cell as usize));
    let (stay, go): (Vec<u32>, Vec<u32>) = parent
        .lists
        .cell(cell as usize)
        .iter()
        .partition(|&&p| spans(&boxes[p as usize], &cell_box));
    let mut bounds = cell_box;
    if params.fit_children && !go.is_empty() {
        let content = go
            .iter()
            .fold(Aabb::empty(), |b, &p| b.union(&boxes[p as usize]));
        // Every primitive of the cell has bounds touching it, so the common
        // part is never empty; it holds every point where they meet the cell.
        let fitted = content.intersection(&cell_box);
        debug_assert!(!fitted.is_empty(), "a cell's primitives touch it");
        if !fitted.is_empty() {
            bounds = fitted;
        }
    }
    let resolution = match params.children {
        ResolutionRule::Fixed(_) => params.children.resolution(&bounds, go.len(), max_cells)?,
        rule => {
            let res = rule.resolution(&bounds, share(&go, boxes, &bounds), max_cells)?;
            no_finer_than_primitives(res, &go, boxes, &bounds)
        }
    };
    Ok(Plan {
        cell_box,
        bounds,
        resolution,
        stay,
        go,
    })
}

/// How many of `prims` the box `b` holds, counting each by the fraction of
/// its bounds inside `b` (along the axes where the bounds have extent), at
/// least one: a primitive straddling four cells counts a quarter in each,
/// as it did once in the parent's resolution rule.
fn share<T: Real>(prims: &[u32], boxes: &[Aabb<T>], b: &Aabb<T>) -> usize {
    let total: f64 = prims
        .iter()
        .map(|&p| {
            let full = boxes[p as usize];
            let inside = full.intersection(b);
            (0..3)
                .map(|a| {
                    let w = full.max[a] - full.min[a];
                    if w > T::ZERO {
                        ((inside.max[a] - inside.min[a]) / w)
                            .to_f64()
                            .clamp(0.0, 1.0)
                    } else {
                        1.0
                    }
                })
                .product::<f64>()
        })
        .sum();
    (total.round() as usize).clamp(1, prims.len().max(1))
}

/// `resolution` for `prims` in `bounds`, with no more cells along an axis
/// than the primitives' mean extent there (their bounds clipped to `bounds`)
/// fits into the box: finer cells would not separate them, only copy their
/// references into more cells. The seed's rule counts objects as points; in a
/// thin box around a patch of surface it would cut cells much smaller than
/// the triangles.
fn no_finer_than_primitives<T: Real>(
    mut resolution: [u32; 3],
    prims: &[u32],
    boxes: &[Aabb<T>],
    bounds: &Aabb<T>,
) -> [u32; 3] {
    let mut sum = [0.0f64; 3];
    for &p in prims {
        let d = boxes[p as usize].intersection(bounds).diagonal();
        for (a, s) in sum.iter_mut().enumerate() {
            *s += d[a].to_f64().max(0.0);
        }
    }
    let width = bounds.diagonal();
    for (a, s) in sum.iter().enumerate() {
        let mean = s / prims.len().max(1) as f64;
        if mean > 0.0 {
            // The guard keeps exact ratios (1 / 0.1) from rounding up a cell.
            let most = (width[a].to_f64() / mean * (1.0 - 1e-9)).ceil().max(1.0);
            if most < f64::from(resolution[a]) {
                resolution[a] = most as u32;
            }
        }
    }
    resolution
}

/// Whether a primitive with bounds `b` spans `cell`: covers its whole extent
/// along all axes but one (of those along which the cell has extent; along
/// the only one, for a cell on a line). It would cross a whole layer of any
/// grid over the cell (a floor under a dense object, a wall), so it is
/// tested once in the cell rather than referenced by every child cell, and
/// the child grid fits what remains (as hierarchical grids keep large objects
/// at coarse levels).
fn spans<T: Real>(b: &Aabb<T>, cell: &Aabb<T>) -> bool {
    let active = (0..3).filter(|&a| cell.max[a] > cell.min[a]);
    let (mut axes, mut covered) = (0, 0);
    for a in active {
        axes += 1;
        covered += usize::from(b.min[a] <= cell.min[a] && b.max[a] >= cell.max[a]);
    }
    axes > 0 && covered >= (axes - 1).max(1)
}

/// Builds the child grid of `plan`, or `None` when it would not pay for
/// itself.
fn refine<T: Real, P: PrimitiveSet<T> + ?Sized>(
    parent: &Draft<T>,
    plan: &Plan<T>,
    prims: &P,
    boxes: &[Aabb<T>],
    max_references: u64,
) -> Result<Option<Draft<T>>, BuildError> {
    if plan.go.is_empty() {
        return Ok(None);
    }
    let geometry = GridGeometry::new(plan.bounds, plan.resolution);
    let visitor = PrimitiveCells {
        geometry: &geometry,
        prims,
        bounds: Some(boxes),
        region: None,
    };
    let lists = CellLists::build_items(geometry.cell_count(), &plan.go, max_references, &visitor)?;
    if !pays_off(plan, &geometry, &lists) {
        return Ok(None);
    }
    Ok(Some(Draft {
        geometry,
        lists,
        level: parent.level + 1,
        links: Vec::new(),
    }))
}

/// Half the surface area of a box with extents `d`, in `f64` (no overflow
/// for `f32` extents of 1e20).
fn half_area(d: [f64; 3]) -> f64 {
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}

/// Whether a child grid is expected to save work over testing, in the
/// cell, the primitives it would take over (`plan.go`; those that span the
/// cell are tested there either way). Two conditions:
///
/// - **It separates them** (its non-empty cells hold at most [`SEPARATION`]
///   of them on average) **or narrows in on them** (they hold hardly more
///   references in it than in the cell, [`SPREAD`]: the classic octree
///   closing in on a small object in a corner). A cell of coincident or
///   mutually overlapping primitives fails both (every child cell they cross
///   holds them all), and would otherwise be refined again at every level
///   around the same surface, its cells multiplying until the depth limit.
/// - **It is cheaper by the surface-area estimate** (a ray that meets a box
///   meets a box inside it with the ratio of their areas): entering it,
///   [`ENTER_COST`], with probability `A(child)/A(cell)`, then one
///   [`CELL_COST`] and the references of each child cell with probability
///   `A(child cell)/A(cell)` (all child cells have the same size), against
///   one test per primitive taken over.
fn pays_off<T: Real>(plan: &Plan<T>, geometry: &GridGeometry<T>, lists: &CellLists) -> bool {
    let moved = plan.go.len() as f64;
    let refs = lists.reference_count() as f64;
    let full = (lists.cell_count() - lists.empty_cells()) as f64;
    let separates = refs <= SEPARATION * moved * full;
    let no_copies = refs <= moved * (1.0 + SPREAD);
    if !(separates || no_copies) {
        return false;
    }
    let cell_area = half_area(extents(&plan.cell_box));
    if !(cell_area > 0.0) {
        // A cell without area (its primitives on a line): no area ratios;
        // separating them is what counts.
        return true;
    }
    let child = extents(geometry.bounds());
    let res = geometry.resolution();
    let leaf: [f64; 3] = core::array::from_fn(|a| child[a] / f64::from(res[a]));
    let cells = geometry.cell_count() as f64;
    let cost =
        (half_area(child) * ENTER_COST + half_area(leaf) * (cells * CELL_COST + refs)) / cell_area;
    cost < moved
}

/// A box's extents in `f64`.
fn extents<T: Real>(b: &Aabb<T>) -> [f64; 3] {
    let d = b.diagonal();
    [d.x.to_f64(), d.y.to_f64(), d.z.to_f64()]
}

/// Joins the drafts' cells into one array, links in place of split cells.
fn assemble<T: Real>(
    drafts: Vec<Draft<T>>,
    parts: usize,
    boxes: &[Aabb<T>],
    capped: bool,
) -> Result<Built<T>, BuildError> {
    let total: u64 = drafts.iter().map(|d| d.lists.cell_count() as u64).sum();
    if total > u64::from(u32::MAX) {
        return Err(BuildError::BudgetExceeded {
            what: "octree cells (u32 offsets)",
            needed: total,
            budget: u64::from(u32::MAX),
        });
    }
    let cells = CellLists::from_cells(drafts.iter().flat_map(|d| {
        let mut links = d.links.iter().peekable();
        (0..d.lists.cell_count()).map(move |c| match links.peek() {
            Some((cell, entry)) if *cell as usize == c => {
                links.next();
                entry.as_slice()
            }
            _ => d.lists.cell(c),
        })
    }))?;
    // A draft's lists still hold what its children took over: their union is
    // everything referenced in the grid or below it.
    let reach: Vec<Aabb<T>> = drafts
        .par_iter()
        .map(|d| {
            d.lists
                .refs()
                .iter()
                .fold(*d.geometry.bounds(), |b, &p| b.union(&boxes[p as usize]))
        })
        .collect();
    let mut base = 0u32;
    let mut nodes: Vec<Node<T>> = drafts
        .into_iter()
        .zip(reach)
        .map(|(d, reach)| {
            let node = Node {
                reach,
                base,
                level: d.level,
                geometry: d.geometry,
            };
            base += d.lists.cell_count() as u32;
            node
        })
        .collect();
    // The collect may reuse the drafts' allocation, sized for the larger
    // drafts and grown by doubling: release what the budget did not count.
    nodes.shrink_to_fit();
    Ok(Built {
        nodes,
        parts,
        cells,
        capped,
    })
}

#[cfg(test)]
mod tests;
