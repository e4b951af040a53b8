//! Measured critical steps: the largest `dt` at which a run stays stable, found by
//! bisection, beside the theoretical limit from the exact highest eigenfrequency
//! ([`super::eigen`], then [`critical_step`]), the estimate the app uses
//! ([`crate::sim::System::stability`]) and the Gershgorin bound
//! ([`crate::sim::stability::estimate`]).
//!
//! Stable means: over a fixed simulated time (at least [`MIN_STEPS`] steps) no value
//! becomes non-finite, the divergence check does not fire, and the mechanical energy
//! `E = kinetic + elastic` stays below [`ENERGY_FACTOR`] times its largest value in
//! an accurate run of the same scene (RK4 at a quarter of the theoretical limit).
//! An unstable mode grows geometrically, so the factor matters little; near their
//! limit the symplectic methods' energy oscillates by up to `1 / (1 - omega h / 2)`,
//! so a factor of 100 puts their measured limit within about 1% of the true one.

use super::eigen;
use super::precision::build;
use crate::scene::Resolved;
use crate::sim::stability::{critical_step, damping_ratio, estimate};
use crate::sim::{Integrator, System};

/// Fewest steps a stability run takes, whatever its step.
pub const MIN_STEPS: u64 = 20;
/// Energy growth beyond which a run counts as unstable.
pub const ENERGY_FACTOR: f64 = 100.0;
/// Iterations of power iteration.
pub const POWER_ITERATIONS: usize = 20_000;

/// What the bisection found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Measured {
    /// Stable at `lo`, unstable at `hi`.
    Between {
        /// Largest stable step found, s.
        lo: f64,
        /// Smallest unstable step found, s.
        hi: f64,
    },
    /// Stable at every step tried, up to this one (the search's cap).
    AtLeast(f64),
    /// Unstable at every step tried, down to this one (the search's floor).
    Below(f64),
    /// No step is stable in theory (explicit Euler and RK2 undamped: their
    /// amplitude grows at every step, RK2's by about `(omega h)⁴ / 8`), yet the
    /// criterion passed over the horizon up to `lo` and failed at `hi`: what the
    /// criterion measures there is how slowly the growth fills [`ENERGY_FACTOR`]
    /// within the horizon, not a stable step.
    Transient {
        /// Largest step whose growth stayed within the criterion over the horizon, s.
        lo: f64,
        /// Smallest step whose growth did not, s.
        hi: f64,
    },
}

impl Measured {
    /// The largest stable step, when one was bracketed.
    pub fn value(&self) -> Option<f64> {
        match *self {
            Self::Between { lo, .. } => Some(lo),
            _ => None,
        }
    }

    /// Short text for tables: `1.234e-3`, `>= 1.2e-1`, `< 1.0e-5`.
    pub fn text(&self) -> String {
        match *self {
            Self::Between { lo, .. } => format!("{lo:.4e}"),
            Self::AtLeast(x) => format!(">= {x:.3e} (cap)"),
            Self::Below(x) => format!("< {x:.3e} (none found)"),
            Self::Transient { lo, .. } => {
                format!(
                    "none (grows at every dt; stays within the bound over the horizon up to {lo:.3e})"
                )
            }
        }
    }
}

/// Largest kinetic plus elastic energy (J) over `horizon` seconds of an accurate run:
/// RK4 at a quarter of symplectic Euler's theoretical limit `2 / omega_max`.
pub fn reference_energy(scene: &Resolved, omega_max: f64, horizon: f64) -> f64 {
    let dt = 0.5 / omega_max.max(1e-9);
    let mut system = build(scene, Integrator::Rk4, dt);
    let steps = ((horizon / dt).ceil() as u64).max(MIN_STEPS);
    let mechanical = |s: &System| {
        let e = s.energy();
        e.kinetic + e.elastic
    };
    let mut worst = mechanical(&system);
    for _ in 0..steps {
        if system.step().is_err() {
            break;
        }
        worst = worst.max(mechanical(&system));
    }
    worst
}

/// Whether `integrator` at step `dt` stays stable over `horizon` seconds (and at
/// least [`MIN_STEPS`] steps): finite, the divergence check silent, and kinetic plus
/// elastic energy at most [`ENERGY_FACTOR`] times `reference_energy`. XPBD is
/// spared the last test: its material softens as its step grows (`Model::
/// stiffness_in_effect`), so a large step lets the cloth sag and swing far more
/// than the stiff reference, which says how soft it is, not that it blew up; the
/// divergence check (its energy budget counts the stiffness XPBD simulates) still
/// applies.
pub fn is_stable(
    scene: &Resolved,
    integrator: Integrator,
    dt: f64,
    horizon: f64,
    reference_energy: f64,
) -> bool {
    let mut system = build(scene, integrator, dt);
    let bound = ENERGY_FACTOR * reference_energy;
    let steps = ((horizon / dt).ceil() as u64).max(MIN_STEPS);
    for n in 0..steps {
        if system.step().is_err() {
            return false;
        }
        if n % 4 == 3 || n + 1 == steps {
            let e = system.energy();
            let mechanical = e.kinetic + e.elastic;
            let softened = integrator == Integrator::Xpbd;
            if mechanical.is_nan() || (mechanical > bound && !softened) {
                return false;
            }
        }
    }
    true
}

