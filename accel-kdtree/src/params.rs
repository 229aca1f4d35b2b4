//! Build parameters: the SAH cost model, the depth limit, and presets.

use accel_core::BuildError;
use accel_core::packed::Layout;

/// Build parameters of a [`crate::KdTree`].
///
/// The surface area heuristic prices a split of node `V` at plane `p` into
/// `L` and `R` holding `n_L` and `n_R` primitives as
///
/// ```text
/// C(p) = traversal_cost + b · intersect_cost · (SA(L)·n_L + SA(R)·n_R) / SA(V)
/// ```
///
/// with `b = 1 − empty_bonus` when one side is empty and `b = 1` otherwise,
/// and a leaf as `intersect_cost · n`. A node is split at its cheapest plane
/// only when that is cheaper than the leaf (Wald & Havran 2006, §4.1), and
/// never below the depth limit.
///
/// The default costs are pbrt-v4's `KdTreeAggregate` (intersection 5,
/// traversal 1, depth `round(8 + 1.3·floor(log2 n))`), the values the
/// workspace's style guide names, with two changes chosen by measurement
/// (camera rays, one thread, beside the uniform grid): an empty bonus of 0.3
/// instead of 0.5, and nodes of at most 2 primitives left unsplit. On the
/// 100k random soup they trace about 25% faster than pbrt's values (fewer,
/// larger leaves: the node steps, not the triangle tests, dominate there);
/// on the sphere and terrain the difference is within noise, on the teapot in
/// a stadium 7% slower. [`KdTreeParams::pbrt`] gives pbrt-v4's values exactly,
/// [`KdTreeParams::best_traversal`] pbrt-v3's (intersection 80).
#[derive(Clone, Debug, PartialEq)]
pub struct KdTreeParams {
    /// Cost of one primitive test, relative to `traversal_cost`. Default 5.
    pub intersect_cost: f64,
    /// Cost of one traversal step (an inner node). Default 1.
    pub traversal_cost: f64,
    /// Fraction of the split cost waived when one child is empty, in `[0, 1)`:
    /// cutting off empty space is worth more than the raw SAH says. Default
    /// 0.3 (pbrt: 0.5).
    pub empty_bonus: f64,
    /// Depth limit; `None` for `round(depth_base + 1.3·floor(log2 n))`
    /// ([`KdTreeParams::depth_base`]). At most [`KdTreeParams::MAX_DEPTH`]
    /// (the traversal stack). A cut that keeps at
    /// most 1/16 of its node's width, with at least 16 times the primitives
    /// it cuts off, does not count for the kept child: it isolates a dense
    /// part (a small mesh in a large sparse scene) that deserves the depth a
    /// scene of its own would get. Paths never exceed `MAX_DEPTH` levels.
    pub max_depth: Option<u32>,
    /// The constant of the depth limit `round(depth_base + 1.3·floor(log2
    /// n))` when `max_depth` is `None`: pbrt's rule, whose constant is 8.
    /// Default 8, pbrt's.
    ///
    /// On meshes of 50k–100k triangles the SAH splits until that limit
    /// binds (the bunny's leaves lie 27.2 levels deep on average under its
    /// limit of 29), each level clipping and copying the triangles that
    /// straddle its planes. Two levels fewer (6) build those meshes
    /// 1.35–1.42× as fast and trace them as fast (within a few percent on
    /// camera, shadow and diffuse rays; the 1M-triangle terrain builds
    /// 1.04× as fast), but a small dense mesh inside a large scene built as
    /// one tree is then split less finely: rays at a sphere of 20k
    /// triangles inside tiled walls 10^4 times wider test 11.7 triangles
    /// each, against 4.7 with the sphere alone. [`KdTreeParams::fast_build`]
    /// takes 3. A finite number; a limit below 0 is 0.
    pub depth_base: f64,
    /// Nodes with at most this many primitives become leaves without an SAH
    /// search (pbrt's `maxPrims`, which is 1; 0 means only the SAH decides).
    /// Default 2. A node holding a large primitive (bounds spanning at least
    /// 1/16 of the scene's largest side, as in [`accel_core::parts`]) is
    /// searched whatever this says: such primitives are few and crossed by
    /// many rays (a stadium's walls, a box's faces).
    pub leaf_size: u32,
    /// The most primitive references the leaves may hold in all (perfect
    /// splits duplicate straddling primitives); more is refused with
    /// [`BuildError::BudgetExceeded`]. Default 2^28.
    pub max_references: u64,
    /// The most bytes the tree may hold: its nodes (8 bytes each, plus a
    /// split position for each inner node of an `f64` tree and one value of
    /// the per-node reach table), its references (4 bytes each) and, with
    /// [`Layout::Packed`], its blocks. Checked before any work against the
    /// least a tree over the scene takes (a node and a reference per
    /// primitive), then counted node by node as the build goes, which stops
    /// at the first node past the budget with
    /// [`BuildError::BudgetExceeded`] (a whole tree never gets built first).
    /// The build's own lists come on top while it runs, up to about as much
    /// again. Default 2^31 (2 GiB), as the octree's.
    ///
    /// Perfect splits copy a primitive into every leaf it straddles, so a
    /// scene of long thin slivers crossing each other can need hundreds of
    /// references per primitive: 100,000 random slivers across a unit cube
    /// take 457 MB (51M nodes, 20.5M references; 23 s to build).
    pub max_bytes: u64,
    /// Subtrees over at least this many primitives are built in parallel
    /// (rayon). Default 4096.
    pub parallel_threshold: usize,
    /// Nodes over more primitives than this choose their split with the
    /// binned SAH (`bins − 1` evenly spaced planes per axis, no sorting)
    /// instead of the exact event sweep, which takes over below. It spares
    /// the whole-scene event sort and halves the memory of the top levels;
    /// on the 1M-triangle terrain the build is 2–12% faster on one thread
    /// and 1.16× faster on two, and rays visit as many nodes and primitives
    /// as in the exact tree (measured with `examples/build_profile` and
    /// `examples/ray_costs`). `usize::MAX` makes every split exact. Default
    /// 4096.
    ///
    /// 0 selects the fast build ([`KdTreeParams::fast_build`]): every node
    /// binned, the bins deciding the leaves too, no event list made at all;
    /// nodes are runs of indices and clipped boxes partitioned in place,
    /// large ones priced from a sample, those of at most 1024 primitives
    /// on their longest axis only, and empty space beyond a node's
    /// primitives cut off without binning (see [`KdTreeParams::clip_above`]).
    pub binned_above: usize,
    /// Bins per axis of the binned SAH, 2 to 4096. Default 64.
    pub bins: u32,
    /// The fast build's (`binned_above` 0) perfect splits: a primitive
    /// straddling a split is clipped to each child exactly in nodes over
    /// this many primitives; in smaller ones its box is cut at the plane,
    /// as conservative and much cheaper, at the price of more references
    /// (256 against 0: 1.3× the references on the bunny, a third of the
    /// clipping time), which [`KdTreeParams::tighten_above`] wins back
    /// for less. The other builds always clip. Default 0; the fast-build
    /// preset's `usize::MAX` (never).
    pub clip_above: usize,
    /// The fast build's cheaper tightening: in nodes over this many
    /// primitives where straddlers are not clipped (`clip_above`), each
    /// half's box cut at the plane is also kept within the triangle's own
    /// part of that half (its vertices on that side and its edges'
    /// crossings with the plane,
    /// [`accel_core::triangle::triangle_halves_bounds`]): a few crossings,
    /// where clipping to the node takes its faces too. The fast-build
    /// preset's 64, with no exact clipping: the same build instructions as
    /// clipping above 256 with boxes cut below, and 6% lower SAH costs on
    /// the bunny and the sphere. `usize::MAX` never tightens. Default
    /// `usize::MAX`.
    pub tighten_above: usize,
    /// Whether a scene that stays one part, with many primitives lying flat
    /// in one axis-aligned plane (a floor), builds them as a part of their
    /// own ([`accel_core::parts::split_flat`]), where primitives with wide
    /// hits ([`accel_core::PrimitiveSet::wide_hits`]) make the walk's beam
    /// thin enough for rays leaving the floor to miss its flat bounds. On
    /// the `flat_field` scene, shadow and diffuse rays then trace 6.7× and
    /// 7.9× as fast, camera rays 2.4×. Default `true`.
    pub flat_part: bool,
    /// Whether leaves' triangles are also kept in packed blocks, tested
    /// several at once ([`Layout`]). Default [`Layout::Indexed`]: packed
    /// leaves traced 0.90–0.94× as fast on the 100k sphere and 0.83–0.92×
    /// on the teapot in a stadium (leaves of two or three triangles). The
    /// answers are the same either way.
    pub layout: Layout,
}

