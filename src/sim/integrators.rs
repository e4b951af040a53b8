//! Time integrators for `x' = v`, `v' = a(x, v, t)`, one step of `h = dt`.
//!
//! | method | order | stability on `x'' = -omega² x` (undamped) |
//! |---|---|---|
//! | explicit (forward) Euler (seed 000) | 1 | unstable at every `h`; with damping ratio `zeta`, `h < 2 zeta / omega` |
//! | symplectic (semi-implicit) Euler, the default | 1 | `h < 2 / omega`; with spring damping `omega² h (h + 2 b/k) < 4` |
//! | position Verlet (seeds 001, 004) | 2 | `h < 2 / omega` |
//! | RK2, explicit midpoint | 2 | unstable at every `h` without damping (\|R(i y)\| > 1) |
//! | RK4, classic (seed 003) | 4 | `h < 2 sqrt(2) / omega` |
//! | implicit Euler, linearised (Baraff & Witkin 1998) | 1 | unconditionally stable |
//! | XPBD, one iteration per step (Macklin et al. 2016, 2019) | 1 | no limit from the springs |
//!
//! Pinned and grabbed particles have zero inverse mass, so their acceleration is zero
//! and, starting at rest, they never move.

use glam::DVec3;

use super::laws::{Method, step_particle};
use super::{Model, State, VerletHistory, Workspace, implicit};

/// Integration method, chosen at run time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Integrator {
    /// Forward Euler: `x += h v; v += h a(x, v)`, both from the old state. Order 1.
    ExplicitEuler,
    /// Semi-implicit Euler: `v += h a(x, v); x += h v` (new velocity). Order 1, symplectic.
    #[default]
    SymplecticEuler,
    /// Position Verlet: `x_next = 2x - x_prev + h² a`. Order 2.
    Verlet,
    /// Explicit midpoint Runge-Kutta. Order 2.
    Rk2,
    /// Classic fourth-order Runge-Kutta. Order 4.
    Rk4,
    /// Backward Euler linearised once per step and solved by conjugate gradients. Order 1.
    ImplicitEuler,
    /// Extended position-based dynamics (Macklin, Müller & Chentanez 2016) with one
    /// constraint iteration per step, the "small steps" of Macklin et al. (2019):
    /// every force but the springs moves the particles by symplectic Euler, then
    /// each spring is a distance constraint of compliance `1/k`
    /// (`laws::xpbd_correction`) and the moves become velocities.
    /// Order 1; no step limit from the springs, at any stiffness.
    Xpbd,
}

impl Integrator {
    /// Every integrator, in display order.
    pub const ALL: [Integrator; 7] = [
        Self::ExplicitEuler,
        Self::SymplecticEuler,
        Self::Verlet,
        Self::Rk2,
        Self::Rk4,
        Self::ImplicitEuler,
        Self::Xpbd,
    ];

    /// The name used in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::ExplicitEuler => "explicit-euler",
            Self::SymplecticEuler => "symplectic-euler",
            Self::Verlet => "verlet",
            Self::Rk2 => "rk2",
            Self::Rk4 => "rk4",
            Self::ImplicitEuler => "implicit-euler",
            Self::Xpbd => "xpbd",
        }
    }

    /// Parses a name from [`Self::name`], in any case and with `_` or a space for
    /// `-` (`Verlet`, `RK4`, `symplectic_euler`), as a newcomer may type it.
    pub fn from_name(name: &str) -> Option<Self> {
        let name = name.trim().to_ascii_lowercase().replace(['_', ' '], "-");
        Self::ALL.into_iter().find(|i| i.name() == name)
    }

    /// Theoretical order of accuracy (global error `O(h^order)`).
    pub fn order(self) -> u32 {
        match self {
            Self::ExplicitEuler | Self::SymplecticEuler | Self::ImplicitEuler | Self::Xpbd => 1,
            Self::Verlet | Self::Rk2 => 2,
            Self::Rk4 => 4,
        }
    }
}

impl std::fmt::Display for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Advances `state` by one step of `model.params.dt` (time is advanced by the caller).
pub fn step(model: &Model, state: &mut State, work: &mut Workspace) {
    let h = model.params.dt;
    let t = state.time;
    let p = &model.params;
    work.fit_forces(model);
    if p.integrator == Integrator::Xpbd || p.self_collision {
        // XPBD's damping and self-collision's friction measure the step's moves.
        work.step_start.clone_from(&state.positions);
    }
    match model.params.integrator {
        Integrator::ExplicitEuler | Integrator::SymplecticEuler | Integrator::Xpbd => {
            let a = &mut work.accelerations;
            model.accelerations(
                &state.positions,
                &state.velocities,
                t,
                &mut work.spring_forces,
                a,
            );
            // XPBD predicts with symplectic Euler; its springs are not a force term
            // (`ForceTerms::springs` is off) but constraints, applied after.
            let symplectic = model.params.integrator != Integrator::ExplicitEuler;
            for (((x, v), a), &w) in state
                .positions
                .iter_mut()
                .zip(&mut state.velocities)
                .zip(a.iter())
                .zip(&model.inv_mass)
            {
                (*x, *v) = euler_update(symplectic, *x, *v, *a, w, h);
            }
        }
        Integrator::Verlet => verlet(model, state, work, h, t),
        Integrator::Rk2 => rk2(model, state, work, h, t),
        Integrator::Rk4 => rk4(model, state, work, h, t),
        Integrator::ImplicitEuler => implicit::step(model, state, &mut work.implicit, h, t),
    }
}

