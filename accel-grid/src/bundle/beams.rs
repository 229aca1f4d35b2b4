//! A packet's beams side by side (a structure of arrays): every member's
//! rectangle in a slab in one pass over plain arrays, which the compiler
//! vectorises, without a branch per member.

use super::PACKET;
use super::member::Member;
use accel_core::Real;

/// Members computed together: the lanes in use are rounded up to this.
const CHUNK: usize = 8;

/// A chunk's members in a packet's mask, from bit 0.
const CHUNK_MASK: u64 = (1 << CHUNK) - 1;

// A packet's chunks fit the `u8` of `Rectangles::chunks`, a chunk's
// members a `u8` mask.
const _: () = assert!(PACKET / CHUNK <= 8 && CHUNK == 8);

/// What each member's rectangle in a slab needs, per member (lane `i` for
/// member `i`), on the packet's main axis `k` and cross axes `u`, `v`.
pub(super) struct Beams<T> {
    /// Lanes in use: the members, rounded up to [`CHUNK`].
    lanes: usize,
    /// Origin on `k` and its reciprocal direction.
    ok: [T; PACKET],
    inv: [T; PACKET],
    /// Origin and direction on `u`, then on `v`.
    o: [[T; PACKET]; 2],
    d: [[T; PACKET]; 2],
    /// The member's pad ([`Member::pad`]).
    pad: [T; PACKET],
    /// Where its interval starts.
    t_start: [T; PACKET],
    /// Slices entered after this parameter are not needed: its interval's
    /// end, drawn in to its best hit plus the hit tolerance as it finds
    /// hits.
    pub(super) limit: [T; PACKET],
}

/// Every member's place in a slab ([`Beams::rectangles`]).
pub(super) struct Rectangles<T> {
    /// The chunks of [`CHUNK`] members computed, a bit each.
    chunks: u8,
    /// Per member, lowest and highest coordinate on `u`, then on `v`,
    /// widened by its pad (meaningful for the members of `within`).
    pub(super) f: [[T; PACKET]; 4],
    /// The members whose beam enters the slab after their limit.
    pub(super) past: u64,
    /// The members whose beam is in the slab before their limit.
    pub(super) within: u64,
}

impl<T: Real> Beams<T> {
    /// The beams of `members` (at most [`PACKET`]) across `axes`.
    pub(super) fn new(members: &[Member<T>], [k, u, v]: [usize; 3]) -> Self {
        debug_assert!(members.len() <= PACKET);
        let mut b = Self {
            lanes: members.len().div_ceil(CHUNK) * CHUNK,
            ok: [T::ZERO; PACKET],
            inv: [T::ZERO; PACKET],
            o: [[T::ZERO; PACKET]; 2],
            d: [[T::ZERO; PACKET]; 2],
            pad: [T::ZERO; PACKET],
            t_start: [T::ZERO; PACKET],
            limit: [T::ZERO; PACKET],
        };
        for (i, m) in members.iter().enumerate() {
            let r = m.tr.ray();
            b.ok[i] = r.origin[k];
            b.inv[i] = m.tr.prepared.inv_dir[k];
            for (j, a) in [u, v].into_iter().enumerate() {
                b.o[j][i] = r.origin[a];
                b.d[j][i] = r.direction[a];
            }
            b.pad[i] = m.pad;
            b.t_start[i] = m.tr.t_start;
            b.limit[i] = m.tr.t_end;
        }
        b
    }

    /// Each member's rectangle on `u`, `v` while its `k` extent meets the
    /// slab `[x_lo, x_hi]`, over its interval up to its limit; which
    /// members are past the slab and which are in it. Computed for the
    /// chunks of [`CHUNK`] members that hold a member of `live`.
    #[inline]
    pub(super) fn rectangles(&self, live: u64, x_lo: T, x_hi: T) -> Rectangles<T> {
        let mut out = Rectangles {
            chunks: 0,
            f: [[T::ZERO; PACKET]; 4],
            past: 0,
            within: 0,
        };
        for c in 0..self.lanes / CHUNK {
            if (live >> (c * CHUNK)) & CHUNK_MASK == 0 {
                continue;
            }
            out.chunks |= 1 << c;
            let mut past = [false; CHUNK];
            let mut not_yet = [false; CHUNK];
            for j in 0..CHUNK {
                let i = c * CHUNK + j;
                let ta = ((x_lo - self.pad[i]) - self.ok[i]) * self.inv[i];
                let tb = ((x_hi + self.pad[i]) - self.ok[i]) * self.inv[i];
                let (enter, leave) = if ta <= tb { (ta, tb) } else { (tb, ta) };
                (past[j], not_yet[j]) = (enter > self.limit[i], leave < self.t_start[i]);
                let t0 = if enter > self.t_start[i] {
                    enter
                } else {
                    self.t_start[i]
                };
                let t1 = if leave < self.limit[i] {
                    leave
                } else {
                    self.limit[i]
                };
                for a in 0..2 {
                    let (o, d) = (self.o[a][i], self.d[a][i]);
                    let (p, q) = (o + d * t0, o + d * t1);
                    let (lo, hi) = if p <= q { (p, q) } else { (q, p) };
                    out.f[2 * a][i] = lo - self.pad[i];
                    out.f[2 * a + 1][i] = hi + self.pad[i];
                }
            }
            out.past |= chunk_mask(c, |j| past[j]);
            out.within |= chunk_mask(c, |j| !past[j] & !not_yet[j]);
        }
        out
    }
}

