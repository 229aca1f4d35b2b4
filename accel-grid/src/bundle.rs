//! Bundles: rays walked together, slice by slice of cells (the coherent grid
//! traversal of Wald, Ize, Kensler, Knoll & Parker 2006, "Ray tracing
//! animated scenes using coherent grid traversal").
//!
//! A packet of up to [`PACKET`] rays whose directions share the sign of one
//! main axis `k`, and whose `k` components are the larger part of them,
//! walks the grid's slices of cells across `k` in the rays' order. In each
//! slice every ray's beam ([`TraversalRay`]) covers a rectangle of the two
//! other coordinates; their union says which cells of the slice to open,
//! and a cell's primitives are tested against each ray whose rectangle
//! meets the cell, with the ray's own mailbox and best hit. Where the grid
//! keeps empty-space blocks ([`crate::blocks`]), a slab of slices whose
//! blocks under the union are all empty is passed over at once.
//!
//! Why each ray's answer is its single-ray answer, bit for bit: a ray is
//! followed, slice by slice, until the parameter at which its beam enters
//! the next slice passes its best hit by the hit tolerance `t_tol` (its
//! single walk's limit), and within a slice its rectangle holds its beam
//! over that stretch, widened by `pad` ([`Member::pad`]) for the rounding of
//! the parameters and coordinates computed here. So every cell the single
//! walk opens before it stops is opened for the ray here, and the ray is
//! tested against every primitive the single walk tests (and perhaps a few
//! more). Each test is exact, and the nearest of them is the smallest `t`,
//! ties to the lowest index, in whatever order they come: the single
//! walk's answer. Rays that do not suit the packet (another main axis or
//! sign, a tiny main component) take the single walk.

use crate::cells::GridGeometry;
use crate::grid::GridPart;
use accel_core::packed::for_each_candidate;
use accel_core::{Hit, Mailbox, PrimitiveSet, QueryError, Ray, Real, TraversalRay, nearer};

/// Rays walked together at most; larger bundles are cut into packets.
pub const PACKET: usize = 64;

/// Fewer rays than this (of a packet, once those going another way are
/// left to the single walk) are not walked together: the slice walk's
/// fixed costs need company to pay.
pub const MIN_PACKET: usize = 16;

/// The cosine of the widest angle between a bundle's first ray and the
/// others that still lets the bundle be walked by packets: unless
/// [`MIN_PACKET`] of its rays head within about 26° of the first, every ray
/// takes the single walk at once (diffuse rays in bundles ran 2–9% slower
/// than single rays when each packet was set up before being given up).
pub const HEADING_COS: f64 = 0.9;

/// How far apart (in cells) a packet's beams may spread across the grid
/// and still be walked together ([`Lines::coherent`]).
pub const COHERENT_CELLS: f64 = 8.0;

/// A ray of a packet and its walk's state.
struct Member<T: Real> {
    /// Its index in the bundle.
    slot: usize,
    tr: TraversalRay<T>,
    /// What the beam's rectangles are widened by: the beam's half-width plus
    /// `gamma(16)` of the largest coordinate magnitude the ray reaches in
    /// its interval, which covers the few roundings of each parameter and
    /// coordinate computed from it.
    pad: T,
    best: Option<Hit<T>>,
    /// Slices entered after this parameter are not needed.
    limit: T,
    done: bool,
    mailbox: Mailbox,
}

/// Where a member's beam lies while it is in a slab of the main axis.
enum Footprint<T> {
    /// The beam reaches the slab only later (its interval starts beyond it).
    NotYet,
    /// The beam enters the slab after its limit: the ray is finished.
    Past,
    /// Lowest and highest coordinate on the two cross axes, widened.
    Within([T; 4]),
}

