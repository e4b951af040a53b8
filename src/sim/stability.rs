//! Stability estimate: how close the step `dt` is to the largest stable one.
//!
//! The highest angular frequency of the linearised spring network is bounded by
//! Gershgorin's theorem on `M^-1 K`: `omega_max <= sqrt(max_i 2 sum_j k_j / m_i)`,
//! summing the springs at particle `i` (and the ground's `k_c`). The critical step
//! of each integrator then follows from its amplification on the test oscillator
//! `x'' = -omega² x - 2 zeta omega x'`, where `zeta` is the damping ratio of that
//! highest mode: spring damping gives `zeta = (b/k) omega / 2` (the smallest `b/k`
//! over the springs), air damping `c / (2 m omega)`. Undamped, this gives
//! symplectic Euler and Verlet `2/omega`, RK4 `2 sqrt 2 / omega`, and no stable step
//! for explicit Euler and RK2; implicit Euler has no limit. Damped, position Verlet
//! reaches its limit sooner than symplectic Euler: its damping sees the velocity
//! half a step late. Air damping and the aerodynamic drag also bound the step on
//! their own, through the decay of a particle's velocity they cause (`decay_limit`):
//! the whole limit where nothing oscillates (a rope of bars), and implicit Euler's
//! only one, as it steps the drag explicitly. XPBD's springs are constraints, not
//! forces: its limit is symplectic Euler's (its prediction) on the forces it
//! integrates (the ground's penalty, air damping, drag), and none without them.

use glam::DVec3;

use super::{Integrator, Model, SpringKind, spectrum};

/// Stability numbers for a model and its step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stability {
    /// The highest angular frequency, rad/s (0 if nothing oscillates): the
    /// spectrum's at the positions where they were given ([`estimate_at`]), within
    /// about 1% below the true one; the Gershgorin bound otherwise.
    pub omega_max: f64,
    /// Gershgorin's upper bound on it, rad/s ([`omega_max_bound`]).
    pub omega_bound: f64,
    /// Damping ratio of the highest mode.
    pub zeta: f64,
    /// Largest stable step for the integrator in s; `None` for "no stable step"
    /// (explicit Euler or RK2 undamped) and `Some(inf)` for "no limit".
    pub dt_critical: Option<f64>,
    /// `dt / dt_critical`: below 1 is stable; 0 for an unconditionally stable
    /// method, infinite when no step is stable.
    pub margin: f64,
}

/// What the estimate reads of the springs, in one pass over them: each particle's
/// sum of spring stiffness (N/m), the part of it whose other end is free (a
/// pinned end is no degree of freedom, so it adds no off-diagonal term), and the
/// smallest `b/k` (s) over the springs; no springs where they are not a force
/// (XPBD's are constraints the step does not integrate).
struct SpringSums {
    stiffness: Vec<f64>,
    to_free: Vec<f64>,
    damping_per_stiffness: f64,
}

fn spring_sums(model: &Model) -> SpringSums {
    let mut stiffness = vec![0.0; model.mass.len()];
    let mut to_free = vec![0.0; model.mass.len()];
    let mut damping_per_stiffness = f64::INFINITY;
    let springs = if model.terms.springs {
        &model.springs[..]
    } else {
        &[]
    };
    let mut present = [false; SpringKind::ALL.len()];
    for s in springs {
        present[s.kind.index()] = true;
        let (a, b) = (s.a as usize, s.b as usize);
        let k = model.material(s.kind).stiffness;
        stiffness[a] += k;
        stiffness[b] += k;
        if model.inv_mass[b] > 0.0 {
            to_free[a] += k;
        }
        if model.inv_mass[a] > 0.0 {
            to_free[b] += k;
        }
    }
    // The smallest `b / k` of the kinds that have springs.
    for kind in SpringKind::ALL.into_iter().filter(|k| present[k.index()]) {
        let m = model.material(kind);
        if m.stiffness > 0.0 {
            damping_per_stiffness = damping_per_stiffness.min(m.damping / m.stiffness);
        }
    }
    SpringSums {
        stiffness,
        to_free,
        damping_per_stiffness,
    }
}

