//! cloth-sandbox: a mass-spring cloth simulator. This library is the headless part:
//! the simulation core ([`sim`]), scene files ([`scene`]) and the accuracy and
//! stability study ([`report`]). The `cloth` binary adds
//! the command line, the window, the renderer and the panel on top of it.

pub mod report;
pub mod scene;
pub mod sim;
