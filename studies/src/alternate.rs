//! `studies alternate`: two or more builds compared by running them in
//! turn, round after round, so that the host's swings fall on all of them
//! alike (the A/B method of `docs/performance-log.md`, as a tool).
//!
//! Each `--run` is a command line (split on whitespace, no quoting) that
//! prints its figure as a number after a word, e.g. the bundles example's
//! `single 1.234 Mrays/s`. Every round runs every command once, odd rounds
//! in reverse order (as `studies peers --rounds` does within one process),
//! and reads the number right after the first `--figure` word of its
//! standard output. The table gives each command's figures, their median
//! and maximum, and the ratio of each median to the first command's.
//! Environment variables (such as `BUNDLES_ONLY`) pass through.

use anyhow::{Context, Result, bail};
use clap::Args;
use std::process::Command;

/// Options of `studies alternate`.
#[derive(Debug, Args)]
pub struct AlternateArgs {
    /// A command to time (at least two): the program and its arguments,
    /// separated by whitespace. The first is the baseline of the ratios.
    #[arg(long = "run", required = true, value_name = "COMMAND")]
    pub runs: Vec<String>,
    /// The word after which each command prints its figure (the number
    /// right after its first occurrence in standard output).
    #[arg(long)]
    pub figure: String,
    /// Rounds: each command runs once per round.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000), allow_negative_numbers = true)]
    pub rounds: u32,
}

/// Runs `studies alternate`.
///
/// # Errors
/// Fewer than two commands, an empty one, a command that cannot start,
/// fails or prints no figure.
pub fn run(args: &AlternateArgs) -> Result<()> {
    if args.runs.len() < 2 {
        bail!("--run: give at least two commands to alternate");
    }
    let commands: Vec<Vec<&str>> = args
        .runs
        .iter()
        .map(|r| r.split_whitespace().collect())
        .collect();
    if let Some(i) = commands.iter().position(Vec::is_empty) {
        bail!("--run number {}: the command is empty", i + 1);
    }
    let mut figures = vec![Vec::new(); commands.len()];
    for round in 0..args.rounds as usize {
        for i in round_order(round, commands.len()) {
            let value = figure_of(&commands[i], &args.figure)
                .with_context(|| format!("round {}, --run {:?}", round + 1, args.runs[i]))?;
            figures[i].push(value);
        }
    }
    print!("{}", table(&args.runs, &figures));
    Ok(())
}

/// The order of the commands in round `round` (from 0): forward in even
/// rounds, backward in odd ones.
fn round_order(round: usize, n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    if !round.is_multiple_of(2) {
        order.reverse();
    }
    order
}

/// Runs `command` and reads its figure after `word`.
fn figure_of(command: &[&str], word: &str) -> Result<f64> {
    let (program, rest) = command.split_first().expect("checked non-empty");
    let out = Command::new(program)
        .args(rest)
        .output()
        .with_context(|| format!("cannot run {program}"))?;
    if !out.status.success() {
        bail!(
            "{program} failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    figure_in(&String::from_utf8_lossy(&out.stdout), word)
}

/// The number right after the first occurrence of the word `word` (a
/// whitespace-separated token) in `output`; an error if there is none, or
/// if the next token is not a finite number.
fn figure_in(output: &str, word: &str) -> Result<f64> {
    let mut tokens = output.split_whitespace();
    if !tokens.any(|t| t == word) {
        bail!("no {word:?} in its output");
    }
    tokens
        .next()
        .and_then(|t| t.trim_end_matches([',', ';', ')']).parse::<f64>().ok())
        .filter(|v| v.is_finite())
        .with_context(|| format!("no number after {word:?} in its output"))
}

/// The table: per command its figures in the order run, median, maximum
/// and the ratio of its median to the first command's.
fn table(runs: &[String], figures: &[Vec<f64>]) -> String {
    let medians: Vec<f64> = figures.iter().map(|f| crate::median(f.clone())).collect();
    let mut out = String::from(
        "| command | median | max | median ÷ first | figures |\n|---|--:|--:|--:|---|\n",
    );
    for ((run, f), m) in runs.iter().zip(figures).zip(&medians) {
        let max = f.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let each: Vec<String> = f.iter().map(|v| format!("{v}")).collect();
        out += &format!(
            "| `{run}` | {m} | {max} | {:.3} | {} |\n",
            m / medians[0],
            each.join(" ")
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_figure_is_the_first_number_after_the_word() {
        let out =
            "grid on 55584 rays, nearest + any hit: single 0.775 Mrays/s, bundles 0.786 Mrays/s";
        assert_eq!(figure_in(out, "single").unwrap(), 0.775);
        assert_eq!(figure_in(out, "bundles").unwrap(), 0.786);
        // A number glued to punctuation still reads.
        assert_eq!(figure_in("a: b 2.5, c", "b").unwrap(), 2.5);
    }

    #[test]
    fn a_missing_word_or_number_is_named() {
        // Not a later number: the one right after the word.
        let e = figure_in("single NaN Mrays/s, bundles 0.786", "single").unwrap_err();
        assert!(format!("{e}").contains("no number after \"single\""), "{e}");
        let e = figure_in("bundles 1.0", "single").unwrap_err();
        assert!(format!("{e}").contains("no \"single\""), "{e}");
    }

    #[test]
    fn odd_rounds_run_backwards() {
        assert_eq!(round_order(0, 3), [0, 1, 2]);
        assert_eq!(round_order(1, 3), [2, 1, 0]);
        assert_eq!(round_order(2, 3), [0, 1, 2]);
    }

    #[test]
    fn the_table_gives_medians_and_their_ratio_to_the_first() {
        let runs = ["a".to_string(), "b".to_string()];
        let t = table(&runs, &[vec![1.0, 3.0, 2.0], vec![4.0, 6.0, 5.0]]);
        assert!(t.contains("| `a` | 2 | 3 | 1.000 | 1 3 2 |"), "{t}");
        assert!(t.contains("| `b` | 5 | 6 | 2.500 | 4 6 5 |"), "{t}");
    }
}
