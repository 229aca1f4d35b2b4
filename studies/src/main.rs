//! `studies`: the workspace's studies (see the library's documentation and
//! `studies --help`).

use std::process::ExitCode;
use studies::cli::{Cli, Command};

fn main() -> ExitCode {
    render::report::main_of("studies", |cli: &Cli| match &cli.command {
        Command::Tradeoff(args) => studies::tradeoff::run(args),
        Command::SweepDensity(args) => studies::sweep::run(args),
        Command::ChooseBench(args) => studies::choose_bench::run(args),
        Command::Peers(args) => studies::peers::run::run(args),
        Command::Alternate(args) => studies::alternate::run(args),
    })
}
