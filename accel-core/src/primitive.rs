//! What an accelerator needs from the things it indexes.
//!
//! Accelerators never copy geometry: they store `u32` indices into a
//! [`PrimitiveSet`] and call back into it. Every accelerator calls the same
//! [`PrimitiveSet::intersect`], which is what makes their answers bit-for-bit
//! identical to [`crate::BruteForce`].

use crate::{Aabb, PreparedRay, PrimHit, Real, Vec3};

/// One primitive that knows its bounds and how a ray meets it.
///
/// Implement this for your own shape and pass a slice of them (`&[MyShape]`)
/// wherever a [`PrimitiveSet`] is expected.
///
/// # Contract
/// - [`Primitive::intersect`] is a pure function of the ray: its `t`, `u`, `v`
///   do not depend on `t_max`, which only decides whether the hit is returned
///   (`ray.t_min ≤ t ≤ t_max`). It never returns NaN.
/// - Its hits are accurate to rounding: the reported point `o + t·d` lies within
///   about `gamma(16)·(max |p − o|)` of the primitive (`p` over its bounds), which
///   the accelerators' conservative traversal allows for.
/// - [`Primitive::overlaps_box`] never answers `false` for a box the primitive
///   truly meets; it may answer `true` for a box within rounding distance.
/// - [`Primitive::clipped_bounds`] holds every point of the primitive that lies
///   in the box (it may hold more), and lies inside the box.
pub trait Primitive<T: Real>: Sync {
    /// A box that holds the primitive.
    fn bounds(&self) -> Aabb<T>;

    /// The hit of `ray` with `ray.t_min ≤ t ≤ t_max`, if any.
    fn intersect(&self, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>>;

    /// Whether every hit is accurate to the rounding of [`Real::Wide`], as
    /// [`PrimitiveSet::wide_hits`] says; `false` (always safe) unless the
    /// test computes in the wide type from `T`'s exact inputs.
    const WIDE_HITS: bool = false;

    /// The vertices, when the primitive is a triangle whose
    /// [`Primitive::intersect`] is exactly
    /// [`crate::triangle::intersect_triangle`] with them: a structure may
    /// then test it in packed blocks ([`crate::packed`]). `None` (the
    /// default) otherwise.
    fn watertight_triangle(&self) -> Option<[Vec3<T>; 3]> {
        None
    }

    /// Whether the primitive meets the closed box `b`. The default tests the
    /// bounds; shapes with an exact test override it, so that long thin shapes
    /// are referenced only by the cells they really touch.
    fn overlaps_box(&self, b: &Aabb<T>) -> bool {
        self.bounds().overlaps(b)
    }

    /// [`Primitive::overlaps_box`] for each of `boxes`, written to the same
    /// place in `out` (as long as `boxes`). A grid asks about all the cells
    /// a primitive's bounds cover at once, so that a shape can prepare its
    /// test once ([`crate::Triangle`] does); the default asks box by box.
    fn overlaps_boxes(&self, boxes: &[Aabb<T>], out: &mut [bool]) {
        for (b, o) in boxes.iter().zip(out) {
            *o = self.overlaps_box(b);
        }
    }

    /// A box holding every point of the primitive that lies in the closed box
    /// `b`, itself inside `b`; empty (see [`Aabb::is_empty`]) when the
    /// primitive surely misses `b`. kD-trees use it for "perfect splits"
    /// (Wald & Havran 2006): a primitive's events are made from its part in
    /// the node, not from its whole bounds.
    ///
    /// It must be conservative: never smaller than the true part of the
    /// primitive in `b`, whatever the rounding. The default,
    /// `bounds() ∩ b`, is; shapes with an exact clipper override it
    /// ([`crate::Triangle`] clips with Sutherland–Hodgman logic).
    fn clipped_bounds(&self, b: &Aabb<T>) -> Aabb<T> {
        self.bounds().intersection(b)
    }

    /// [`Primitive::clipped_bounds`] for the two halves of `b` cut at
    /// `x[axis] = s` (below, then above, as [`Aabb::split_at`]). It must
    /// equal the two calls; the default makes them, and
    /// [`crate::Triangle`] shares their work.
    fn clipped_bounds_split(&self, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        let (below, above) = b.split_at(axis, s);
        [self.clipped_bounds(&below), self.clipped_bounds(&above)]
    }
}

/// An indexed collection of primitives: a triangle mesh, a slice of spheres,
/// a user's own set. Indices run over `0..len()`.
///
/// The same contract as [`Primitive`] holds for each index.
pub trait PrimitiveSet<T: Real>: Sync {
    /// Number of primitives.
    fn len(&self) -> usize;

    /// True when there are no primitives.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bounds of primitive `i`.
    fn bounds(&self, i: usize) -> Aabb<T>;

