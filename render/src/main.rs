//! `render`: render, heat-map and benchmark the accelerators (see the
//! library's documentation and `render --help`).

use clap::Parser;
use clap::error::ErrorKind;
use render::cli::{Cli, Command};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) => {
            e.exit()
        }
        Err(e) => {
            let message = render::report::clap_line(&e);
            eprintln!("render: error: {message} (see render --help)");
            return ExitCode::from(2);
        }
    };
    let result = match &cli.command {
        Some(Command::Bench(args)) => render::app::run_bench(args),
        Some(Command::Merge(args)) => render::part_io::run_merge(args),
        None => render::app::run_render(&cli.render),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line: the error and its causes, outermost first, each once.
            eprintln!("render: error: {}", render::report::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
