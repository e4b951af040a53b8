//! Running the `cloth` binary as a user does, for the tests of the command line
//! (only with the `app` feature: a group that includes this module declares it
//! `#[cfg(feature = "app")]` or has `required-features = ["app"]`).

#![allow(dead_code)]

use std::process::{Command, Output};

/// Runs `cloth` with `args` and waits for it.
pub fn cloth(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cloth"))
        .args(args)
        .output()
        .expect("runs")
}

/// What it printed on standard output.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// What it printed on standard error.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
