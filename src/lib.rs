//! cloth-sandbox: a mass-spring cloth simulator. This library is the headless part:
//! the simulation core ([`sim`]) and scene files ([`scene`]). The `cloth` binary adds
//! the command line, the window, the renderer and the panel on top of it.

pub mod scene;
pub mod sim;
