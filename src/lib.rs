//! cloth-sandbox: a mass-spring cloth simulator. This library is the headless part:
//! the simulation core ([`sim`]) and scene files ([`scene`]), plus what an
//! interactive front end needs without any GPU or window: the camera and picking
//! maths ([`view`]) and a running scene with live edits ([`session`]), and the
//! accuracy and stability study (`report`). The `cloth` binary adds the command
//! line, the window, the renderer and the panel on top.
//!
//! Features: `app` (default) builds the `cloth` binary with its command line,
//! window, renderer and panel; `report` (default, and enabled by `app`) adds the
//! `report` module and its plotting; `gpu` (enabled by `app`) adds the GPU
//! engine ([`gpu`], wgpu compute shaders). With `default-features = false` the library
//! depends on no window, GPU, command-line or plotting crate.
//!
//! Building a built-in scene, stepping it and reading the positions:
//!
//! ```rust
//! use cloth_sandbox::scene::{Edit, Scene};
//!
//! // A name from `builtin_scenes()`, or a path to a scene file; typed edits are
//! // checked as `--set width=8` is (`Scene::set` takes the text form).
//! let scene = Scene::load("cloth")?.with(Edit::Width(8))?.with(Edit::Height(8))?;
//! let mut system = scene.build()?;
//!
//! let dt = system.params().dt;
//! let steps = (0.5 / dt).round() as u64; // half a second
//! system.run(steps).expect("the default cloth stays stable");
//!
//! let positions = system.positions(); // one `glam::DVec3` per particle, in m
//! assert_eq!(positions.len(), 64);
//! let lowest = positions.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
//! println!("after {:.2} s the lowest particle is at y = {lowest:.3} m", system.time());
//! # Ok::<(), cloth_sandbox::scene::SceneError>(())
//! ```

pub mod export;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod limits;
#[cfg(feature = "report")]
pub mod report;
pub mod scene;
pub mod session;
pub mod sim;
pub mod view;
