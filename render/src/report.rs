//! One-line error reports: an error and its causes, each said once.
//!
//! Library errors often name their cause in their own message *and* return
//! it from `source()` (thiserror does so for any field called `source`), so
//! the usual `{:#}` chain printed `X: X`. [`one_line`] walks the chain and
//! skips a cause whose text the message already contains (issue 32, item 5).
//! [`clap_line`] does the same for a command-line error. Both binaries,
//! `render` and `studies`, report through them.

/// The error and its causes, outermost first, joined by `": "`, leaving out
/// every cause whose text is already part of the report.
#[must_use]
pub fn one_line(err: &anyhow::Error) -> String {
    let mut report = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if text.is_empty() || report.contains(&text) {
            continue;
        }
        if !report.is_empty() {
            report.push_str(": ");
        }
        report.push_str(&text);
    }
    report
}

/// A command-line error in one line: clap's first line, without its
/// `error: ` prefix, then the possible values and tips, on the same line.
#[must_use]
pub fn clap_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let mut lines = text.lines().map(str::trim);
    let first = lines.next().unwrap_or("invalid arguments");
    let mut message = first.strip_prefix("error: ").unwrap_or(first).to_owned();
    for l in lines.filter(|l| l.starts_with("[possible values") || l.starts_with("tip:")) {
        message.push_str("; ");
        message.push_str(l);
    }
    message
}

/// A binary's `main`: parses the command line with `parse` (help and
/// version print and exit; any other error is one line on stderr, exit 2),
/// runs it with `run`, and reports an error in one line (exit 1). `binary`
/// names the program in the messages.
pub fn main_of<C: clap::Parser>(
    binary: &str,
    run: impl FnOnce(&C) -> anyhow::Result<()>,
) -> std::process::ExitCode {
    use clap::error::ErrorKind;
    let cli = match C::try_parse() {
        Ok(cli) => cli,
        Err(e) if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) => {
            e.exit()
        }
        Err(e) => {
            eprintln!("{binary}: error: {} (see {binary} --help)", clap_line(&e));
            return std::process::ExitCode::from(2);
        }
    };
    match run(&cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            // One line: the error and its causes, outermost first, each once.
            eprintln!("{binary}: error: {}", one_line(&e));
            std::process::ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::one_line;

    #[derive(Debug, thiserror::Error)]
    #[error("disk full")]
    struct Inner;

    /// Names its source in its message and returns it from `source()`.
    #[derive(Debug, thiserror::Error)]
    #[error("writing out.png: {source}")]
    struct Outer {
        source: Inner,
    }

    // See: issue 32, item 5 (every error printed twice).
    #[test]
    fn a_cause_named_in_the_message_is_said_once() {
        let err = anyhow::Error::from(Outer { source: Inner });
        assert_eq!(format!("{err:#}"), "writing out.png: disk full: disk full");
        assert_eq!(one_line(&err), "writing out.png: disk full");
    }

    #[test]
    fn context_and_unnamed_causes_are_kept_in_order() {
        let err = anyhow::Error::from(Inner).context("rendering");
        assert_eq!(one_line(&err), "rendering: disk full");
    }
}
