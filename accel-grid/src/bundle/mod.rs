//! Bundles: rays walked together, slice by slice of cells (the coherent grid
//! traversal of Wald, Ize, Kensler, Knoll & Parker 2006, "Ray tracing
//! animated scenes using coherent grid traversal"), on a uniform grid or on
//! a grid whose cells are refined by nested grids (the octree).
//!
//! A [`Packet`] of up to [`PACKET`] rays whose directions share the sign of
//! one main axis `k`, and whose `k` components are the larger part of them,
//! walks a grid's slices of cells across `k` in the rays' order. In each
//! slice every ray's beam ([`TraversalRay`]) covers a rectangle of the two
//! other coordinates; their union says which cells of the slice to open,
//! and a cell is handed to its grid ([`SliceCells::visit`]) with the rays
//! whose rectangles meet it. The grid tests its primitives against each of
//! them ([`Packet::test`], with the ray's own mailbox and best hit) and, if
//! a nested grid refines the cell, walks that grid with those rays alone:
//! slice by slice ([`Packet::walk`]) or one ray at a time with each ray's
//! state ([`Packet::each_alone`]). Where a grid keeps empty-space
//! blocks ([`crate::blocks`]), a slab of slices whose blocks under the union
//! are all empty is passed over at once.
//!
//! Why each ray's answer is its single-ray answer, bit for bit: a ray is
//! followed, slice by slice, until the parameter at which its beam enters
//! the next slice passes its best hit by the hit tolerance `t_tol` (its
//! single walk's limit), and within a slice its rectangle holds its beam
//! over that stretch, widened by a pad for the rounding of
//! the parameters and coordinates computed here. So every cell, at every
//! level, that the single walk opens before it stops is opened for the ray
//! here (the single walk of a nested grid narrows the beam and the
//! tolerance; the packet keeps the wider ones, which open more), and the
//! ray is tested against every primitive the single walk tests (and
//! perhaps a few more). Each test is exact, and the nearest of them is the
//! smallest `t`, ties to the lowest index, in whatever order they come: the
//! single walk's answer. Rays that do not suit the packet (another main
//! axis or sign, a tiny main component) take the single walk.

mod beams;
mod member;
mod part;
#[cfg(test)]
mod tests;

use crate::blocks::Blocks;
use crate::cells::GridGeometry;
use accel_core::packed::{PackedTriangles, RayQuad, SimdLevel, for_each_candidate, simd_level};
use accel_core::{Hit, Mailbox, PreparedRay, PrimitiveSet, QueryError, Ray, Real, TraversalRay};
use beams::Beams;
use member::{Lines, Member, bits, candidate, coherent};

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

/// Slices where full cells under the hull times members exceed this mark
/// each member's cells from its rectangle's cell range
/// ([`Packet::spread`]); the others compare each member with each full
/// cell ([`Packet::cull`]).
const SPREAD_PAIRS: usize = 1024;

/// How far apart (in cells of the first grid walked) a packet's beams may
/// spread and still be walked together.
pub const COHERENT_CELLS: f64 = 8.0;

/// The rays of a packet too spread to walk together are tried in runs of
/// this many slots (a 4 × 4 block of a tile in Z order), each walked
/// together where it is coherent.
pub const SUB_PACKET: usize = 16;

/// The fewest rays of a run of [`SUB_PACKET`] slots walked together.
pub const MIN_SUB_PACKET: usize = 8;

/// A bundle cut into runs of up to [`PACKET`] rays: each run's first index
/// in the bundle, its rays, and whether enough of them ([`MIN_PACKET`])
/// head within the angle of [`HEADING_COS`] of its first ray to try a
/// packet (rays heading every way, diffuse bounces, cannot make one and
/// should go one at a time without a packet's set-up).
pub fn runs<T: Real>(rays: &[Ray<T>]) -> impl Iterator<Item = (usize, &[Ray<T>], bool)> {
    rays.chunks(PACKET).enumerate().map(|(c, run)| {
        let together = run[0].count_heading_with(run, HEADING_COS) >= MIN_PACKET;
        (c * PACKET, run, together)
    })
}