/// pbrt's depth limit constant: `round(8 + 1.3·floor(log2 n))`.
const PBRT_DEPTH_BASE: f64 = 8.0;

/// [`KdTreeParams::fast_build`]'s depth limit constant: five levels fewer.
const FAST_BUILD_DEPTH_BASE: f64 = 3.0;

impl Default for KdTreeParams {
    fn default() -> Self {
        Self {
            intersect_cost: 5.0,
            traversal_cost: 1.0,
            empty_bonus: 0.3,
            max_depth: None,
            depth_base: PBRT_DEPTH_BASE,
            leaf_size: 2,
            max_references: 1 << 28,
            max_bytes: 1 << 31,
            parallel_threshold: 4096,
            binned_above: 4096,
            bins: 64,
            clip_above: 0,
            tighten_above: usize::MAX,
            flat_part: true,
            layout: Layout::Indexed,
        }
    }
}

impl KdTreeParams {
    /// The deepest tree the traversal stack supports.
    pub const MAX_DEPTH: u32 = 64;
    /// The most bins per axis of the binned SAH.
    pub const MAX_BINS: u32 = 4096;

    /// Quicker to build, slower to trace: the fast build (`binned_above`
    /// 0, 32 bins, no exact clipping, straddlers' boxes tightened to the
    /// triangle's halves above 64 primitives), nodes of up to 8
    /// primitives left unsearched, a traversal cost of 2 and a depth limit
    /// five levels lower than the default's ([`KdTreeParams::depth_base`]
    /// 3). On one thread it builds 2–9× as fast as the default (0.77–1.26×
    /// obvhs's speed: at least 1.0 on the sphere, soup, terrain and flat
    /// field, 0.77–0.97 on the scans and the teapot in a stadium) and
    /// traces 0.73–0.99× as fast (performance log, 2026-12-06; since
    /// 2026-12-07 the tightening instead of clipping above 256: the same
    /// build instructions, 1–6% lower SAH costs, 4% fewer instructions
    /// tracing the sphere).
    #[must_use]
    pub fn fast_build() -> Self {
        Self {
            leaf_size: 8,
            traversal_cost: 2.0,
            depth_base: FAST_BUILD_DEPTH_BASE,
            binned_above: 0,
            bins: 32,
            clip_above: usize::MAX,
            tighten_above: 64,
            ..Self::default()
        }
    }

