//! Why a build was refused.

/// Why an accelerator could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BuildError {
    /// A primitive has NaN or infinite bounds: a NaN or infinite coordinate,
    /// or finite ones whose bounds overflow (a sphere of radius near
    /// `T::MAX` away from the origin).
    #[error(
        "primitive {index} has non-finite bounds (NaN or infinite coordinates, \
         or bounds past the largest finite value)"
    )]
    NonFinitePrimitive {
        /// Index of the primitive.
        index: usize,
    },
    /// More primitives than `u32` indices can name.
    #[error("{count} primitives exceed the limit of {} (u32 indices)", u32::MAX)]
    TooManyPrimitives {
        /// Number given.
        count: usize,
    },
    /// A build parameter is out of its range.
    #[error("parameter {name} = {value} is invalid: expected {expected}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given, as text.
        value: String,
        /// What is accepted.
        expected: &'static str,
    },
    /// The structure would exceed a memory budget.
    #[error("{what}: at least {needed} needed, over the budget of {budget}")]
    BudgetExceeded {
        /// What was counted (cells, references, bytes).
        what: &'static str,
        /// How many the build needs, or, where the build stopped counting
        /// the moment it passed the budget (a grid's references), how many
        /// it had counted by then: always more than `budget`, at most the
        /// whole need.
        needed: u64,
        /// The configured budget.
        budget: u64,
    },
    /// Every coordinate is finite, but the scene (or a user-given region)
    /// reaches beyond `±T::LIMIT` ([`crate::Real::LIMIT`]): cell widths,
    /// split positions, ray parameters and the triangle tests' products
    /// across it could overflow.
    #[error(
        "the scene reaches {} on {}, beyond ±{}, the largest {precision} coordinate the \
         accelerators accept; {}",
        shortest(precision, *value),
        ["x", "y", "z"][*axis % 3],
        shortest(precision, *limit),
        remedy(precision)
    )]
    OutOfRange {
        /// The precision of the build (`"f32"` or `"f64"`).
        precision: &'static str,
        /// The first axis with a coordinate beyond the limit (0, 1, 2 for
        /// x, y, z).
        axis: usize,
        /// That coordinate.
        value: f64,
        /// The limit, [`crate::Real::LIMIT`].
        limit: f64,
    },
    /// A user-given region has a NaN or infinite corner, or is empty.
    #[error("the build region is not a finite, non-empty box")]
    InvalidRegion,
}

/// `v`, a value of the precision named `precision`, written as that
/// precision writes it (`3e38`, not the `f64` digits of the `f32` value).
fn shortest(precision: &str, v: f64) -> String {
    if precision == "f32" {
        format!("{:e}", v as f32)
    } else {
        format!("{v:e}")
    }
}

/// What to do about a scene beyond the limit of `precision`.
fn remedy(precision: &str) -> &'static str {
    if precision == "f32" {
        "build the scene in f64"
    } else {
        "scale the scene down"
    }
}