/// Where the answers of a run of a bundle go: `answer` with the run's
/// indices moved by `base` ([`answer_bundle`]).
pub struct Reply<'a, F> {
    base: usize,
    answer: &'a mut F,
}

impl<F> Reply<'_, F> {
    /// Answers ray `i` of the run.
    #[inline]
    pub fn send<T>(&mut self, i: usize, a: Result<Answer<T>, QueryError>)
    where
        F: FnMut(usize, Result<Answer<T>, QueryError>),
    {
        (self.answer)(self.base + i, a);
    }
}

/// Answers a bundle, `answer(i, …)` for each ray `rays[i]`: with
/// `by_packets`, each run of rays that head together ([`runs`]) through
/// `packet` (the run, and where its answers go), every other ray through
/// `single`, one at a time; the driver of the grid's and the octree's
/// bundle queries.
pub fn answer_bundle<T: Real, F: FnMut(usize, Result<Answer<T>, QueryError>)>(
    rays: &[Ray<T>],
    by_packets: bool,
    single: impl Fn(&Ray<T>) -> Result<Answer<T>, QueryError>,
    mut packet: impl FnMut(&[Ray<T>], Reply<'_, F>),
    mut answer: F,
) {
    if !by_packets {
        for (i, ray) in rays.iter().enumerate() {
            answer(i, single(ray));
        }
        return;
    }
    for (base, run, together) in runs(rays) {
        if together {
            let answer = &mut answer;
            packet(run, Reply { base, answer });
        } else {
            for (i, ray) in run.iter().enumerate() {
                answer(base + i, single(ray));
            }
        }
    }
}

/// The two bundle queries of an `Accelerator` impl (`intersect_bundle`,
/// `occluded_bundle`), for a structure whose inherent method
/// `by_packets::<ANY>(&self, rays, answer)` answers each ray of a bundle
/// with an [`Answer`]: the grid's and the octree's, written once. Use it
/// inside `impl<T: Real, ...> Accelerator<T> for ...` (the impl's float
/// type must be named `T`).
#[macro_export]
macro_rules! bundle_queries_by_packets {
    () => {
        /// Packets of up to `accel_grid::bundle::PACKET` rays walked
        /// together slice by slice where that pays (`bundles_by_packets`),
        /// elsewhere one ray at a time; every ray answered as alone.
        fn intersect_bundle(
            &self,
            rays: &[$crate::__core::Ray<T>],
            out: &mut [::core::result::Result<
                ::core::option::Option<$crate::__core::Hit<T>>,
                $crate::__core::QueryError,
            >],
        ) {
            assert_eq!(rays.len(), out.len(), "one answer per ray of the bundle");
            self.by_packets::<false>(rays, |i, a| {
                out[i] = a.map($crate::bundle::Answer::into_hit);
            });
        }

        /// As `intersect_bundle`, stopping each ray at its first hit.
        fn occluded_bundle(
            &self,
            rays: &[$crate::__core::Ray<T>],
            out: &mut [::core::result::Result<bool, $crate::__core::QueryError>],
        ) {
            assert_eq!(rays.len(), out.len(), "one answer per ray of the bundle");
            self.by_packets::<true>(rays, |i, a| out[i] = a.map($crate::bundle::Answer::hits));
        }
    };
}

/// One ray's answer: its nearest hit, or whether it hits anything.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Answer<T> {
    /// A nearest-hit query's answer.
    Nearest(Option<Hit<T>>),
    /// An any-hit query's answer.
    Any(bool),
}

impl<T> Answer<T> {
    /// The answer to a query for the nearest hit (`ANY` false) or for any
    /// hit of a ray that hits nothing.
    #[must_use]
    pub fn nothing<const ANY: bool>() -> Self {
        if ANY {
            Self::Any(false)
        } else {
            Self::Nearest(None)
        }
    }

    /// The nearest hit of a nearest-hit query's answer.
    ///
    /// # Panics
    /// For an any-hit query's answer (a bug of the caller).
    #[must_use]
    pub fn into_hit(self) -> Option<Hit<T>> {
        match self {
            Self::Nearest(h) => h,
            Self::Any(_) => unreachable!("a nearest-hit query answers with its hit"),
        }
    }

