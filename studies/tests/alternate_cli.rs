//! End-to-end runs of `studies alternate`, with `echo` as the commands
//! timed: the figures read, their order, medians and ratios, and the
//! errors for commands that fail or print no figure.

use std::process::Output;

/// Runs the `studies` binary with `args`.
fn run(args: &[&str]) -> Output {
    assert_cmd::cargo::cargo_bin_cmd!("studies")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn figures_of_two_commands_give_medians_and_their_ratio() {
    let o = run(&[
        "alternate",
        "--figure",
        "single",
        "--rounds",
        "3",
        "--run",
        "echo rays: single 2 Mrays/s, bundles 9",
        "--run",
        "echo rays: single 5 Mrays/s, bundles 1",
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("| 2 | 2 | 1.000 | 2 2 2 |"), "{out}");
    assert!(out.contains("| 5 | 5 | 2.500 | 5 5 5 |"), "{out}");
}

/// Runs `studies alternate --figure FIGURE --run FIRST --run SECOND`,
/// asserts that it fails without printing a table, and returns its stderr.
fn failure(figure: &str, first: &str, second: &str) -> String {
    let o = run(&[
        "alternate",
        "--figure",
        figure,
        "--run",
        first,
        "--run",
        second,
    ]);
    assert!(!o.status.success());
    assert!(o.stdout.is_empty(), "no table from a failed run");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_command_without_its_figure_or_that_fails_is_named() {
    let err = failure("single", "echo single 1", "echo bundles 1");
    assert!(
        err.contains("echo bundles 1") && err.contains("no \"single\""),
        "{err}"
    );
    let err = failure("single", "echo single 1", "/nonexistent/bench single");
    assert!(err.contains("cannot run /nonexistent/bench"), "{err}");
    let err = failure("x", "echo x 1", "false");
    assert!(err.contains("false failed"), "{err}");
}

#[test]
fn one_command_or_no_rounds_is_refused() {
    let o = run(&["alternate", "--figure", "x", "--run", "echo x 1"]);
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("at least two"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = run(&[
        "alternate",
        "--figure",
        "x",
        "--rounds",
        "0",
        "--run",
        "echo x 1",
        "--run",
        "echo x 2",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--rounds"));
}
