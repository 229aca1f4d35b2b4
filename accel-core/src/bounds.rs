//! Bounds of a whole primitive set, checked for the builders.

use crate::{Aabb, BuildError, PrimitiveSet, Real};
use rayon::prelude::*;

/// The bounds of every primitive, computed in parallel, and their union.
///
/// Every builder starts here, so that a scene with a NaN or infinite
/// coordinate is refused with the index of the first bad primitive.
///
/// # Errors
/// [`BuildError::NonFinitePrimitive`] or [`BuildError::TooManyPrimitives`].
pub fn primitive_bounds<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
) -> Result<(Vec<Aabb<T>>, Aabb<T>), BuildError> {
    let n = prims.len();
    if n > u32::MAX as usize {
        return Err(BuildError::TooManyPrimitives { count: n });
    }
    let boxes: Vec<Aabb<T>> = (0..n).into_par_iter().map(|i| prims.bounds(i)).collect();
    // One pass for the union and the first non-finite box.
    let (total, first_bad) = boxes
        .par_iter()
        .enumerate()
        .fold(
            || (Aabb::empty(), usize::MAX),
            |(total, bad), (i, b)| {
                let bad = if bad == usize::MAX && !b.is_finite() {
                    i
                } else {
                    bad
                };
                (total.union(b), bad)
            },
        )
        .reduce(
            || (Aabb::empty(), usize::MAX),
            |a, b| (a.0.union(&b.0), a.1.min(b.1)),
        );
    if first_bad != usize::MAX {
        return Err(BuildError::NonFinitePrimitive { index: first_bad });
    }
    Ok((boxes, total))
}