    /// Whether the ray hits anything.
    #[must_use]
    pub fn hits(self) -> bool {
        match self {
            Self::Nearest(h) => h.is_some(),
            Self::Any(b) => b,
        }
    }
}

/// A grid as a packet's slice walk sees it: its geometry, its empty-space
/// blocks, which cells hold something, and what opening a cell does.
pub trait SliceCells<T: Real> {
    /// The grid's box, resolution and boundaries.
    fn geometry(&self) -> &GridGeometry<T>;

    /// Its empty-space blocks, if it keeps them.
    fn blocks(&self) -> Option<&Blocks<T>>;

    /// Whether the cell of linear index `cell` holds anything (primitives or
    /// a nested grid).
    fn holds(&self, cell: usize) -> bool;

    /// Opens the cell of linear index `cell` for the members of `meeting`
    /// (a bit per member of `packet`): tests what it holds against them
    /// ([`Packet::test`]) and walks the grid that refines it, if any
    /// ([`Packet::walk`]).
    fn visit(&self, packet: &mut Packet<T>, cell: usize, meeting: u64);
}

/// The scratch space of one grid's slice walk: the cells of a slice under
/// the packet's hull that hold something, and per cell of that window the
/// members whose rectangles meet it.
#[derive(Default)]
struct Scratch {
    /// Each full cell's linear index, place in the window, and cross-axis
    /// coordinates.
    cells: Vec<(usize, usize, [u32; 2])>,
    /// A bit per member, per cell of the window (row by row).
    meeting: Vec<u64>,
}

/// The cells of a slice under a hull: lowest and highest cell on each cross
/// axis.
#[derive(Clone, Copy)]
struct Window {
    u: [u32; 2],
    v: [u32; 2],
}

impl Window {
    /// The window of cells of `geom` under `hull` on the cross axes `u`, `v`.
    fn under<T: Real>(geom: &GridGeometry<T>, [_, u, v]: [usize; 3], hull: &[T; 4]) -> Self {
        Self {
            u: [geom.axis_cell(u, hull[0]), geom.axis_cell(u, hull[1])],
            v: [geom.axis_cell(v, hull[2]), geom.axis_cell(v, hull[3])],
        }
    }

    /// Cells per row.
    fn width(&self) -> usize {
        (self.u[1] - self.u[0]) as usize + 1
    }

    /// How many cells it holds.
    fn len(&self) -> usize {
        self.width() * ((self.v[1] - self.v[0]) as usize + 1)
    }
}

/// Rays walked together (see the module docs), each with its own interval,
/// mailbox and best hit.
pub struct Packet<T: Real> {
    members: Vec<Member<T>>,
    /// The members four by four, for the SIMD first stage of the triangle
    /// test ([`Packet::test`]): quad `q` holds members `4q..4q + 4`, `None`
    /// where they do not share their axes. Empty where the CPU lacks AVX2
    /// or the packet is too small to walk.
    quads: Vec<Option<RayQuad>>,
    /// The main axis, then the two cross axes.
    axes: [usize; 3],
    /// Whether the rays go up the main axis.
    up: bool,
    /// Where on the main axis the members' lines are taken from (the
    /// first member's origin; [`Lines`]).
    pivot: T,
    /// A bit per member that needs nothing more (an any-hit query's hit).
    finished: u64,
    /// Scratch space, one per grid being walked (nested walks stack up).
    scratch: Vec<Scratch>,
    /// The members' beams side by side, with their limits.
    beams: Beams<T>,
}

/// What becomes of a ray a packet does not take.
pub enum Alone<T: Real> {
    /// The ray is invalid.
    Refused(QueryError),
    /// Its beam misses the grid: nothing is hit.
    Misses,
    /// It goes another way than the packet: it takes the single walk on
    /// this beam.
    Single(TraversalRay<T>),
}