impl<T: Real> Rectangles<T> {
    /// The members whose rectangles meet the closed rectangle `[u0, u1] ×
    /// [v0, v1]` (a cell's cross section), among the chunks computed: as
    /// `within`, meaningful only for the members in the slab.
    #[inline]
    pub(super) fn meeting(&self, [u0, u1, v0, v1]: [T; 4]) -> u64 {
        let f = &self.f;
        let mut m = 0;
        let mut chunks = self.chunks;
        while chunks != 0 {
            let c = chunks.trailing_zeros() as usize;
            chunks &= chunks - 1;
            m |= chunk_mask(c, |j| {
                let i = c * CHUNK + j;
                (f[0][i] <= u1) & (f[1][i] >= u0) & (f[2][i] <= v1) & (f[3][i] >= v0)
            });
        }
        m
    }
}

/// The members of chunk `c` (`c·CHUNK ..`) where `bit(j)` holds for the
/// chunk's `j`-th, a bit each at its place in a packet's mask (which the
/// compiler turns into a vector compare and a mask move).
#[inline(always)]
fn chunk_mask(c: usize, bit: impl Fn(usize) -> bool) -> u64 {
    let mut b = 0u8;
    for j in 0..CHUNK {
        b |= u8::from(bit(j)) << j;
    }
    u64::from(b) << (c * CHUNK)
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::{Aabb, Ray, TraversalRay, Vec3};
    use accel_scenes::generated::SplitMix64;

    /// Random rays through a box, some starting inside it, as members with
    /// random limits; on random slabs across `k`, every point of a member's
    /// ray (computed in `f64`) between its start and its limit and inside
    /// the slab marks the member as within the slab and lies in its
    /// rectangle; a member past the slab has no such point before its
    /// limit; `meeting` marks exactly the computed members whose
    /// rectangles meet a cell's closed cross section.
    #[test]
    fn rectangles_hold_each_beam_in_its_slab() {
        let bounds = Aabb::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0));
        let axes = [2, 0, 1];
        let mut rng = SplitMix64::new(5);
        let (mut within, mut points) = (0, 0);
        for _ in 0..40 {
            let mut members = Vec::new();
            while members.len() < 40 {
                let o = Vec3::new(
                    rng.range(-0.5, 1.5),
                    rng.range(-0.5, 1.5),
                    rng.range(-2.0, 0.8),
                );
                let d = Vec3::new(
                    rng.range(-0.4, 0.4),
                    rng.range(-0.4, 0.4),
                    rng.range(0.5, 1.5),
                );
                let ray: Ray<f32> = Ray::new(o, d).unwrap().cast();
                if let Some(tr) = TraversalRay::new(&ray, &bounds) {
                    members.push(Member::new(members.len(), tr));
                }
            }
            let mut beams = Beams::new(&members, axes);
            for (i, m) in members.iter().enumerate() {
                let (t0, t1) = (m.tr.t_start, m.tr.t_end);
                beams.limit[i] = t0 + (t1 - t0) * rng.range(0.2, 1.0) as f32;
            }
            let live = (1u64 << members.len()) - 1;
            for _ in 0..20 {
                let x_lo = rng.range(-0.1, 1.0) as f32;
                let x_hi = x_lo + rng.range(0.01, 0.3) as f32;
                let r = beams.rectangles(live, x_lo, x_hi);
                for (i, m) in members.iter().enumerate() {
                    let ray = m.tr.ray();
                    let (o, d) = (ray.origin.map(f64::from), ray.direction.map(f64::from));
                    let (t0, limit) = (f64::from(m.tr.t_start), f64::from(beams.limit[i]));
                    for s in 0..=64 {
                        let t = t0 + (limit - t0) * f64::from(s) / 64.0;
                        let p = o + d * t;
                        if p.z < f64::from(x_lo) || p.z > f64::from(x_hi) {
                            continue;
                        }
                        points += 1;
                        assert_eq!(r.past & (1 << i), 0, "member {i} past a slab it is in");
                        assert_ne!(r.within & (1 << i), 0, "member {i} not within");
                        let f = [0, 1, 2, 3].map(|j| f64::from(r.f[j][i]));
                        assert!(f[0] <= p.x && p.x <= f[1] && f[2] <= p.y && p.y <= f[3]);
                    }
                    within += usize::from(r.within & (1 << i) != 0);
                }
                let cell = [0.2f32, 0.45, 0.3, 0.6];
                let meets = (0..members.len()).fold(0u64, |acc, i| {
                    let f = [0, 1, 2, 3].map(|j| r.f[j][i]);
                    let m =
                        f[0] <= cell[1] && f[1] >= cell[0] && f[2] <= cell[3] && f[3] >= cell[2];
                    acc | (u64::from(m) << i)
                });
                assert_eq!(r.meeting(cell) & live, meets);
            }
        }
        assert!(
            within > 2000 && points > 20_000,
            "{within} within, {points} points"
        );
    }
}
