//! `studies`: the workspace's studies (see the library's documentation and
//! `studies --help`).

use clap::Parser;
use clap::error::ErrorKind;
use std::process::ExitCode;
use studies::cli::{Cli, Command};

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) => {
            e.exit()
        }
        Err(e) => {
            let message = render::report::clap_line(&e);
            eprintln!("studies: error: {message} (see studies --help)");
            return ExitCode::from(2);
        }
    };
    let result = match &cli.command {
        Command::Tradeoff(args) => studies::tradeoff::run(args),
        Command::SweepDensity(args) => studies::sweep::run(args),
        Command::ChooseBench(args) => studies::choose_bench::run(args),
        Command::Peers(args) => studies::peers::run::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line: the error and its causes, outermost first, each once.
            eprintln!("studies: error: {}", render::report::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
