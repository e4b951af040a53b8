//! The `cloth` command line as a user runs it (`CARGO_BIN_EXE_cloth`, so the `app`
//! feature): exit codes, output and error messages, `--dump` files, run limits,
//! divergence diagnostics and `cloth report --out`.

#[path = "../binary/mod.rs"]
mod binary;
#[path = "../common/mod.rs"]
mod common;

mod command_line;
mod divergence_diagnostics;
mod dump_output;
mod report_out;
mod run_limits;
