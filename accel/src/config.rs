//! The structures by name, with their parameters and presets.
//!
//! Adding an accelerator means one [`AccelKind`] variant, its name, one
//! [`AccelConfig`] variant, one [`AnyAccelerator`] variant and one arm of
//! [`build_config`]. [`crate::choose`] picks among them per scene.

use crate::AnyAccelerator;
use accel_core::packed::Layout;
use accel_core::{BruteForce, BuildError, PrimitiveSet, Real};
use accel_grid::{Grid, GridParams};
use accel_kdtree::{KdTree, KdTreeParams};
use accel_octree::{Octree, OctreeParams, ResolutionRule};
use std::fmt;
use std::str::FromStr;

/// An acceleration structure [`build`] can build.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AccelKind {
    /// `accel_grid::Grid`: the uniform grid.
    Grid,
    /// `accel_octree::Octree`: the octree of nested grids.
    Octree,
    /// `accel_kdtree::KdTree`: the SAH kD-tree.
    KdTree,
    /// `accel_core::BruteForce`: every primitive for every ray (the reference).
    Brute,
}

impl AccelKind {
    /// Every kind, in report order.
    pub const ALL: [Self; 4] = [Self::Grid, Self::Octree, Self::KdTree, Self::Brute];

    /// The name used on the command line and in reports.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Grid => "grid",
            Self::Octree => "octree",
            Self::KdTree => "kdtree",
            Self::Brute => "brute",
        }
    }

    /// The kind called `name` ([`AccelKind::name`]: `grid`, `octree`,
    /// `kdtree`, `brute`).
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

impl fmt::Display for AccelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Why an accelerator could not be built.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AccelError {
    /// The build refused the scene.
    #[error("building the {kind}: {cause}")]
    Build {
        /// Which structure.
        kind: AccelKind,
        /// Why. Named in the message, so not also a `source()`: a report
        /// of the error's chain (`{:#}`) would say it twice.
        cause: BuildError,
    },
}

/// Builds the structure of `kind`, with its default parameters, over `prims`.
///
/// # Errors
/// [`AccelError::Build`]: the structure's own [`BuildError`].
pub fn build<'a, T: Real, P: PrimitiveSet<T> + ?Sized>(
    kind: AccelKind,
    prims: &'a P,
) -> Result<AnyAccelerator<'a, T, P>, AccelError> {
    build_config(&AccelConfig::default_for(kind), prims)
}

/// Builds the structure `config` describes over `prims`.
///
/// # Errors
/// [`AccelError::Build`]: the structure's own [`BuildError`] (parameters out
/// of range are refused there, naming the parameter).
pub fn build_config<'a, T: Real, P: PrimitiveSet<T> + ?Sized>(
    config: &AccelConfig,
    prims: &'a P,
) -> Result<AnyAccelerator<'a, T, P>, AccelError> {
    build_config_within(config, prims, None)
}

/// [`build_config`] within a memory budget of `max_bytes` (`None`: the
/// structures' own defaults), refused with the figure as soon as the build
/// counts past it: the octree's and the kD-tree's `max_bytes`, and the
/// grid's cells and references (4 bytes each) at most half of it each. A
/// budget only lowers the structures' defaults, never raises them.
///
/// # Errors
/// As [`build_config`]; [`BuildError::BudgetExceeded`] past the budget.
pub fn build_config_within<'a, T: Real, P: PrimitiveSet<T> + ?Sized>(
    config: &AccelConfig,
    prims: &'a P,
    max_bytes: Option<u64>,
) -> Result<AnyAccelerator<'a, T, P>, AccelError> {
    let kind = config.kind();
    let wrap = |cause| AccelError::Build { kind, cause };
    let cap =
        |default: u64, share: u64| max_bytes.map_or(default, |b| default.min((b / share).max(1)));
    Ok(match config {
        AccelConfig::Grid {
            density,
            layout,
            parts,
        } => {
            let defaults = GridParams::with_density(*density);
            let params = GridParams {
                layout: *layout,
                parts: *parts,
                max_cells: cap(defaults.max_cells, 8),
                max_references: cap(defaults.max_references, 8),
                ..defaults
            };
            AnyAccelerator::Grid(Grid::with_params(prims, &params).map_err(wrap)?)
        }
        AccelConfig::Octree(p) => {
            let p = OctreeParams {
                max_bytes: cap(p.max_bytes, 1),
                ..p.clone()
            };
            AnyAccelerator::Octree(Octree::with_params(prims, &p).map_err(wrap)?)
        }
        AccelConfig::KdTree(p) => {
            let p = KdTreeParams {
                max_bytes: cap(p.max_bytes, 1),
                ..p.clone()
            };
            AnyAccelerator::KdTree(KdTree::with_params(prims, &p).map_err(wrap)?)
        }
        AccelConfig::Brute => AnyAccelerator::Brute(BruteForce::new(prims).map_err(wrap)?),
    })
}

