//! The 3D-DDA of Amanatides & Woo (1987), walked by a thin beam.
//!
//! The classic DDA keeps, per axis, the parameter `t_next` at which the ray
//! crosses the next cell boundary, and always steps along the smallest. Here the
//! ray is the beam of [`TraversalRay`]: the box of half-width `delta` swept along
//! it. Per axis the beam's cross-section spans the cells from a *trail* index
//! (where `x − delta` is, for a positive direction) to a *lead* index (where
//! `x + delta` is). A lead crossing opens a new slab of cells (the new lead index
//! times the current ranges of the other axes, almost always one cell); a trail
//! crossing only narrows a range, so trails are caught up lazily at each lead
//! event. The walk thus visits every cell within `delta` of the ray, in the
//! order the beam first touches them: the classic DDA when the ray is far from
//! cell edges, and both neighbours when it runs along a face, an edge or through
//! a corner, where rounding could otherwise skip a cell.
//!
//! Crossing parameters are computed from the stored boundaries as
//! `((boundary − origin) ∓ delta) / d`, never accumulated, so their error is a
//! few roundings relative to `|t|`, which `delta` covers.

use crate::cells::{CellBox, GridGeometry};
use accel_core::{Real, TraversalRay, Vec3};

/// The margin, in units of `gamma(1)` relative to the parameter, that
/// [`BeamWalk::settled`] keeps from computed crossings: they take about four
/// roundings (a difference, an offset, a reciprocal and a product).
pub const SETTLED_MARGIN: u32 = 16;

/// What one step of a [`BeamWalk`] opens.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The walk is over.
    End,
    /// One cell: the common case of a beam far from cell edges.
    Cell([u32; 3]),
    /// A box of cells (the beam runs along a face, an edge or a corner).
    Cells(CellBox),
}

/// Where [`BeamWalk::pass`] stopped.
#[derive(Clone, Copy, Debug)]
enum Passed<T> {
    /// The walk is over.
    End,
    /// It opened a cell that holds something.
    Met,
    /// Its last step, along the axis, turns it wide: its trail crosses at
    /// the parameter, after the next event.
    Widened(usize, T),
}

/// Where [`BeamWalk::place`] put a walk.
#[derive(Clone, Copy)]
enum Placed {
    /// In this one cell.
    One([u32; 3]),
    /// Across several cells ([`BeamWalk::spread_cells`]).
    Spread,
}

/// What [`BeamWalk::restart`] learns of one axis from its first guess.
#[derive(Clone, Copy)]
struct ThinProbe<T> {
    /// The guessed cell.
    cell: u32,
    /// The lead's crossing out of it (`+∞` where there is none).
    t_lead: T,
    /// Whether the beam lies in that cell alone along the axis.
    alone: bool,
}

/// A beam walking the cells of one grid front to back.
///
/// While the beam is *thin* (its trail equals its lead on every axis, so its
/// cross-section lies in one cell) a step is the classic DDA step plus one
/// trail crossing, done at once: the trail left behind on the stepped axis
/// catches up as soon as it is known to cross before the next lead event,
/// which is exactly when the lazy catch-up of the general step would have
/// moved it. Only when it cannot (the ray is near another axis's boundary)
/// does the walk turn *wide* and take the general step.
#[derive(Clone, Debug)]
pub struct BeamWalk<'g, T> {
    bounds: [&'g [T]; 3],
    origin: Vec3<T>,
    dir: Vec3<T>,
    inv_dir: Vec3<T>,
    /// The beam's half-width.
    delta: T,
    /// Per axis, the beam front's offset from a boundary: `−delta` for a
    /// positive direction, `+delta` for a negative one (the trail's is its
    /// negation).
    lead_off: [T; 3],
    /// Per axis, 1 when stepping up (a cell's exit is its upper boundary,
    /// index `cell + 1`), else 0.
    up: [u32; 3],
    step: [i32; 3],
    lead: [u32; 3],
    /// Valid only while the walk is wide (`!thin`); equal to `lead` otherwise.
    trail: [u32; 3],
    t_lead: [T; 3],
    /// Valid only while the walk is wide; `+∞` on every axis otherwise.
    t_trail: [T; 3],
    thin: bool,
    /// The parameter of the last lead crossing (`t_start` before the first).
    t_event: T,
    /// While thin: when the beam came to lie wholly in the lead cell (its
    /// trail's last crossing, or `t_start`).
    t_settled: T,
}

impl<'g, T: Real> BeamWalk<'g, T> {
    /// Starts the walk at parameter `t_start` (inside or at the entry of the
    /// grid; the caller clips it with [`TraversalRay`] or a slab test).
    /// Returns the walk and the cells the beam touches at `t_start`.
    ///
    /// Hot callers take [`BeamWalk::unplaced`] and [`BeamWalk::restart`]
    /// instead: returned after `restart` has written it through a
    /// reference, the walk is copied (`memcpy`) in wide loads straddling the
    /// narrower stores that had just written it (no store forwarding).
    #[inline]
    pub fn start(geom: &'g GridGeometry<T>, ray: &TraversalRay<T>, t_start: T) -> (Self, CellBox) {
        let mut walk = Self::unplaced(geom, ray);
        let cells = walk.restart(geom, t_start);
        (walk, cells)
    }

