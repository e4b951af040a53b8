//! cloth-sandbox: a mass-spring cloth simulator. This library is the headless part:
//! the simulation core ([`sim`]) and scene files ([`scene`]), plus what an
//! interactive front end needs without any GPU or window: the camera and picking
//! maths ([`view`]) and a running scene with live edits ([`session`]), and the
//! accuracy and stability study ([`report`]). The `cloth` binary adds the command
//! line, the window, the renderer and the panel on top.

#[cfg(feature = "report")]
pub mod report;
pub mod scene;
pub mod session;
pub mod sim;
pub mod view;
