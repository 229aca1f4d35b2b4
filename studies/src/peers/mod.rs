//! Peers: other ray-tracing libraries, run on the same scenes and rays as
//! our accelerators by `studies peers` ([`run`]).
//!
//! Each peer is behind a cargo feature, so that default builds and CI do not
//! compile it:
//! - `peers`: [obvhs](https://crates.io/crates/obvhs) (a BVH2 from its
//!   PLOC builder, medium quality), [parry3d](https://crates.io/crates/parry3d)
//!   (`TriMesh` ray casts) and the [bvh](https://crates.io/crates/bvh) crate
//!   (its SAH BVH, our Möller–Trumbore triangle test);
//! - `embree`: Embree 3 through the system library (`libembree-dev`), in its
//!   default mode and with `RTC_SCENE_FLAG_ROBUST`.
//!
//! A peer gets an `f32` copy of the scene ([`PeerMesh`]) and answers the
//! two queries of [`Tracer`]: the nearest hit (its `t` and triangle) and
//! any hit. Peers use their own triangle tests, so their answers are compared
//! with ours with a tolerance ([`compare`]), not bit for bit.

pub mod run;

#[cfg(feature = "peers")]
pub mod bvh;
#[cfg(feature = "embree")]
pub mod embree;
#[cfg(feature = "peers")]
pub mod obvhs;
#[cfg(feature = "peers")]
pub mod parry;

use accel_core::{Ray, TriangleMesh};
use render::bench::Answers;
use serde::Serialize;
use std::time::Duration;

/// The scene as every peer receives it: `f32` positions and triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct PeerMesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Vertex indices of each triangle.
    pub indices: Vec<[u32; 3]>,
}

impl PeerMesh {
    /// Copies `mesh`.
    #[must_use]
    pub fn new(mesh: &TriangleMesh<f32>) -> Self {
        Self {
            positions: mesh.positions().iter().map(|p| [p.x, p.y, p.z]).collect(),
            indices: mesh.indices().to_vec(),
        }
    }

    /// The three corners of triangle `i`.
    #[must_use]
    pub fn triangle(&self, i: usize) -> [[f32; 3]; 3] {
        self.indices[i].map(|v| self.positions[v as usize])
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }
}

/// A nearest hit as every tool can report it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PeerHit {
    /// Ray parameter, in units of the ray's direction as given.
    pub t: f32,
    /// Index of the triangle hit.
    pub prim: u32,
}

/// The two queries of the benchmark, on one thread, one ray at a time and,
/// where the tool has them, in packets.
///
/// The packet queries answer exactly what the single ones would, ray for
/// ray (up to the tool's own rounding: a tool's packet kernels may round
/// differently from its single-ray ones). Their defaults loop the single
/// queries; a tool with real packet queries overrides them and lists its
/// widths in [`Tracer::packet_widths`], and only those are measured as
/// packet figures, so that no report presents a loop as a packet figure.
pub trait Tracer {
    /// The nearest hit with `t ∈ [ray.t_min, ray.t_max]`, if any.
    fn nearest(&self, ray: &Ray<f32>) -> Option<PeerHit>;
    /// Whether anything is hit with `t ∈ [ray.t_min, ray.t_max]`.
    fn occluded(&self, ray: &Ray<f32>) -> bool;