impl<T: Real> Packet<T> {
    /// A packet of the rays (at most [`PACKET`]) whose beams meet `bounds`
    /// and go the way most of them go; every other ray is handed to `alone`
    /// with its index. `None` when no ray is left.
    pub fn form(
        rays: &[Ray<T>],
        bounds: &accel_core::Aabb<T>,
        mut alone: impl FnMut(usize, Alone<T>),
    ) -> Option<Self> {
        debug_assert!(rays.len() <= PACKET);
        let mut members: Vec<Member<T>> = Vec::with_capacity(rays.len());
        let mut weight = [T::ZERO; 3];
        for (slot, ray) in rays.iter().enumerate() {
            if let Err(e) = ray.validate() {
                alone(slot, Alone::Refused(e));
                continue;
            }
            match TraversalRay::new(ray, bounds) {
                Some(tr) => {
                    for (a, w) in weight.iter_mut().enumerate() {
                        *w += ray.direction[a];
                    }
                    members.push(Member::new(slot, tr));
                }
                None => alone(slot, Alone::Misses),
            }
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
        members.retain(|m| {
            let d = m.tr.ray().direction;
            let along = if up { d[k] } else { -d[k] };
            let suits = along > T::ZERO
                && m.tr.prepared.inv_dir[k].is_finite()
                && along + along >= d.abs().max_component();
            if !suits {
                alone(m.slot, Alone::Single(m.tr));
            }
            suits
        });
        let axes = [k, (k + 1) % 3, (k + 2) % 3];
        let pivot = members.first().map_or(T::ZERO, |m| m.tr.ray().origin[k]);
        for m in &mut members {
            m.set_axes(axes, pivot);
        }
        let quads = if members.len() >= MIN_PACKET && simd_level() >= SimdLevel::Avx2 {
            members
                .chunks(RayQuad::LANES)
                .map(|quad| {
                    let rays: [&PreparedRay<T>; RayQuad::LANES] =
                        core::array::from_fn(|l| &quad[l.min(quad.len() - 1)].tr.prepared);
                    RayQuad::new(&rays)
                })
                .collect()
        } else {
            Vec::new()
        };
        (!members.is_empty()).then(|| Self {
            beams: Beams::new(&members, axes),
            quads,
            members,
            axes,
            pivot,
            up,
            finished: 0,
            scratch: Vec::new(),
        })
    }

    /// Answers a packet of `rays` (at most [`PACKET`]) on the grid `root`,
    /// as the single walk (`single`, on a ray's beam through `root`'s box)
    /// answers each: `answer(i, …)` is called once for each ray `rays[i]`,
    /// with its nearest hit, or (if `ANY`) whether it hits anything, or the
    /// error that refuses it. Packets of fewer than [`MIN_PACKET`] rays go
    /// one ray at a time; those whose rays spread over more than
    /// [`COHERENT_CELLS`] cells of `root` are walked by the runs of
    /// [`SUB_PACKET`] rays that do not (`walk_coherent`), their
    /// other rays one at a time.
    pub fn answer<const ANY: bool, G: SliceCells<T> + ?Sized>(
        root: &G,
        rays: &[Ray<T>],
        single: impl Fn(&TraversalRay<T>) -> Answer<T>,
        mut answer: impl FnMut(usize, Result<Answer<T>, QueryError>),
    ) {
        let formed = Self::form(rays, root.geometry().bounds(), |slot, alone| {
            answer(
                slot,
                match alone {
                    Alone::Refused(e) => Err(e),
                    Alone::Misses => Ok(Answer::nothing::<ANY>()),
                    Alone::Single(tr) => Ok(single(&tr)),
                },
            );
        });
        let Some(mut packet) = formed else {
            return;
        };
        let walked = packet.walk_coherent(root);
        for (i, m) in packet.members.iter().enumerate() {
            answer(
                m.slot,
                Ok(if walked & (1 << i) == 0 {
                    single(&m.tr)
                } else if ANY {
                    Answer::Any(packet.finished & (1 << i) != 0)
                } else {
                    Answer::Nearest(m.best)
                }),
            );
        }
    }

    /// Walks `root` with the members whose rays stay close enough together
    /// ([`coherent`]): all of them if they do, else each run of
    /// [`SUB_PACKET`] consecutive slots (in a tile in Z order, a 4 × 4
    /// block of pixels) whose members do and number [`MIN_SUB_PACKET`] or
    /// more; nothing if the packet has fewer than [`MIN_PACKET`] members.
    /// Returns the members walked, a bit each.
    fn walk_coherent<G: SliceCells<T> + ?Sized>(&mut self, root: &G) -> u64 {
        let n = self.members.len();
        if n < MIN_PACKET {
            return 0;
        }
        let (geom, axes) = (root.geometry(), self.axes);
        let runs = |lo: usize, hi: usize| (u64::MAX >> (64 - (hi - lo))) << lo;
        if coherent(&self.members, geom, axes) {
            self.walk(root, runs(0, n));
            return runs(0, n);
        }
        let mut walked = 0;
        let mut lo = 0;
        while lo < n {
            let run = self.members[lo].slot / SUB_PACKET;
            let hi = lo
                + self.members[lo..]
                    .iter()
                    .take_while(|m| m.slot / SUB_PACKET == run)
                    .count();
            if hi - lo >= MIN_SUB_PACKET && coherent(&self.members[lo..hi], geom, axes) {
                self.walk(root, runs(lo, hi));
                walked |= runs(lo, hi);
            }
            lo = hi;
        }
        walked
    }

    /// Walks the slices of `grid` with the members of `mask` (a bit per
    /// member), in the rays' order, opening each cell that holds something
    /// under their beams ([`SliceCells::visit`]) until every one of them
    /// has passed its limit or finished.
    pub fn walk<G: SliceCells<T> + ?Sized>(&mut self, grid: &G, mask: u64) {
        let axes = self.axes;
        let k = axes[0];
        let mut live = mask & !self.finished;
        let Some(mut lines) = Lines::of(&self.members, live, self.pivot) else {
            return;
        };
        let mut lines_of = live;
        let geom = grid.geometry();
        let n = geom.resolution()[k];
        let xs = geom.boundaries(k);
        // The slices the members' beams reach, in the order they go.
        let (mut x_min, mut x_max) = (T::INFINITY, T::NEG_INFINITY);
        for i in bits(live) {
            let m = &self.members[i];
            let r = m.tr.ray();
            for t in [m.tr.t_start, self.beams.limit[i]] {
                let x = r.origin[k] + r.direction[k] * t;
                x_min = x_min.min(x - m.pad);
                x_max = x_max.max(x + m.pad);
            }
        }
        let (first, last) = (geom.axis_cell(k, x_min), geom.axis_cell(k, x_max));
        let (shift, blocks) = match grid.blocks() {
            Some(b) => (b.shift(), Some(b)),
            None => (0, None),
        };
        let mut scratch = self.scratch.pop().unwrap_or_default();
        let (slab_first, slab_last) = (first >> shift, last >> shift);
        'slabs: for step in 0..=(slab_last - slab_first) {
            let slab = if self.up {
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
                let i = if self.up { lo + step } else { hi - step };
                let (x_lo, x_hi) = (xs[i as usize], xs[i as usize + 1]);
                let window = Window::under(geom, axes, &lines.hull(x_lo, x_hi));
                full_cells(grid, axes, i, window, &mut scratch.cells);
                if scratch.cells.is_empty() {
                    continue;
                }
                let pairs = scratch.cells.len() * live.count_ones() as usize;
                live = if pairs > SPREAD_PAIRS {
                    self.spread(live, geom, x_lo, x_hi, window, &mut scratch.meeting)
                } else {
                    self.cull(live, geom, x_lo, x_hi, window, &mut scratch)
                };
                for &(cell, place, _) in &scratch.cells {
                    let meeting = scratch.meeting[place] & !self.finished;
                    if meeting != 0 {
                        grid.visit(self, cell, meeting);
                    }
                }
                live &= !self.finished;
                if live != lines_of {
                    lines_of = live;
                    match Lines::of(&self.members, live, self.pivot) {
                        Some(l) => lines = l,
                        None => break 'slabs,
                    }
                }
            }
        }
        self.scratch.push(scratch);
    }

