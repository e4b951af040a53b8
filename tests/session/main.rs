//! What the app does, headless: the panel's parameter and typed edits, undo, redo
//! and defaults, saving and loading the setup, safe stepping at the sliders'
//! extremes, the fixed-step clock, and the camera and picking maths. The one test
//! that runs the `cloth` binary needs the `app` feature.

#[path = "../common/mod.rs"]
mod common;

mod clock;
mod cut_undo;
mod divergence_report;
mod gpu_session;
mod live_reference;
mod save_load;
mod session_params;
mod session_safe_stepping;
mod slider_ends;
mod typed_edits;
mod undo_defaults;
mod view_picking;