    /// The walk of `ray` over `geom`, not yet placed: it opens no cell until
    /// [`BeamWalk::restart`] places it at a parameter and returns the cells
    /// the beam touches there. Always inlined and built by one struct
    /// expression, so that it is written where the caller keeps it, and
    /// `restart` places it there: no copy, where [`BeamWalk::start`]'s
    /// returned walk is copied.
    #[inline(always)]
    #[must_use]
    pub fn unplaced(geom: &'g GridGeometry<T>, ray: &TraversalRay<T>) -> Self {
        let r = ray.ray();
        let (dir, delta) = (r.direction, ray.delta);
        let sign = |a: usize| {
            if dir[a] > T::ZERO {
                (1, 1, -delta)
            } else if dir[a] < T::ZERO {
                (-1, 0, delta)
            } else {
                (0, 0, T::ZERO)
            }
        };
        let signs = [sign(0), sign(1), sign(2)];
        Self {
            bounds: [geom.boundaries(0), geom.boundaries(1), geom.boundaries(2)],
            origin: r.origin,
            dir,
            inv_dir: ray.prepared.inv_dir,
            delta,
            lead_off: signs.map(|s| s.2),
            up: signs.map(|s| s.1),
            step: signs.map(|s| s.0),
            lead: [0; 3],
            trail: [0; 3],
            t_lead: [T::INFINITY; 3],
            t_trail: [T::INFINITY; 3],
            thin: false,
            t_event: T::ZERO,
            t_settled: T::ZERO,
        }
    }

    /// Starts this walk again, in place, at parameter `t` (as
    /// [`BeamWalk::start`], on the same grid `geom` and ray), and returns the
    /// cells the beam touches there; places a [`BeamWalk::unplaced`] walk.
    ///
    /// The common case, a beam that lies in one cell on every axis there
    /// (the first guess of each axis's cell right, the beam clear of its
    /// boundaries), is settled from one guess and two boundaries per axis,
    /// with no branch per axis; any other case takes
    /// [`BeamWalk::restart_each_axis`]. Both give the same walk, bit for
    /// bit.
    ///
    /// The cells come back from the out-of-line part ([`BeamWalk::place`])
    /// in registers: a [`CellBox`] returned from a call went through memory
    /// in six 4-byte stores that the caller read back in 8-byte loads, each
    /// straddling two of them (no store forwarding).
    #[inline(always)]
    pub fn restart(&mut self, geom: &GridGeometry<T>, t: T) -> CellBox {
        match self.place(geom, t) {
            Placed::One(cell) => CellBox::single(cell),
            Placed::Spread => self.spread_cells(),
        }
    }

    /// [`BeamWalk::restart`], returning the one cell the beam lies in, or
    /// [`Placed::Spread`] when it spans several (those between the walk's
    /// trail and lead, [`BeamWalk::spread_cells`]).
    #[inline]
    fn place(&mut self, geom: &GridGeometry<T>, t: T) -> Placed {
        debug_assert!(core::ptr::eq(self.bounds[0], geom.boundaries(0)));
        self.t_event = t;
        self.t_settled = t;
        let [x, y, z] = [0, 1, 2].map(|a| self.thin_probe(geom, a, t));
        if x.alone & y.alone & z.alone {
            let cell = [x.cell, y.cell, z.cell];
            self.lead = cell;
            self.trail = cell;
            self.t_lead = [x.t_lead, y.t_lead, z.t_lead];
            self.t_trail = [T::INFINITY; 3];
            self.thin = true;
            return Placed::One(cell);
        }
        self.restart_each_axis(geom, t);
        Placed::Spread
    }

    /// The cells a walk just placed spans: per axis, from the lower to the
    /// higher of its trail and lead (the trail is the low end when stepping
    /// up or parallel, the high end when stepping down).
    #[cold]
    fn spread_cells(&self) -> CellBox {
        CellBox {
            lo: [0, 1, 2].map(|a| self.trail[a].min(self.lead[a])),
            hi: [0, 1, 2].map(|a| self.trail[a].max(self.lead[a])),
        }
    }

    /// Whether, at `t`, the beam lies in one cell along `axis`, found from
    /// `geom`'s first guess alone ([`GridGeometry::guess_cell`]), and that
    /// cell and its lead crossing if so.
    ///
    /// The guess `m` is [`GridGeometry::axis_cell_relative`]'s answer for
    /// `rel` exactly when `rel` lies at or past boundary `m` (or `m` is the
    /// first cell) and before boundary `m + 1` (or `m` is the last), and
    /// [`BeamWalk::beam_cells`] then gives `m` for both edges exactly when
    /// `rel − delta` and `rel + delta` do too. Those imply the tests on
    /// `rel` itself, since `rel − delta ≤ rel ≤ rel + delta` after rounding.
    /// The crossing is [`BeamWalk::lead_time`]'s expression on the boundary
    /// already read.
    #[inline(always)]
    fn thin_probe(&self, geom: &GridGeometry<T>, axis: usize, t: T) -> ThinProbe<T> {
        let (b, o) = (self.bounds[axis], self.origin[axis]);
        let rel = self.dir[axis] * t;
        let m = geom.guess_cell(axis, o, rel) as usize;
        let last = b.len() - 2;
        let (low_edge, high_edge) = (b[m] - o, b[m + 1] - o);
        // Bitwise, not short-circuit: one branch for all three axes.
        let alone = ((m == 0) | (rel - self.delta >= low_edge))
            & ((m == last) | (rel + self.delta < high_edge));
        let up = self.up[axis] as usize;
        let exit = m + up;
        let t_lead = if self.step[axis] != 0 && exit > 0 && exit <= last {
            let edge = if up == 1 { high_edge } else { low_edge };
            self.time(axis, edge + self.lead_off[axis])
        } else {
            T::INFINITY
        };
        ThinProbe {
            cell: m as u32,
            t_lead,
            alone,
        }
    }