/// Gershgorin bound on the highest angular frequency (rad/s) of the model's springs
/// and ground contact, over free particles: `sqrt(max_i (sum_j k_j + sum_{j free}
/// k_j + k_c) / m_i)`, the largest row sum of `M^-1 K` over the free degrees of
/// freedom (one spring to a pinned end: `sqrt(k / m)`, exact). It needs no
/// positions, so it is the estimate where there are none; [`estimate_at`] refines
/// it with the network's own spectrum.
pub fn omega_max_bound(model: &Model) -> f64 {
    omega_max_of(model, &spring_sums(model))
}

fn omega_max_of(model: &Model, sums: &SpringSums) -> f64 {
    let ground = model.params.ground.map_or(0.0, |g| g.stiffness);
    let mut worst: f64 = 0.0;
    for (i, (&k, &to_free)) in sums.stiffness.iter().zip(&sums.to_free).enumerate() {
        if model.inv_mass[i] > 0.0 {
            worst = worst.max((k + to_free + ground) * model.inv_mass[i]);
        }
    }
    worst.sqrt()
}

/// Damping ratio of a mode of angular frequency `omega` (rad/s), from the springs'
/// smallest `b/k` and the air damping over the heaviest free particle.
pub fn damping_ratio(model: &Model, omega: f64) -> f64 {
    damping_ratio_of(model, &spring_sums(model), omega)
}

fn damping_ratio_of(model: &Model, sums: &SpringSums, omega: f64) -> f64 {
    if omega <= 0.0 {
        return 0.0;
    }
    let spring_ratio = sums.damping_per_stiffness;
    let spring_ratio = if spring_ratio.is_finite() {
        spring_ratio
    } else {
        0.0
    };
    let heaviest = (model.mass.iter().zip(&model.inv_mass))
        .filter(|(_, w)| **w > 0.0)
        .map(|(m, _)| *m)
        .fold(0.0, f64::max);
    let air = if model.terms.air_damping && heaviest > 0.0 {
        model.params.air_damping / (2.0 * heaviest * omega)
    } else {
        0.0
    };
    spring_ratio * omega / 2.0 + air
}

/// Estimate for `model` at its step `dt` with its integrator, on the Gershgorin
/// bound alone ([`omega_max_bound`]): what can be said without positions. A
/// system's own estimate, [`super::System::stability`], is [`estimate_at`] its
/// positions.
pub fn estimate(model: &Model) -> Stability {
    let areas = model.terms.aero.then(|| drag_areas(model));
    estimate_with(model, None, areas.as_deref())
}

/// Estimate for `model` linearised at `positions`: the highest frequency of its
/// spring network found by Lanczos iteration (`super::spectrum`), never above
/// the Gershgorin bound.
pub fn estimate_at(model: &Model, positions: &[DVec3]) -> Stability {
    let areas = model.terms.aero.then(|| drag_areas(model));
    let spectrum = spectrum::Cache::default();
    estimate_with(model, Some((positions, &spectrum)), areas.as_deref())
}

/// [`estimate`] (or [`estimate_at`] `positions`) given each particle's drag area
/// at rest ([`drag_areas`]; `None` where the model has no drag). Only the springs'
/// rest lengths and the triangles decide those areas, so a running system keeps
/// them across edits of its other coefficients.
/// `positions` come with the [`spectrum::Cache`] of the system they are of.
pub(crate) fn estimate_with(
    model: &Model,
    positions: Option<(&[DVec3], &spectrum::Cache)>,
    drag_areas: Option<&[f64]>,
) -> Stability {
    let sums = spring_sums(model);
    let omega_bound = omega_max_of(model, &sums);
    let omega_max = match positions {
        Some((x, cache)) if omega_bound > 0.0 => cache.omega_max(model, x).min(omega_bound),
        _ => omega_bound,
    };
    let zeta = damping_ratio_of(model, &sums, omega_max);
    let stepper = stepper(model.params.integrator);
    let decay = decay_limit(model, stepper, drag_areas.filter(|_| model.terms.aero));
    let dt_critical = critical_step(stepper, omega_max, zeta).map(|c| c.min(decay));
    let margin = match dt_critical {
        None => f64::INFINITY,
        Some(c) if c.is_infinite() => 0.0,
        Some(c) => model.params.dt / c,
    };
    Stability {
        omega_max,
        omega_bound,
        zeta,
        dt_critical,
        margin,
    }
}

