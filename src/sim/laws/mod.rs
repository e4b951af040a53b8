//! The physical laws, each written once over [`Lanes`]: `f64` for one particle
//! (the f64 reference engine), a kernel's vectors for a block
//! of particles (the grid and lattice engines). An engine chooses the order in
//! which particles and springs are visited and how its state is stored; the
//! arithmetic of a law is here and nowhere else.
//!
//! | law | function |
//! |---|---|
//! | damped spring `f_a = ((-b (d·dv)/l + k L)/l - k) d` | [`spring_force`] ([`spring_factor`]) |
//! | aero drag on a triangle, a third to each vertex | [`triangle_drag`] ([`drag_factor`], [`air_velocity`]) |
//! | viscous air damping `-c v` | [`air_damped`] |
//! | ground penalty `k_c d - c_g v_y` at depth `d > 0` | [`ground_support`] |
//! | `a = F w + g` (0 when pinned, `w = 0`) | [`acceleration`], [`free_acceleration`] |
//! | symplectic Euler, explicit Euler, position Verlet | [`update`] |
//! | `x' = x + h v` on float positions | [`advanced`] |
//! | sphere and ground contact with Coulomb friction | [`Contact::resolve_lanes`] |
//! | the sphere's surface point nearest a particle `d` from its centre, `r d / l` | [`surface_offset`] |
//! | a length restored (stretch limit `(1 + tau) L`, a bar): `s = (l - goal) / (l w)` | [`length_factor`] ([`length_correction`]) |
//! | XPBD's correction of a spring of compliance `1/k` | [`xpbd_factor`] ([`xpbd_correction`]) |
//! | a collider's push out, friction on the velocity relative to its surface | [`collide`] |
//! | the speed limit | [`speed_limit`] |
//! | the tear test `l > (1 + tau) L` | [`overstretched`] |
//!
//! Units are SI: m, m/s, N, kg. `Lanes::mul_add` is fused in the vector kernels
//! and rounded twice in `f64`, so the reference keeps plain IEEE arithmetic.

mod collide;
mod constraints;
mod contact;
mod forces;
mod motion;

pub(crate) use crate::sim::lanes::{Lanes, V3};
pub(crate) use collide::{collide, end_of_step_contacts};
pub(crate) use constraints::{
    XpbdCoefficients, XpbdSpring, length_correction, length_factor, xpbd_correction, xpbd_factor,
};
pub use constraints::{overstretched, speed_limit};
pub(crate) use contact::{Contact, Near, out_of_sphere, surface_offset};
pub use forces::EPSILON_LENGTH;
pub(crate) use forces::{
    SpringCoefficients, acceleration, air_damped, air_velocity, drag_factor, free_acceleration,
    ground_support, spring_factor, spring_force, triangle_drag,
};
pub(crate) use motion::{Method, advanced, step_particle, update};
