//! Bounds of a whole primitive set, checked for the builders.

use crate::{Aabb, BuildError, PrimitiveSet, Real};
use rayon::prelude::*;

/// The bounds of every primitive, computed in parallel, and their union.
///
/// Every builder starts here (or at [`bounds_union`]), so that a scene with
/// a NaN or infinite coordinate is refused with the index of the first bad
/// primitive.
///
/// # Errors
/// [`BuildError::NonFinitePrimitive`] or [`BuildError::TooManyPrimitives`].
pub fn primitive_bounds<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
) -> Result<(Vec<Aabb<T>>, Aabb<T>), BuildError> {
    check_count(prims)?;
    let boxes: Vec<Aabb<T>> = (0..prims.len())
        .into_par_iter()
        .map(|i| prims.bounds(i))
        .collect();
    let total = checked_union(boxes.par_iter().copied().enumerate())?;
    Ok((boxes, total))
}

/// The union of every primitive's bounds, checked as [`primitive_bounds`]
/// but without keeping the boxes: for a builder that asks the primitives
/// again when it needs one (the uniform grid, brute force), and so writes
/// no array of boxes (24 bytes a triangle in `f32`).
///
/// # Errors
/// As [`primitive_bounds`].
pub fn bounds_union<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
) -> Result<Aabb<T>, BuildError> {
    check_count(prims)?;
    checked_union(
        (0..prims.len())
            .into_par_iter()
            .map(|i| (i, prims.bounds(i))),
    )
}

/// Refuses more primitives than `u32` indices reach.
fn check_count<T: Real, P: PrimitiveSet<T> + ?Sized>(prims: &P) -> Result<(), BuildError> {
    let count = prims.len();
    if count > u32::MAX as usize {
        return Err(BuildError::TooManyPrimitives { count });
    }
    Ok(())
}

/// The union of indexed boxes, or the lowest index of a non-finite one, in
/// one pass.
fn checked_union<T: Real>(
    boxes: impl ParallelIterator<Item = (usize, Aabb<T>)>,
) -> Result<Aabb<T>, BuildError> {
    let (total, first_bad) = boxes
        .fold(
            || (Aabb::empty(), usize::MAX),
            |(total, bad), (i, b)| {
                let bad = if bad == usize::MAX && !b.is_finite() {
                    i
                } else {
                    bad
                };
                (total.union(&b), bad)
            },
        )
        .reduce(
            || (Aabb::empty(), usize::MAX),
            |a, b| (a.0.union(&b.0), a.1.min(b.1)),
        );
    if first_bad != usize::MAX {
        return Err(BuildError::NonFinitePrimitive { index: first_bad });
    }
    Ok(total)
}