    /// [`BeamWalk::restart`] axis by axis, for any beam: each axis's cells
    /// located and fixed against the stored boundaries, the walk wide
    /// where the beam spans more than one cell.
    #[inline(never)]
    fn restart_each_axis(&mut self, geom: &GridGeometry<T>, t: T) -> CellBox {
        let mut cells = CellBox::single([0; 3]);
        for a in 0..3 {
            let rel = self.dir[a] * t;
            let (low, high) = self.beam_cells(geom, a, rel);
            cells.lo[a] = low;
            cells.hi[a] = high;
            if self.step[a] > 0 {
                self.trail[a] = low;
                self.lead[a] = high;
            } else if self.step[a] < 0 {
                self.trail[a] = high;
                self.lead[a] = low;
            } else {
                // Parallel to the axis: the range never changes.
                self.trail[a] = low;
                self.lead[a] = high;
                self.t_lead[a] = T::INFINITY;
                self.t_trail[a] = T::INFINITY;
                continue;
            }
            self.t_lead[a] = self.lead_time(a);
            self.t_trail[a] = self.trail_time(a);
        }
        self.thin = self.trail == self.lead;
        cells
    }

    /// The cells along `axis` holding `origin + rel ∓ delta`, as
    /// [`GridGeometry::axis_cell_relative`] gives them, located once: the
    /// cell of `rel` is both unless the beam reaches past one of its
    /// boundaries (the cells are those of monotone comparisons against the
    /// same stored boundaries, so this is the same answer).
    #[inline]
    fn beam_cells(&self, geom: &GridGeometry<T>, axis: usize, rel: T) -> (u32, u32) {
        let (b, o) = (self.bounds[axis], self.origin[axis]);
        let mid = geom.axis_cell_relative(axis, o, rel);
        let (m, last) = (mid as usize, b.len() - 2);
        let (below, above) = (rel - self.delta, rel + self.delta);
        let low = if m == 0 || below >= b[m] - o {
            mid
        } else {
            geom.axis_cell_relative(axis, o, below)
        };
        let high = if m == last || above < b[m + 1] - o {
            mid
        } else {
            geom.axis_cell_relative(axis, o, above)
        };
        (low, high)
    }

    /// The walk of the same ray over `blocks`, the grid of blocks of
    /// `2^shift` cells of this one ([`GridGeometry::coarsened`]), from
    /// parameter `t` at which, exactly, the beam lies in this walk's lead
    /// cell alone (one that [`BeamWalk::settled`] returned): it starts in
    /// that cell's block, as [`BeamWalk::start`] would at `t` without
    /// locating it again.
    #[inline]
    #[must_use]
    pub fn settled_block(&self, blocks: &'g GridGeometry<T>, shift: u32, t: T) -> Self {
        debug_assert!(self.thin);
        let lead = self.lead.map(|c| c >> shift);
        let mut walk = Self {
            bounds: [
                blocks.boundaries(0),
                blocks.boundaries(1),
                blocks.boundaries(2),
            ],
            lead,
            trail: lead,
            t_lead: [T::INFINITY; 3],
            t_trail: [T::INFINITY; 3],
            thin: true,
            t_event: t,
            t_settled: t,
            ..*self
        };
        for a in 0..3 {
            if walk.step[a] != 0 {
                walk.t_lead[a] = walk.lead_time(a);
            }
        }
        walk
    }

    /// As [`BeamWalk::step`], passing over the cells that `empty` (given
    /// each cell's linear index in the walk's grid, x fastest, and its
    /// coordinates) says to pass over, while the walk stays thin: returns
    /// the first step that opens a cell not passed over, or turns the walk
    /// wide ([`Step::Cell`] of its lead, as `step` returns it), or the end.
    /// A wide walk takes one general step.
    ///
    /// The thin steps are those of [`BeamWalk::pass`], on a copy of the
    /// walk in registers, written back once.
    #[inline(always)]
    pub fn step_past_empty(
        &mut self,
        limit: T,
        empty: impl FnMut(usize, [u32; 3]) -> bool,
    ) -> Step {
        if !self.thin {
            return self.step(limit);
        }
        let mut w = self.clone();
        let passed = w.pass(limit, empty);
        *self = w;
        match passed {
            Passed::End => Step::End,
            Passed::Met => Step::Cell(self.lead),
            Passed::Widened(a, tau) => {
                self.widen(a, tau);
                Step::Cell(self.lead)
            }
        }
    }

    /// The parameter of the crossing that opens the first cell of this thin
    /// walk (one of blocks, from [`BeamWalk::settled_block`]) that
    /// `occupied` (per cell, x fastest) says holds something, or that the
    /// beam enters while it still spans the last (the walk would turn wide
    /// over two cells there; rare, since the beam is thin). `None` when the
    /// walk ends first. The walk is consumed: it lives in registers
    /// ([`BeamWalk::pass`]) and is never written back.
    #[inline]
    pub(crate) fn pass_thin(mut self, limit: T, occupied: &[bool]) -> Option<T> {
        debug_assert!(self.thin);
        match self.pass(limit, |b, _| !occupied[b]) {
            Passed::End => None,
            Passed::Met | Passed::Widened(..) => Some(self.t_event),
        }
    }

