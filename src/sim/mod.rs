//! The headless mass-spring core. It knows nothing of windows or GPUs.
//!
//! - `model`: parameters, colliders, topology: what stays fixed ([`Model`]);
//! - `state`: positions and velocities, what advances ([`State`]), and [`Energy`];
//! - `system`: [`System`], a model with its state and scratch space, and the step;
//! - `laws`: every physical law, once, over lanes of any width;
//! - `forces`, `integrators`, `implicit`, `constraints`: the physics of a step
//!   (the f64 general engine, the reference);
//! - [`grid_kernel`], `fast_path`: the fast engines and their hook
//!   into [`System::run`]; `duo`: its two threads handing over each step by
//!   spinning; `lanes`: float64 lanes, so that contact is written once for one
//!   particle and for a block of them;
//! - `colliders`: boxes, capsules, meshes and moving spheres the cloth meets;
//! - `self_collision`: particles of a cloth kept a thickness apart, with friction;
//! - `tearing`: springs that tear past a strain or are cut, and leave the model;
//! - `divergence`, `energy_budget`, `limiters`, [`stability`],
//!   `spectrum`, [`safe`]: when a run has blown up (runaways, energy past its
//!   budget, a blow-up a limiter holds back), the stable step from the spring
//!   network's highest frequency, and safe stepping;
//! - `springs`, `wind`, `clock`: springs and their adjacency, gusts, the
//!   fixed-step clock.
//!
//! State is structure-of-arrays; stepping allocates nothing.

pub(crate) mod clock;
pub(crate) mod colliders;
pub(crate) mod constraints;
pub(crate) mod divergence;
pub(crate) mod duo;
pub(crate) mod energy_budget;
pub(crate) mod fast_path;
pub(crate) mod forces;
pub(crate) mod grab;
pub mod grid_kernel;
pub(crate) mod implicit;
pub(crate) mod integrators;
pub(crate) mod lanes;
pub(crate) mod laws;
pub(crate) mod limiters;
pub(crate) mod model;
pub mod safe;
pub(crate) mod self_collision;
pub(crate) mod spectrum;
pub(crate) mod springs;
pub mod stability;
pub(crate) mod state;
pub(crate) mod system;
pub(crate) mod tearing;
pub(crate) mod verlet;
pub(crate) mod wind;

pub use clock::Clock;
pub use colliders::{Collider, ColliderMesh, Pose, Shape};
pub use divergence::{Divergence, RUNAWAY_EXTENT, RUNAWAY_SPEED, bounding_sphere, max_speed};
pub use energy_budget::{ENERGY_CHECK_STEPS, EnergyBudget};
#[cfg(feature = "gpu")]
pub(crate) use fast_path::Stepped;
pub use fast_path::{Engine, GridShape, PrecisionRule};
pub use forces::ForceTerms;
pub use grab::{Grab, HAND_REACH};
pub use grid_kernel::lattice::LatticeShape;
pub use integrators::Integrator;
pub use limiters::Activity as LimiterActivity;
pub use model::{Ground, Model, Params, Sphere, Topology};
pub use safe::{SafeStep, safe_step, safe_substeps};
pub use self_collision::{MAX_PAIRS_PER_PARTICLE, SelfCollision};
pub use springs::{Adjacency, Bar, BarPairs, Spring, SpringKind, SpringMaterial, SpringMaterials};
pub use stability::Stability;
pub use state::{Energy, State};
pub use system::{System, Workspace};
pub use verlet::VerletHistory;
pub use wind::Wind;
