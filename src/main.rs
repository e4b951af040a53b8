//! The `cloth` binary: the desktop app when run without a subcommand, and the
//! command line (`run`, `info`, `scenes`, `screenshot`, `report`) otherwise.

mod app;
mod cli;
mod render;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,winit=error"))
        .init();
    let args = cli::Args::parse();
    match args.command {
        Some(command) => cli::run_command(command),
        None => app::main(app::AppOptions {
            scene: args.scene,
            set: args.set,
        }),
    }
}