    /// The packet widths (rays per packet) of the tool's real packet
    /// queries, widest first; none by default.
    fn packet_widths(&self) -> &'static [usize] {
        &[]
    }

    /// [`Tracer::nearest`] for each ray of one packet of up to `width` rays
    /// (`width` one of [`Tracer::packet_widths`]; a short packet has its
    /// other lanes inactive): `out[i]` becomes the answer to `rays[i]`.
    /// `coherent` says whether the rays are neighbours (a tile of camera
    /// rays), a hint a tool may pass on to its traversal. By default one
    /// ray at a time.
    ///
    /// # Panics
    /// If `rays` and `out` differ in length, or (tools with packets) if
    /// there are more rays than `width` or `width` is not one of theirs.
    fn nearest_packet(
        &self,
        width: usize,
        coherent: bool,
        rays: &[Ray<f32>],
        out: &mut [Option<PeerHit>],
    ) {
        let _ = (width, coherent);
        assert_eq!(rays.len(), out.len(), "one answer per ray of the packet");
        for (ray, answer) in rays.iter().zip(out) {
            *answer = self.nearest(ray);
        }
    }

    /// [`Tracer::occluded`] for each ray of one packet, as
    /// [`Tracer::nearest_packet`]. By default one ray at a time.
    ///
    /// # Panics
    /// As [`Tracer::nearest_packet`].
    fn occluded_packet(&self, width: usize, coherent: bool, rays: &[Ray<f32>], out: &mut [bool]) {
        let _ = (width, coherent);
        assert_eq!(rays.len(), out.len(), "one answer per ray of the packet");
        for (ray, answer) in rays.iter().zip(out) {
            *answer = self.occluded(ray);
        }
    }
}

/// Every answer of `tracer` to `rays`, through its packet queries
/// `width` rays at a time (the last packet short when `width` does not
/// divide the count): nearest hits, or with `any_hit` whether each ray is
/// blocked.
#[must_use]
pub fn packet_answers(
    tracer: &dyn Tracer,
    width: usize,
    coherent: bool,
    any_hit: bool,
    rays: &[Ray<f32>],
) -> SetAnswers {
    let width = width.max(1);
    if any_hit {
        let mut out = vec![false; rays.len()];
        for (packet, answers) in rays.chunks(width).zip(out.chunks_mut(width)) {
            tracer.occluded_packet(width, coherent, packet, answers);
        }
        SetAnswers::Occluded(out)
    } else {
        let mut out = vec![None; rays.len()];
        for (packet, answers) in rays.chunks(width).zip(out.chunks_mut(width)) {
            tracer.nearest_packet(width, coherent, packet, answers);
        }
        SetAnswers::Nearest(out)
    }
}

/// Hits of one pass of `tracer`'s packet queries over `rays`, `width` rays
/// at a time, on this thread: [`packet_answers`] without keeping them.
///
/// # Panics
/// If `width` is over 16, the widest packet of any peer.
#[must_use]
pub fn count_packet_hits(
    tracer: &dyn Tracer,
    width: usize,
    coherent: bool,
    any_hit: bool,
    rays: &[Ray<f32>],
) -> u64 {
    /// Lanes of the answer buffers: the widest packet any peer has.
    const MAX_WIDTH: usize = 16;
    assert!(width <= MAX_WIDTH, "packets of {width} rays");
    let width = width.max(1);
    let mut hits = 0;
    let mut nearest = [None; MAX_WIDTH];
    let mut any = [false; MAX_WIDTH];
    for packet in rays.chunks(width) {
        let n = packet.len();
        if any_hit {
            tracer.occluded_packet(width, coherent, packet, &mut any[..n]);
            hits += any[..n].iter().map(|&b| u64::from(b)).sum::<u64>();
        } else {
            tracer.nearest_packet(width, coherent, packet, &mut nearest[..n]);
            hits += nearest[..n]
                .iter()
                .map(|h| u64::from(h.is_some()))
                .sum::<u64>();
        }
    }
    hits
}

/// A peer, built: its tracer and how long the build took.
pub struct BuiltPeer {
    /// The structure, ready for queries.
    pub tracer: Box<dyn Tracer>,
    /// Build time from the [`PeerMesh`] (copies into the peer's own format
    /// included; device or library start-up excluded).
    pub build: Duration,
}

/// Builds a peer over a mesh, or says why it cannot.
pub type BuildFn = fn(&PeerMesh) -> Result<BuiltPeer, String>;