    /// [`Packet::spread`] for a slice with few full cells (`scratch.cells`):
    /// each member's rectangle is compared with each full cell's, and only
    /// the full cells' places in `scratch.meeting` are set.
    fn cull(
        &self,
        live: u64,
        geom: &GridGeometry<T>,
        x_lo: T,
        x_hi: T,
        window: Window,
        scratch: &mut Scratch,
    ) -> u64 {
        let [_, u, v] = self.axes;
        let (bu, bv) = (geom.boundaries(u), geom.boundaries(v));
        scratch.meeting.resize(window.len(), 0);
        for &(_, place, _) in &scratch.cells {
            scratch.meeting[place] = 0;
        }
        let open = live & !self.finished;
        let r = self.beams.rectangles(open, x_lo, x_hi);
        let within = open & r.within;
        if within != 0 {
            for &(_, place, [cu, cv]) in &scratch.cells {
                let (cu, cv) = (cu as usize, cv as usize);
                let cell = [bu[cu], bu[cu + 1], bv[cv], bv[cv + 1]];
                scratch.meeting[place] = r.meeting(cell) & within;
            }
        }
        live & !(open & r.past)
    }

    /// Marks, per cell of `window` (in `meeting`), the members of `live`
    /// whose rectangles in the slab `[x_lo, x_hi]` meet it: every cell
    /// whose closed box meets the closed rectangle (a rectangle's edge on a
    /// boundary meets the cells on both sides). Returns `live` without the
    /// members past the slab.
    fn spread(
        &self,
        live: u64,
        geom: &GridGeometry<T>,
        x_lo: T,
        x_hi: T,
        window: Window,
        meeting: &mut Vec<u64>,
    ) -> u64 {
        let [_, u, v] = self.axes;
        meeting.clear();
        meeting.resize(window.len(), 0);
        let width = window.width();
        // The cells on `axis` the closed interval `[lo, hi]` meets, within
        // `[first, last]`.
        let span = |axis: usize, lo: T, hi: T, [first, last]: [u32; 2]| {
            let mut a = geom.axis_cell(axis, lo);
            if a > 0 && geom.boundaries(axis)[a as usize] == lo {
                a -= 1;
            }
            (a.max(first), geom.axis_cell(axis, hi).min(last))
        };
        self.footprints(live, x_lo, x_hi, |i, f| {
            let (u0, u1) = span(u, f[0], f[1], window.u);
            let (v0, v1) = span(v, f[2], f[3], window.v);
            for cv in v0..=v1 {
                let row = (cv - window.v[0]) as usize * width;
                for cu in u0..=u1 {
                    meeting[row + (cu - window.u[0]) as usize] |= 1 << i;
                }
            }
        })
    }