impl<T: Real> Member<T> {
    fn new(slot: usize, tr: TraversalRay<T>) -> Self {
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
            limit: tr.t_end,
            tr,
            pad,
            best: None,
            done: false,
            mailbox: Mailbox::new(),
        }
    }

    /// The beam's rectangle on axes `u`, `v` while its `k` extent meets the
    /// slab `[x_lo, x_hi]`, over the ray's interval up to its limit.
    #[inline]
    fn footprint(&self, [k, u, v]: [usize; 3], x_lo: T, x_hi: T) -> Footprint<T> {
        let r = self.tr.ray();
        let (o, d, inv) = (r.origin, r.direction, self.tr.prepared.inv_dir[k]);
        let ta = ((x_lo - self.pad) - o[k]) * inv;
        let tb = ((x_hi + self.pad) - o[k]) * inv;
        let (enter, leave) = if ta <= tb { (ta, tb) } else { (tb, ta) };
        if enter > self.limit {
            return Footprint::Past;
        }
        if leave < self.tr.t_start {
            return Footprint::NotYet;
        }
        let t0 = if enter > self.tr.t_start {
            enter
        } else {
            self.tr.t_start
        };
        let t1 = if leave < self.limit {
            leave
        } else {
            self.limit
        };
        let span = |a: usize| {
            let (p, q) = (o[a] + d[a] * t0, o[a] + d[a] * t1);
            let (lo, hi) = if p <= q { (p, q) } else { (q, p) };
            (lo - self.pad, hi + self.pad)
        };
        let ((u0, u1), (v0, v1)) = (span(u), span(v));
        Footprint::Within([u0, u1, v0, v1])
    }
}

/// Whether rectangles `f` and `g` (lowest and highest `u`, then `v`) meet.
#[inline]
fn meets<T: Real>(f: &[T; 4], g: &[T; 4]) -> bool {
    f[0] <= g[1] && f[1] >= g[0] && f[2] <= g[3] && f[3] >= g[2]
}

/// A cell of a slice that holds something: its references (and where they
/// start) and its rectangle on the cross axes.
struct Cell<'c, T> {
    start: usize,
    refs: &'c [u32],
    rect: [T; 4],
}

/// The unfinished members' lines across the main axis `k`,
/// `x_a = c + m·x_k` on each cross axis `a`, as intervals of intercepts
/// and slopes: a rectangle holding every member's beam in a slab, in a few
/// operations however many rays the packet has (rays starting or stopping
/// inside the slab are covered as if they went on; the per-ray rectangles
/// cull).
struct Lines<T> {
    /// Per cross axis, lowest and highest intercept.
    c: [[T; 2]; 2],
    /// Per cross axis, lowest and highest slope.
    m: [[T; 2]; 2],
    /// The widest member's pad.
    pad: T,
    /// Largest origin coordinate, intercept and slope magnitudes, for the
    /// rounding allowance.
    o_mag: T,
    c_mag: T,
    m_mag: T,
}

impl<T: Real> Lines<T> {
    fn of(members: &[Member<T>], [k, u, v]: [usize; 3]) -> Option<Self> {
        let mut lines: Option<Self> = None;
        for m in members.iter().filter(|m| !m.done) {
            let r = m.tr.ray();
            let inv = m.tr.prepared.inv_dir[k];
            let line = |a: usize| {
                let slope = r.direction[a] * inv;
                (r.origin[a] - r.origin[k] * slope, slope)
            };
            let ((cu, mu), (cv, mv)) = (line(u), line(v));
            let o = r.origin.abs().max_component();
            let l = lines.get_or_insert(Self {
                c: [[cu, cu], [cv, cv]],
                m: [[mu, mu], [mv, mv]],
                pad: m.pad,
                o_mag: o,
                c_mag: T::ZERO,
                m_mag: T::ZERO,
            });
            for (j, (c, s)) in [(cu, mu), (cv, mv)].into_iter().enumerate() {
                l.c[j] = [l.c[j][0].min(c), l.c[j][1].max(c)];
                l.m[j] = [l.m[j][0].min(s), l.m[j][1].max(s)];
                l.c_mag = l.c_mag.max(c.abs());
                l.m_mag = l.m_mag.max(s.abs());
            }
            l.pad = l.pad.max(m.pad);
            l.o_mag = l.o_mag.max(o);
        }
        lines
    }

