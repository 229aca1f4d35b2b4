//! Hits and the rule that orders them.

use crate::Real;

/// Where a ray meets one primitive: the parameter and the surface coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimHit<T> {
    /// Ray parameter of the hit.
    pub t: T,
    /// First surface coordinate (for triangles the barycentric weight of vertex 1).
    pub u: T,
    /// Second surface coordinate (for triangles the barycentric weight of vertex 2).
    pub v: T,
}

/// The nearest hit of a query: [`PrimHit`] plus the primitive's index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit<T> {
    /// Ray parameter of the hit.
    pub t: T,
    /// Index of the primitive in its set.
    pub prim: u32,
    /// First surface coordinate.
    pub u: T,
    /// Second surface coordinate.
    pub v: T,
}

impl<T: Real> Hit<T> {
    /// Attaches a primitive index to a primitive hit.
    #[inline]
    #[must_use]
    pub fn new(prim: u32, h: PrimHit<T>) -> Self {
        Self {
            t: h.t,
            prim,
            u: h.u,
            v: h.v,
        }
    }

    /// The workspace's order of hits: smaller `t` first, and among equal `t`
    /// the lower primitive index. Every accelerator keeps the first hit in
    /// this order, which makes their answers identical to brute force.
    #[inline]
    #[must_use]
    pub fn is_before(&self, other: &Self) -> bool {
        self.t < other.t || (self.t == other.t && self.prim < other.prim)
    }

    /// The raw bits of every field: equal keys mean bit-for-bit equal hits.
    #[inline]
    #[must_use]
    pub fn bit_key(&self) -> (u64, u32, u64, u64) {
        (
            self.t.to_bits_u64(),
            self.prim,
            self.u.to_bits_u64(),
            self.v.to_bits_u64(),
        )
    }
}

/// Keeps the first of two optional hits in the order of [`Hit::is_before`].
#[inline]
#[must_use]
pub fn nearer<T: Real>(best: Option<Hit<T>>, candidate: Hit<T>) -> Option<Hit<T>> {
    match best {
        Some(b) if !candidate.is_before(&b) => Some(b),
        _ => Some(candidate),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ties_go_to_the_lower_index() {
        let a = Hit {
            t: 1.0f32,
            prim: 7,
            u: 0.1,
            v: 0.2,
        };
        let b = Hit { prim: 3, ..a };
        assert!(b.is_before(&a));
        assert!(!a.is_before(&b));
        assert_eq!(nearer(Some(a), b), Some(b));
        assert_eq!(nearer(Some(b), a), Some(b));
        let c = Hit {
            t: 0.5,
            prim: 9,
            ..a
        };
        assert_eq!(nearer(Some(b), c), Some(c));
    }
}