    /// pbrt-v3's parameters (intersection 80, traversal 1, empty bonus 0.5,
    /// pbrt's depth limit, every node searched, every split exact): deeper trees with the fewest primitives per
    /// leaf, for scenes where the primitive tests dominate (expensive
    /// user primitives); on triangle scenes it traces about as fast as the
    /// default.
    #[must_use]
    pub fn best_traversal() -> Self {
        Self {
            intersect_cost: 80.0,
            empty_bonus: 0.5,
            depth_base: PBRT_DEPTH_BASE,
            leaf_size: 0,
            binned_above: usize::MAX,
            ..Self::default()
        }
    }

    /// pbrt-v4's `KdTreeAggregate` parameters exactly (intersection 5,
    /// traversal 1, empty bonus 0.5, depth `round(8 + 1.3·floor(log2 n))`,
    /// every node searched, every split exact).
    #[must_use]
    pub fn pbrt() -> Self {
        Self {
            empty_bonus: 0.5,
            depth_base: PBRT_DEPTH_BASE,
            leaf_size: 0,
            binned_above: usize::MAX,
            ..Self::default()
        }
    }

    /// The depth limit for `n` primitives.
    #[must_use]
    pub fn depth_limit(&self, n: usize) -> u32 {
        match self.max_depth {
            Some(d) => d,
            None => {
                let log2 = if n <= 1 { 0 } else { n.ilog2() };
                // A float-to-int cast saturates: below 0 is 0.
                let d = (self.depth_base + 1.3 * f64::from(log2)).round() as u32;
                d.min(Self::MAX_DEPTH)
            }
        }
    }