/// The grid's default layout ([`GridParams::layout`]).
pub const GRID_LAYOUT: Layout = accel_grid::DEFAULT_LAYOUT;

/// An accelerator and its build parameters: the structure-quality dial.
///
/// - grid: density `m` (about `m³·n` cells; more cells mean fewer tests per
///   ray but more cells walked and more memory);
/// - octree: [`OctreeParams`] (split threshold, depth, resolution rules and
///   presets);
/// - kD-tree: [`KdTreeParams`] (SAH costs, empty bonus, leaf size, presets).
#[derive(Clone, Debug, PartialEq)]
pub enum AccelConfig {
    /// A uniform grid of density `m`.
    Grid {
        /// Cells per object along each axis.
        density: f64,
        /// Whether cells' triangles are also packed ([`Layout`]).
        layout: Layout,
        /// Whether a small dense part or a floor gets a grid of its own
        /// ([`GridParams::parts`]).
        parts: bool,
    },
    /// An octree of nested grids.
    Octree(OctreeParams),
    /// A SAH kD-tree.
    KdTree(KdTreeParams),
    /// Brute force.
    Brute,
}

impl AccelConfig {
    /// A grid of density `m` with the default layout.
    #[must_use]
    pub fn grid(density: f64) -> Self {
        Self::Grid {
            density,
            layout: GRID_LAYOUT,
            parts: true,
        }
    }

    /// The structure with its default parameters.
    #[must_use]
    pub fn default_for(kind: AccelKind) -> Self {
        match kind {
            AccelKind::Grid => Self::grid(2.0),
            AccelKind::Octree => Self::Octree(OctreeParams::default()),
            AccelKind::KdTree => Self::KdTree(KdTreeParams::default()),
            AccelKind::Brute => Self::Brute,
        }
    }

    /// Which structure.
    #[must_use]
    pub const fn kind(&self) -> AccelKind {
        match self {
            Self::Grid { .. } => AccelKind::Grid,
            Self::Octree(_) => AccelKind::Octree,
            Self::KdTree(_) => AccelKind::KdTree,
            Self::Brute => AccelKind::Brute,
        }
    }