    /// Hands `within` each unfinished member of `live` whose beam is in the
    /// slab `[x_lo, x_hi]`, with its rectangle there ([`Beams::rectangles`]);
    /// returns `live` without the unfinished members past the slab.
    #[inline]
    fn footprints(
        &self,
        live: u64,
        x_lo: T,
        x_hi: T,
        mut within: impl FnMut(usize, [T; 4]),
    ) -> u64 {
        let open = live & !self.finished;
        let r = self.beams.rectangles(open, x_lo, x_hi);
        for i in bits(open & r.within) {
            within(i, [r.f[0][i], r.f[1][i], r.f[2][i], r.f[3][i]]);
        }
        live & !(open & r.past)
    }

    /// Hands each unfinished member of `meeting` alone to `walk`, with its
    /// beam, its best hit and its mailbox, for a walk of its own below a
    /// cell (a nested grid walked one ray at a time); `walk` returns
    /// whether an any-hit query (`ANY`) is answered.
    #[inline]
    pub fn each_alone<const ANY: bool>(
        &mut self,
        meeting: u64,
        mut walk: impl FnMut(&TraversalRay<T>, &mut Option<Hit<T>>, &mut Mailbox) -> bool,
    ) {
        for i in bits(meeting & !self.finished) {
            let m = &mut self.members[i];
            let found = walk(&m.tr, &mut m.best, &mut m.mailbox);
            self.settle::<ANY>(i, found);
        }
    }

    /// After member `i` was tested: finished if an any-hit query found a
    /// hit, else its limit drawn in to its best hit plus the tolerance.
    #[inline]
    fn settle<const ANY: bool>(&mut self, i: usize, found: bool) {
        let m = &mut self.members[i];
        if ANY && found {
            self.finished |= 1 << i;
        } else if let Some(b) = m.best {
            let reach = b.t + m.tr.t_tol;
            let limit = &mut self.beams.limit[i];
            if reach < *limit {
                *limit = reach;
            }
        }
    }

