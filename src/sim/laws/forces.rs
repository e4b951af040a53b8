//! Force laws: the damped spring, aerodynamic drag on a triangle, air damping,
//! the ground's penalty and the acceleration they give a particle.

use super::{Lanes, V3};

/// Below this length (m) a spring or triangle edge is degenerate: no direction.
pub const EPSILON_LENGTH: f64 = 1e-12;

/// Squared length under which a spring has no direction, hence no force.
pub(crate) const DEGENERATE_LENGTH2: f64 = EPSILON_LENGTH * EPSILON_LENGTH;

/// Added to `|v_rel|² |m|²` so that a triangle with no area or no relative wind
/// gives no drag without a test; it moves any other drag by under float32's
/// rounding wherever `|v_rel|² |m|²` is over 1e-23.
pub(crate) const DRAG_TINY: f64 = 1e-30;

/// A spring's coefficients as its force uses them: `-k` (N/m), `k L` (N) and
/// `-b` (N·s/m).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpringCoefficients<L> {
    pub neg_k: L,
    pub k_rest: L,
    pub neg_b: L,
}

impl SpringCoefficients<f64> {
    /// The coefficients of a spring of stiffness `k`, rest length `rest` and
    /// damping `b`.
    #[inline(always)]
    pub fn new(k: f64, rest: f64, b: f64) -> Self {
        Self {
            neg_k: -k,
            k_rest: k * rest,
            neg_b: -b,
        }
    }
}

/// The damped spring's force on its end `a` as a multiple of `d = x_a - x_b`:
/// `f_a = s d` with `s = (-b (d·dv)/l + k L)/l - k`, `l = |d|`, `dv = v_a - v_b`.
/// That is `-(k (l - L) + b (dv·u)) u` with `u = d / l`. Zero for coincident ends.
#[inline(always)]
pub(crate) fn spring_factor<L: Lanes>(d: V3<L>, dv: V3<L>, c: SpringCoefficients<L>) -> L {
    let l2 = d.dot(d);
    let along = d.dot(dv);
    let inv = l2.rsqrt_or_zero(DEGENERATE_LENGTH2);
    (c.neg_b * along)
        .mul_add(inv, c.k_rest)
        .mul_add(inv, c.neg_k)
}

/// The damped spring's force on its end `a` ([`spring_factor`] times `d`).
#[inline(always)]
pub(crate) fn spring_force<L: Lanes>(d: V3<L>, dv: V3<L>, c: SpringCoefficients<L>) -> V3<L> {
    d.scale(spring_factor(d, dv, c))
}

/// Aerodynamic drag on each vertex of a triangle whose edges' cross product is
/// `m` (`|m| = 2A`), moving at `v_rel` relative to the air, as a multiple of `m`:
/// `F = a m` with `a = neg_drag (v_rel·m) |v_rel| / |m|`, where `neg_drag = -ρ C_d
/// / 12` gives each vertex a third of `-1/2 ρ C_d A (v_rel·n) |v_rel| n`.
/// `|v_rel| / |m|` is taken as `|v_rel|² / sqrt(|v_rel|² |m|² + DRAG_TINY)`.
#[inline(always)]
pub(crate) fn drag_factor<L: Lanes>(m: V3<L>, v_rel: V3<L>, neg_drag: L) -> L {
    let m2 = m.dot(m);
    let vr2 = v_rel.dot(v_rel);
    let vm = v_rel.dot(m);
    let tiny = vr2.splat(DRAG_TINY);
    let ratio = vr2 * vr2.mul_add(m2, tiny).rsqrt();
    (neg_drag * vm) * ratio
}

/// A triangle's velocity relative to the air: its vertices' mean velocity less
/// the `wind`, `v_0 t + ((v_1 + v_2) t - wind)` with `t = 1/3` (a kernel that
/// scales velocities passes `t` and the wind scaled alike).
#[inline(always)]
pub(crate) fn air_velocity<L: Lanes>(v: [V3<L>; 3], wind: V3<L>, third: L) -> V3<L> {
    let rest = (v[1] + v[2]).zip(wind, |s, w| s.mul_sub(third, w));
    v[0].zip(rest, |a, r| a.mul_add(third, r))
}

/// The drag on each vertex of the triangle `x` whose vertices move at `v`, in a
/// `wind`, with `half_rho_cd = ρ C_d / 2`: [`drag_factor`] of the edges' cross
/// product at the [`air_velocity`].
#[inline(always)]
pub(crate) fn triangle_drag<L: Lanes>(
    x: [V3<L>; 3],
    v: [V3<L>; 3],
    wind: V3<L>,
    half_rho_cd: L,
) -> V3<L> {
    let v_rel = air_velocity(v, wind, half_rho_cd.splat(1.0 / 3.0));
    let m = (x[1] - x[0]).cross(x[2] - x[0]);
    let neg_drag = half_rho_cd * half_rho_cd.splat(-1.0 / 6.0);
    m.scale(drag_factor(m, v_rel, neg_drag))
}

/// A force component `f` with viscous air damping added: `f - c v`, written
/// `neg_c v + f` with `neg_c = -c`.
#[inline(always)]
pub(crate) fn air_damped<L: Lanes>(f: L, neg_c: L, v: L) -> L {
    neg_c.mul_add(v, f)
}

/// The ground's upward push (N) on particles `depth` m below it moving up at `vy`:
/// `k_c d - c_g v_y` where `d > 0`, else 0 (stiffness `k_c`, damping `c_g`).
#[inline(always)]
pub(crate) fn ground_support<L: Lanes>(depth: L, vy: L, k_c: L, c_g: L) -> L {
    depth.keep_if_positive(k_c.mul_sub(depth, c_g * vy))
}

/// A particle's acceleration along one axis under force `f` with inverse mass
/// `w` and gravity `g`: `f w + g`, and 0 for a pinned particle (`w = 0`).
#[inline(always)]
pub(crate) fn acceleration<L: Lanes>(f: L, w: L, g: L) -> L {
    w.keep_if_positive(free_acceleration(f, w, g))
}

/// [`acceleration`] as a free particle's, `f w + g` whatever `w`: for a step
/// that goes straight into [`super::update`], which keeps a pinned particle at
/// rest itself.
#[inline(always)]
pub(crate) fn free_acceleration<L: Lanes>(f: L, w: L, g: L) -> L {
    f.mul_add(w, g)
}