    /// [`BeamWalk::step`]'s thin steps, repeated while they open cells that
    /// `empty` says hold nothing and the walk stays thin; the walk is left
    /// thin, after the step it stopped at (not yet widened, when that step
    /// turns it wide).
    ///
    /// The axis of each step is dispatched to code of its own
    /// ([`BeamWalk::thin_step_on`]): every index into the walk is then a
    /// constant, so a walk that its caller keeps locally (a copy) lives in
    /// registers, where `step` reloads from memory what its last step stored
    /// (indexed by the axis). The cell's index moves by a stride instead of
    /// being computed from its coordinates.
    #[inline(always)]
    fn pass(&mut self, limit: T, mut empty: impl FnMut(usize, [u32; 3]) -> bool) -> Passed<T> {
        let [nx, ny] = [0, 1].map(|a| self.bounds[a].len() - 1);
        let stride = |a: usize, along: usize| along.wrapping_mul(self.step[a] as isize as usize);
        let moves = [stride(0, 1), stride(1, nx), stride(2, nx * ny)];
        let [x, y, z] = self.lead.map(|c| c as usize);
        let mut index = x + nx * (y + ny * z);
        loop {
            let [t0, t1, t2] = self.t_lead;
            let (a01, t01) = if t1 < t0 { (1, t1) } else { (0, t0) };
            let (a, t) = if t2 < t01 { (2, t2) } else { (a01, t01) };
            // As in `step`: +∞ ends the walk even when `limit` is +∞.
            if !(t <= limit) || t == T::INFINITY {
                return Passed::End;
            }
            self.t_event = t;
            let tau = match a {
                0 => {
                    index = index.wrapping_add(moves[0]);
                    self.thin_step_on::<0>()
                }
                1 => {
                    index = index.wrapping_add(moves[1]);
                    self.thin_step_on::<1>()
                }
                _ => {
                    index = index.wrapping_add(moves[2]);
                    self.thin_step_on::<2>()
                }
            };
            self.t_settled = tau;
            if !(tau <= self.next_lead()) {
                return Passed::Widened(a, tau);
            }
            if !empty(index, self.lead) {
                return Passed::Met;
            }
        }
    }

    /// The lead's move of [`BeamWalk::step`]'s thin step along axis `A`,
    /// whose crossing is the next event; returns `tau`, when the trail left
    /// behind crosses after it.
    #[inline(always)]
    fn thin_step_on<const A: usize>(&mut self) -> T {
        let old_lead = self.lead[A];
        self.lead[A] = old_lead.wrapping_add_signed(self.step[A]);
        self.t_lead[A] = self.lead_time(A);
        self.time(A, self.exit_offset(A, old_lead) - self.lead_off[A])
    }

    /// `next_event` without its NaN handling: crossings are never NaN.
    #[inline(always)]
    fn next_lead(&self) -> T {
        let [t0, t1, t2] = self.t_lead;
        let t01 = if t1 < t0 { t1 } else { t0 };
        if t2 < t01 { t2 } else { t01 }
    }

    /// Turns a thin walk wide after a lead step along `a` whose trail
    /// crosses at `tau`, after the next event: the trail lags a cell behind
    /// on `a`.
    #[inline(never)]
    fn widen(&mut self, a: usize, tau: T) {
        self.trail = self.lead;
        self.trail[a] = self.lead[a].wrapping_add_signed(-self.step[a]);
        self.t_trail = [T::INFINITY; 3];
        self.t_trail[a] = tau;
        self.thin = false;
    }

    /// The parameter of the next lead crossing (`+∞` when the beam's front has
    /// reached the last cell on every axis).
    #[inline]
    #[must_use]
    pub fn next_event(&self) -> T {
        self.t_lead[0].min(self.t_lead[1]).min(self.t_lead[2])
    }

    /// The parameter of the crossing that opened the last cells (the start
    /// parameter before the first step), as computed: within a few roundings
    /// of the exact one, relative to its magnitude.
    #[inline]
    #[must_use]
    pub fn event_time(&self) -> T {
        self.t_event
    }

    /// While the beam lies in one cell (the walk is thin), that cell and a
    /// parameter at which, exactly, the beam lies in it alone: past the
    /// moment it settled there and before its next crossing, each by a margin
    /// of `gamma(SETTLED_MARGIN)` relative to the parameter, which covers the
    /// rounding of both computed crossings. `None` while the beam spans
    /// several cells, or when the window is too narrow for the margins (or
    /// the beam never leaves the cell).
    #[inline]
    #[must_use]
    pub fn settled(&self) -> Option<([u32; 3], T)> {
        if !self.thin {
            return None;
        }
        let t = self.t_settled + T::gamma(SETTLED_MARGIN) * self.t_settled.abs();
        let next = self.next_event();
        // An infinite `next` makes the right side NaN: no window.
        (t < next - T::gamma(SETTLED_MARGIN) * next.abs()).then_some((self.lead, t))
    }

    /// Moves the front to its next crossing if that happens at or before
    /// `limit`, and returns the cells it opens; `None` ends the walk.
    #[inline]
    pub fn advance(&mut self, limit: T) -> Option<CellBox> {
        match self.step(limit) {
            Step::End => None,
            Step::Cell(c) => Some(CellBox::single(c)),
            Step::Cells(b) => Some(b),
        }
    }

    /// As [`BeamWalk::advance`], telling a single cell apart from a box.
    /// Always inlined: a walk's loop is built around it (a call per cell
    /// cost the sphere's camera rays 3% more instructions where the grid's
    /// two walks, with and without occupancy bits, made it too large for
    /// the inliner's taste).
    #[inline(always)]
    pub fn step(&mut self, limit: T) -> Step {
        let [t0, t1, t2] = self.t_lead;
        // The smallest crossing, ties to the lowest axis, without branches.
        let (a01, t01) = if t1 < t0 { (1, t1) } else { (0, t0) };
        let a = if t2 < t01 { 2 } else { a01 };
        let t = self.t_lead[a];
        // +∞ is both the sentinel of an axis whose front is in its last cell
        // and what a crossing beyond T's range rounds to (a tiny direction):
        // no representable hit lies past it, so the walk ends there even when
        // `limit` is +∞ too (else the trails would chase +∞ forever).
        if !(t <= limit) || t == T::INFINITY {
            return Step::End;
        }
        self.t_event = t;
        if !self.thin {
            return self.wide_step(a, t);
        }
        let old_lead = self.lead[a];
        self.lead[a] = old_lead.wrapping_add_signed(self.step[a]);
        self.t_lead[a] = self.lead_time(a);
        // The trail on `a` now lags at `old_lead`; the other trails have no
        // crossing ahead, so the general step would open the one cell `lead`
        // and catch this trail up at the first event at or after its
        // crossing: now if that is the next event, else the walk turns wide.
        let tau = self.time(a, self.exit_offset(a, old_lead) - self.lead_off[a]);
        self.t_settled = tau;
        if !(tau <= self.next_lead()) {
            self.widen(a, tau);
        }
        Step::Cell(self.lead)
    }