    /// A short label: the kind and what differs from its defaults
    /// (`grid m=3`, `octree classic`, `kdtree fast-build`, `kdtree ci=20
    /// ct=1 eb=0.3`). Configurations that build different structures get
    /// different labels; the budgets (`max_bytes` and the like) and the
    /// parallel threshold, which do not change a structure, are left out.
    #[must_use]
    pub fn label(&self) -> String {
        match self {
            Self::Grid {
                density,
                layout,
                parts,
            } => {
                let whole = if *parts { "" } else { " one-part" };
                format!(
                    "grid m={density}{whole}{}",
                    layout_label(*layout, GRID_LAYOUT)
                )
            }
            Self::Octree(p) => {
                let shape = match octree_preset_name(p) {
                    Some("default") => "octree".to_owned(),
                    Some(name) => format!("octree {name}"),
                    None => format!(
                        "octree t={} d={}{}{}",
                        p.split_threshold,
                        p.max_depth,
                        octree_rules_label(p),
                        flat_label(p.flat_part)
                    ),
                };
                shape + &layout_label(p.layout, OctreeParams::default().layout)
            }
            Self::KdTree(p) => {
                let shape = match kdtree_preset_name(p) {
                    Some("default") => "kdtree".to_owned(),
                    Some(name) => format!("kdtree {name}"),
                    None => format!(
                        "kdtree ci={} ct={} eb={}{}{}{}{}",
                        p.intersect_cost,
                        p.traversal_cost,
                        p.empty_bonus,
                        binning_label(p),
                        depth_label(p),
                        leaves_label(p),
                        flat_label(p.flat_part)
                    ),
                };
                shape + &layout_label(p.layout, KdTreeParams::default().layout)
            }
            Self::Brute => "brute".to_owned(),
        }
    }
}

/// How a kD-tree's splits are chosen, when not the default: ` exact`, or
/// ` binned>N/K` (binned SAH above N primitives, K bins).
fn binning_label(p: &KdTreeParams) -> String {
    let d = KdTreeParams::default();
    if p.binned_above == usize::MAX {
        " exact".to_owned()
    } else if (p.binned_above, p.bins) == (d.binned_above, d.bins) {
        String::new()
    } else {
        format!(" binned>{}/{}", p.binned_above, p.bins)
    }
}

/// The layout when not the structure's default: ` indexed`, ` packed`.
fn layout_label(layout: Layout, default: Layout) -> String {
    if layout == default {
        String::new()
    } else {
        format!(" {}", layout.name())
    }
}

/// ` no-flat` for a tree built without a flat part.
fn flat_label(flat_part: bool) -> &'static str {
    if flat_part { "" } else { " no-flat" }
}

/// A kD-tree's depth limit when not the default: ` db=D` (its constant),
/// ` depth=N` (a fixed limit).
fn depth_label(p: &KdTreeParams) -> String {
    let mut label = String::new();
    if p.depth_base != KdTreeParams::default().depth_base {
        label += &format!(" db={}", p.depth_base);
    }
    if let Some(depth) = p.max_depth {
        label += &format!(" depth={depth}");
    }
    label
}

/// What else shapes a kD-tree's leaves, when not the default: ` ls=N` (the
/// leaf size) and, for the fast build (`binned_above` 0, the only one that
/// reads them), ` clip>N` or ` no-clip` and ` tighten>N` or ` no-tighten`.
/// The budgets and the parallel threshold do not change the tree and are
/// left out.
fn leaves_label(p: &KdTreeParams) -> String {
    let d = KdTreeParams::default();
    let mut label = String::new();
    if p.leaf_size != d.leaf_size {
        label += &format!(" ls={}", p.leaf_size);
    }
    if p.binned_above == 0 {
        let above = |name: &str, n: usize, default: usize| match n {
            _ if n == default => String::new(),
            usize::MAX => format!(" no-{name}"),
            n => format!(" {name}>{n}"),
        };
        label += &above("clip", p.clip_above, d.clip_above);
        label += &above("tighten", p.tighten_above, d.tighten_above);
    }
    label
}

/// An octree's resolution rules and fitting when not the default:
/// ` root=R`, ` children=R` (`m2`: density 2; `m2/1`: nested, density 2,
/// one level planned below; `2x2x2`: fixed) and ` unfitted`.
fn octree_rules_label(p: &OctreeParams) -> String {
    let d = OctreeParams::default();
    let rule = |r: ResolutionRule| match r {
        ResolutionRule::Density(m) => format!("m{m}"),
        ResolutionRule::Nested { density, levels } => format!("m{density}/{levels}"),
        ResolutionRule::Fixed([x, y, z]) => format!("{x}x{y}x{z}"),
    };
    let mut label = String::new();
    if p.root != d.root {
        label += &format!(" root={}", rule(p.root));
    }
    if p.children != d.children {
        label += &format!(" children={}", rule(p.children));
    }
    if !p.fit_children {
        label += " unfitted";
    }
    label
}

