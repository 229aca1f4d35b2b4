//! The workspace's studies, one binary (`studies`): measurements that
//! inform the library's defaults and the docs, kept apart from the `render`
//! binary, whose library they use for scenes, ray sets and output files.
//!
//! - `studies tradeoff SCENE|all` measures every speed-against-accuracy
//!   dial ([`tradeoff`]): precision, triangle test (the watertight test of
//!   Woop, Benthin & Wald 2013 against Möller & Trumbore 1997), spawn
//!   offset (pbrt-v4's error bounds against a fixed epsilon) and structure
//!   quality, as throughput against mismatches, leaks and self-hits (table,
//!   CSV, PNG plot via [`plot`]).
//! - `studies sweep-density` sweeps the grid density ([`sweep`]): the
//!   seed's claim (Cleary & Wyvill) of 8 to 10 cells per object.
//! - `studies choose-bench` checks `render --accel auto`
//!   ([`accel::choose_with_probe`]) against the best accelerator per scene
//!   ([`choose_bench`]).
//! - `studies alternate --run A --run B --figure WORD` times two or more
//!   builds' commands in alternation, round after round ([`alternate`]).
//! - `studies peers SCENE` runs our accelerators and other libraries
//!   (obvhs, parry3d, the bvh crate, Embree 3; each behind a cargo feature)
//!   on the same scene and rays on one thread, and checks that they agree
//!   ([`peers`]).
//!
//! Each subcommand owns its options; the command line ([`cli`]) only lists
//! them and `src/main.rs` dispatches, so no module imports another's
//! caller.

pub mod alternate;
pub mod choose_bench;
pub mod cli;
pub mod peers;
pub mod plot;
pub mod sweep;
pub mod tradeoff;

/// Median of the values (upper median for even counts; NaN for none).
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}