    /// Checks every parameter's range.
    ///
    /// # Errors
    /// [`BuildError::InvalidParameter`] naming the first bad parameter.
    pub fn validate(&self) -> Result<(), BuildError> {
        let bad = |name: &'static str, value: String, expected: &'static str| {
            Err(BuildError::InvalidParameter {
                name,
                value,
                expected,
            })
        };
        if !(self.intersect_cost > 0.0 && self.intersect_cost.is_finite()) {
            return bad(
                "intersect_cost",
                self.intersect_cost.to_string(),
                "a finite number > 0",
            );
        }
        if !(self.traversal_cost >= 0.0 && self.traversal_cost.is_finite()) {
            return bad(
                "traversal_cost",
                self.traversal_cost.to_string(),
                "a finite number >= 0",
            );
        }
        if !(0.0..1.0).contains(&self.empty_bonus) {
            return bad(
                "empty_bonus",
                self.empty_bonus.to_string(),
                "a number in [0, 1)",
            );
        }
        if !self.depth_base.is_finite() {
            return bad("depth_base", self.depth_base.to_string(), "a finite number");
        }
        if let Some(d) = self.max_depth
            && d > Self::MAX_DEPTH
        {
            return bad("max_depth", d.to_string(), "at most 64");
        }
        if self.max_bytes == 0 {
            return bad("max_bytes", "0".into(), "a positive number of bytes");
        }
        if !(2..=Self::MAX_BINS).contains(&self.bins) {
            return bad("bins", self.bins.to_string(), "2 to 4096");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_limit_follows_pbrt() {
        // pbrt's rule, round(8 + 1.3·floor(log2 n)), by default and in
        // both pbrt presets.
        for p in [
            KdTreeParams::default(),
            KdTreeParams::pbrt(),
            KdTreeParams::best_traversal(),
        ] {
            assert_eq!(p.depth_limit(0), 8);
            assert_eq!(p.depth_limit(1), 8);
            // floor(log2(1000)) = 9: 8 + 11.7 = 19.7 -> 20.
            assert_eq!(p.depth_limit(1000), 20);
            // 2^20: 8 + 26 = 34.
            assert_eq!(p.depth_limit(1 << 20), 34);
        }
        // The same rule with the fast-build preset's constant, 3.
        let p = KdTreeParams::fast_build();
        assert_eq!(p.depth_limit(1), 3);
        // 3 + 11.7 = 14.7 -> 15; 3 + 26 = 29.
        assert_eq!(p.depth_limit(1000), 15);
        assert_eq!(p.depth_limit(1 << 20), 29);
        // Far below: a single leaf; far above: the traversal stack.
        let low = KdTreeParams {
            depth_base: -100.0,
            ..p.clone()
        };
        assert_eq!(low.depth_limit(1 << 20), 0);
        let high = KdTreeParams {
            depth_base: 100.0,
            ..p.clone()
        };
        assert_eq!(high.depth_limit(1 << 20), KdTreeParams::MAX_DEPTH);
        let fixed = KdTreeParams {
            max_depth: Some(3),
            ..p
        };
        assert_eq!(fixed.depth_limit(1 << 20), 3);
    }

    #[test]
    fn bad_parameters_are_named() {
        let cases = [
            KdTreeParams {
                intersect_cost: 0.0,
                ..KdTreeParams::default()
            },
            KdTreeParams {
                traversal_cost: f64::NAN,
                ..KdTreeParams::default()
            },
            KdTreeParams {
                empty_bonus: 1.0,
                ..KdTreeParams::default()
            },
            KdTreeParams {
                max_depth: Some(65),
                ..KdTreeParams::default()
            },
            KdTreeParams {
                bins: 1,
                ..KdTreeParams::default()
            },
            KdTreeParams {
                depth_base: f64::INFINITY,
                ..KdTreeParams::default()
            },
        ];
        let names = [
            "intersect_cost",
            "traversal_cost",
            "empty_bonus",
            "max_depth",
            "bins",
            "depth_base",
        ];
        for (p, want) in cases.iter().zip(names) {
            match p.validate() {
                Err(BuildError::InvalidParameter { name, .. }) => assert_eq!(name, want),
                other => panic!("{want}: {other:?}"),
            }
        }
        assert!(KdTreeParams::fast_build().validate().is_ok());
        assert!(KdTreeParams::best_traversal().validate().is_ok());
        assert!(KdTreeParams::pbrt().validate().is_ok());
    }
}
