//! Drawing through the real binary on whatever graphics adapter the machine has
//! (`cloth screenshot`, `cloth record`; the `app` feature): the picture, GPU
//! buffers within the adapter's limits, GIF and PNG recordings.
//!
//! Without any adapter the drawing tests print a note and pass, unless
//! `CLOTH_REQUIRE_ADAPTER` is set (CI sets it), in which case they fail.

#[path = "../binary/mod.rs"]
mod binary;
#[path = "../common/mod.rs"]
mod common;

mod gpu_buffer_limits;
mod offscreen;
mod record;
