//! Bundles: rays of one direction octant walked down the tree together, as
//! packets (Wald, Slusallek, Benthin & Wagner, "Interactive rendering with
//! coherent ray tracing", Eurographics 2001).
//!
//! A packet holds [`MIN_PACKET`] to [`PACKET`] consecutive rays of the
//! bundle whose direction components all have the same signs, none zero,
//! and whose directions lie within about 26° of the first one's
//! ([`COHERENT_COS`]); other rays go alone. The tree is walked once for the packet: a node
//! is fetched once, each ray computes its own plane band as the single walk
//! does ([`crate::traverse`]), and the packet goes to the near child if any
//! of its rays does, to the far child if any does (the far child waiting on
//! the stack with each ray's own interval). A ray takes part in a node only
//! where its own interval and cutoff let its single walk enter it, and leaves
//! are tested for those rays alone.
//!
//! **Exact per ray.** Since every ray of a packet shares the near side of
//! every plane, the packet's order of nodes is the single walk's order for
//! each of its rays. Restricted to the nodes a ray takes part in, it is that
//! ray's single walk: the same intervals, from the same arithmetic, the same
//! leaves tested in the same order with the same mailbox, hence the same
//! cutoffs and the same answer, bit for bit. Which rays share a packet
//! decides only speed.

use crate::build::decode_split;
use crate::reach::node_beam;
use crate::traverse::{AnyHit, BAND_ROUNDINGS, Nearest, STACK, Visitor};
use crate::tree::KdTree;
use accel_core::{Hit, PrimitiveSet, QueryError, Ray, Real, TraversalRay};
use core::borrow::Borrow;
use lanes::{Baseline, LaneRays, LaneSet, Lanes, PACKET};

mod lanes;

/// The lanes of a packet of `n` rays.
fn first_lanes(n: usize) -> Lanes {
    (1 << n) - 1
}

/// The lanes' traversal rays, as references: lanes without one (not in
/// the packet's set) repeat one that has.
fn lane_refs<T>(trs: &[Option<TraversalRay<T>>; PACKET]) -> [&TraversalRay<T>; PACKET] {
    let filler = trs.iter().flatten().next();
    core::array::from_fn(|l| {
        trs[l]
            .as_ref()
            .or(filler)
            .expect("packet_rays returns at least one lane")
    })
}

/// The packet a valid ray may join: the signs of its direction's components
/// (bit `a` set for a positive component `a`), or `None` when a component
/// is zero or subnormal, so the ray goes alone. Normal components have
/// finite reciprocals, which the packet walk needs (it takes the single
/// walk's `FINITE` path); no division is needed to know it. (Without
/// branches, so that [`whole_packet`] checks rays side by side.)
#[inline]
fn octant<T: Real>(ray: &Ray<T>) -> Option<u8> {
    let d = ray.direction;
    let normal = (d.x.abs() >= T::MIN_POSITIVE)
        & (d.y.abs() >= T::MIN_POSITIVE)
        & (d.z.abs() >= T::MIN_POSITIVE);
    let key = u8::from(d.x > T::ZERO) | u8::from(d.y > T::ZERO) << 1 | u8::from(d.z > T::ZERO) << 2;
    normal.then_some(key)
}

/// Whether `rays` make one packet as they come: [`PACKET`] of them, each
/// valid, of the first one's octant and heading within the angle of
/// [`COHERENT_COS`] of it: the packet [`by_octant`]'s gathering makes of
/// them where its look-ahead lets it gather. One pass without branches
/// per ray, where the gathering looks at each ray three times (for the
/// look-ahead, the octant and the heading, then for validity when handing
/// out): kD bundles of camera rays on the sphere ran 12% faster with the
/// grouping skipped altogether. The second ray's octant is asked first, so
/// that rays heading every way (diffuse bounces, three times in four of
/// another octant) are turned down before the pass.
fn whole_packet<T: Real>(rays: &[Ray<T>]) -> bool {
    let first = &rays[0];
    let key = octant(first);
    rays.len() == PACKET
        && key.is_some()
        && octant(&rays[1]) == key
        && rays
            .iter()
            .fold(true, |ok, r| ok & r.is_valid() & joins(first, key, r))
}

