//! `render`: render, heat-map and benchmark the accelerators (see the
//! library's documentation and `render --help`).

use render::cli::{Cli, Command};
use std::process::ExitCode;

fn main() -> ExitCode {
    render::report::main_of("render", |cli: &Cli| match &cli.command {
        Some(Command::Bench(args)) => render::app::run_bench(args),
        Some(Command::Merge(args)) => render::part_io::run_merge(args),
        None => render::app::run_render(&cli.render),
    })
}
