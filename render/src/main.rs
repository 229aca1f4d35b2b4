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
            // clap's first line names the problem; of the rest, keep the
            // possible values and tips, on the same line.
            let text = e.render().to_string();
            let mut lines = text.lines().map(str::trim);
            let first = lines.next().unwrap_or("invalid arguments");
            let mut message = first.strip_prefix("error: ").unwrap_or(first).to_owned();
            for l in lines.filter(|l| l.starts_with("[possible values") || l.starts_with("tip:")) {
                message.push_str("; ");
                message.push_str(l);
            }
            eprintln!("render: error: {message} (see render --help)");
            return ExitCode::from(2);
        }
    };
    let result = match &cli.command {
        Some(Command::Bench(args)) => render::app::run_bench(args),
        Some(Command::Tradeoff(args)) => render::tradeoff::run(args),
        Some(Command::SweepDensity(args)) => render::sweep::run(args),
        Some(Command::ChooseBench(args)) => render::choose_bench::run(args),
        Some(Command::Peers(args)) => render::peers::run::run(args),
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