/// A peer the binary knows, built in or not.
#[derive(Clone, Copy, Debug)]
pub struct PeerKind {
    /// Its name in reports.
    pub name: &'static str,
    /// The cargo feature that builds it in.
    pub feature: &'static str,
    /// Whether it is a Rust library (the "best Rust peer" ratio).
    pub rust: bool,
    /// Its build function, when the feature is enabled.
    pub build: Option<BuildFn>,
}

/// Every peer, in report order, with a build function for those compiled in.
#[must_use]
pub fn peer_kinds() -> Vec<PeerKind> {
    #[cfg(feature = "peers")]
    let rust: [Option<BuildFn>; 3] = [Some(obvhs::build), Some(parry::build), Some(bvh::build)];
    #[cfg(not(feature = "peers"))]
    let rust: [Option<BuildFn>; 3] = [None; 3];
    #[cfg(feature = "embree")]
    let embree: [Option<BuildFn>; 2] = [Some(embree::build_default), Some(embree::build_robust)];
    #[cfg(not(feature = "embree"))]
    let embree: [Option<BuildFn>; 2] = [None; 2];
    let kind = |name, feature, rust, build| PeerKind {
        name,
        feature,
        rust,
        build,
    };
    vec![
        kind("obvhs", "peers", true, rust[0]),
        kind("parry3d", "peers", true, rust[1]),
        kind("bvh", "peers", true, rust[2]),
        kind("embree", "embree", false, embree[0]),
        kind("embree-robust", "embree", false, embree[1]),
    ]
}

/// The name of the default-mode Embree peer, the reference of the "vs
/// Embree" ratio.
pub const EMBREE: &str = "embree";

/// Every ray's answer to one set.
#[derive(Clone, Debug, PartialEq)]
pub enum SetAnswers {
    /// Nearest-hit queries: the hit or `None`.
    Nearest(Vec<Option<PeerHit>>),
    /// Any-hit queries: whether the ray is blocked.
    Occluded(Vec<bool>),
}

impl SetAnswers {
    /// Rays answered.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Self::Nearest(v) => v.len(),
            Self::Occluded(v) => v.len(),
        }
    }

    /// Whether no ray was answered.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether ray `i` hit something.
    #[must_use]
    pub fn hit(&self, i: usize) -> bool {
        match self {
            Self::Nearest(v) => v[i].is_some(),
            Self::Occluded(v) => v[i],
        }
    }

    /// These answers, listed in the order `order` gives the rays (answer
    /// `j` is that of ray `order[j]` of the set: the order of the bundle
    /// passes, [`render::bench::RaySet::bundle_order`]), put back in the
    /// set's order.
    ///
    /// # Panics
    /// If `order` is not a permutation of the answers' indices.
    #[must_use]
    pub fn in_set_order(&self, order: &[usize]) -> Self {
        fn place<A: Copy + Default>(answers: &[A], order: &[usize]) -> Vec<A> {
            assert_eq!(answers.len(), order.len(), "one index per answer");
            let mut out = vec![A::default(); answers.len()];
            let mut seen = vec![false; answers.len()];
            for (&a, &i) in answers.iter().zip(order) {
                assert!(!std::mem::replace(&mut seen[i], true), "ray {i} twice");
                out[i] = a;
            }
            out
        }
        match self {
            Self::Nearest(v) => Self::Nearest(place(v, order)),
            Self::Occluded(v) => Self::Occluded(place(v, order)),
        }
    }

    /// Hit count, sum of `t` and a digest of `(t, triangle)` per ray
    /// ([`Answers`]; `t` only for nearest-hit sets).
    #[must_use]
    pub fn summary(&self) -> Answers {
        match self {
            Self::Nearest(v) => Answers::of_nearest(v.iter().map(|h| {
                h.map(|h| {
                    (
                        f64::from(h.t),
                        [u64::from(h.t.to_bits()), u64::from(h.prim)],
                    )
                })
            })),
            Self::Occluded(v) => Answers::of_occluded(v.iter().copied()),
        }
    }
}

