//! Why a build was refused.

/// Why an accelerator could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BuildError {
    /// A primitive has NaN or infinite bounds.
    #[error("primitive {index} has non-finite bounds (NaN or infinite coordinates)")]
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
    #[error("{what}: {needed} needed, over the budget of {budget}")]
    BudgetExceeded {
        /// What was counted (cells, references, bytes).
        what: &'static str,
        /// How many the build needs.
        needed: u64,
        /// The configured budget.
        budget: u64,
    },
    /// A user-given region has a NaN or infinite corner, or is empty.
    #[error("the build region is not a finite, non-empty box")]
    InvalidRegion,
}
