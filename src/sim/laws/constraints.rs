//! Constraint laws, corrections of positions after the step: a spring or bar
//! brought to a length (the stretch limit, a bar), XPBD's correction of a spring
//! of compliance `1/k`, the speed limit, and the tear test.

use glam::DVec3;

use super::forces::EPSILON_LENGTH;

/// The correction `c` that brings particles at `xa` and `xb` (inverse masses `wa`,
/// `wb`) to distance `target(l)` when it returns a length: `xa -= wa c`, `xb += wb c`
/// (a pinned end stays put). `None` when nothing moves: both ends pinned, coincident
/// particles (no direction), or no target.
pub(crate) fn length_correction(
    xa: DVec3,
    xb: DVec3,
    wa: f64,
    wb: f64,
    target: impl Fn(f64) -> Option<f64>,
) -> Option<DVec3> {
    let w = wa + wb;
    if w == 0.0 {
        return None;
    }
    let d = xa - xb;
    let l = d.length();
    if l <= EPSILON_LENGTH {
        return None;
    }
    let goal = target(l)?;
    Some((l - goal) / (l * w) * d)
}

/// A spring as XPBD's pass sees it at step `h`: its rest length and its
/// coefficients ([`xpbd_coefficients`]), worked out once for every spring that
/// shares them (the grid engine's springs of one kind).
#[derive(Clone, Copy, Debug)]
pub(crate) struct XpbdSpring {
    pub(crate) rest: f64,
    /// `α̃ = 1 / (k h²)`.
    pub(crate) alpha: f64,
    /// `γ = b / (k h)`.
    pub(crate) gamma: f64,
}

impl XpbdSpring {
    /// The spring `(rest, k, b)` at step `h`; `None` for `k <= 0`, which
    /// constrains nothing.
    #[inline]
    pub(crate) fn new(rest: f64, k: f64, b: f64, h: f64) -> Option<Self> {
        let (alpha, gamma) = xpbd_coefficients(k, b, h);
        (k > 0.0).then_some(Self { rest, alpha, gamma })
    }
}

/// XPBD's correction of a `spring` between particles now at `x = [xa, xb]` that
/// were at `prev` at the start of the step, with inverse masses `wa`, `wb`, and its
/// multiplier so far `λ`: `xa -= wa c`, `xb += wb c`, as [`length_correction`].
/// Returns `c` and the multiplier's change `Δλ`.
///
/// The spring `(rest, k, b)` is the constraint `C = l - L` with compliance `α = 1/k`
/// (the same k, the same material), `α̃ = α / h²`, and the XPBD paper's damping
/// `γ = α̃ β̃ / h` with `β̃ = h² b`, i.e. `γ = b / (k h)`. One iteration:
/// `Δλ = -(C + α̃ λ + γ ∇C·(x - x_prev)) / ((1 + γ)(wa + wb) + α̃)`, `c = -Δλ n`
/// with `n = (xa - xb) / l`.
///
/// The grid and lattice engines do the same arithmetic in float32 lanes, a
/// colour class at a time (`grid_kernel/spring_passes.rs`, as they do
/// [`length_correction`]), the lattice's keeping `α̃ λ` rather than `λ`;
/// `tests/engines/fast_engine.rs`, `tests/no_allocation/grid_kernel.rs` and `tests/engines/lattice_kernel.rs`
/// hold them together.
#[inline(always)]
pub(crate) fn xpbd_correction(
    x: [DVec3; 2],
    prev: [DVec3; 2],
    wa: f64,
    wb: f64,
    spring: &XpbdSpring,
    lambda: f64,
) -> Option<(DVec3, f64)> {
    let w = wa + wb;
    if w == 0.0 {
        return None;
    }
    let d = x[0] - x[1];
    let l = d.length();
    if l <= EPSILON_LENGTH {
        return None;
    }
    let n = d * (1.0 / l);
    let moved = n.dot((x[0] - prev[0]) - (x[1] - prev[1]));
    let (alpha, gamma) = (spring.alpha, spring.gamma);
    // `C + α̃ λ`, with `α̃ λ` taken from the rest length, off the chain of
    // positions that a Gauss-Seidel pass waits on.
    let stretch = l - (spring.rest - alpha * lambda);
    let delta = -(stretch + gamma * moved) / ((1.0 + gamma) * w + alpha);
    Some((-delta * n, delta))
}

/// XPBD's `(α̃, γ) = (1 / (k h²), b / (k h))` for a spring `(k, b)` at step `h`.
#[inline]
pub(crate) fn xpbd_coefficients(k: f64, b: f64, h: f64) -> (f64, f64) {
    (1.0 / (k * h * h), b / (k * h))
}

/// The factor a particle's velocity `v` is scaled by under the speed limit
/// `max_speed` (m/s): `max_speed / |v|` when it is faster, else 1 (also for a
/// non-finite `v`, which is a divergence, not a speed to limit). Under Verlet the
/// update velocity `(x - x_prev) / h` is scaled by the same factor.
pub fn speed_limit(v: DVec3, max_speed: f64) -> f64 {
    let speed = v.length();
    if speed > max_speed && speed.is_finite() {
        max_speed / speed
    } else {
        1.0
    }
}

/// Whether a spring of rest length `rest` between `a` and `b` is past the tear
/// strain `tau`: longer than `(1 + tau) rest`, with a finite length (a NaN or an
/// infinity is a divergence, which its own check reports).
pub fn overstretched(a: DVec3, b: DVec3, rest: f64, tau: f64) -> bool {
    let l = (a - b).length();
    l.is_finite() && l > (1.0 + tau) * rest
}