/// Whether `r` may share a packet with `first`, whose octant is `key`: of
/// that octant, heading within the angle of [`COHERENT_COS`] of it. Without
/// branches, for the look-ahead's passes over many rays.
#[inline(always)]
fn joins<T: Real>(first: &Ray<T>, key: Option<u8>, r: &Ray<T>) -> bool {
    (octant(r) == key) & first.heads_within(r, COHERENT_COS)
}

/// The fewest rays walked as a packet: fewer go alone.
const MIN_PACKET: usize = 4;

/// The cosine of the widest angle between a packet's first ray and the
/// others: packets of rays that diverge more visit many nodes for few of
/// their rays each (random rays in packets of one octant ran 0.72–0.97× as
/// fast as single rays), so such rays go alone.
const COHERENT_COS: f64 = 0.9;

/// The rays gathered for the next packet.
struct Gathered {
    /// Indices of the rays in the bundle.
    index: [usize; PACKET],
    /// Rays gathered.
    len: usize,
    /// Their octant.
    key: u8,
}

/// How [`by_octant`] hands out a bundle's rays.
enum Group<'g> {
    /// The indices of a packet of two or more rays of one octant.
    Packet(&'g [usize]),
    /// The index of a ray that goes alone (invalid rays included, so that
    /// they answer the single query's error).
    Single(usize),
}

/// Rays looked at together to decide whether a bundle can make packets.
const LOOK_AHEAD: usize = 64;