    /// The general step (Amanatides & Woo on the lead, lazy trails) along
    /// axis `a`, whose crossing `t` is the next event.
    #[inline(never)]
    fn wide_step(&mut self, a: usize, t: T) -> Step {
        let old_lead = self.lead[a];
        self.lead[a] = old_lead.wrapping_add_signed(self.step[a]);
        self.t_lead[a] = self.lead_time(a);
        if self.trail[a] == old_lead {
            // The trail had caught up with the lead; it now has a crossing ahead.
            self.t_trail[a] = self.trail_time(a);
        }
        let mut cells = CellBox::single(self.lead);
        for b in 0..3 {
            while self.t_trail[b] <= t {
                self.trail[b] = self.trail[b].wrapping_add_signed(self.step[b]);
                self.t_trail[b] = self.trail_time(b);
            }
            if b != a {
                cells.lo[b] = self.trail[b].min(self.lead[b]);
                cells.hi[b] = self.trail[b].max(self.lead[b]);
            }
        }
        // A caught-up trail has no crossing ahead (`trail_time` is +∞), so
        // the walk is thin again exactly when every trail is at its lead.
        self.thin = self.trail == self.lead;
        if cells.lo == cells.hi {
            Step::Cell(cells.lo)
        } else {
            Step::Cells(cells)
        }
    }

    /// `rel / d` along `axis`, by the reciprocal when it is finite (a
    /// component so small that `1/d` overflows takes the division).
    #[inline]
    fn time(&self, axis: usize, rel: T) -> T {
        let inv = self.inv_dir[axis];
        if inv.is_finite() {
            rel * inv
        } else {
            rel / self.dir[axis]
        }
    }

    /// `boundary − origin` for the boundary through which the beam leaves
    /// cell `cell` along `axis` (the caller checks that it is interior).
    #[inline]
    fn exit_offset(&self, axis: usize, cell: u32) -> T {
        self.bounds[axis][(cell + self.up[axis]) as usize] - self.origin[axis]
    }

    /// When the beam's front crosses into the cell after `lead`: `+∞` when
    /// that exit is the grid's outer boundary.
    #[inline]
    fn lead_time(&self, axis: usize) -> T {
        let b = self.bounds[axis];
        let exit = (self.lead[axis] + self.up[axis]) as usize;
        if exit > 0 && exit < b.len() - 1 {
            self.time(axis, (b[exit] - self.origin[axis]) + self.lead_off[axis])
        } else {
            T::INFINITY
        }
    }

