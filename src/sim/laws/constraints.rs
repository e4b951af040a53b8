//! Constraint laws, corrections of positions after the step: a spring or bar
//! brought to a length (the stretch limit, a bar), XPBD's correction of a spring
//! of compliance `1/k`, the speed limit, and the tear test.

use glam::DVec3;

use super::forces::{DEGENERATE_LENGTH2, EPSILON_LENGTH};
use super::{Lanes, V3};

/// The factor `s` that brings the ends of a spring of vector `d = x_a - x_b` to
/// length `goal`, with `w = w_a + w_b` their inverse masses summed: `x_a -= w_a s
/// d`, `x_b += w_b s d`, with `s = (l - goal) / (l w)`, `l = |d|`, for `l w > 0`:
/// coincident ends have no direction and ends both pinned do not move, which
/// the callers leave alone (the f64 engines before the call, the kernels by
/// their lanes' masks; a guard here cost the bars' relaxation 4% of its
/// instructions, a test that the f64 engines had made already).
#[inline(always)]
pub(crate) fn length_factor<L: Lanes>(d: V3<L>, goal: L, w: L) -> L {
    let l = d.length();
    (l - goal) / (l * w)
}

/// The correction `c` that brings particles at `xa` and `xb` (inverse masses `wa`,
/// `wb`) to distance `target(l)` when it returns a length: `xa -= wa c`, `xb += wb c`
/// (a pinned end stays put), `c = s d` with `s` the [`length_factor`]. `None` when
/// nothing moves: both ends pinned, coincident particles (no direction), or no
/// target.
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
    let d = V3::from(xa - xb);
    let l = d.length();
    if l <= EPSILON_LENGTH {
        return None;
    }
    let goal = target(l)?;
    Some(d.scale(length_factor(d, goal, w)).into())
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

/// XPBD's correction of a spring of vector `d = x_a - x_b`, whose first end moved
/// by `moved` more than its second since the start of the step, with `w = w_a +
/// w_b` its ends' inverse masses summed, coefficients `c` and `α̃ λ` its multiplier
/// so far times `α̃` (`None` for `λ = 0`): `(s, t)`, with `x_a -= w_a s d`, `x_b +=
/// w_b s d`, and the multiplier's change `Δλ = -t`.
///
/// The spring `(rest, k, b)` is the constraint `C = l - L` with compliance `α = 1/k`
/// (the same k, the same material), `α̃ = α / h²`, and the XPBD paper's damping
/// `γ = α̃ β̃ / h` with `β̃ = h² b`, i.e. `γ = b / (k h)`. One iteration:
/// `t = -Δλ = (C + α̃ λ + γ n·Δ) / ((1 + γ) w + α̃)` with `n = d / l`, `Δ = moved`,
/// and `s = t / l` (0 for coincident ends, which have no direction: their `t`
/// means nothing). The denominator is positive for `k > 0` ([`XpbdSpring::new`]).
#[inline(always)]
pub(crate) fn xpbd_factor<L: Lanes>(
    d: V3<L>,
    moved: V3<L>,
    w: L,
    c: XpbdCoefficients<L>,
    alpha_lambda: Option<L>,
) -> (L, L) {
    let l2 = d.dot(d);
    let inv_l = l2.rsqrt_or_zero(DEGENERATE_LENGTH2);
    // `C + α̃ λ` as `l - (L - α̃ λ)`: `α̃ λ` taken from the rest length, off the
    // chain of positions that a Gauss-Seidel pass waits on.
    let rest = match alpha_lambda {
        Some(alpha_lambda) => c.rest - alpha_lambda,
        None => c.rest,
    };
    let stretch = l2.mul_sub(inv_l, rest);
    let along = d.dot(moved) * inv_l;
    let t = c.gamma.mul_add(along, stretch) / c.one_gamma.mul_add(w, c.alpha);
    (t * inv_l, t)
}

/// XPBD's coefficients of a spring as [`xpbd_factor`] takes them, in lanes: its
/// rest length `L`, `α̃`, `γ` and `1 + γ` ([`XpbdSpring`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct XpbdCoefficients<L> {
    pub rest: L,
    pub alpha: L,
    pub gamma: L,
    pub one_gamma: L,
}

/// [`xpbd_factor`] for one spring between particles now at `x = [xa, xb]` that
/// were at `prev` at the start of the step, with inverse masses `wa`, `wb`, and
/// multiplier so far `λ`: `xa -= wa c`, `xb += wb c`, as [`length_correction`].
/// Returns `c` and the multiplier's change `Δλ`; `None` where nothing moves (both
/// ends pinned, coincident ends).
///
/// The grid and lattice engines call [`xpbd_factor`] on blocks of springs, a
/// colour class at a time (`grid_kernel/spring_passes/lines.rs`, as they do
/// [`length_factor`]), keeping `α̃ λ` rather than `λ`.
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
    let d = V3::from(x[0] - x[1]);
    if w == 0.0 || d.dot(d) <= DEGENERATE_LENGTH2 {
        return None;
    }
    let moved = V3::from((x[0] - prev[0]) - (x[1] - prev[1]));
    let c = XpbdCoefficients {
        rest: spring.rest,
        alpha: spring.alpha,
        gamma: spring.gamma,
        one_gamma: 1.0 + spring.gamma,
    };
    let (s, t) = xpbd_factor(d, moved, w, c, Some(spring.alpha * lambda));
    Some((d.scale(s).into(), -t))
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

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::overstretched;

    #[test]
    fn no_spring_breaks_on_a_non_finite_length() {
        let a = DVec3::ZERO;
        for b in [DVec3::splat(f64::NAN), DVec3::new(f64::INFINITY, 0.0, 0.0)] {
            assert!(!overstretched(a, b, 1.0, 0.1));
        }
        assert!(overstretched(a, DVec3::X * 1.2, 1.0, 0.1));
        assert!(!overstretched(a, DVec3::X * 1.05, 1.0, 0.1));
    }
}
