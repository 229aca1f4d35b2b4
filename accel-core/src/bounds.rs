//! Bounds of a whole primitive set, checked for the builders.

use crate::real::{greater, lesser};
use crate::{Aabb, BuildError, PrimitiveSet, Real, Vec3};
use rayon::prelude::*;

/// The bounds of every primitive, computed in parallel, and their union.
///
/// Every builder starts here (or at [`bounds_union`]), so that a scene with
/// a NaN or infinite coordinate is refused with the index of the first bad
/// primitive.
///
/// # Errors
/// [`BuildError::NonFinitePrimitive`], [`BuildError::TooManyPrimitives`], or
/// [`BuildError::OutOfRange`] for finite coordinates beyond [`Real::LIMIT`].
pub fn primitive_bounds<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
) -> Result<(Vec<Aabb<T>>, Aabb<T>), BuildError> {
    check_count(prims)?;
    let boxes: Vec<Aabb<T>> = (0..prims.len())
        .into_par_iter()
        .map(|i| prims.bounds(i))
        .collect();
    let total = boxes
        .par_chunks(CHUNK)
        .map(|chunk| chunk.iter().fold(Union::EMPTY, Union::add))
        .reduce(|| Union::EMPTY, Union::merge);
    total.checked(|| boxes.iter().position(|b| !b.is_finite()))?;
    check_range(&total.bounds)?;
    Ok((boxes, total.bounds))
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
    bounds_survey(prims).map(|s| s.bounds)
}

/// What one pass over a scene's primitive boxes learns: their union, and
/// enough to tell a builder, without another pass, that the scene has no
/// part to set apart ([`crate::parts::split_surveyed`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneSurvey<T> {
    /// The union of every primitive's bounds.
    pub bounds: Aabb<T>,
    /// The largest side of any primitive's bounds.
    pub widest: T,
    /// Per axis, how many primitives' bounds are flat on it (zero extent).
    pub flat: [usize; 3],
}

/// [`bounds_union`], with the rest of the [`SceneSurvey`] from the same
/// pass.
///
/// # Errors
/// As [`primitive_bounds`].
pub fn bounds_survey<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
) -> Result<SceneSurvey<T>, BuildError> {
    check_count(prims)?;
    let n = prims.len();
    let total = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            (c * CHUNK..n.min((c + 1) * CHUNK))
                .map(|i| prims.bounds(i))
                .fold(Union::EMPTY, |u, b| u.add(&b))
        })
        .reduce(|| Union::EMPTY, Union::merge);
    total.checked(|| (0..n).position(|i| !prims.bounds(i).is_finite()))?;
    check_range(&total.bounds)?;
    Ok(SceneSurvey {
        bounds: total.bounds,
        widest: total.widest,
        flat: total.flat.map(|c| c as usize),
    })
}

/// Refuses a finite box that reaches beyond `±T::LIMIT` ([`Real::LIMIT`]):
/// past it, cell widths, split positions and ray parameters across the box
/// could overflow. An empty box passes.
///
/// # Errors
/// [`BuildError::OutOfRange`] naming the first such axis and coordinate.
pub fn check_range<T: Real>(b: &Aabb<T>) -> Result<(), BuildError> {
    if b.is_empty() {
        return Ok(());
    }
    let beyond = |x: T| !(x.abs() <= T::LIMIT);
    match (0..3).find(|&a| beyond(b.min[a]) || beyond(b.max[a])) {
        None => Ok(()),
        Some(axis) => {
            let (lo, hi) = (b.min[axis], b.max[axis]);
            let value = if beyond(lo) { lo } else { hi };
            Err(BuildError::OutOfRange {
                precision: T::NAME,
                axis,
                value: value.to_f64(),
                limit: T::LIMIT.to_f64(),
            })
        }
    }
}

/// Primitives per task of the unions: each task folds a run of boxes with
/// plain selects, and rayon's per-item splitting is paid once per run.
const CHUNK: usize = 1 << 14;

/// Refuses more primitives than `u32` indices reach.
fn check_count<T: Real, P: PrimitiveSet<T> + ?Sized>(prims: &P) -> Result<(), BuildError> {
    let count = prims.len();
    if count > u32::MAX as usize {
        return Err(BuildError::TooManyPrimitives { count });
    }
    Ok(())
}

/// A running union of boxes that also learns, without a branch per box,
/// whether any was not finite.
#[derive(Clone, Copy, Debug)]
struct Union<T> {
    bounds: Aabb<T>,
    /// The largest side of any box added.
    widest: T,
    /// Per axis, how many boxes added were flat on it.
    flat: [u32; 3],
    /// The sum of every corner times zero: zero while each corner is
    /// finite, NaN for good once one is not (`∞ · 0` and anything with a
    /// NaN are NaN), which the plain selects of the union would not show.
    probe: Vec3<T>,
}