/// The relative difference in `t` above which two hits disagree.
pub const T_TOLERANCE: f64 = 1e-4;

/// How one tool's answers differ from the reference's on the same rays.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Agreement {
    /// Rays compared.
    pub rays: u64,
    /// Rays where one hits and the other misses.
    pub hit_miss: u64,
    /// Rays both hit, on different triangles.
    pub prim: u64,
    /// Rays both hit, with `t` differing by more than [`T_TOLERANCE`]
    /// relative to the larger.
    pub t: u64,
    /// The first few differing rays, described.
    pub examples: Vec<String>,
}

impl Agreement {
    /// Whether no ray differs.
    #[must_use]
    pub fn agrees(&self) -> bool {
        self.hit_miss == 0 && self.prim == 0 && self.t == 0
    }
}

/// Whether `a` and `b` differ by more than [`T_TOLERANCE`] relative to the
/// larger magnitude.
#[must_use]
pub fn t_differs(a: f32, b: f32) -> bool {
    let (a, b) = (f64::from(a), f64::from(b));
    (a - b).abs() > T_TOLERANCE * a.abs().max(b.abs())
}

/// Compares `other` (named `other_name`) with `reference` (named
/// `ref_name`), ray by ray, keeping up to `max_examples` descriptions of
/// differing rays (with the ray, from `rays`).
///
/// # Panics
/// If the two answer different kinds of query or different numbers of rays.
#[must_use]
pub fn compare(
    reference: &SetAnswers,
    ref_name: &str,
    other: &SetAnswers,
    other_name: &str,
    rays: &[Ray<f32>],
    max_examples: usize,
) -> Agreement {
    assert_eq!(reference.len(), other.len(), "different ray counts");
    let mut a = Agreement {
        rays: reference.len() as u64,
        ..Agreement::default()
    };
    let describe = |i: usize, what: String| {
        let [ox, oy, oz, dx, dy, dz, t0, t1] = accel_scenes::rayfile::ray_values(&rays[i]);
        format!(
            "ray {i} (o = ({ox:e}, {oy:e}, {oz:e}), d = ({dx:e}, {dy:e}, {dz:e}), t in [{t0:e}, {t1:e}]): {what}"
        )
    };
    let show = |h: Option<PeerHit>| {
        h.map_or_else(
            || "miss".to_owned(),
            |h| format!("triangle {} at t = {:e}", h.prim, h.t),
        )
    };
    match (reference, other) {
        (SetAnswers::Nearest(x), SetAnswers::Nearest(y)) => {
            for (i, (&hx, &hy)) in x.iter().zip(y).enumerate() {
                let mut differs = false;
                match (hx, hy) {
                    (Some(p), Some(q)) => {
                        if p.prim != q.prim {
                            a.prim += 1;
                            differs = true;
                        }
                        if t_differs(p.t, q.t) {
                            a.t += 1;
                            differs = true;
                        }
                    }
                    (None, None) => {}
                    _ => {
                        a.hit_miss += 1;
                        differs = true;
                    }
                }
                if differs && a.examples.len() < max_examples {
                    a.examples.push(describe(
                        i,
                        format!("{ref_name} {}, {other_name} {}", show(hx), show(hy)),
                    ));
                }
            }
        }
        (SetAnswers::Occluded(x), SetAnswers::Occluded(y)) => {
            let word = |b: bool| if b { "blocked" } else { "clear" };
            for (i, (&bx, &by)) in x.iter().zip(y).enumerate() {
                if bx != by {
                    a.hit_miss += 1;
                    if a.examples.len() < max_examples {
                        a.examples.push(describe(
                            i,
                            format!("{ref_name} {}, {other_name} {}", word(bx), word(by)),
                        ));
                    }
                }
            }
        }
        _ => panic!("comparing nearest-hit answers with any-hit answers"),
    }
    a
}

