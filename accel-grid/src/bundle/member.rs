//! A packet's rays: each one's walk state and its test of a primitive, and
//! the rectangles that hold all their beams in a slab (each one's own
//! rectangle: [`super::beams`]).

use crate::cells::GridGeometry;
use accel_core::{Hit, Mailbox, PrimitiveSet, Real, TraversalRay, nearer};

use super::COHERENT_CELLS;

/// A ray of a packet and its walk's state.
pub(super) struct Member<T: Real> {
    /// Its index in the bundle.
    pub(super) slot: usize,
    pub(super) tr: TraversalRay<T>,
    /// What the beam's rectangles are widened by: the beam's half-width plus
    /// `gamma(16)` of the largest coordinate magnitude the ray reaches in
    /// its interval, which covers the few roundings of each parameter and
    /// coordinate computed from it.
    pub(super) pad: T,
    pub(super) best: Option<Hit<T>>,
    pub(super) mailbox: Mailbox,
    /// Its line across the main axis on each cross axis, `x_a = c +
    /// m·(x_k − pivot)`: `[c, m]` ([`Lines`]); set once the packet's axes
    /// and pivot are known.
    pub(super) line: [[T; 2]; 2],
    /// The largest magnitude of its origin's coordinates.
    o_mag: T,
}

impl<T: Real> Member<T> {
    pub(super) fn new(slot: usize, tr: TraversalRay<T>) -> Self {
        let r = tr.ray();
        let o = r.origin.abs().max_component();
        let d = r.direction.abs().max_component();
        let t = if tr.t_start.abs() > tr.t_end.abs() {
            tr.t_start.abs()
        } else {
            tr.t_end.abs()
        };
        let pad = tr.delta + T::gamma(16) * (o + d * t);
        Self {
            slot,
            tr,
            pad,
            best: None,
            mailbox: Mailbox::new(),
            line: [[T::ZERO; 2]; 2],
            o_mag: o,
        }
    }

    /// Sets its lines across main axis `k` on the cross axes `u`, `v`,
    /// about `pivot` on the main axis (a coordinate of some member's
    /// origin, so at most the origins' largest magnitude).
    pub(super) fn set_axes(&mut self, [k, u, v]: [usize; 3], pivot: T) {
        let r = self.tr.ray();
        // Arrays, whose index is an address, where `Vec3`'s is a match.
        let (o, d) = (r.origin.to_array(), r.direction.to_array());
        let inv = self.tr.prepared.inv_dir.to_array()[k];
        self.line = [u, v].map(|a| {
            let slope = d[a] * inv;
            [o[a] + (pivot - o[k]) * slope, slope]
        });
    }
}

/// Tests primitive `p` of `prims` against the ray of `tr` (unless
/// `mailbox` has seen it), as its single walk does: keeps the nearer hit in
/// `best` and returns whether an any-hit query (`ANY`) is answered. (The
/// parts of a [`Member`], so that its beam can be read while the rest
/// changes.)
#[inline]
pub(super) fn candidate<const ANY: bool, T: Real, P: PrimitiveSet<T> + ?Sized>(
    tr: &TraversalRay<T>,
    mailbox: &mut Mailbox,
    best: &mut Option<Hit<T>>,
    p: u32,
    prims: &P,
) -> bool {
    if mailbox.seen(p) {
        return false;
    }
    let ray_max = tr.ray().t_max;
    let t_max = if ANY {
        ray_max
    } else {
        best.map_or(ray_max, |b| b.t)
    };
    match prims.intersect(p as usize, &tr.prepared, t_max) {
        Some(h) => {
            *best = nearer(*best, Hit::new(p, h));
            ANY
        }
        None => false,
    }
}

