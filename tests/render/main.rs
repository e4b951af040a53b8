//! Drawing through the real binary on whatever graphics adapter the machine has
//! (`cloth screenshot`, `cloth record`; the `app` feature): the picture, GPU
//! buffers within the adapter's limits, GIF and PNG recordings; and the
//! renderer itself, compiled into this test (`staging`): shadows, ground, sky,
//! the two sides of the cloth, tubes for chains, FXAA.
//!
//! Without any adapter the drawing tests print a note and pass, unless
//! `CLOTH_REQUIRE_ADAPTER` is set (CI sets it), in which case they fail.

#[path = "../binary/mod.rs"]
mod binary;
#[path = "../common/mod.rs"]
mod common;

#[allow(dead_code, unused_imports)]
#[path = "../../src/app/frame.rs"]
mod frame;
/// The binary's renderer and its frame building, as the binary compiles them
/// (what the tests do not call is dead code here).
#[allow(dead_code, unused_imports)]
#[path = "../../src/render/mod.rs"]
mod render;

mod gpu_buffer_limits;
mod gpu_engine;
mod offscreen;
mod record;
mod staging;