/// Ray `ray` with `t_min` moved to 0 by moving its origin, for tools whose
/// rays start at their origin; returns the shifted ray and the offset to add
/// back to its `t`.
#[must_use]
pub fn start_at_zero(ray: &Ray<f32>) -> (Ray<f32>, f32) {
    if ray.t_min == 0.0 {
        (*ray, 0.0)
    } else {
        let shifted = Ray {
            origin: ray.at(ray.t_min),
            direction: ray.direction,
            t_min: 0.0,
            t_max: ray.t_max - ray.t_min,
        };
        (shifted, ray.t_min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::Vec3;

    fn ray(i: u32) -> Ray<f32> {
        Ray {
            origin: Vec3::new(i as f32, 0.0, 0.0),
            direction: Vec3::new(0.0, 0.0, 1.0),
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }

    #[test]
    fn the_agreement_checker_counts_each_kind_of_difference() {
        let rays: Vec<_> = (0..6).map(ray).collect();
        let hit = |t, prim| Some(PeerHit { t, prim });
        let reference = SetAnswers::Nearest(vec![
            hit(1.0, 0),
            hit(2.0, 1),
            None,
            hit(3.0, 2),
            hit(4.0, 3),
            hit(1000.0, 4),
        ]);
        let other = SetAnswers::Nearest(vec![
            hit(1.0, 0),     // same
            None,            // hit vs miss
            hit(5.0, 9),     // miss vs hit
            hit(3.0, 7),     // other triangle, same t (a shared edge)
            hit(4.01, 3),    // t off by 2.5e-3: differs
            hit(1000.05, 4), // t off by 5e-5: within tolerance
        ]);
        let a = compare(&reference, "grid", &other, "peer", &rays, 2);
        assert_eq!((a.rays, a.hit_miss, a.prim, a.t), (6, 2, 1, 1));
        assert!(!a.agrees());
        assert_eq!(a.examples.len(), 2);
        assert!(a.examples[0].starts_with("ray 1 "), "{}", a.examples[0]);
        assert!(
            a.examples[0].contains("grid triangle 1 at t = 2e0, peer miss"),
            "{}",
            a.examples[0]
        );
        // A tool agrees with itself; the summaries see the differences too.
        assert!(compare(&reference, "a", &reference, "b", &rays, 2).agrees());
        let (sr, so) = (reference.summary(), other.summary());
        assert_eq!((sr.hits, so.hits), (5, 5));
        assert_ne!(sr.digest, so.digest);
        assert_eq!(sr.t_sum, Some(1010.0));

        let blocked = SetAnswers::Occluded(vec![true, false, true, true, false, false]);
        let other = SetAnswers::Occluded(vec![true, true, true, false, false, false]);
        let a = compare(&blocked, "grid", &other, "peer", &rays, 10);
        assert_eq!((a.hit_miss, a.prim, a.t), (2, 0, 0));
        assert_eq!(a.examples.len(), 2);
        assert!(
            a.examples[1].ends_with("grid blocked, peer clear"),
            "{}",
            a.examples[1]
        );
        assert_eq!(blocked.summary().hits, 3);
        assert_eq!(blocked.summary().t_sum, None);
    }

    /// A tool without packets: its nearest hit is the ray's `x` when that
    /// is even, and it counts its single-ray queries.
    struct EvenX(std::cell::Cell<u32>);

    impl Tracer for EvenX {
        fn nearest(&self, ray: &Ray<f32>) -> Option<PeerHit> {
            self.0.set(self.0.get() + 1);
            let x = ray.origin.x as u32;
            x.is_multiple_of(2).then_some(PeerHit {
                t: ray.origin.x,
                prim: x,
            })
        }

        fn occluded(&self, ray: &Ray<f32>) -> bool {
            self.nearest(ray).is_some()
        }
    }

    #[test]
    fn the_default_packets_loop_the_single_queries_and_claim_no_width() {
        let tool = EvenX(std::cell::Cell::new(0));
        assert!(tool.packet_widths().is_empty());
        let rays: Vec<_> = (0..21).map(ray).collect();
        let single = SetAnswers::Nearest(rays.iter().map(|r| tool.nearest(r)).collect());
        for width in [1, 8, 16] {
            let got = packet_answers(&tool, width, false, false, &rays);
            assert_eq!(got, single, "{width}");
            let any = packet_answers(&tool, width, true, true, &rays);
            assert_eq!(any.summary().hits, 11);
            assert_eq!(count_packet_hits(&tool, width, false, false, &rays), 11);
        }
        // 21 singles, then 3 × (21 + 21 + 21) through the packets.
        assert_eq!(tool.0.get(), 21 + 3 * 63);
    }

    #[test]
    fn answers_in_bundle_order_go_back_to_the_set_s_order() {
        let hit = |t: f32| Some(PeerHit { t, prim: t as u32 });
        // Rays 2, 0, 3, 1 were traced in that order.
        let traced = SetAnswers::Nearest(vec![hit(2.0), hit(0.0), None, hit(1.0)]);
        assert_eq!(
            traced.in_set_order(&[2, 0, 3, 1]),
            SetAnswers::Nearest(vec![hit(0.0), hit(1.0), hit(2.0), None])
        );
        let blocked = SetAnswers::Occluded(vec![true, false, false]);
        assert_eq!(
            blocked.in_set_order(&[1, 2, 0]),
            SetAnswers::Occluded(vec![false, true, false])
        );
        let twice = std::panic::catch_unwind(|| blocked.in_set_order(&[1, 1, 0]));
        assert!(twice.is_err());
    }

    #[test]
    fn rays_are_moved_to_start_at_zero() {
        let r = Ray {
            t_min: 2.0,
            t_max: 5.0,
            ..ray(1)
        };
        let (s, off) = start_at_zero(&r);
        assert_eq!((s.origin.z, s.t_min, s.t_max, off), (2.0, 0.0, 3.0, 2.0));
        assert_eq!(start_at_zero(&ray(1)), (ray(1), 0.0));
    }

    #[test]
    fn every_peer_is_listed_with_its_feature() {
        let kinds = peer_kinds();
        let names: Vec<_> = kinds.iter().map(|k| k.name).collect();
        assert_eq!(
            names,
            ["obvhs", "parry3d", "bvh", "embree", "embree-robust"]
        );
        let features = [
            ("peers", cfg!(feature = "peers")),
            ("embree", cfg!(feature = "embree")),
        ];
        for k in &kinds {
            let (_, enabled) = features.iter().find(|f| f.0 == k.feature).unwrap();
            assert_eq!(k.build.is_some(), *enabled, "{}", k.name);
        }
    }

    /// Each peer compiled in agrees with brute force on hit/miss and
    /// triangle (and `t` within tolerance) for rays that pass no triangle
    /// edge closely: every triangle scaled by 1 ± 10⁻³ about its centroid
    /// gives the same hit or miss, and the two nearest hits are not close.
    #[cfg(feature = "peers")]
    #[test]
    fn every_peer_agrees_with_brute_force_away_from_edges() {
        use accel_core::triangle::intersect_triangle;
        use accel_core::{Accelerator, BruteForce, PreparedRay};
        use accel_scenes::{random_rays, random_soup, uv_sphere};

        let mut scene = random_soup(600, 0x5EED);
        scene
            .append(&uv_sphere(Vec3::new(0.5, 0.5, 1.6), 0.3, 400))
            .unwrap();
        let mesh = scene.cast::<f32>().unwrap();
        let brute = BruteForce::new(&mesh).unwrap();
        let scaled = |i: usize, s: f32| {
            let p = mesh.triangle(i);
            let c = (p[0] + p[1] + p[2]) * (1.0 / 3.0);
            p.map(|q| c + (q - c) * s)
        };
        let rays: Vec<Ray<f32>> = random_rays(&scene.bounds(), 3000, 0xA11);
        let mut clean = Vec::new();
        for r in &rays {
            let pr = PreparedRay::new(*r);
            let mut ts = Vec::new();
            let mut edgy = false;
            for i in 0..mesh.triangle_count() {
                let [a, b, c] = scaled(i, 1.001);
                let big = intersect_triangle(&pr, a, b, c, f32::INFINITY);
                let [a, b, c] = scaled(i, 0.999);
                let small = intersect_triangle(&pr, a, b, c, f32::INFINITY);
                edgy |= big.is_some() != small.is_some();
                if let Some(h) = small {
                    ts.push(h.t);
                }
            }
            ts.sort_by(f32::total_cmp);
            let close = ts.windows(2).any(|w| w[1] - w[0] <= 1e-3 * w[1].abs());
            if !edgy && !close {
                clean.push(*r);
            }
        }
        assert!(clean.len() > 2000, "{} clean rays", clean.len());
        let expected: Vec<Option<PeerHit>> = clean
            .iter()
            .map(|r| {
                brute.intersect(r).unwrap().map(|h| PeerHit {
                    t: h.t,
                    prim: h.prim,
                })
            })
            .collect();
        let hits = expected.iter().filter(|h| h.is_some()).count();
        assert!(hits > 150 && hits + 150 < clean.len(), "{hits} hits");
        // Shadow-like rays ending halfway to the nearest hit see nothing.
        let halfway: Vec<Ray<f32>> = clean
            .iter()
            .zip(&expected)
            .map(|(r, h)| Ray {
                t_max: h.map_or(f32::INFINITY, |h| h.t * 0.5),
                ..*r
            })
            .collect();
        let peer_mesh = PeerMesh::new(&mesh);
        let reference = SetAnswers::Nearest(expected.clone());
        let blocked = SetAnswers::Occluded(expected.iter().map(Option::is_some).collect());
        let clear = SetAnswers::Occluded(vec![false; clean.len()]);
        for kind in peer_kinds() {
            let Some(build) = kind.build else { continue };
            let peer = build(&peer_mesh).unwrap().tracer;
            let nearest = SetAnswers::Nearest(clean.iter().map(|r| peer.nearest(r)).collect());
            let a = compare(&reference, "brute", &nearest, kind.name, &clean, 3);
            assert!(a.agrees(), "{}: {a:?}", kind.name);
            let any = SetAnswers::Occluded(clean.iter().map(|r| peer.occluded(r)).collect());
            let a = compare(&blocked, "brute", &any, kind.name, &clean, 3);
            assert!(a.agrees(), "{}: {a:?}", kind.name);
            // Rays that hit now end halfway there; the others still miss.
            let half = SetAnswers::Occluded(halfway.iter().map(|r| peer.occluded(r)).collect());
            let a = compare(&clear, "brute", &half, kind.name, &halfway, 3);
            assert!(a.agrees(), "{} (halfway): {a:?}", kind.name);
            // The same through the packet queries of a tool that has them.
            for &width in peer.packet_widths() {
                for coherent in [false, true] {
                    let name = format!("{} in packets of {width}", kind.name);
                    let p = peer.as_ref();
                    let nearest = packet_answers(p, width, coherent, false, &clean);
                    let a = compare(&reference, "brute", &nearest, &name, &clean, 3);
                    assert!(a.agrees(), "{name}: {a:?}");
                    let any = packet_answers(p, width, coherent, true, &clean);
                    let a = compare(&blocked, "brute", &any, &name, &clean, 3);
                    assert!(a.agrees(), "{name}: {a:?}");
                    let half = packet_answers(p, width, coherent, true, &halfway);
                    let a = compare(&clear, "brute", &half, &name, &halfway, 3);
                    assert!(a.agrees(), "{name} (halfway): {a:?}");
                }
            }
        }
    }
}