/// The indices of the set bits of `mask`, lowest first.
#[inline]
pub(super) fn bits(mut mask: u64) -> impl Iterator<Item = usize> {
    core::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

/// Some members' lines across the main axis `k`, `x_a = c + m·(x_k −
/// pivot)` on each cross axis `a`, as intervals of values at the pivot and
/// of slopes: a rectangle holding every such member's beam in a slab, in a
/// few operations however many rays the packet has (rays starting or
/// stopping inside the slab are covered as if they went on; the per-ray
/// rectangles cull). The pivot is a member's origin coordinate: rays from
/// one point (a camera's) then share `c`, and the rectangle is their exact
/// envelope; about the axis origin instead, it was too wide by the slopes'
/// spread times the origin's distance from it.
pub(super) struct Lines<T> {
    /// Per cross axis, lowest and highest value at the pivot.
    c: [[T; 2]; 2],
    /// Per cross axis, lowest and highest slope.
    m: [[T; 2]; 2],
    /// Where on the main axis the lines are taken from.
    pivot: T,
    /// The widest member's pad.
    pad: T,
    /// Largest origin coordinate, intercept and slope magnitudes, for the
    /// rounding allowance.
    o_mag: T,
    c_mag: T,
    m_mag: T,
}

impl<T: Real> Lines<T> {
    /// The lines of the members of `live` (a bit per member), `None` when
    /// there is none.
    pub(super) fn of(members: &[Member<T>], live: u64, pivot: T) -> Option<Self> {
        let mut lines: Option<Self> = None;
        for m in bits(live).map(|i| &members[i]) {
            let [[cu, mu], [cv, mv]] = m.line;
            let l = lines.get_or_insert(Self {
                c: [[cu, cu], [cv, cv]],
                m: [[mu, mu], [mv, mv]],
                pivot,
                pad: m.pad,
                o_mag: m.o_mag,
                c_mag: T::ZERO,
                m_mag: T::ZERO,
            });
            for (j, [c, s]) in m.line.into_iter().enumerate() {
                l.c[j] = [l.c[j][0].min(c), l.c[j][1].max(c)];
                l.m[j] = [l.m[j][0].min(s), l.m[j][1].max(s)];
                l.c_mag = l.c_mag.max(c.abs());
                l.m_mag = l.m_mag.max(s.abs());
            }
            l.pad = l.pad.max(m.pad);
            l.o_mag = l.o_mag.max(m.o_mag);
        }
        lines
    }

    /// A rectangle holding every member's beam while it meets the slab
    /// `[x_lo, x_hi]`: the lines over the slab widened by the pad, with
    /// `gamma(16)` of the magnitudes for the roundings of the slopes, the
    /// values at the pivot and this evaluation (`|pivot| ≤ o_mag`, so
    /// `|pivot − o_k| ≤ 2·o_mag` and `|x − pivot| ≤ x_mag + o_mag`).
    pub(super) fn hull(&self, x_lo: T, x_hi: T) -> [T; 4] {
        let (x0, x1) = (x_lo - self.pad - self.pivot, x_hi + self.pad - self.pivot);
        let x_mag = (x_lo - self.pad).abs().max((x_hi + self.pad).abs());
        let o = self.o_mag;
        let err = self.pad + T::gamma(16) * (o + self.c_mag + self.m_mag * (x_mag + o + o + o));
        let mut out = [T::ZERO; 4];
        for j in 0..2 {
            let [m0, m1] = self.m[j];
            let ends = [m0 * x0, m0 * x1, m1 * x0, m1 * x1];
            let lo = ends.iter().fold(T::INFINITY, |a, &b| a.min(b));
            let hi = ends.iter().fold(T::NEG_INFINITY, |a, &b| a.max(b));
            out[2 * j] = (self.c[j][0] + lo) - err;
            out[2 * j + 1] = (self.c[j][1] + hi) + err;
        }
        out
    }
}

/// Whether the members' rays stay within [`COHERENT_CELLS`] cells of each
/// other across the grid: on each cross axis, the spread of their lines
/// where they enter and where they leave the grid's depth along `axes[0]`,
/// in cells. A tile of camera rays does, diffuse rays leaving a surface do
/// not, and walking those together would open most of every slice for each
/// of them. (A choice of speed only: any packet is answered exactly.)
pub(super) fn coherent<T: Real>(
    members: &[Member<T>],
    geom: &GridGeometry<T>,
    [k, u, v]: [usize; 3],
) -> bool {
    let b = geom.bounds();
    let n = geom.resolution();
    let cell = |a: usize| (b.max[a] - b.min[a]) / T::from_usize(n[a] as usize);
    let limits = [u, v].map(|a| cell(a) * T::from_f64(COHERENT_CELLS));
    [b.min[k], b.max[k]].iter().all(|&x| {
        let mut span = [[T::INFINITY, T::NEG_INFINITY]; 2];
        for m in members {
            let r = m.tr.ray();
            let (o, d) = (r.origin.to_array(), r.direction.to_array());
            let t = (x - o[k]) * m.tr.prepared.inv_dir.to_array()[k];
            for (j, &a) in [u, v].iter().enumerate() {
                let p = o[a] + d[a] * t;
                span[j] = [span[j][0].min(p), span[j][1].max(p)];
            }
        }
        (0..2).all(|j| span[j][1] - span[j][0] <= limits[j])
    })
}