/// One Euler step of a particle at `x` moving at `v` with acceleration `a` (of the
/// old state) and inverse mass `w`, `laws::update`: symplectic
/// Euler moves with the new velocity, explicit Euler with the old one. Returns the
/// new position and velocity.
#[inline]
pub fn euler_update(
    symplectic: bool,
    x: DVec3,
    v: DVec3,
    a: DVec3,
    w: f64,
    h: f64,
) -> (DVec3, DVec3) {
    let method = if symplectic {
        Method::SymplecticEuler
    } else {
        Method::ExplicitEuler
    };
    let [x, _, v] = step_particle(method, x, v, a, w, h);
    (x, v)
}

/// Position Verlet in velocity form ([`update`](super::laws::update)), its update velocity `u =
/// (x - x_prev) / h` taken from the positions. The velocity the forces see is the
/// second-order estimate `u' + h/2 a`, so damping keeps the method second order.
fn verlet(model: &Model, state: &mut State, work: &mut Workspace, h: f64, t: f64) {
    let a = &mut work.accelerations;
    model.accelerations(
        &state.positions,
        &state.velocities,
        t,
        &mut work.spring_forces,
        a,
    );
    let State {
        positions,
        velocities,
        verlet:
            VerletHistory {
                positions: prev_positions,
                accelerations: prev_accelerations,
            },
        ..
    } = state;
    for i in 0..positions.len() {
        let x = positions[i];
        let u = (x - prev_positions[i]) / h;
        let [next, _, v] = step_particle(Method::Verlet, x, u, a[i], model.inv_mass[i], h);
        prev_positions[i] = x;
        positions[i] = next;
        velocities[i] = v;
        prev_accelerations[i] = a[i];
    }
}

/// Explicit midpoint: `k1 = f(y)`, `y_mid = y + h/2 k1`, `y += h f(y_mid)`.
fn rk2(model: &Model, state: &mut State, work: &mut Workspace, h: f64, t: f64) {
    let Workspace {
        spring_forces,
        accelerations: a,
        x_tmp,
        v_tmp,
        ..
    } = work;
    let (x, v) = (&mut state.positions, &mut state.velocities);
    model.accelerations(x, v, t, spring_forces, a);
    for i in 0..x.len() {
        x_tmp[i] = x[i] + 0.5 * h * v[i];
        v_tmp[i] = v[i] + 0.5 * h * a[i];
    }
    model.accelerations(x_tmp, v_tmp, t + 0.5 * h, spring_forces, a);
    for i in 0..x.len() {
        x[i] += h * v_tmp[i];
        v[i] += h * a[i];
    }
}

/// Classic RK4 on the first-order system `(x, v)`: slopes `k1..k4` at `t`, `t + h/2`
/// (twice) and `t + h`, combined with weights `1, 2, 2, 1` over 6.
fn rk4(model: &Model, state: &mut State, work: &mut Workspace, h: f64, t: f64) {
    let Workspace {
        spring_forces,
        accelerations: a,
        x_tmp,
        v_tmp,
        dx_sum,
        dv_sum,
        ..
    } = work;
    let (x, v) = (&mut state.positions, &mut state.velocities);
    let n = x.len();
    model.accelerations(x, v, t, spring_forces, a);
    for i in 0..n {
        dx_sum[i] = v[i];
        dv_sum[i] = a[i];
        x_tmp[i] = x[i] + 0.5 * h * v[i];
        v_tmp[i] = v[i] + 0.5 * h * a[i];
    }
    // Stages 2 and 3: the stage's slope (v_tmp, a) weighs 2, and the next stage is
    // taken from the start state with that slope over h/2 (then over h).
    for next_step in [0.5 * h, h] {
        model.accelerations(x_tmp, v_tmp, t + 0.5 * h, spring_forces, a);
        for i in 0..n {
            let stage_v = v_tmp[i];
            dx_sum[i] += 2.0 * stage_v;
            dv_sum[i] += 2.0 * a[i];
            x_tmp[i] = x[i] + next_step * stage_v;
            v_tmp[i] = v[i] + next_step * a[i];
        }
    }
    model.accelerations(x_tmp, v_tmp, t + h, spring_forces, a);
    for i in 0..n {
        dx_sum[i] += v_tmp[i];
        dv_sum[i] += a[i];
        x[i] += h / 6.0 * dx_sum[i];
        v[i] += h / 6.0 * dv_sum[i];
    }
}