/// Largest stable step of `integrator` near `guess`: doubling up to `guess * up` or
/// halving down to `guess / down` to bracket it, then `iterations` geometric
/// bisections.
pub fn critical_dt(
    scene: &Resolved,
    integrator: Integrator,
    guess: f64,
    horizon: f64,
    reference_energy: f64,
    (down, up): (f64, f64),
    iterations: u32,
) -> Measured {
    let stable = |dt: f64| is_stable(scene, integrator, dt, horizon, reference_energy);
    let (mut lo, mut hi);
    if stable(guess) {
        lo = guess;
        hi = 2.0 * guess;
        while stable(hi) {
            lo = hi;
            hi *= 2.0;
            if hi > guess * up {
                return Measured::AtLeast(lo);
            }
        }
    } else {
        hi = guess;
        lo = 0.5 * guess;
        while !stable(lo) {
            hi = lo;
            lo *= 0.5;
            if lo < guess / down {
                return Measured::Below(hi);
            }
        }
    }
    for _ in 0..iterations {
        let mid = (lo * hi).sqrt();
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Measured::Between { lo, hi }
}

/// Theory for a scene: its exact highest frequency, the estimate the app uses and
/// the Gershgorin bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Theory {
    /// Highest angular frequency by power iteration, rad/s.
    pub omega_exact: f64,
    /// Power iterations taken.
    pub iterations: usize,
    /// The app's estimate of it ([`crate::sim::System::stability`]: Lanczos at the
    /// initial state), rad/s.
    pub omega_estimate: f64,
    /// Gershgorin bound, rad/s.
    pub omega_gershgorin: f64,
    /// Damping ratio of the exact highest mode.
    pub zeta_exact: f64,
    /// Damping ratio the app assumes (at its estimate).
    pub zeta_estimate: f64,
    /// Damping ratio at the Gershgorin frequency.
    pub zeta_gershgorin: f64,
}

impl Theory {
    /// Computes all three at the scene's initial state.
    pub fn of(scene: &Resolved) -> Self {
        let system = scene.build();
        let power = eigen::omega_max(system.model(), system.positions(), POWER_ITERATIONS, 1e-10);
        let stability = system.stability();
        let bound = estimate(system.model());
        Self {
            omega_exact: power.omega_max,
            iterations: power.iterations,
            omega_estimate: stability.omega_max,
            omega_gershgorin: bound.omega_max,
            zeta_exact: damping_ratio(system.model(), power.omega_max),
            zeta_estimate: stability.zeta,
            zeta_gershgorin: bound.zeta,
        }
    }

    /// Critical step of `integrator` on the exact highest mode.
    pub fn exact(&self, integrator: Integrator) -> Option<f64> {
        critical_step(integrator, self.omega_exact, self.zeta_exact)
    }

    /// Critical step the app's estimate gives.
    pub fn estimate(&self, integrator: Integrator) -> Option<f64> {
        critical_step(integrator, self.omega_estimate, self.zeta_estimate)
    }

    /// Critical step on the Gershgorin bound.
    pub fn gershgorin(&self, integrator: Integrator) -> Option<f64> {
        critical_step(integrator, self.omega_gershgorin, self.zeta_gershgorin)
    }
}

/// One row of the stability table.
#[derive(Clone, Debug)]
pub struct Row {
    /// Case name.
    pub case: String,
    /// Spring stiffness, N/m.
    pub stiffness: f64,
    /// Spring damping, N·s/m.
    pub damping: f64,
    /// Integrator.
    pub integrator: Integrator,
    /// Measured limit.
    pub measured: Measured,
    /// The theory.
    pub theory: Theory,
    /// Simulated time of each stability run, s.
    pub horizon: f64,
    /// Largest kinetic plus elastic energy of the accurate run, J.
    pub reference_energy: f64,
}

/// Measures every integrator in `integrators` on `scene`. The horizon is
/// `horizon_periods` times `2 / omega_exact` (symplectic Euler's undamped limit).
pub fn measure_case(
    case: &str,
    scene: &Resolved,
    integrators: &[Integrator],
    horizon_periods: f64,
    search: (f64, f64),
    iterations: u32,
) -> Vec<Row> {
    let theory = Theory::of(scene);
    let reference = 2.0 / theory.omega_exact;
    let horizon = horizon_periods * reference;
    let energy = reference_energy(scene, theory.omega_exact, horizon);
    integrators
        .iter()
        .map(|&integrator| {
            let guess = match theory.exact(integrator) {
                Some(c) if c.is_finite() => c,
                _ => reference,
            };
            let measured = critical_dt(
                scene, integrator, guess, horizon, energy, search, iterations,
            );
            // Where theory has no stable step, a bracket is the horizon's, not a
            // limit.
            let measured = match (measured, theory.exact(integrator)) {
                (Measured::Between { lo, hi }, None) => Measured::Transient { lo, hi },
                (measured, _) => measured,
            };
            Row {
                case: case.to_string(),
                stiffness: scene.stiffness,
                damping: scene.damping,
                integrator,
                measured,
                theory,
                horizon,
                reference_energy: energy,
            }
        })
        .collect()
}

/// Symplectic Euler's limit with spring damping `b` on a mode `omega`:
/// the positive root of `omega² h (h + 2 b/k) = 4`.
pub fn damped_symplectic_limit(omega: f64, b_over_k: f64) -> f64 {
    -b_over_k + (b_over_k * b_over_k + 4.0 / (omega * omega)).sqrt()
}