    /// The hit of `ray` with primitive `i` in `[ray.t_min, t_max]`, if any.
    fn intersect(&self, i: usize, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>>;

    /// Whether primitive `i` meets the closed box `b` (conservatively).
    fn overlaps_box(&self, i: usize, b: &Aabb<T>) -> bool;

    /// Whether every hit is accurate to the rounding of [`Real::Wide`], not
    /// only of `T`: the reported point `o + t·d`, before `t` is rounded to
    /// `T`, lies within `gamma(16)·(max |p − o|)` **of `T::Wide`** of the
    /// primitive. A test that computes in `T::Wide` from `T`'s exact
    /// inputs (the watertight triangle test) is; one that rounds in `T`
    /// first is not. A traversal may then use a beam as thin as the wide
    /// type's rounding ([`crate::TraversalRay::with_wide_hits`]), which lets
    /// a ray that leaves a surface skip it. The default, `false`, is always
    /// safe.
    fn wide_hits(&self) -> bool {
        false
    }

    /// The vertices of primitive `i`, when it is a triangle whose
    /// [`PrimitiveSet::intersect`] is exactly
    /// [`crate::triangle::intersect_triangle`] with them, as
    /// [`Primitive::watertight_triangle`]. A set answers for all its
    /// primitives alike. `None` (the default) keeps structures indexed.
    fn watertight_triangle(&self, i: usize) -> Option<[Vec3<T>; 3]> {
        let _ = i;
        None
    }

    /// [`PrimitiveSet::overlaps_box`] of primitive `i` for each of `boxes`,
    /// written to the same place in `out` (as long as `boxes`), as
    /// [`Primitive::overlaps_boxes`]: one call per primitive lets a set
    /// prepare its test once ([`crate::TriangleMesh`] does). The default asks
    /// box by box.
    fn overlaps_boxes(&self, i: usize, boxes: &[Aabb<T>], out: &mut [bool]) {
        for (b, o) in boxes.iter().zip(out) {
            *o = self.overlaps_box(i, b);
        }
    }

    /// A box holding every point of primitive `i` inside the closed box `b`,
    /// itself inside `b` (empty when the primitive surely misses `b`), as
    /// [`Primitive::clipped_bounds`]. The default is `bounds(i) ∩ b`.
    fn clipped_bounds(&self, i: usize, b: &Aabb<T>) -> Aabb<T> {
        self.bounds(i).intersection(b)
    }

    /// [`PrimitiveSet::clipped_bounds`] for the two halves of `b` cut at
    /// `x[axis] = s` (below, then above, as [`Aabb::split_at`]): what a
    /// kD-tree build asks of each primitive its split plane straddles. It
    /// must equal the two calls; a set whose clipper can share their work
    /// overrides it ([`crate::TriangleMesh`] does). The default makes the
    /// two calls.
    fn clipped_bounds_split(&self, i: usize, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        let (below, above) = b.split_at(axis, s);
        [
            self.clipped_bounds(i, &below),
            self.clipped_bounds(i, &above),
        ]
    }
}

impl<T: Real, P: Primitive<T>> PrimitiveSet<T> for [P] {
    #[inline]
    fn wide_hits(&self) -> bool {
        P::WIDE_HITS
    }
    #[inline]
    fn watertight_triangle(&self, i: usize) -> Option<[Vec3<T>; 3]> {
        self[i].watertight_triangle()
    }
    #[inline]
    fn len(&self) -> usize {
        <[P]>::len(self)
    }
    #[inline]
    fn bounds(&self, i: usize) -> Aabb<T> {
        self[i].bounds()
    }
    #[inline]
    fn intersect(&self, i: usize, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        self[i].intersect(ray, t_max)
    }
    #[inline]
    fn overlaps_box(&self, i: usize, b: &Aabb<T>) -> bool {
        self[i].overlaps_box(b)
    }
    #[inline]
    fn overlaps_boxes(&self, i: usize, boxes: &[Aabb<T>], out: &mut [bool]) {
        self[i].overlaps_boxes(boxes, out);
    }
    #[inline]
    fn clipped_bounds(&self, i: usize, b: &Aabb<T>) -> Aabb<T> {
        self[i].clipped_bounds(b)
    }
    #[inline]
    fn clipped_bounds_split(&self, i: usize, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        self[i].clipped_bounds_split(b, axis, s)
    }
}

impl<T: Real, P: Primitive<T>> PrimitiveSet<T> for Vec<P> {
    #[inline]
    fn wide_hits(&self) -> bool {
        P::WIDE_HITS
    }
    #[inline]
    fn watertight_triangle(&self, i: usize) -> Option<[Vec3<T>; 3]> {
        self[i].watertight_triangle()
    }
    #[inline]
    fn len(&self) -> usize {
        Vec::len(self)
    }
    #[inline]
    fn bounds(&self, i: usize) -> Aabb<T> {
        self[i].bounds()
    }
    #[inline]
    fn intersect(&self, i: usize, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        self[i].intersect(ray, t_max)
    }
    #[inline]
    fn overlaps_box(&self, i: usize, b: &Aabb<T>) -> bool {
        self[i].overlaps_box(b)
    }
    #[inline]
    fn overlaps_boxes(&self, i: usize, boxes: &[Aabb<T>], out: &mut [bool]) {
        self[i].overlaps_boxes(boxes, out);
    }
    #[inline]
    fn clipped_bounds(&self, i: usize, b: &Aabb<T>) -> Aabb<T> {
        self[i].clipped_bounds(b)
    }
    #[inline]
    fn clipped_bounds_split(&self, i: usize, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        self[i].clipped_bounds_split(b, axis, s)
    }
}
