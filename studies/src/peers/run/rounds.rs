//! Timed passes in interleaved rounds: every figure of a ray set (each
//! tool's single rays and bundles) takes its passes a slice at a time, in
//! turn with the others, so that a swing of the host's speed falls on all of
//! them alike.
//!
//! Timed one after the other, each figure for `--min-time` seconds, the
//! figures of one set were measured up to a minute apart, and the ratios
//! between them carried the host's swings: the same binary's kD-tree diffuse
//! bundles ran 0.76–1.06× its single rays on the flat field in three runs
//! (2026-12-07). Interleaved, the figures share the swings, and so their
//! ratios lose most of them.

use anyhow::Result;
use render::bench;
use std::time::Duration;

/// One figure's timed pass and what it measured.
pub(super) struct Timed<'a> {
    /// One pass over the set: the number of hits it found.
    pass: Box<dyn FnMut() -> Result<u64> + 'a>,
    /// The hits every pass must find (those recorded with the answers).
    expected: u64,
    /// Each pass's wall time, in the order run.
    pub(super) times: Vec<Duration>,
    /// A pass's hits that differed from `expected`, the first one seen.
    pub(super) unexpected: Option<u64>,
}

impl<'a> Timed<'a> {
    /// A figure whose passes run `pass`, each expected to find `expected`
    /// hits.
    pub(super) fn new(expected: u64, pass: impl FnMut() -> Result<u64> + 'a) -> Self {
        Self {
            pass: Box::new(pass),
            expected,
            times: Vec::new(),
            unexpected: None,
        }
    }

    /// Runs passes until `slice` has gone by and at least `at_least` ran
    /// ([`bench::pass_times`]).
    fn run_slice(&mut self, slice: Duration, at_least: usize) -> Result<()> {
        let (pass, expected, unexpected) = (&mut self.pass, self.expected, &mut self.unexpected);
        let times = bench::pass_times(slice, at_least, || -> Result<()> {
            let hits = std::hint::black_box(pass()?);
            if hits != expected && unexpected.is_none() {
                *unexpected = Some(hits);
            }
            Ok(())
        })?;
        self.times.extend(times);
        Ok(())
    }
}

/// Times every figure of `figures` in `rounds` interleaved rounds. In each
/// round each figure runs passes for `min_time / rounds` (so about
/// `min_time` in all, as when timed alone), and at least enough that it
/// ends with `min_passes`. Odd rounds take the figures in reverse order, so
/// that no figure always runs after the same one.
///
/// # Errors
/// The first error of a pass.
pub(super) fn time_interleaved(
    figures: &mut [Timed<'_>],
    min_time: Duration,
    rounds: u32,
    min_passes: usize,
) -> Result<()> {
    let rounds = rounds.max(1);
    let slice = min_time / rounds;
    let per_round = min_passes.div_ceil(rounds as usize).max(1);
    for round in 0..rounds {
        if round % 2 == 0 {
            for f in figures.iter_mut() {
                f.run_slice(slice, per_round)?;
            }
        } else {
            for f in figures.iter_mut().rev() {
                f.run_slice(slice, per_round)?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;

    #[test]
    fn rounds_alternate_figures_and_give_each_its_passes() {
        let log = RefCell::new(Vec::new());
        let mut figures: Vec<Timed<'_>> = (0..3u64)
            .map(|i| {
                let log = &log;
                Timed::new(i, move || {
                    log.borrow_mut().push(i);
                    Ok(i)
                })
            })
            .collect();
        time_interleaved(&mut figures, Duration::ZERO, 4, 7).unwrap();
        // Two passes per figure per round (7 over 4 rounds), forward then
        // backward.
        let expected: Vec<u64> = [0, 0, 1, 1, 2, 2, 2, 2, 1, 1, 0, 0]
            .repeat(2)
            .into_iter()
            .collect();
        assert_eq!(*log.borrow(), expected);
        for f in &figures {
            assert_eq!(f.times.len(), 8);
            assert_eq!(f.unexpected, None);
        }
    }

    #[test]
    fn a_pass_with_other_hits_is_reported_and_an_error_stops_the_rounds() {
        let mut calls = 0;
        let mut odd = [Timed::new(5, move || {
            calls += 1;
            Ok(if calls == 2 { 4 } else { 5 })
        })];
        time_interleaved(&mut odd, Duration::ZERO, 3, 3).unwrap();
        assert_eq!(odd[0].unexpected, Some(4));
        let mut failing = [Timed::new(0, || Err(anyhow::anyhow!("refused")))];
        let err = time_interleaved(&mut failing, Duration::ZERO, 3, 3).unwrap_err();
        assert_eq!(err.to_string(), "refused");
    }

    #[test]
    fn each_figure_takes_its_slice_of_the_time() {
        let mut figures = [Timed::new(0, || Ok(0))];
        let start = std::time::Instant::now();
        time_interleaved(&mut figures, Duration::from_millis(30), 3, 1).unwrap();
        assert!(start.elapsed() >= Duration::from_millis(30));
        assert!(figures[0].times.len() >= 3);
    }
}
