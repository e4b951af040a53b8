//! The `cloth` binary: the desktop app when run without a subcommand, and the
//! command line (`run`, `info`, `scenes`, `screenshot`, `report`) otherwise.
// `cloth info`'s one `json!` object has more fields than the macro's default depth.
#![recursion_limit = "256"]

mod app;
mod cli;
mod render;

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let runtime_dir = quiet_missing_runtime_dir();
    let code = run();
    if let Some(dir) = runtime_dir {
        let _ = std::fs::remove_dir(dir);
    }
    code
}

fn run() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,winit=error"))
        .init();
    let args = cli::Args::parse();
    match args.command {
        Some(command) => cli::run_command(command),
        None => app::main(app::AppOptions {
            scene: args.scene,
            set: args.set,
            engine: args.engine,
        }),
    }
}

/// Mesa's Vulkan driver prints "error: XDG_RUNTIME_DIR is invalid or not set in
/// the environment." twice when that variable is missing (containers, CI, a
/// plain `ssh -X`), although nothing here needs it without a Wayland display. It
/// then gets a private directory of its own (returned, to remove at the end), so
/// launches are quiet.
fn quiet_missing_runtime_dir() -> Option<std::path::PathBuf> {
    let set =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if set || std::env::var_os("WAYLAND_DISPLAY").is_some() {
        return None;
    }
    let dir = std::env::temp_dir().join(format!("cloth-sandbox-runtime-{}", std::process::id()));
    #[cfg(unix)]
    let made = {
        use std::os::unix::fs::DirBuilderExt as _;
        std::fs::DirBuilder::new().mode(0o700).create(&dir)
    };
    #[cfg(not(unix))]
    let made = std::fs::create_dir(&dir);
    made.ok()?;
    // SAFETY: first thing in `main`, before any other thread exists.
    unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    Some(dir)
}