    /// Tests the primitives `refs` of a cell (whose references start at
    /// `start` in the cell lists that `packed` was built from) against each
    /// unfinished member of `meeting`, as the single walk tests them: where
    /// the packet has quads (AVX2), triangle by triangle with the first
    /// stage four members at a time (`test_by_triangles`, which leaves
    /// `packed` aside), else member by member.
    #[inline]
    pub fn test<const ANY: bool, P: PrimitiveSet<T> + ?Sized>(
        &mut self,
        meeting: u64,
        prims: &P,
        packed: Option<&PackedTriangles<T>>,
        start: usize,
        refs: &[u32],
    ) {
        if refs.is_empty() {
            return;
        }
        let open = meeting & !self.finished;
        #[cfg(target_arch = "x86_64")]
        if !self.quads.is_empty() {
            // SAFETY: quads are made only where the CPU has AVX2 (`form`).
            unsafe { self.test_by_triangles::<ANY, P>(open, prims, refs) };
            return;
        }
        for i in bits(open) {
            let Member {
                tr, mailbox, best, ..
            } = &mut self.members[i];
            let found = for_each_candidate(packed, start, refs, &tr.prepared, |p| {
                candidate::<ANY, T, P>(tr, mailbox, best, p, prims)
            });
            self.settle::<ANY>(i, found);
        }
    }

    /// [`Packet::test`] triangle by triangle: each triangle's first stage
    /// of the watertight test runs on every quad with a member in
    /// `meeting` ([`RayQuad::survivors_avx2`]; one member alone already
    /// gained: sphere camera rays 4.09 Mrays/s against 3.90 with two or
    /// more), and the members it keeps (all those of a quad whose rays do
    /// not share their axes) test it as their single walk would
    /// ([`candidate`]), so each member meets the cell's primitives in the
    /// cell's order.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn test_by_triangles<const ANY: bool, P: PrimitiveSet<T> + ?Sized>(
        &mut self,
        meeting: u64,
        prims: &P,
        refs: &[u32],
    ) {
        const QUAD: u64 = (1 << RayQuad::LANES) - 1;
        let (mut open, mut found) = (meeting, 0u64);
        for &p in refs {
            let mut kept = open;
            if let Some(triangle) = prims.watertight_triangle(p as usize) {
                let mut quads = open;
                while quads != 0 {
                    let shift = quads.trailing_zeros() as usize / RayQuad::LANES * RayQuad::LANES;
                    quads &= !(QUAD << shift);
                    if let Some(quad) = &self.quads[shift / RayQuad::LANES] {
                        // SAFETY: the caller promises AVX2.
                        let keep = u64::from(unsafe { quad.survivors_avx2(&triangle) });
                        kept &= !(QUAD << shift) | (keep & QUAD) << shift;
                    }
                }
            }
            for i in bits(kept & open) {
                let m = &mut self.members[i];
                if candidate::<ANY, T, P>(&m.tr, &mut m.mailbox, &mut m.best, p, prims) {
                    found |= 1 << i;
                    open &= !(1 << i);
                }
            }
            if open == 0 {
                break;
            }
        }
        for i in bits(meeting) {
            self.settle::<ANY>(i, found & (1 << i) != 0);
        }
    }
}

/// The cells of slice `i` (across `axes[0]`) of `grid` in `window` that
/// hold something, with their places in the window, in `cells`.
fn full_cells<T: Real, G: SliceCells<T> + ?Sized>(
    grid: &G,
    [k, u, v]: [usize; 3],
    i: u32,
    window: Window,
    cells: &mut Vec<(usize, usize, [u32; 2])>,
) {
    cells.clear();
    let geom = grid.geometry();
    let mut place = 0;
    for cv in window.v[0]..=window.v[1] {
        for cu in window.u[0]..=window.u[1] {
            let mut c = [0u32; 3];
            (c[k], c[u], c[v]) = (i, cu, cv);
            let index = geom.linear_index(c);
            if grid.holds(index) {
                cells.push((index, place, [cu, cv]));
            }
            place += 1;
        }
    }
}
