//! The `cloth` command line as a user runs it (`CARGO_BIN_EXE_cloth`, so the `app`
//! feature): exit codes, output and error messages, `--dump` files, run limits,
//! divergence diagnostics and `cloth report --out`; the checks' honesty (the stability
//! estimate, limiters that hide a blow-up), crashes and hangs, outputs that never
//! replace inputs, and messages that name the cause.

#[path = "../binary/mod.rs"]
mod binary;
#[path = "../common/mod.rs"]
mod common;

mod command_line;
mod crash_hang_memory;
mod divergence_diagnostics;
mod dump_output;
mod engine_choice;
mod limiters_hide_no_blow_up;
mod messages;
mod outputs_never_overwrite;
mod report_out;
mod run_limits;
mod stability_checks;