impl fmt::Display for AccelConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.label())
    }
}

/// A name [`AccelConfig::from_str`] does not know.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown accelerator {0:?}: expected grid [m=DENSITY], octree [{octree}], kdtree [{kdtree}] or brute",
    octree = OCTREE_PRESETS.join("|"),
    kdtree = KDTREE_PRESETS.join("|")
)]
pub struct UnknownAccel(pub String);

impl FromStr for AccelKind {
    type Err = UnknownAccel;

    /// [`AccelKind::from_name`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::from_name(s.trim()).ok_or_else(|| UnknownAccel(s.to_owned()))
    }
}

impl FromStr for AccelConfig {
    type Err = UnknownAccel;

    /// A structure by name with its default parameters (`grid`, `octree`,
    /// `kdtree`, `brute`), a preset (`octree two-level`, `kdtree
    /// fast-build`: [`OCTREE_PRESETS`], [`KDTREE_PRESETS`]), or a grid
    /// density (`grid m=3`): the short forms of [`AccelConfig::label`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let unknown = || UnknownAccel(s.to_owned());
        let mut words = s.split_whitespace();
        let kind = AccelKind::from_name(words.next().ok_or_else(unknown)?).ok_or_else(unknown)?;
        let config = match (kind, words.next()) {
            (_, None) => Self::default_for(kind),
            (AccelKind::Grid, Some(m)) => {
                let density = m
                    .strip_prefix("m=")
                    .and_then(|d| d.parse::<f64>().ok())
                    .filter(|d| d.is_finite() && *d > 0.0)
                    .ok_or_else(unknown)?;
                Self::grid(density)
            }
            (AccelKind::Octree, Some(p)) => Self::Octree(octree_preset(p).ok_or_else(unknown)?),
            (AccelKind::KdTree, Some(p)) => Self::KdTree(kdtree_preset(p).ok_or_else(unknown)?),
            (AccelKind::Brute, Some(_)) => return Err(unknown()),
        };
        if words.next().is_some() {
            return Err(unknown());
        }
        Ok(config)
    }
}

/// The octree presets by name.
pub const OCTREE_PRESETS: [&str; 4] = ["default", "classic", "two-level", "grid-root"];
/// The kD-tree presets by name.
pub const KDTREE_PRESETS: [&str; 4] = ["default", "fast-build", "best-traversal", "pbrt"];

/// The octree preset called `name` (see [`OCTREE_PRESETS`]).
#[must_use]
pub fn octree_preset(name: &str) -> Option<OctreeParams> {
    Some(match name {
        "default" => OctreeParams::default(),
        "classic" => OctreeParams::classic(),
        "two-level" => OctreeParams::two_level(),
        "grid-root" => OctreeParams::grid_root(),
        _ => return None,
    })
}

/// The kD-tree preset called `name` (see [`KDTREE_PRESETS`]).
#[must_use]
pub fn kdtree_preset(name: &str) -> Option<KdTreeParams> {
    Some(match name {
        "default" => KdTreeParams::default(),
        "fast-build" => KdTreeParams::fast_build(),
        "best-traversal" => KdTreeParams::best_traversal(),
        "pbrt" => KdTreeParams::pbrt(),
        _ => return None,
    })
}

/// The name of the preset `p` is, whatever its layout.
fn octree_preset_name(p: &OctreeParams) -> Option<&'static str> {
    OCTREE_PRESETS.into_iter().find(|n| {
        octree_preset(n).is_some_and(|preset| {
            preset
                == OctreeParams {
                    layout: preset.layout,
                    ..p.clone()
                }
        })
    })
}

