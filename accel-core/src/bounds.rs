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
    if let Some(index) = boxes.par_iter().position_first(|b| !b.is_finite()) {
        return Err(BuildError::NonFinitePrimitive { index });
    }
    let total = boxes
        .par_iter()
        .copied()
        .reduce(Aabb::empty, |a, b| a.union(&b));
    Ok((boxes, total))
}
