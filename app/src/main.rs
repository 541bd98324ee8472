//! `lodstudio`: the studio (no subcommand, or `open FILE`) and the batch CLI.
//!
//! Exit status (DESIGN.md): 0 success, 2 bad input with one line on stderr,
//! 1 any other failure. A panic prints one line, never a backtrace.

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown".into());
        let msg = msg.lines().next().unwrap_or_default();
        eprintln!("lodstudio: internal error: {msg}");
    }));
    match std::panic::catch_unwind(cli::run) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("lodstudio: {}", e.message().replace('\n', " "));
            ExitCode::from(e.code())
        }
        Err(_) => ExitCode::from(1),
    }
}