/// The name of the preset `p` is, whatever its layout.
fn kdtree_preset_name(p: &KdTreeParams) -> Option<&'static str> {
    KDTREE_PRESETS.into_iter().find(|n| {
        kdtree_preset(n).is_some_and(|preset| {
            preset
                == KdTreeParams {
                    layout: preset.layout,
                    ..p.clone()
                }
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::{Accelerator, Hit, Ray, TriangleMesh, Vec3};
    use accel_scenes::uv_sphere;

    /// A sphere, a ray that hits it, and brute force's answer.
    fn sphere_ray_and_reference() -> (TriangleMesh<f64>, Ray<f64>, Option<Hit<f64>>) {
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 500);
        let ray = Ray::new(Vec3::new(0.1, 0.2, -5.0), Vec3::new(0.0, 0.0, 1.0)).unwrap();
        let reference = build(AccelKind::Brute, &mesh)
            .unwrap()
            .intersect(&ray)
            .unwrap();
        (mesh, ray, reference)
    }

    #[test]
    fn every_available_kind_builds_and_answers_like_brute_force() {
        let (mesh, ray, reference) = sphere_ray_and_reference();
        assert!(reference.is_some());
        for kind in AccelKind::ALL {
            let accel = build(kind, &mesh).unwrap();
            assert_eq!(accel.stats().kind, kind.name());
            assert_eq!(accel.intersect(&ray).unwrap(), reference, "{kind}");
        }
        // A build refusal names the structure.
        let err = AccelError::Build {
            kind: AccelKind::KdTree,
            cause: BuildError::TooManyPrimitives { count: 1 << 33 },
        };
        assert!(
            err.to_string().starts_with("building the kdtree: "),
            "{err}"
        );
        // The cause once, also in the chain `render` prints.
        let cause = BuildError::TooManyPrimitives { count: 1 << 33 }.to_string();
        let chain = format!("{:#}", anyhow::Error::from(err));
        assert_eq!(chain.matches(&cause).count(), 1, "{chain}");
    }

    #[test]
    fn configs_build_label_and_refuse_bad_parameters() {
        let (mesh, ray, reference) = sphere_ray_and_reference();
        let mut labels = Vec::new();
        let configs = [AccelConfig::grid(3.0)]
            .into_iter()
            .chain(OCTREE_PRESETS.map(|n| AccelConfig::Octree(octree_preset(n).unwrap())))
            .chain(KDTREE_PRESETS.map(|n| AccelConfig::KdTree(kdtree_preset(n).unwrap())));
        for config in configs {
            let accel = build_config(&config, &mesh).unwrap();
            assert_eq!(accel.stats().kind, config.kind().name());
            assert_eq!(accel.intersect(&ray).unwrap(), reference, "{config}");
            labels.push(config.label());
        }
        assert_eq!(labels[0], "grid m=3");
        assert_eq!(labels[1], "octree");
        assert_eq!(labels[2], "octree classic");
        assert_eq!(labels[6], "kdtree fast-build");
        let custom = KdTreeParams {
            intersect_cost: 20.0,
            ..KdTreeParams::default()
        };
        assert_eq!(
            AccelConfig::KdTree(custom.clone()).label(),
            "kdtree ci=20 ct=1 eb=0.3"
        );
        let exact = KdTreeParams {
            binned_above: usize::MAX,
            ..custom.clone()
        };
        assert_eq!(
            AccelConfig::KdTree(exact).label(),
            "kdtree ci=20 ct=1 eb=0.3 exact"
        );
        let binned = KdTreeParams {
            binned_above: 100,
            bins: 16,
            ..custom.clone()
        };
        assert_eq!(
            AccelConfig::KdTree(binned).label(),
            "kdtree ci=20 ct=1 eb=0.3 binned>100/16"
        );
        let shallower = KdTreeParams {
            depth_base: 6.0,
            ..custom
        };
        assert_eq!(
            AccelConfig::KdTree(shallower).label(),
            "kdtree ci=20 ct=1 eb=0.3 db=6"
        );
        // Out-of-range parameters are refused by the structure, by name.
        let bad = AccelConfig::KdTree(KdTreeParams {
            empty_bonus: 1.5,
            ..KdTreeParams::default()
        });
        let err = build_config(&bad, &mesh).err().unwrap().to_string();
        assert!(err.contains("empty_bonus"), "{err}");
        let bad = AccelConfig::KdTree(KdTreeParams {
            depth_base: f64::NAN,
            ..KdTreeParams::default()
        });
        let err = build_config(&bad, &mesh).err().unwrap().to_string();
        assert!(err.contains("depth_base"), "{err}");
        let err = build_config(&AccelConfig::grid(-1.0), &mesh)
            .err()
            .unwrap()
            .to_string();
        assert!(err.starts_with("building the grid"), "{err}");
        assert!(octree_preset("nope").is_none() && kdtree_preset("nope").is_none());
    }

    #[test]
    fn moller_trumbore_equals_brute_force_in_every_accelerator() {
        use accel_core::{MollerTrumboreMesh, TriangleMesh};
        use accel_scenes::aimed::leak_rays;
        use accel_scenes::{SplitMix64, random_rays};
        // Closed shapes (shared edges and vertices to aim at) and a soup.
        let mut mesh = uv_sphere(Vec3::new(0.2, 0.1, -0.3), 1.0, 3_000);
        mesh.append(&accel_scenes::torus(
            Vec3::new(2.5, 0.0, 0.0),
            1.0,
            0.3,
            40,
            16,
        ))
        .unwrap();
        mesh.append(&accel_scenes::random_soup(500, 4)).unwrap();
        let mut rays: Vec<Ray<f64>> = leak_rays(&mesh, 3_000, 9);
        rays.extend(random_rays::<f64>(&mesh.bounds(), 1_000, 2));
        let mut rng = SplitMix64::new(1);
        for r in &mut rays {
            // Unbounded versions too: hits past the aimed-at target count.
            if rng.next_f64() < 0.5 {
                r.t_max = f64::INFINITY;
            }
        }
        let check = |mesh: &TriangleMesh<f32>| {
            let fast = MollerTrumboreMesh::new(mesh);
            let brute = build(AccelKind::Brute, &fast).unwrap();
            let watertight = build(AccelKind::Brute, mesh).unwrap();
            let rays32: Vec<Ray<f32>> = rays.iter().map(|r| r.cast()).collect();
            let reference: Vec<_> = rays32.iter().map(|r| brute.intersect(r).unwrap()).collect();
            // The premise: the two tests answer differently somewhere.
            let differ = rays32
                .iter()
                .zip(&reference)
                .filter(|(r, h)| watertight.intersect(r).unwrap() != **h)
                .count();
            assert!(
                differ > 0,
                "the tests never differ: the check proves nothing"
            );
            let configs = [AccelConfig::grid(1.0), AccelConfig::grid(3.0)]
                .into_iter()
                .chain(OCTREE_PRESETS.map(|n| AccelConfig::Octree(octree_preset(n).unwrap())))
                .chain(KDTREE_PRESETS.map(|n| AccelConfig::KdTree(kdtree_preset(n).unwrap())));
            for config in configs {
                let accel = build_config(&config, &fast).unwrap();
                for (r, want) in rays32.iter().zip(&reference) {
                    let got = accel.intersect(r).unwrap();
                    assert_eq!(
                        got.map(|h| h.bit_key()),
                        want.map(|h| h.bit_key()),
                        "{config}: {r:?}"
                    );
                    assert_eq!(
                        accel.occluded(r).unwrap(),
                        want.is_some(),
                        "{config}: {r:?}"
                    );
                }
            }
        };
        check(&mesh.cast::<f32>().unwrap());
    }

    /// Every field that shapes a tree shows in the label: two configurations
    /// one field apart (from any preset) never share a label, as in the
    /// fast-build preset with 16 bins against the default with the fast
    /// build's binning and depth, which differ in clipping and leaf size.
    #[test]
    fn configs_that_shape_different_trees_get_different_labels() {
        type KdEdit = fn(&mut KdTreeParams);
        let kd_edits: [KdEdit; 12] = [
            |p| p.intersect_cost += 1.0,
            |p| p.traversal_cost += 1.0,
            |p| p.empty_bonus = 0.1,
            |p| p.max_depth = Some(9),
            |p| p.depth_base += 1.0,
            |p| p.leaf_size += 1,
            |p| p.binned_above = 7,
            |p| p.bins = 16,
            |p| p.clip_above = 500,
            |p| p.tighten_above = 100,
            |p| p.flat_part = !p.flat_part,
            |p| p.layout = Layout::Packed,
        ];
        type OctreeEdit = fn(&mut OctreeParams);
        let octree_edits: [OctreeEdit; 7] = [
            |p| p.root = ResolutionRule::Fixed([3, 3, 3]),
            |p| p.children = ResolutionRule::Density(2.5),
            |p| p.split_threshold += 1,
            |p| p.max_depth -= 1,
            |p| p.fit_children = !p.fit_children,
            |p| p.flat_part = !p.flat_part,
            |p| p.layout = Layout::Packed,
        ];
        let mut configs = Vec::new();
        for name in KDTREE_PRESETS {
            let preset = kdtree_preset(name).unwrap();
            configs.push(AccelConfig::KdTree(preset.clone()));
            for edit in kd_edits {
                let mut p = preset.clone();
                edit(&mut p);
                // Clipping and tightening shape only the fast build.
                if p.binned_above == 0 || preset.binned_above == 0 {
                    configs.push(AccelConfig::KdTree(p));
                }
            }
        }
        for name in OCTREE_PRESETS {
            let preset = octree_preset(name).unwrap();
            configs.push(AccelConfig::Octree(preset.clone()));
            for edit in octree_edits {
                let mut p = preset.clone();
                edit(&mut p);
                configs.push(AccelConfig::Octree(p));
            }
        }
        let mut fast_16 = KdTreeParams::fast_build();
        fast_16.bins = 16;
        let binned_16 = KdTreeParams {
            binned_above: 0,
            bins: 16,
            depth_base: fast_16.depth_base,
            traversal_cost: fast_16.traversal_cost,
            ..KdTreeParams::default()
        };
        configs.push(AccelConfig::KdTree(fast_16));
        configs.push(AccelConfig::KdTree(binned_16));
        for (i, a) in configs.iter().enumerate() {
            for b in &configs[..i] {
                if a != b {
                    assert_ne!(a.label(), b.label(), "{a:?}\n{b:?}");
                }
            }
        }
    }

    #[test]
    fn names_and_presets_parse_back() {
        for k in AccelKind::ALL {
            assert_eq!(AccelKind::from_name(k.name()), Some(k));
            assert_eq!(
                k.name().parse::<AccelConfig>(),
                Ok(AccelConfig::default_for(k))
            );
        }
        for name in OCTREE_PRESETS {
            let c: AccelConfig = format!("octree {name}").parse().unwrap();
            assert_eq!(c, AccelConfig::Octree(octree_preset(name).unwrap()));
        }
        for name in KDTREE_PRESETS {
            let c: AccelConfig = format!("kdtree {name}").parse().unwrap();
            assert_eq!(c, AccelConfig::KdTree(kdtree_preset(name).unwrap()));
            // A preset's label parses back to it.
            assert_eq!(c.label().parse::<AccelConfig>(), Ok(c));
        }
        assert_eq!(
            "grid m=3".parse::<AccelConfig>(),
            Ok(AccelConfig::grid(3.0))
        );
        for bad in [
            "",
            "bvh",
            "grid m=0",
            "grid m=x",
            "octree fast",
            "brute x",
            "kdtree pbrt x",
        ] {
            assert!(bad.parse::<AccelConfig>().is_err(), "{bad:?}");
        }
    }
}