    /// A rectangle holding every member's beam while it meets the slab
    /// `[x_lo, x_hi]`: the lines over the slab widened by the pad, with
    /// `gamma(16)` of the magnitudes for the roundings of the slopes,
    /// intercepts and this evaluation.
    fn hull(&self, x_lo: T, x_hi: T) -> [T; 4] {
        let (x0, x1) = (x_lo - self.pad, x_hi + self.pad);
        let x_mag = x0.abs().max(x1.abs());
        let err = self.pad
            + T::gamma(16)
                * (self.o_mag + self.c_mag + self.m_mag * (x_mag + self.o_mag + self.o_mag));
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
fn coherent<T: Real>(members: &[Member<T>], geom: &GridGeometry<T>, [k, u, v]: [usize; 3]) -> bool {
    let b = geom.bounds();
    let n = geom.resolution();
    let cell = |a: usize| (b.max[a] - b.min[a]) / T::from_usize(n[a] as usize);
    let limits = [u, v].map(|a| cell(a) * T::from_f64(COHERENT_CELLS));
    [b.min[k], b.max[k]].iter().all(|&x| {
        let mut span = [[T::INFINITY, T::NEG_INFINITY]; 2];
        for m in members {
            let r = m.tr.ray();
            let t = (x - r.origin[k]) * m.tr.prepared.inv_dir[k];
            for (j, &a) in [u, v].iter().enumerate() {
                let p = r.origin[a] + r.direction[a] * t;
                span[j] = [span[j][0].min(p), span[j][1].max(p)];
            }
        }
        (0..2).all(|j| span[j][1] - span[j][0] <= limits[j])
    })
}

/// One ray's answer: its nearest hit, or whether it hits anything.
pub(crate) enum Answer<T> {
    Nearest(Option<Hit<T>>),
    Any(bool),
}

impl<T> Answer<T> {
    /// The nearest hit of a nearest-hit query's answer.
    pub(crate) fn into_hit(self) -> Option<Hit<T>> {
        match self {
            Self::Nearest(h) => h,
            Self::Any(_) => unreachable!("a nearest-hit query answers with its hit"),
        }
    }

    /// Whether the ray hits anything.
    pub(crate) fn hits(self) -> bool {
        match self {
            Self::Nearest(h) => h.is_some(),
            Self::Any(b) => b,
        }
    }
}

impl<T: Real> GridPart<T> {
    /// Answers a packet of rays (at most [`PACKET`]) as the single walk
    /// answers each: `answer(i, …)` is called once for each ray `rays[i]`,
    /// with its nearest hit, or (if `ANY`) whether it hits anything, or
    /// the error that refuses it.
    pub(crate) fn packet<const ANY: bool, P: PrimitiveSet<T> + ?Sized>(
        &self,
        prims: &P,
        rays: &[Ray<T>],
        mut answer: impl FnMut(usize, Result<Answer<T>, QueryError>),
    ) {
        debug_assert!(rays.len() <= PACKET);
        let nothing = || {
            Ok(if ANY {
                Answer::Any(false)
            } else {
                Answer::Nearest(None)
            })
        };
        let bounds = self.geometry.bounds();
        let mut members: Vec<Member<T>> = Vec::with_capacity(rays.len());
        let mut weight = [T::ZERO; 3];
        for (slot, ray) in rays.iter().enumerate() {
            if let Err(e) = ray.validate() {
                answer(slot, Err(e));
                continue;
            }
            match TraversalRay::new(ray, bounds) {
                Some(tr) => {
                    for (a, w) in weight.iter_mut().enumerate() {
                        *w += ray.direction[a];
                    }
                    members.push(Member::new(slot, tr));
                }
                None => answer(slot, nothing()),
            }
        }
        if members.is_empty() {
            return;
        }
        let k = (0..3)
            .max_by(|&a, &b| {
                weight[a]
                    .abs()
                    .partial_cmp(&weight[b].abs())
                    .unwrap_or(core::cmp::Ordering::Equal)
            })
            .unwrap_or(0);
        let up = weight[k] >= T::ZERO;
        // Rays that do not go the packet's way take the single walk.
        members.retain(|m| {
            let d = m.tr.ray().direction;
            let along = if up { d[k] } else { -d[k] };
            let suits = along > T::ZERO
                && m.tr.prepared.inv_dir[k].is_finite()
                && along + along >= d.abs().max_component();
            if !suits {
                answer(m.slot, Ok(self.single::<ANY, P>(prims, &m.tr)));
            }
            suits
        });
        if members.is_empty() {
            return;
        }
        if !self.walk_slices::<ANY, P>(prims, &mut members, k, up) {
            // Too divergent to walk together: one at a time.
            for m in members {
                answer(m.slot, Ok(self.single::<ANY, P>(prims, &m.tr)));
            }
            return;
        }
        for m in members {
            answer(
                m.slot,
                Ok(if ANY {
                    Answer::Any(m.best.is_some())
                } else {
                    Answer::Nearest(m.best)
                }),
            );
        }
    }

    /// One ray's answer by the single walk.
    fn single<const ANY: bool, P: PrimitiveSet<T> + ?Sized>(
        &self,
        prims: &P,
        tr: &TraversalRay<T>,
    ) -> Answer<T> {
        if ANY {
            Answer::Any(self.any(prims, tr, &mut ()))
        } else {
            Answer::Nearest(self.nearest(prims, tr, None, &mut ()))
        }
    }

    /// The slice walk of a packet along main axis `k` (`up`: increasing);
    /// `false`, with nothing done, when the packet is too divergent for it
    /// ([`Lines::coherent`]).
    fn walk_slices<const ANY: bool, P: PrimitiveSet<T> + ?Sized>(
        &self,
        prims: &P,
        members: &mut [Member<T>],
        k: usize,
        up: bool,
    ) -> bool {
        let axes = [k, (k + 1) % 3, (k + 2) % 3];
        let geom = &self.geometry;
        let n = geom.resolution()[k];
        let xs = geom.boundaries(k);
        if members.len() < MIN_PACKET || !coherent(members, geom, axes) {
            return false;
        }
        let Some(mut lines) = Lines::of(members, axes) else {
            return true;
        };
        // The slices the members' beams reach, in the order they go.
        let (mut first, mut last) = (u32::MAX, 0u32);
        for m in members.iter() {
            let r = m.tr.ray();
            for t in [m.tr.t_start, m.tr.t_end] {
                let x = r.origin[k] + r.direction[k] * t;
                first = first.min(geom.axis_cell(k, x - m.pad));
                last = last.max(geom.axis_cell(k, x + m.pad));
            }
        }
        let (shift, blocks) = match &self.blocks {
            Some(b) => (b.shift(), Some(b)),
            None => (0, None),
        };
        let mut active = members.iter().filter(|m| !m.done).count();
        let mut rects: Vec<Option<[T; 4]>> = vec![None; members.len()];
        let mut cells: Vec<Cell<'_, T>> = Vec::new();
        let (slab_first, slab_last) = (first >> shift, last >> shift);
        for step in 0..=(slab_last - slab_first) {
            let slab = if up {
                slab_first + step
            } else {
                slab_last - step
            };
            if let Some(blocks) = blocks {
                let bx = blocks.geometry().boundaries(k);
                let hull = lines.hull(bx[slab as usize], bx[slab as usize + 1]);
                if !blocks.any_occupied_under(axes, slab, &hull) {
                    continue;
                }
            }
            let lo = (slab << shift).max(first);
            let hi = (((slab + 1) << shift) - 1).min(last).min(n - 1);
            for step in 0..=(hi - lo) {
                let i = if up { lo + step } else { hi - step };
                let (x_lo, x_hi) = (xs[i as usize], xs[i as usize + 1]);
                self.full_cells(axes, i, &lines.hull(x_lo, x_hi), &mut cells);
                if cells.is_empty() {
                    continue;
                }
                self.rectangles(members, axes, x_lo, x_hi, &mut rects);
                for cell in &cells {
                    for (m, rect) in members.iter_mut().zip(&rects) {
                        let Some(f) = rect else { continue };
                        if !m.done && meets(f, &cell.rect) {
                            self.test_cell::<ANY, P>(prims, m, cell.start, cell.refs);
                        }
                    }
                }
                let now = members.iter().filter(|m| !m.done).count();
                if now != active {
                    active = now;
                    match Lines::of(members, axes) {
                        Some(l) => lines = l,
                        None => return true,
                    }
                }
            }
        }
        true
    }

    /// The cells of slice `i` (across `axes[0]`) under `hull` that hold
    /// something, in `cells`.
    fn full_cells<'c>(
        &'c self,
        [k, u, v]: [usize; 3],
        i: u32,
        hull: &[T; 4],
        cells: &mut Vec<Cell<'c, T>>,
    ) {
        cells.clear();
        let geom = &self.geometry;
        let (bu, bv) = (geom.boundaries(u), geom.boundaries(v));
        let (u_lo, u_hi) = (geom.axis_cell(u, hull[0]), geom.axis_cell(u, hull[1]));
        let (v_lo, v_hi) = (geom.axis_cell(v, hull[2]), geom.axis_cell(v, hull[3]));
        let bits = self.cells.has_occupied_bits();
        for cv in v_lo..=v_hi {
            for cu in u_lo..=u_hi {
                let mut c = [0u32; 3];
                (c[k], c[u], c[v]) = (i, cu, cv);
                let index = geom.linear_index(c);
                let (start, refs) = if bits {
                    self.cells.occupied_cell(index)
                } else {
                    self.cells.cell_at(index)
                };
                if !refs.is_empty() {
                    let (cu, cv) = (cu as usize, cv as usize);
                    cells.push(Cell {
                        start,
                        refs,
                        rect: [bu[cu], bu[cu + 1], bv[cv], bv[cv + 1]],
                    });
                }
            }
        }
    }

    /// Each unfinished member's rectangle in the slab `[x_lo, x_hi]` (in
    /// `rects`, `None` for a member not in it), marking finished the ones
    /// past it.
    fn rectangles(
        &self,
        members: &mut [Member<T>],
        axes: [usize; 3],
        x_lo: T,
        x_hi: T,
        rects: &mut [Option<[T; 4]>],
    ) {
        for (m, rect) in members.iter_mut().zip(rects.iter_mut()) {
            *rect = None;
            if m.done {
                continue;
            }
            match m.footprint(axes, x_lo, x_hi) {
                Footprint::Past => m.done = true,
                Footprint::NotYet => {}
                Footprint::Within(f) => *rect = Some(f),
            }
        }
    }

    /// Tests a cell's primitives against one member.
    #[inline]
    fn test_cell<const ANY: bool, P: PrimitiveSet<T> + ?Sized>(
        &self,
        prims: &P,
        m: &mut Member<T>,
        start: usize,
        refs: &[u32],
    ) {
        let ray_max = m.tr.ray().t_max;
        let prepared = &m.tr.prepared;
        let (mailbox, best) = (&mut m.mailbox, &mut m.best);
        let found = for_each_candidate(self.packed.as_ref(), start, refs, prepared, |p| {
            if mailbox.seen(p) {
                return false;
            }
            let t_max = if ANY {
                ray_max
            } else {
                best.map_or(ray_max, |b| b.t)
            };
            match prims.intersect(p as usize, prepared, t_max) {
                Some(h) => {
                    *best = nearer(*best, Hit::new(p, h));
                    ANY
                }
                None => false,
            }
        });
        if ANY && found {
            m.done = true;
        } else if let Some(b) = m.best {
            let reach = b.t + m.tr.t_tol;
            if reach < m.limit {
                m.limit = reach;
            }
        }
    }
}