/// The method whose step limit `integrator`'s is: XPBD predicts with symplectic
/// Euler, whose limit the forces it integrates (the ground's penalty) set; its
/// springs set none.
fn stepper(integrator: Integrator) -> Integrator {
    match integrator {
        Integrator::Xpbd => Integrator::SymplecticEuler,
        integrator => integrator,
    }
}

/// Largest step (s) at which the velocity damping that `stepper` integrates
/// explicitly decays rather than grows on the free particle it slows fastest: air
/// damping, `c / m`, and the aerodynamic drag, linearised at the relative speed it
/// may meet, `ρ C_d A s / m` (`A` from `drag_areas`, each particle's: [`drag_areas`]
/// at rest; `s`: the strongest wind, plus the
/// speed at which the particle would fall through still air). One step of the
/// decay `v' = -gamma v`, `g = gamma h`, stays within 1 up to `g = 2` for the Euler
/// methods and RK2, 2.785 for RK4 and 1 for position Verlet (whose velocity lags
/// half a step). Implicit Euler solves for air damping but steps the drag
/// explicitly, as explicit Euler would; XPBD predicts with symplectic Euler. The
/// oscillator of [`critical_step`] sees the damping only through its mode of
/// `omega_max`, over the heaviest particle; with nothing oscillating (bars alone:
/// the rope) this is the whole limit, and with springs the lower of the two.
/// Infinite when nothing damps explicitly.
fn decay_limit(model: &Model, stepper: Integrator, drag_areas: Option<&[f64]>) -> f64 {
    let air = if model.terms.air_damping {
        model.params.air_damping
    } else {
        0.0
    };
    let (stepper, air) = match stepper {
        Integrator::ImplicitEuler => (Integrator::ExplicitEuler, 0.0),
        Integrator::Xpbd => (Integrator::SymplecticEuler, air),
        stepper => (stepper, air),
    };
    let p = &model.params;
    let (k, gravity) = (p.half_rho_cd(), p.gravity.length());
    let wind = model.wind.base.length() + model.wind.gust.abs();
    let area = |i: usize| drag_areas.map_or(0.0, |a| a[i]);
    let gamma = (model.inv_mass.iter().enumerate()).fold(0.0, |fastest: f64, (i, &w)| {
        let area = area(i);
        // `ρ C_d A / m` times the wind, and times the speed of the fall through
        // still air, `sqrt(2 m g / (ρ C_d A))`.
        let drag = 2.0 * k * area * wind * w + (4.0 * k * area * gravity * w).sqrt();
        fastest.max(air * w + drag)
    });
    if gamma.is_nan() || gamma <= 0.0 {
        return f64::INFINITY;
    }
    // The oscillator's step with no stiffness and damping `gamma h = g` is stable
    // on `[0, g*]`; every method here is unstable by g = 8.
    let (mut lo, mut hi) = (0.0, 8.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if step_radius(stepper, 0.0, -mid) <= 1.0 + 1e-12 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo / gamma
}

/// The critical step of [`estimate`] (its `dt_critical`, `at_rest`) with the drag
/// also taken on the triangles' areas at `positions`: the lower of the two limits.
/// A soft cloth that hangs or blows stretched far past its rest length catches the
/// air on areas many times its rest ones, and the decay of its velocity that the
/// drag then causes bounds the step below the estimate at rest (the peers' cloth at
/// 128 x 128 hangs 20 m long from its 1 m of rest length, and in its 5 m/s wind
/// ran away on position Verlet at a step of 0.19 of the estimate). `at_rest` where
/// the model has no drag. One pass over the triangles.
pub fn dt_critical_at(model: &Model, positions: &[DVec3], at_rest: Option<f64>) -> Option<f64> {
    if !model.terms.aero || positions.len() != model.mass.len() {
        return at_rest;
    }
    let mut areas = vec![0.0; positions.len()];
    for &[a, b, c] in &model.triangles {
        let [pa, pb, pc] = [a, b, c].map(|i| positions[i as usize]);
        let third = (pb - pa).cross(pc - pa).length() / 6.0;
        for i in [a, b, c] {
            areas[i as usize] += third;
        }
    }
    let now = decay_limit(model, stepper(model.params.integrator), Some(&areas));
    at_rest.map(|c| c.min(now))
}

/// Each particle's share (m²) of the drag triangles' area at rest: a third of each
/// of its triangles', taken as `L1 L2 / 2` for the two shortest of the triangle's
/// edges that are springs (its area where they meet at a right angle, as on the
/// grid; more otherwise), and 0 for a triangle with fewer than two.
pub(crate) fn drag_areas(model: &Model) -> Vec<f64> {
    let rest = |a: u32, b: u32| {
        (model.adjacency().springs_of(a as usize))
            .map(|(s, _)| &model.springs[s])
            .find(|s| (s.a == b) || (s.b == b))
            .map(|s| s.rest)
    };
    let mut areas = vec![0.0; model.mass.len()];
    for &[a, b, c] in &model.triangles {
        // Missing edges sort last.
        let mut edges = [rest(a, b), rest(b, c), rest(c, a)].map(|l| l.unwrap_or(f64::INFINITY));
        edges.sort_by(f64::total_cmp);
        let share = edges[0] * edges[1] / 6.0;
        if share.is_finite() {
            for i in [a, b, c] {
                areas[i as usize] += share;
            }
        }
    }
    areas
}

/// Largest `h` such that `integrator` is stable for every step in `(0, h]` on the
/// oscillator of angular frequency `omega` and damping ratio `zeta`.
/// `Some(inf)`: no limit; `None`: unstable at every step.
pub fn critical_step(integrator: Integrator, omega: f64, zeta: f64) -> Option<f64> {
    if matches!(integrator, Integrator::ImplicitEuler | Integrator::Xpbd) || omega <= 0.0 {
        return Some(f64::INFINITY);
    }
    // Undamped, explicit Euler (|1 + i y| > 1) and RK2 (|R(i y)|² = 1 + y⁴/4) grow at
    // every step. Their growth at the scan's first step is below the tolerance that
    // lets the neutrally stable methods through, so the scan would report a tiny
    // finite limit instead: decide it here.
    if zeta <= 0.0 && matches!(integrator, Integrator::ExplicitEuler | Integrator::Rk2) {
        return None;
    }
    let stable = |h: f64| spectral_radius(integrator, omega * h, zeta) <= 1.0 + 1e-12;
    // Scan up in small factors to the first unstable step, then bisect. Heavy
    // damping of an explicit method can put the limit below the scan's start
    // (b = 1e9 N·s/m on a 10 g particle: about 1e-11 s): scan down to it first.
    let mut lo = 0.0;
    let mut hi = 1e-6 / omega;
    while !stable(hi) {
        lo = 0.5 * hi;
        if lo * omega < 1e-30 {
            return None;
        }
        if stable(lo) {
            break;
        }
        hi = lo;
    }
    while stable(hi) {
        lo = hi;
        hi *= 1.05;
        if hi * omega > 100.0 {
            return Some(f64::INFINITY);
        }
    }
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// Spectral radius of one step of size `h` (given as `omega h`) on the oscillator.
pub fn spectral_radius(integrator: Integrator, omega_h: f64, zeta: f64) -> f64 {
    step_radius(integrator, -omega_h * omega_h, -2.0 * zeta * omega_h)
}

/// Spectral radius of one step on `x'' = a = (k x + c v) / h²` (in units of the
/// step: `k = -(omega h)²`, `c = -2 zeta omega h`, or `c = -gamma h` for a decay
/// alone), in the state `(x, h v)` and, for Verlet, `h² a_prev`.
fn step_radius(integrator: Integrator, k: f64, c: f64) -> f64 {
    match integrator {
        Integrator::SymplecticEuler => {
            // h v' = h v + k x + c h v; x' = x + h v'.
            matrix_radius(1.0 + k, 1.0 + c, k, 1.0 + c)
        }
        Integrator::Verlet => {
            // Position Verlet damps its velocity estimate `v = u + h/2 a_prev` (`u =
            // (x - x_prev) / h`), half a step behind: `h² a = k x + c (h u + h² a_prev
            // / 2)`, `h u' = h u + h² a`, `x' = x + h u'`. Undamped, the last column
            // is 0 and this is symplectic Euler's step.
            cubic_radius([
                [1.0 + k, 1.0 + c, 0.5 * c],
                [k, 1.0 + c, 0.5 * c],
                [k, c, 0.5 * c],
            ])
        }
        Integrator::ImplicitEuler | Integrator::Xpbd => 0.0,
        Integrator::ExplicitEuler | Integrator::Rk2 | Integrator::Rk4 => {
            // Eigenvalues of the continuous system times h: l² - c l - k = 0.
            let disc = 0.25 * c * c + k;
            let roots = if disc < 0.0 {
                let im = (-disc).sqrt();
                [(0.5 * c, im), (0.5 * c, -im)]
            } else {
                let r = disc.sqrt();
                [(0.5 * c + r, 0.0), (0.5 * c - r, 0.0)]
            };
            let order = integrator.order();
            roots
                .iter()
                .map(|&(re, im)| taylor_amplification(re, im, order))
                .fold(0.0, f64::max)
        }
    }
}

/// Spectral radius of a 3x3 matrix: a real root of its characteristic polynomial
/// `l³ - t l² + s l - d` by bisection, then the quadratic left.
fn cubic_radius(m: [[f64; 3]; 3]) -> f64 {
    let t = m[0][0] + m[1][1] + m[2][2];
    let s = (m[0][0] * m[1][1] - m[0][1] * m[1][0])
        + (m[0][0] * m[2][2] - m[0][2] * m[2][0])
        + (m[1][1] * m[2][2] - m[1][2] * m[2][1]);
    let d = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    let p = |l: f64| ((l - t) * l + s) * l - d;
    // Every root lies within Cauchy's bound; p < 0 below it and > 0 above.
    let bound = 1.0 + t.abs().max(s.abs()).max(d.abs());
    let (mut lo, mut hi) = (-bound, bound);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if p(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let r = 0.5 * (lo + hi);
    // p(l) = (l - r)(l² + b l + c).
    let b = r - t;
    let c = s + r * b;
    let disc = 0.25 * b * b - c;
    let pair = if disc >= 0.0 {
        let root = disc.sqrt();
        (-0.5 * b + root).abs().max((-0.5 * b - root).abs())
    } else {
        c.abs().sqrt()
    };
    r.abs().max(pair)
}

/// `|sum_{k=0}^{order} z^k / k!|` for complex `z = re + i im`: the amplification of an
/// explicit Runge-Kutta method of that order and stage count.
fn taylor_amplification(re: f64, im: f64, order: u32) -> f64 {
    let (mut term_re, mut term_im) = (1.0, 0.0);
    let (mut sum_re, mut sum_im) = (1.0, 0.0);
    for k in 1..=order {
        let (r, i) = (term_re * re - term_im * im, term_re * im + term_im * re);
        term_re = r / k as f64;
        term_im = i / k as f64;
        sum_re += term_re;
        sum_im += term_im;
    }
    (sum_re * sum_re + sum_im * sum_im).sqrt()
}

fn matrix_radius(a11: f64, a12: f64, a21: f64, a22: f64) -> f64 {
    let trace = a11 + a22;
    let det = a11 * a22 - a12 * a21;
    let disc = trace * trace / 4.0 - det;
    if disc >= 0.0 {
        let r = disc.sqrt();
        (trace / 2.0 + r).abs().max((trace / 2.0 - r).abs())
    } else {
        det.abs().sqrt()
    }
}