    /// When the beam's back leaves the cell `trail` (never past the lead).
    #[inline]
    fn trail_time(&self, axis: usize) -> T {
        debug_assert!(if self.step[axis] > 0 {
            self.trail[axis] <= self.lead[axis]
        } else {
            self.trail[axis] >= self.lead[axis]
        });
        if self.trail[axis] != self.lead[axis] {
            self.time(
                axis,
                self.exit_offset(axis, self.trail[axis]) - self.lead_off[axis],
            )
        } else {
            T::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::{Aabb, Ray};
    use std::collections::BTreeSet;

    fn grid() -> GridGeometry<f64> {
        GridGeometry::new(
            Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(4.0, 4.0, 4.0)),
            [4, 4, 4],
        )
    }

    /// Every cell the walk visits, in order of first visit.
    fn walk(g: &GridGeometry<f64>, o: [f64; 3], d: [f64; 3]) -> Vec<[u32; 3]> {
        let ray = Ray::new(o.into(), d.into()).unwrap();
        let tr = TraversalRay::new(&ray, g.bounds()).expect("ray meets the grid");
        let (mut w, first) = BeamWalk::start(g, &tr, tr.t_start);
        let mut seen = Vec::new();
        let mut push = |cb: CellBox| {
            for c in cb.iter() {
                if !seen.contains(&c) {
                    seen.push(c);
                }
            }
        };
        push(first);
        while let Some(cb) = w.advance(tr.t_end) {
            push(cb);
        }
        seen
    }

    /// The cells whose closed box the exact segment passes through, sampled finely.
    fn sampled(o: [f64; 3], d: [f64; 3], t0: f64, t1: f64) -> BTreeSet<[u32; 3]> {
        let mut s = BTreeSet::new();
        for i in 0..=20_000 {
            let t = t0 + (t1 - t0) * i as f64 / 20_000.0;
            let p: Vec<f64> = (0..3).map(|a| o[a] + t * d[a]).collect();
            if p.iter().all(|&x| (0.0..=4.0).contains(&x)) {
                s.insert([0, 1, 2].map(|a| (p[a].floor() as u32).min(3)));
            }
        }
        s
    }

    #[test]
    fn oblique_ray_visits_its_cells_in_order() {
        let g = grid();
        let (o, d) = ([-1.0, 0.3, 0.7], [1.0, 0.41, 0.23]);
        let cells = walk(&g, o, d);
        let want = sampled(o, d, 0.0, 20.0);
        let got: BTreeSet<_> = cells.iter().copied().collect();
        assert_eq!(got, want);
        // Front to back: the parameter of each cell's entry never decreases.
        let entry = |c: &[u32; 3]| {
            let b = g.cell_bounds(*c);
            b.line_interval(o.into(), d.into()).unwrap().0
        };
        for w in cells.windows(2) {
            assert!(entry(&w[0]) <= entry(&w[1]) + 1e-12, "{w:?}");
        }
    }

    #[test]
    fn axis_parallel_rays_with_signed_zeros() {
        let g = grid();
        for z in [0.0, -0.0] {
            let cells = walk(&g, [-1.0, 1.5, 2.5], [1.0, z, z]);
            assert_eq!(cells, vec![[0, 1, 2], [1, 1, 2], [2, 1, 2], [3, 1, 2]]);
            let back = walk(&g, [9.0, 1.5, 2.5], [-2.0, z, -z]);
            assert_eq!(back, vec![[3, 1, 2], [2, 1, 2], [1, 1, 2], [0, 1, 2]]);
        }
    }

    #[test]
    fn ray_along_a_face_walks_both_rows() {
        let g = grid();
        // On the plane y = 2 between rows 1 and 2, parallel to it.
        let cells: BTreeSet<_> = walk(&g, [-1.0, 2.0, 0.5], [1.0, 0.0, 0.0])
            .into_iter()
            .collect();
        let want: BTreeSet<_> = (0..4).flat_map(|x| [[x, 1, 0], [x, 2, 0]]).collect();
        assert_eq!(cells, want);
    }

    #[test]
    fn ray_along_an_edge_walks_all_four_neighbours() {
        let g = grid();
        let cells: BTreeSet<_> = walk(&g, [1.0, 3.0, -5.0], [0.0, 0.0, -1.0].map(|x: f64| -x))
            .into_iter()
            .collect();
        let want: BTreeSet<_> = (0..4)
            .flat_map(|z| [[0, 2, z], [1, 2, z], [0, 3, z], [1, 3, z]])
            .collect();
        assert_eq!(cells, want);
    }

    #[test]
    fn ray_through_a_corner_visits_the_cells_around_it() {
        let g = grid();
        // Through the grid corner (2,2,2) along the diagonal: the exact ray
        // meets the cells (i,i,i) only at shared corners, and rounding could
        // send a plain DDA through any neighbour, so the beam visits all cells
        // around each crossed corner.
        let cells: BTreeSet<_> = walk(&g, [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0])
            .into_iter()
            .collect();
        for i in 0..4 {
            assert!(cells.contains(&[i, i, i]));
        }
        for c in [
            [1, 1, 2],
            [1, 2, 1],
            [2, 1, 1],
            [1, 2, 2],
            [2, 1, 2],
            [2, 2, 1],
        ] {
            assert!(
                cells.contains(&c),
                "missing neighbour {c:?} of corner (2,2,2)"
            );
        }
        // Nothing far from the diagonal.
        assert!(
            cells
                .iter()
                .all(|c| c.iter().max().unwrap() - c.iter().min().unwrap() <= 1)
        );
    }

    #[test]
    fn rays_starting_inside_outside_and_on_a_face() {
        let g = grid();
        // Inside, in cell (2,1,3).
        let inside = walk(&g, [2.5, 1.5, 3.5], [-1.0, 0.0, 0.0]);
        assert_eq!(inside, vec![[2, 1, 3], [1, 1, 3], [0, 1, 3]]);
        // On the face x = 2, going -x: the walk starts a hair behind the origin
        // (the hit tolerance), so in cell 2, and crosses into cell 1 at once.
        let on_face = walk(&g, [2.0, 1.5, 3.5], [-1.0, 0.0, 0.0]);
        assert_eq!(on_face, vec![[2, 1, 3], [1, 1, 3], [0, 1, 3]]);
        // On the grid's outer face, going in.
        let entering = walk(&g, [0.0, 1.5, 3.5], [1.0, 0.0, 0.0]);
        assert_eq!(entering, vec![[0, 1, 3], [1, 1, 3], [2, 1, 3], [3, 1, 3]]);
        // Outside, going away: nothing.
        let r = Ray::new(Vec3::new(5.0, 1.5, 3.5), Vec3::new(1.0, 0.0, 0.0)).unwrap();
        assert!(TraversalRay::new(&r, g.bounds()).is_none());
    }

    /// Every step of `w` until the end (or 10,000 steps).
    fn steps(mut w: BeamWalk<'_, f64>) -> Vec<Step> {
        let mut out = Vec::new();
        loop {
            let s = w.step(f64::INFINITY);
            out.push(s);
            if s == Step::End || out.len() > 10_000 {
                return out;
            }
        }
    }

    /// An origin from which direction `d` passes through an inner edge of
    /// `g`'s cells: the line where the boundaries `i` and `j` of the two
    /// axes other than `free` meet, at the share `along` of `free`'s extent
    /// (which starts at 0).
    fn aimed_at_edge(
        g: &GridGeometry<f64>,
        (free, i, j, along): (usize, usize, usize, f64),
        d: [f64; 3],
    ) -> [f64; 3] {
        let [u, v] = [(free + 1) % 3, (free + 2) % 3];
        let mut p = [0.0; 3];
        p[u] = g.boundaries(u)[i];
        p[v] = g.boundaries(v)[j];
        p[free] = along * g.bounds().max[free];
        [0, 1, 2].map(|a| p[a] - 3.0 * d[a])
    }

    /// Whether [`BeamWalk::restart`] and [`BeamWalk::restart_each_axis`],
    /// at the share `at` of the ray's interval in `g`, return the same cells
    /// and leave the same walk (every field, bit for bit: `Debug` prints
    /// each float's shortest exact form, `-0` included); true when the ray
    /// misses `g`.
    ///
    /// `at` of `None` restarts at parameter 3, where a ray from
    /// [`aimed_at_edge`] meets the edge (the beam spans the cells around
    /// it), or at the start when 3 lies outside the interval.
    fn restarts_agree<T: Real>(g: &GridGeometry<T>, o: [T; 3], d: [T; 3], at: Option<T>) -> bool {
        let Ok(ray) = Ray::new(o.into(), d.into()) else {
            return true;
        };
        let Some(tr) = TraversalRay::new(&ray, g.bounds()) else {
            return true;
        };
        let edge = T::from_f64(3.0);
        let t = match at {
            Some(at) => tr.t_start + at * (tr.t_end - tr.t_start),
            None if tr.t_start <= edge && edge <= tr.t_end => edge,
            None => tr.t_start,
        };
        let (mut guessed, mut each) = (BeamWalk::unplaced(g, &tr), BeamWalk::unplaced(g, &tr));
        let cells = (guessed.restart(g, t), each.restart_each_axis(g, t));
        each.t_event = t;
        each.t_settled = t;
        cells.0 == cells.1 && format!("{guessed:?}") == format!("{each:?}")
    }

    proptest::proptest! {
        /// A walk started again in place at `t` is the walk started at `t`:
        /// the same first cells and the same steps after; a walk not yet
        /// placed opens no cell.
        #[test]
        fn restarting_in_place_is_starting_afresh(
            o in proptest::array::uniform3(-1.0..5.0f64),
            d in proptest::array::uniform3(-1.0..1.0f64),
            first in 0.0..1.0f64,
            then in 0.0..1.0f64,
        ) {
            let g = GridGeometry::new(
                Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(4.0, 3.0, 5.0)),
                [7, 5, 9],
            );
            let Ok(ray) = Ray::new(o.into(), d.into()) else { return Ok(()) };
            let Some(tr) = TraversalRay::new(&ray, g.bounds()) else { return Ok(()) };
            let at = |u: f64| tr.t_start + u * (tr.t_end - tr.t_start);
            let (mut moved, _) = BeamWalk::start(&g, &tr, at(first));
            let _ = moved.step(f64::INFINITY);
            let again = moved.restart(&g, at(then));
            let (fresh, cells) = BeamWalk::start(&g, &tr, at(then));
            proptest::prop_assert_eq!(again, cells);
            proptest::prop_assert_eq!(steps(moved), steps(fresh));
            // Not yet placed, a walk opens nothing.
            let mut idle = BeamWalk::unplaced(&g, &tr);
            proptest::prop_assert_eq!(idle.step(f64::INFINITY), Step::End);
        }

        /// A restart from the first guesses is the restart axis by axis:
        /// the same cells and the same walk, bit for bit, in both
        /// precisions, for rays through cells' edges too, restarted where
        /// they meet the edge: the beam spans the cells around it there,
        /// and the guesses give way.
        #[test]
        fn restarting_from_guesses_is_restarting_each_axis(
            o in proptest::array::uniform3(-1.0..9.0f64),
            d in proptest::array::uniform3(-1.0..1.0f64),
            zero in proptest::option::of(0usize..3),
            at in proptest::option::of(0.0..1.0f64),
            edge in proptest::option::of((0usize..3, 1usize..13, 1usize..13, 0.0..1.0f64)),
        ) {
            let g = GridGeometry::new(
                Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(8.0, 7.0, 9.0)),
                [16, 13, 18],
            );
            let mut d = d;
            if let Some(a) = zero {
                d[a] = 0.0;
            }
            let o = edge.map_or(o, |e| aimed_at_edge(&g, e, d));
            let f32_grid = GridGeometry::new(g.bounds().cast::<f32>(), [16, 13, 18]);
            proptest::prop_assert!(restarts_agree(&g, o, d, at));
            proptest::prop_assert!(restarts_agree(
                &f32_grid,
                o.map(|x| x as f32),
                d.map(|x| x as f32),
                at.map(|x| x as f32)
            ));
        }