/// Splits `rays` into packets of one octant whose directions lie within the
/// angle of [`COHERENT_COS`] of their first ray's, in order, and the rays
/// that go alone, for `visit`. [`LOOK_AHEAD`] rays that are whole packets
/// of [`PACKET`] as they come ([`whole_packet`]; a tile of camera rays) are
/// handed out as such at once. Elsewhere rays are gathered one by one:
/// every [`LOOK_AHEAD`] rays whose neighbours seldom head together
/// ([`may_gather`]: diffuse bounces, random rays) go alone at once, and
/// rays are validated only when they would join a packet (the others'
/// single queries validate them anyway).
fn by_octant<T: Real>(rays: &[Ray<T>], mut visit: impl FnMut(Group<'_>)) {
    let mut g = Gathered {
        index: [0; PACKET],
        len: 0,
        key: 0,
    };
    for (c, chunk) in rays.chunks(LOOK_AHEAD).enumerate() {
        let base = c * LOOK_AHEAD;
        if chunk.chunks(PACKET).all(whole_packet) {
            for p in (base..base + chunk.len()).step_by(PACKET) {
                let index: [usize; PACKET] = core::array::from_fn(|l| p + l);
                visit(Group::Packet(&index));
            }
            continue;
        }
        if !may_gather(chunk) {
            for i in base..base + chunk.len() {
                visit(Group::Single(i));
            }
            continue;
        }
        for (i, ray) in (base..).zip(chunk) {
            let Some(key) = octant(ray) else {
                visit(Group::Single(i));
                continue;
            };
            if g.len > 0 && (g.key != key || !rays[g.index[0]].heads_within(ray, COHERENT_COS)) {
                flush(rays, &mut g, &mut visit);
            }
            if g.len == 0 {
                g.key = key;
            }
            g.index[g.len] = i;
            g.len += 1;
            if g.len == PACKET {
                flush(rays, &mut g, &mut visit);
            }
        }
        flush(rays, &mut g, &mut visit);
    }
}

/// Whether gathering `chunk`'s rays one by one could make packets, which
/// are runs of consecutive rays of one octant heading together: at least
/// half of the neighbours sampled (every [`NEIGHBOUR_STEP`]-th ray and the
/// one before it) share their octant and head within the angle of
/// [`COHERENT_COS`]. Four pairs, without a branch per pair, where every
/// ray of the look-ahead was compared with its first before, each a
/// branch that rays heading every way mispredict: callgrind, the flat
/// field's diffuse rays in kD bundles, 1,260.5M → 1,228.9M instructions
/// (single rays 1,183.8M).
fn may_gather<T: Real>(chunk: &[Ray<T>]) -> bool {
    let (mut sampled, mut together) = (0, 0);
    for k in (1..chunk.len()).step_by(NEIGHBOUR_STEP) {
        let (a, b) = (&chunk[k - 1], &chunk[k]);
        let key = octant(a);
        sampled += 1;
        together += usize::from(key.is_some() & joins(a, key, b));
    }
    2 * together >= sampled
}

/// The step between the neighbours [`may_gather`] asks: four pairs of a
/// look-ahead of 64.
const NEIGHBOUR_STEP: usize = 16;

/// Hands out the gathered rays, as a packet if [`MIN_PACKET`] or more of
/// them are valid (invalid ones go alone, to answer their error), and
/// empties the gathering.
#[inline]
fn flush<T: Real>(rays: &[Ray<T>], g: &mut Gathered, visit: &mut impl FnMut(Group<'_>)) {
    let gathered = g.len;
    g.len = 0;
    for k in 0..gathered {
        let i = g.index[k];
        if gathered >= MIN_PACKET && rays[i].is_valid() {
            g.index[g.len] = i;
            g.len += 1;
        } else {
            visit(Group::Single(i));
        }
    }
    if g.len >= MIN_PACKET {
        visit(Group::Packet(&g.index[..g.len]));
    } else {
        for &i in &g.index[..g.len] {
            visit(Group::Single(i));
        }
    }
    g.len = 0;
}

/// A packet's entry on the traversal stack: a node, the lanes that enter it
/// and each lane's interval. A bundle's packets share one stack (at most
/// [`STACK`] entries).
type Entry<T> = (u32, Lanes, [T; PACKET], [T; PACKET]);

/// A packet walk's stack: entries at strictly increasing depths, so at most
/// [`STACK`] (the trees' depth limit).
type Stack<T> = [Entry<T>; STACK];

/// What a bundle asks of each of its rays: its nearest hit ([`NearestHits`])
/// or whether it hits anything ([`AnyHits`]), for a packet in the lanes of
/// a [`LaneSet`] and for a ray that goes alone.
trait Query<T: Real>: Copy {
    /// One ray's answer.
    type Answer: Copy;

    /// The answers of a packet's rays (`index` into `rays`), part by part
    /// as the single query ([`KdTree::nearest`], [`KdTree::any`]).
    fn packet<P: PrimitiveSet<T> + ?Sized, S: Borrow<P>, L: LaneSet>(
        self,
        tree: &KdTree<'_, T, P, S>,
        set: L,
        rays: &[Ray<T>],
        index: &[usize],
        stack: &mut Stack<T>,
    ) -> [Self::Answer; PACKET];

    /// The answer of a ray alone, written into `slot` (see
    /// [`KdTree::nearest_into`]).
    fn single<P: PrimitiveSet<T> + ?Sized, S: Borrow<P>>(
        self,
        tree: &KdTree<'_, T, P, S>,
        ray: &Ray<T>,
        slot: &mut Result<Self::Answer, QueryError>,
    );
}

/// [`Query`] for the nearest hits.
#[derive(Clone, Copy)]
struct NearestHits;

impl<T: Real> Query<T> for NearestHits {
    type Answer = Option<Hit<T>>;

    #[inline(always)]
    fn packet<P: PrimitiveSet<T> + ?Sized, S: Borrow<P>, L: LaneSet>(
        self,
        tree: &KdTree<'_, T, P, S>,
        set: L,
        rays: &[Ray<T>],
        index: &[usize],
        stack: &mut Stack<T>,
    ) -> [Self::Answer; PACKET] {
        let mut best = [None; PACKET];
        let mut trs = [None; PACKET];
        for part in &tree.parts {
            let lanes = tree.packet_rays(rays, index, &part.bounds, &mut trs);
            if lanes == 0 {
                continue;
            }
            let trs = lane_refs(&trs);
            let mut v: [Nearest<'_, T, P>; PACKET] =
                core::array::from_fn(|l| tree.nearest_visitor(trs[l], best[l]));
            tree.walk_packet(set, part.root, &trs, lanes, &mut v, stack);
            for (b, v) in best.iter_mut().zip(&v) {
                *b = v.best;
            }
        }
        best
    }

    #[inline(always)]
    fn single<P: PrimitiveSet<T> + ?Sized, S: Borrow<P>>(
        self,
        tree: &KdTree<'_, T, P, S>,
        ray: &Ray<T>,
        slot: &mut Result<Self::Answer, QueryError>,
    ) {
        tree.nearest_into(ray, slot);
    }
}

/// [`Query`] for whether anything is hit.
#[derive(Clone, Copy)]
struct AnyHits;

impl<T: Real> Query<T> for AnyHits {
    type Answer = bool;

    #[inline(always)]
    fn packet<P: PrimitiveSet<T> + ?Sized, S: Borrow<P>, L: LaneSet>(
        self,
        tree: &KdTree<'_, T, P, S>,
        set: L,
        rays: &[Ray<T>],
        index: &[usize],
        stack: &mut Stack<T>,
    ) -> [Self::Answer; PACKET] {
        let mut found = [false; PACKET];
        let mut open = first_lanes(index.len());
        let mut trs = [None; PACKET];
        for part in &tree.parts {
            let lanes = tree.packet_rays(rays, index, &part.bounds, &mut trs);
            if lanes == 0 {
                continue;
            }
            let trs = lane_refs(&trs);
            let mut v: [AnyHit<'_, T, P>; PACKET] =
                core::array::from_fn(|l| tree.any_visitor(trs[l]));
            tree.walk_packet(set, part.root, &trs, lanes & open, &mut v, stack);
            for (l, v) in v.iter().enumerate() {
                if v.found {
                    found[l] = true;
                    open &= !(1 << l);
                }
            }
            if open == 0 {
                break;
            }
        }
        found
    }

    #[inline(always)]
    fn single<P: PrimitiveSet<T> + ?Sized, S: Borrow<P>>(
        self,
        tree: &KdTree<'_, T, P, S>,
        ray: &Ray<T>,
        slot: &mut Result<Self::Answer, QueryError>,
    ) {
        *slot = tree.any(ray, &mut ());
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> KdTree<'_, T, P, S> {
    /// [`accel_core::Accelerator::intersect_bundle`]: packets of one octant,
    /// other rays one at a time.
    pub(crate) fn nearest_bundle(
        &self,
        rays: &[Ray<T>],
        out: &mut [Result<Option<Hit<T>>, QueryError>],
    ) {
        self.bundle(NearestHits, rays, out);
    }

    /// [`accel_core::Accelerator::occluded_bundle`], as
    /// [`KdTree::nearest_bundle`].
    pub(crate) fn any_bundle(&self, rays: &[Ray<T>], out: &mut [Result<bool, QueryError>]) {
        self.bundle(AnyHits, rays, out);
    }

    /// Answers a bundle's `query`: `out[i]` for the ray `rays[i]`, by
    /// packets for the packets of [`by_octant`] (with a stack their walks
    /// share), alone for the other rays.
    fn bundle<Q: Query<T>>(
        &self,
        query: Q,
        rays: &[Ray<T>],
        out: &mut [Result<Q::Answer, QueryError>],
    ) {
        assert_eq!(rays.len(), out.len(), "one answer per ray of the bundle");
        // Filled on the first packet only: a bundle whose rays all go alone
        // (diffuse bounces) does not clear it.
        let mut stack = None;
        by_octant(rays, |group| match group {
            Group::Packet(index) => {
                // Lazily: `get_or_insert` would fill a new stack per packet.
                #[allow(clippy::unnecessary_lazy_evaluations)]
                let stack = stack
                    .get_or_insert_with(|| [(0, 0, [T::ZERO; PACKET], [T::ZERO; PACKET]); STACK]);
                for (&i, answer) in index.iter().zip(self.packet(query, rays, index, stack)) {
                    out[i] = Ok(answer);
                }
            }
            Group::Single(i) => query.single(self, &rays[i], &mut out[i]),
        });
    }

    /// A packet's answers to `query`, in AVX lanes where the CPU has AVX2,
    /// else in the baseline's.
    fn packet<Q: Query<T>>(
        &self,
        query: Q,
        rays: &[Ray<T>],
        index: &[usize],
        stack: &mut Stack<T>,
    ) -> [Q::Answer; PACKET] {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = lanes::Avx::detect() {
            // SAFETY: an `Avx` exists only where the CPU has AVX2.
            return unsafe { self.packet_avx(avx, query, rays, index, stack) };
        }
        query.packet(self, Baseline, rays, index, stack)
    }

    /// [`KdTree::packet`] compiled for AVX2: the AVX lanes' intrinsics
    /// inline into the walk, and the rays' preparation side by side is
    /// vectorised for AVX's width.
    ///
    /// # Safety
    /// The CPU must have AVX2 (as `avx`'s existence shows).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn packet_avx<Q: Query<T>>(
        &self,
        avx: lanes::Avx,
        query: Q,
        rays: &[Ray<T>],
        index: &[usize],
        stack: &mut Stack<T>,
    ) -> [Q::Answer; PACKET] {
        query.packet(self, avx, rays, index, stack)
    }

    /// The traversal rays of the packet's rays (`index` into `rays`) through
    /// a part with `bounds`, prepared side by side into `trs`; returns the
    /// lanes whose beam meets the part.
    #[inline(always)]
    fn packet_rays(
        &self,
        rays: &[Ray<T>],
        index: &[usize],
        bounds: &accel_core::Aabb<T>,
        trs: &mut [Option<TraversalRay<T>>; PACKET],
    ) -> Lanes {
        // Unused lanes repeat the first ray, and are not in the set.
        let members: [&Ray<T>; PACKET] =
            core::array::from_fn(|l| &rays[*index.get(l).unwrap_or(&index[0])]);
        if self.primitives().wide_hits() {
            TraversalRay::lanes_with_wide_hits(members, bounds, trs);
        } else {
            *trs = members.map(|ray| TraversalRay::new(ray, bounds));
        }
        trs.iter()
            .enumerate()
            .fold(0, |m, (l, t)| m | (Lanes::from(t.is_some()) << l))
            & first_lanes(index.len())
    }

    /// Walks a packet in the lanes of `set`, narrowing each ray's beam per
    /// node where the tree says it pays (as [`KdTree::walk`]).
    #[inline(always)]
    fn walk_packet<L: LaneSet, V: Visitor<T>>(
        &self,
        set: L,
        root: usize,
        trs: &[&TraversalRay<T>; PACKET],
        lanes: Lanes,
        v: &mut [V; PACKET],
        stack: &mut Stack<T>,
    ) {
        if self.reach.is_empty() {
            self.walk_packet_with::<false, L, V>(set, root, trs, lanes, v, stack);
        } else {
            self.walk_packet_with::<true, L, V>(set, root, trs, lanes, v, stack);
        }
    }

    /// The packet walk: the single walk's `FINITE` path
    /// (`KdTree::walk_with`), lane by lane, with the lanes that enter each
    /// node as a bit set.
    #[inline(always)]
    fn walk_packet_with<const NARROW: bool, L: LaneSet, V: Visitor<T>>(
        &self,
        set: L,
        root: usize,
        trs: &[&TraversalRay<T>; PACKET],
        lanes: Lanes,
        v: &mut [V; PACKET],
        stack: &mut Stack<T>,
    ) {
        // Per-axis values indexed by `axis & 3`, as in the single walk (the
        // fourth row is never read).
        let widen = T::ONE + T::gamma(BAND_ROUNDINGS);
        let mut rays = LaneRays {
            o: [[T::ZERO; PACKET]; 4],
            inv: [[T::ZERO; PACKET]; 4],
            half_inv: [[T::ZERO; PACKET]; 4],
        };
        let (mut delta, mut max_d) = ([T::ZERO; PACKET], [T::ZERO; PACKET]);
        let (mut t0, mut t1) = ([T::ZERO; PACKET], [T::ZERO; PACKET]);
        for (l, t) in trs.iter().enumerate() {
            for a in 0..3 {
                rays.o[a][l] = t.ray().origin[a];
                rays.inv[a][l] = t.prepared.inv_dir[a];
                rays.half_inv[a][l] = t.prepared.inv_dir[a].abs() * widen;
            }
            (delta[l], max_d[l]) = (t.delta, t.ray().direction.abs().max_component());
            (t0[l], t1[l]) = (t.t_start, t.t_end);
        }
        // One octant: the first lane's signs are every lane's.
        let positive: [bool; 4] =
            core::array::from_fn(|a| a < 3 && trs[0].ray().direction[a] > T::ZERO);
        let mut cutoff: [T; PACKET] = core::array::from_fn(|l| v[l].cutoff());
        // Lanes whose walk has ended (an any-hit query that found one).
        let mut ended: Lanes = 0;
        let mut sp = 0;
        let (mut idx, mut mask) = (root, lanes);
        loop {
            let live = set.at_or_before(&t0, &cutoff) & mask & !ended;
            if live != 0 {
                let node = &self.nodes[idx];
                if !node.is_leaf() {
                    let axis = node.axis() & 3;
                    let s = decode_split(node.split_word(), &self.splits);
                    let below = if node.has_below() { idx + 1 } else { 0 };
                    let above = node.above_child() as usize;
                    let (near, far) = if positive[axis] {
                        (below, above)
                    } else {
                        (above, below)
                    };
                    let narrowed;
                    let delta = if NARROW {
                        narrowed = core::array::from_fn(|l| {
                            node_beam(self.reach[idx], t0[l], t1[l], max_d[l], delta[l])
                        });
                        &narrowed
                    } else {
                        &delta
                    };
                    let c = set.cross(&rays, axis, delta, s, &t0, &t1);
                    let (near_t1, far_t0) = (c.near_t1, c.far_t0);
                    let (mut to_near, mut to_far) = (c.to_near, c.to_far);
                    to_near &= if near != 0 { live } else { 0 };
                    to_far &= if far != 0 { live } else { 0 };
                    if to_near != 0 {
                        // Written always, kept only when the far child is
                        // entered (no branch to mispredict); `sp < STACK`
                        // here, as in the single walk.
                        stack[sp] = (far as u32, to_far, far_t0, t1);
                        sp += usize::from(to_far != 0);
                        (idx, mask, t1) = (near, to_near, near_t1);
                        continue;
                    }
                    if to_far != 0 {
                        (idx, mask, t0) = (far, to_far, far_t0);
                        continue;
                    }
                } else {
                    let (start, prims) = self.leaf_list(node);
                    let mut rest = live;
                    while rest != 0 {
                        let l = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        if v[l].leaf(start, prims, &mut ()) {
                            ended |= 1 << l;
                        } else {
                            cutoff[l] = v[l].cutoff();
                        }
                    }
                    if lanes & !ended == 0 {
                        return;
                    }
                }
            }
            if sp == 0 {
                return;
            }
            sp -= 1;
            let (i, m, a, b) = stack[sp];
            (idx, mask, t0, t1) = (i as usize, m, a, b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::Vec3;

    fn ray(d: Vec3<f64>) -> Ray<f64> {
        Ray::new(Vec3::new(0.0, 0.0, 0.0), d).expect("a valid ray")
    }

    #[test]
    fn packets_hold_coherent_rays_of_one_octant_in_order_and_the_rest_go_alone() {
        let plus = ray(Vec3::new(1.0, 2.0, 3.0));
        let minus_x = ray(Vec3::new(-1.0, 2.0, 3.0));
        let zero_y = ray(Vec3::new(1.0, 0.0, 3.0));
        // Same octant as `plus`, but about 60° away from it.
        let aside = ray(Vec3::new(3.0, 0.1, 0.1));
        let mut invalid = plus;
        invalid.t_min = f64::NAN;
        let mut rays = vec![plus; 4]; // 0..4: a packet
        rays.push(minus_x); // 4: gathered alone, so single
        rays.push(zero_y); // 5: single, and the gathering goes on
        rays.extend([plus; 3]); // 6..9: too few, single
        rays.push(aside); // 9: single
        rays.extend([minus_x; 10]); // 10..20: a full packet of 8, then 2 single
        rays.extend([plus, plus, invalid, plus, plus]); // 20..25: a packet without 22
        let (mut packets, mut singles) = (Vec::new(), Vec::new());
        by_octant(&rays, |g| match g {
            Group::Packet(p) => packets.push(p.to_vec()),
            Group::Single(i) => singles.push(i),
        });
        assert_eq!(
            packets,
            vec![vec![0, 1, 2, 3], (10..18).collect(), vec![20, 21, 23, 24]]
        );
        singles.sort_unstable();
        assert_eq!(singles, vec![4, 5, 6, 7, 8, 9, 18, 19, 22]);
    }

    /// The packets and lone rays of `rays`, in the order handed out.
    fn groups(rays: &[Ray<f64>]) -> (Vec<Vec<usize>>, Vec<usize>) {
        let (mut packets, mut singles) = (Vec::new(), Vec::new());
        by_octant(rays, |g| match g {
            Group::Packet(p) => packets.push(p.to_vec()),
            Group::Single(i) => singles.push(i),
        });
        (packets, singles)
    }

    #[test]
    fn look_aheads_of_whole_packets_are_cut_as_they_come_and_the_rest_gathered() {
        let plus = ray(Vec3::new(1.0, 2.0, 3.0));
        // Within 26° of `plus`, same octant.
        let near = ray(Vec3::new(1.2, 2.0, 3.0));
        let eighths = |n: usize| {
            (0..n)
                .map(|p| (8 * p..8 * p + 8).collect())
                .collect::<Vec<Vec<usize>>>()
        };
        // A tile of 64 coherent rays and a last run of 16: whole packets.
        let mut rays = vec![plus; 80];
        rays[9] = near;
        assert_eq!(groups(&rays), (eighths(10), vec![]));
        // One invalid ray: its look-ahead is gathered, the ray goes alone
        // and its seven companions still make a packet.
        let mut invalid = plus;
        invalid.t_max = f64::NAN;
        rays[13] = invalid;
        let mut expected = eighths(10);
        expected[1] = vec![8, 9, 10, 11, 12, 14, 15];
        assert_eq!(groups(&rays), (expected, vec![13]));
        // A run that is not a whole packet (12 rays left over) is gathered
        // too: packets of 8 and 4.
        let (packets, singles) = groups(&vec![plus; 76]);
        assert!(singles.is_empty());
        assert_eq!(packets[8], (64..72).collect::<Vec<_>>());
        assert_eq!(packets[9], (72..76).collect::<Vec<_>>());
        // Rays of another octant (within 26° of `plus`) in a run of eight:
        // two packets of four.
        let mut mixed = vec![plus; 64];
        for r in &mut mixed[4..8] {
            *r = ray(Vec3::new(-0.1, 2.0, 3.0));
        }
        let (packets, _) = groups(&mixed);
        assert_eq!(packets[0], vec![0, 1, 2, 3]);
        assert_eq!(packets[1], vec![4, 5, 6, 7]);
        // A ray of the octant but 60° away splits its run.
        let mut aside = vec![plus; 64];
        aside[9] = ray(Vec3::new(3.0, 0.1, 0.1));
        let (packets, singles) = groups(&aside);
        assert!(singles.contains(&9));
        assert!(packets.iter().all(|p| !p.contains(&9)));
        // Eight runs of eight, each of one octant but every run of another:
        // whole packets, though fewer than a quarter of the look-ahead
        // head with its first ray (which would send every ray alone).
        let octants: Vec<Ray<f64>> = (0..64)
            .map(|i| {
                let o = i / 8;
                let sign = |bit: usize| if o >> bit & 1 == 1 { 1.0 } else { -1.0 };
                ray(Vec3::new(sign(0), 2.0 * sign(1), 3.0 * sign(2)))
            })
            .collect();
        assert_eq!(groups(&octants), (eighths(8), vec![]));
    }

    /// A look-ahead whose neighbours head every way (diffuse bounces: each
    /// ray 90° from the one before, in another octant) goes alone at once,
    /// ray by ray, though a quarter of it heads with its first ray; one
    /// whose sampled neighbours mostly head together is gathered into
    /// packets, even where some runs break.
    #[test]
    fn look_aheads_whose_neighbours_head_every_way_go_alone() {
        let dirs = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-3.0, 0.5, 1.0),
            Vec3::new(1.0, -2.0, 3.0),
            Vec3::new(3.0, 0.5, -1.0),
        ];
        // Every fourth ray is the first one's direction: a quarter heads
        // with it, which gathered the look-ahead before.
        let diffuse: Vec<Ray<f64>> = (0..64).map(|i| ray(dirs[i % 4])).collect();
        assert!(!may_gather(&diffuse));
        let (packets, singles) = groups(&diffuse);
        assert!(packets.is_empty());
        assert_eq!(singles, (0..64).collect::<Vec<_>>());
        // Coherent, but every eighth ray of another octant: not whole
        // packets, gathered into runs.
        let plus = ray(Vec3::new(1.0, 2.0, 3.0));
        let mut broken = vec![plus; 64];
        for i in (7..64).step_by(8) {
            broken[i] = ray(Vec3::new(-0.1, 2.0, 3.0));
        }
        assert!(may_gather(&broken));
        let (packets, _) = groups(&broken);
        assert_eq!(packets[0], (0..7).collect::<Vec<_>>());
    }
}
