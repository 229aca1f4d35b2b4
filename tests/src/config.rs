//! Proptest configuration: bounded case counts for CI, scaled by
//! `PROPTEST_CASES`, and regression files kept under `proptest-regressions/`.

use proptest::test_runner::{Config, FileFailurePersistence};

/// The configuration of one property: `ci_cases` cases unless the
/// `PROPTEST_CASES` environment variable sets the count, and failures
/// persisted to `proptest-regressions/<name>.txt` in this crate (commit them:
/// proptest replays them before new cases).
#[must_use]
pub fn config(name: &str, ci_cases: u32) -> Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(ci_cases);
    let path = format!(
        "{}/proptest-regressions/{name}.txt",
        env!("CARGO_MANIFEST_DIR")
    );
    Config {
        cases,
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            // One small string per property per test run.
            Box::leak(path.into_boxed_str()),
        ))),
        ..Config::default()
    }
}
