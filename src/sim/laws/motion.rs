//! Update rules: one step `h` of a particle's velocity and position under its
//! acceleration, one axis at a time.
//!
//! - symplectic Euler: `u' = u + h a`, moving with `u'`;
//! - explicit Euler: `u' = u + h a`, moving with the old `u`;
//! - position Verlet in velocity form: `u' = u + h a`, moving with `u'`, whose
//!   velocity estimate for the forces is `v' = u' + h/2 a` (with `u = (x -
//!   x_prev) / h` it is `x' = 2x - x_prev + h² a`).

use super::Lanes;

/// The update rule of [`update`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Method {
    SymplecticEuler,
    ExplicitEuler,
    Verlet,
}

/// One axis of a particle after a step: the velocity its position moves with
/// (`x' = x + h moving`, [`advanced`]), its update velocity `u'` and the velocity
/// `v'` the forces see next (`u'` but under Verlet).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Update<L> {
    pub moving: L,
    pub u: L,
    pub v: L,
}

/// One step `h` of `method` from update velocity `u` under acceleration `a`
/// ([`super::free_acceleration`]) for a particle of inverse mass `w`; `half_h =
/// h / 2`. A pinned particle (`w = 0`) is left at rest: its new velocities are 0.
#[inline(always)]
pub(crate) fn update<L: Lanes>(method: Method, u: L, a: L, w: L, h: L, half_h: L) -> Update<L> {
    let u_new = w.keep_if_positive(h.mul_add(a, u));
    match method {
        Method::SymplecticEuler => Update {
            moving: u_new,
            u: u_new,
            v: u_new,
        },
        Method::ExplicitEuler => Update {
            moving: u,
            u: u_new,
            v: u_new,
        },
        Method::Verlet => Update {
            moving: u_new,
            u: u_new,
            v: w.keep_if_positive(half_h.mul_add(a, u_new)),
        },
    }
}

/// A float position `x` after moving at `v` for `h`: `x + h v`. (Fixed-point
/// positions are an encoding that moves by the same `h v`, rounded to a unit.)
#[inline(always)]
pub(crate) fn advanced<L: Lanes>(x: L, h: L, v: L) -> L {
    h.mul_add(v, x)
}

/// [`update`] and [`advanced`] of a whole particle of inverse mass `w` in f64
/// (the f64 engine's): returns `x'`, `u'` and `v'`.
#[inline(always)]
pub(crate) fn step_particle(
    method: Method,
    x: glam::DVec3,
    u: glam::DVec3,
    a: glam::DVec3,
    w: f64,
    h: f64,
) -> [glam::DVec3; 3] {
    let mut out = [glam::DVec3::ZERO; 3];
    for axis in 0..3 {
        let next = update(method, u[axis], a[axis], w, h, 0.5 * h);
        out[0][axis] = advanced(x[axis], h, next.moving);
        out[1][axis] = next.u;
        out[2][axis] = next.v;
    }
    out
}
