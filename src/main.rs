//! The `cloth` binary: the desktop app when run without a subcommand, and the
//! headless command line (`run`, `info`, `scenes`, ...) otherwise.

mod cli;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let args = cli::Args::parse();
    match args.command {
        Some(command) => cli::run_command(command),
        None => run_app(),
    }
}

/// The desktop app (its own module lands separately).
fn run_app() -> ExitCode {
    eprintln!(
        "error: the desktop app is not part of this build yet; try `cloth run --scene cloth`"
    );
    ExitCode::from(2)
}