        /// The block walk made from a settled cell walk is the walk over the
        /// blocks started at that parameter, and lies where the cell is.
        #[test]
        fn a_settled_walk_hands_over_to_its_block(
            o in proptest::array::uniform3(-1.0..9.0f64),
            d in proptest::array::uniform3(-1.0..1.0f64),
            skip in 0usize..40,
        ) {
            let g = GridGeometry::new(
                Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(8.0, 7.0, 9.0)),
                [16, 13, 18],
            );
            let blocks = g.coarsened(2);
            let Ok(ray) = Ray::new(o.into(), d.into()) else { return Ok(()) };
            let Some(tr) = TraversalRay::new(&ray, g.bounds()) else { return Ok(()) };
            let (mut w, _) = BeamWalk::start(&g, &tr, tr.t_start);
            for _ in 0..skip {
                if w.step(f64::INFINITY) == Step::End {
                    return Ok(());
                }
            }
            let Some((cell, t)) = w.settled() else { return Ok(()) };
            proptest::prop_assert_eq!(cell, w.lead);
            // Exactly in the cell alone: a fresh start there opens it only.
            let (_, here) = BeamWalk::start(&g, &tr, t);
            proptest::prop_assert_eq!(here, CellBox::single(cell));
            let handed = w.settled_block(&blocks, 2, t);
            let (fresh, first) = BeamWalk::start(&blocks, &tr, t);
            proptest::prop_assert_eq!(first, CellBox::single(cell.map(|c| c >> 2)));
            proptest::prop_assert_eq!(steps(handed), steps(fresh));
        }

        /// The thin pass over empty blocks stops where the general walk,
        /// stepped over the same blocks, first opens an occupied one or
        /// turns wide, at the same crossing bit for bit, and ends where it
        /// ends.
        #[test]
        fn the_thin_pass_stops_where_the_walk_meets_a_block_or_turns_wide(
            o in proptest::array::uniform3(-1.0..9.0f64),
            d in proptest::array::uniform3(-1.0..1.0f64),
            full in proptest::collection::vec(proptest::bool::weighted(0.08), 4 * 4 * 5),
            limit_share in 0.0..1.5f64,
            edge in proptest::option::of((0usize..3, 1usize..4, 1usize..4, 0.0..1.0f64)),
        ) {
            let g = GridGeometry::new(
                Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(8.0, 7.0, 9.0)),
                [16, 13, 18],
            );
            let blocks = g.coarsened(2);
            proptest::prop_assert_eq!(blocks.cell_count(), full.len());
            // Often through an inner edge of the blocks, where the beam
            // comes to span two blocks and the pass stops.
            let o = edge.map_or(o, |e| aimed_at_edge(&blocks, e, d));
            let Ok(ray) = Ray::new(o.into(), d.into()) else { return Ok(()) };
            let Some(tr) = TraversalRay::new(&ray, g.bounds()) else { return Ok(()) };
            let (w, _) = BeamWalk::start(&g, &tr, tr.t_start);
            let Some((_, t)) = w.settled() else { return Ok(()) };
            let limit = if limit_share > 1.0 {
                f64::INFINITY
            } else {
                t + limit_share * (tr.t_end - t)
            };
            let mut general = w.settled_block(&blocks, 2, t);
            let want = loop {
                match general.step(limit) {
                    Step::End => break None,
                    Step::Cell(b) if general.thin && !full[blocks.linear_index(b)] => {}
                    Step::Cell(_) => break Some(general.event_time()),
                    Step::Cells(b) => panic!("a thin walk opened {b:?}"),
                }
            };
            let got = w.settled_block(&blocks, 2, t).pass_thin(limit, &full);
            proptest::prop_assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits));
        }

        /// Stepping past empty cells is stepping until a cell that holds
        /// something, or a wide walk: the same steps, at the same crossings
        /// bit for bit, to the end; with rays through the cells' edges,
        /// where the walk turns wide.
        #[test]
        fn stepping_past_empty_cells_is_stepping_until_one_is_not(
            o in proptest::array::uniform3(-1.0..9.0f64),
            d in proptest::array::uniform3(-1.0..1.0f64),
            full in proptest::collection::vec(proptest::bool::weighted(0.1), 8 * 7 * 9),
            limit_share in 0.0..1.5f64,
            edge in proptest::option::of((0usize..3, 1usize..7, 1usize..7, 0.0..1.0f64)),
        ) {
            let g = GridGeometry::new(
                Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(8.0, 7.0, 9.0)),
                [8, 7, 9],
            );
            let o = edge.map_or(o, |e| aimed_at_edge(&g, e, d));
            let Ok(ray) = Ray::new(o.into(), d.into()) else { return Ok(()) };
            let Some(tr) = TraversalRay::new(&ray, g.bounds()) else { return Ok(()) };
            let limit = if limit_share > 1.0 {
                f64::INFINITY
            } else {
                tr.t_start + limit_share * (tr.t_end - tr.t_start)
            };
            let (mut general, _) = BeamWalk::start(&g, &tr, tr.t_start);
            let mut passing = general.clone();
            let empty = |c: [u32; 3]| !full[g.linear_index(c)];
            for _ in 0..1000 {
                let want = if general.thin {
                    loop {
                        match general.step(limit) {
                            Step::Cell(c) if general.thin && empty(c) => {}
                            other => break other,
                        }
                    }
                } else {
                    general.step(limit)
                };
                let got = passing.step_past_empty(limit, |c, at| {
                    assert_eq!(c, g.linear_index(at));
                    !full[c]
                });
                proptest::prop_assert_eq!(got, want);
                if want == Step::End {
                    return Ok(());
                }
                proptest::prop_assert_eq!(
                    passing.event_time().to_bits(),
                    general.event_time().to_bits()
                );
                proptest::prop_assert_eq!(passing.thin, general.thin);
                let settled = |w: &BeamWalk<'_, f64>| w.settled().map(|(c, t)| (c, t.to_bits()));
                proptest::prop_assert_eq!(settled(&passing), settled(&general));
            }
            proptest::prop_assert!(false, "the walk did not end");
        }

        /// The beam's cells located once ([`BeamWalk::beam_cells`]) are
        /// those of locating both of its edges, at boundaries, beyond the
        /// grid, and for beams as wide as cells.
        #[test]
        fn beam_cells_are_those_of_both_edges(
            o in -3.0..7.0f64,
            rel in -6.0..6.0f64,
            on_boundary in proptest::bool::ANY,
            delta_exp in -60i32..1,
            boundary in 0usize..9,
        ) {
            let g = GridGeometry::new(
                Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(4.0, 1.0, 1.0)),
                [8, 1, 1],
            );
            let ray = Ray::new(Vec3::new(o, 0.5, 0.5), Vec3::new(1.0, 0.0, 0.0)).unwrap();
            let Some(tr) = TraversalRay::new(&ray, g.bounds()) else { return Ok(()) };
            let (mut w, _) = BeamWalk::start(&g, &tr, tr.t_start);
            w.delta = 2f64.powi(delta_exp);
            // Either anywhere, or exactly a beam's half-width off a boundary.
            let rel = if on_boundary {
                g.boundaries(0)[boundary] - o + rel.signum() * w.delta
            } else {
                rel
            };
            let want = (
                g.axis_cell_relative(0, o, rel - w.delta),
                g.axis_cell_relative(0, o, rel + w.delta),
            );
            proptest::prop_assert_eq!(w.beam_cells(&g, 0, rel), want);
        }
    }
}