impl<T: Real> Union<T> {
    const EMPTY: Self = Self {
        bounds: Aabb::empty(),
        widest: T::ZERO,
        flat: [0; 3],
        probe: Vec3::splat(T::ZERO),
    };

    /// Adds one primitive's box.
    #[inline]
    fn add(self, b: &Aabb<T>) -> Self {
        let side = (b.max - b.min).max_component();
        Self {
            bounds: selected_union(&self.bounds, b),
            widest: greater(self.widest, side),
            flat: [0, 1, 2].map(|a| self.flat[a] + u32::from(b.min[a] == b.max[a])),
            probe: self.probe + b.min * T::ZERO + b.max * T::ZERO,
        }
    }

    /// Joins the unions of two runs.
    fn merge(self, other: Self) -> Self {
        Self {
            bounds: selected_union(&self.bounds, &other.bounds),
            widest: greater(self.widest, other.widest),
            flat: [0, 1, 2].map(|a| self.flat[a] + other.flat[a]),
            probe: self.probe + other.probe,
        }
    }

    /// `Ok` when every box added was finite; else the error naming the
    /// first bad primitive, which `first_bad` finds (a second pass, taken
    /// only for a bad scene).
    fn checked(&self, first_bad: impl FnOnce() -> Option<usize>) -> Result<(), BuildError> {
        let p = self.probe;
        if p.x == T::ZERO && p.y == T::ZERO && p.z == T::ZERO {
            return Ok(());
        }
        Err(BuildError::NonFinitePrimitive {
            index: first_bad().unwrap_or(0),
        })
    }
}

/// [`Aabb::union`] by plain selects, which compile to single min/max
/// instructions (`f32::min`'s NaN rule costs more); [`Union::probe`]
/// catches the NaNs they would drop.
#[inline]
fn selected_union<T: Real>(a: &Aabb<T>, b: &Aabb<T>) -> Aabb<T> {
    let (lo, hi) = (a.min, a.max);
    Aabb {
        min: Vec3::new(
            lesser(lo.x, b.min.x),
            lesser(lo.y, b.min.y),
            lesser(lo.z, b.min.z),
        ),
        max: Vec3::new(
            greater(hi.x, b.max.x),
            greater(hi.y, b.max.y),
            greater(hi.z, b.max.z),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Triangle;

    /// Triangles over several runs of [`CHUNK`], spread over a few binades
    /// of either sign.
    fn triangles(n: usize) -> Vec<Triangle<f32>> {
        (0..n)
            .map(|i| {
                let f = |k: usize| {
                    let h = (i * 3 + k).wrapping_mul(0x9E37_79B9) % 2001;
                    (h as f32 - 1000.0) * 0.37
                };
                let v = |k| Vec3::new(f(k), f(k + 7), f(k + 13));
                Triangle {
                    vertices: [v(0), v(1), v(2)],
                }
            })
            .collect()
    }

    #[test]
    fn the_union_is_every_box_joined_one_by_one() {
        let tris = triangles(3 * CHUNK + 5);
        let want = (0..tris.len()).fold(Aabb::empty(), |u, i| u.union(&tris.bounds(i)));
        assert_eq!(bounds_union(tris.as_slice()), Ok(want));
        let (boxes, total) = primitive_bounds(tris.as_slice()).unwrap();
        assert_eq!(total, want);
        assert!((0..tris.len()).all(|i| boxes[i] == tris.bounds(i)));
        let none: &[Triangle<f32>] = &[];
        assert_eq!(bounds_union(none), Ok(Aabb::empty()));
    }

    #[test]
    fn the_first_non_finite_primitive_is_named_in_whichever_run() {
        for (bad, value) in [
            (vec![CHUNK + 3], f32::NAN),
            (vec![2 * CHUNK + 1, CHUNK + 9], f32::INFINITY),
            (vec![3 * CHUNK + 4, 0], f32::NEG_INFINITY),
        ] {
            let mut tris = triangles(3 * CHUNK + 5);
            for (j, &i) in bad.iter().enumerate() {
                tris[i].vertices[j % 3].y = value;
            }
            let want = Err(BuildError::NonFinitePrimitive {
                index: *bad.iter().min().unwrap(),
            });
            assert_eq!(
                bounds_union(tris.as_slice()).map(|_| ()),
                want,
                "{bad:?} {value}"
            );
            assert_eq!(primitive_bounds(tris.as_slice()).map(|_| ()), want);
        }
    }
}
