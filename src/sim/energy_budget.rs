//! The energy check: a run whose mechanical energy climbs past anything its forces
//! could supply has diverged, even when nothing overflows (an unstable step whose
//! growth the springs' nonlinearity saturates).
//!
//! **What may raise the energy.** The mechanical energy `E` (kinetic, gravity,
//! spring and ground-contact elastic; [`super::Model::energy`]) of a run left alone
//! can only fall: spring, air and ground damping dissipate. It rises only by
//! 1. the user: a grab, a pin, a new parameter. Each such edit starts a new
//!    budget from the energy just after it ([`EnergyBudget::new`]), so the edit's
//!    own work is never counted against the run. Moving the particle already
//!    held is the exception: its work, the change in its springs' energy, is
//!    added to the budget in effect ([`EnergyBudget::add_work`]). A drag is then
//!    one budget, not one per mouse move (each a pass over the whole system), and
//!    a run that diverges while it is dragged still fills its budget, where a
//!    new budget at every move would keep granting it a new margin;
//! 2. the wind, through aerodynamic drag. Rather than summing `f·v dt` in every
//!    engine's hot loop, the budget allows what wind can hold in a cloth: the
//!    kinetic energy of moving at the strongest gust's speed, `1/2 M w²`, plus the
//!    work of the largest drag force on the whole area over the cloth's size,
//!    `1/2 ρ C_d A w² D`;
//! 3. the integrator. Symplectic Euler and Verlet conserve a modified energy; the
//!    true energy of an oscillation swings about it by up to a factor
//!    `(1 + r) / (1 - r)` at `r = dt / dt_crit` (19 at `r` = 0.9: the quadratic
//!    form `1/2 v² + 1/2 ω² x² - 1/2 h ω² x v` has eigenvalues `1 ± hω/2`), and a
//!    nonlinearity can take the square of that ([`swing`]). `dt_crit` is the
//!    estimate's ([`super::stability`]), whose frequency is never above the true
//!    one at the state it was found in (0.2% below it on the 256 x 256 cloth); a
//!    cloth that then sags stiffens a little (1.4% on the hanging 32 x 32 one).
//!    RK4 and implicit Euler lose energy inside their limits;
//! 4. the constraints: the stretch limit and the sphere move particles and give
//!    them the velocity `δ/h` of the move;
//! 5. a moving collider, which can throw the cloth at twice its surface's speed
//!    `u`: `2 M u²`.
//!
//! **The budget.** `E ≤ E_0 + margin`, with `margin = (SLACK + swing(r)) × scale`.
//! `scale` is the energy the system can legitimately hold: its free mass falling
//! its own size `M |g| D`, the wind's share above, the kinetic and elastic energy
//! it started from, and every spring stretched by 1% (so that a system at rest
//! with no gravity still has a scale). `SLACK` = 4 covers items 3 and 4 for the
//! other integrators; a diverging run grows geometrically, so any fixed margin is
//! passed within a bounded number of steps once its energy reaches it.
//!
//! **Cost.** The energy is one pass over particles and springs. The general engine
//! checks it every [`ENERGY_CHECK_STEPS`] steps; the fast engines when they copy
//! their state back, at most that far apart in their chunks, so no engine pays
//! anything per step.

use glam::DVec3;

use super::{Divergence, Energy, Integrator, Model, Stability, bounding_sphere};

/// Steps between energy checks (the fast engines check at their chunk boundaries,
/// at most this many steps apart).
pub const ENERGY_CHECK_STEPS: u64 = 1024;

/// The margin's part that does not depend on the step (see the module doc).
pub const SLACK: f64 = 4.0;

/// The margin, in multiples of the scale, of a system in which nothing oscillates
/// but self-collision may push against its bars (see [`EnergyBudget::new`]):
/// explicit Euler's drift in free fall, `1/2 M g² h t`, reaches it only after
/// about `200 D / (g h)` seconds (11 hours for a 2 m rope at 1/960 s).
pub const UNBOUNDED_SLACK: f64 = 100.0;

/// How much mechanical energy a run may hold before it counts as diverged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnergyBudget {
    /// Mechanical energy (J) when the budget was set: the start or the last edit.
    pub base: f64,
    /// The energy the system can legitimately hold (J), from the module doc.
    pub scale: f64,
    /// How far (J) the energy may rise above `base`: `(SLACK + swing(r)) ×
    /// scale`, or infinite for a system in which nothing oscillates.
    pub allowed: f64,
    /// `dt / dt_crit` of the stability estimate the budget was set with
    /// (infinite: no step is stable; 0: no limit), for `super::limiters`.
    pub margin: f64,
    /// Springs broken (torn or cut) when the budget was set.
    pub broken: usize,
    /// Springs when the budget was set.
    pub springs: usize,
}

impl EnergyBudget {
    /// The budget for `model` at `positions` now, whose energy is `energy`,
    /// stepped with stability numbers `stability`.
    pub fn new(model: &Model, positions: &[DVec3], energy: Energy, stability: &Stability) -> Self {
        let p = &model.params;
        let free_mass: f64 = (model.mass.iter().zip(&model.inv_mass))
            .filter(|(_, w)| **w > 0.0)
            .map(|(m, _)| m)
            .sum();
        let size = 2.0 * bounding_sphere(positions).1;
        // The applied force moves each free particle across the system too.
        let free = (0..model.mass.len())
            .filter(|&i| model.inv_mass[i] > 0.0)
            .count();
        let falling = (free_mass * p.gravity.length() + free as f64 * p.force.length()) * size;
        let wind = if model.terms.aero {
            let speed = model.wind.base.length() + model.wind.gust.abs();
            let area: f64 = (model.triangles.iter())
                .map(|t| {
                    let [a, b, c] = t.map(|i| positions[i as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum();
            let force = 0.5 * p.air_density * p.drag_coefficient.abs() * area * speed * speed;
            0.5 * free_mass * speed * speed + force * size
        } else {
            0.0
        };
        let strained: f64 = (model.springs.iter())
            .map(|s| 0.5 * model.stiffness_in_effect(s).abs() * (0.01 * s.rest).powi(2))
            .sum();
        // A moving collider can throw the cloth off at twice its surface's speed
        // (an elastic bounce).
        let fastest = (model.colliders.iter())
            .map(|c| c.surface_speed())
            .fold(0.0, f64::max);
        let thrown = 2.0 * free_mass * fastest * fastest;
        let scale =
            falling + wind + thrown + energy.kinetic.abs() + energy.elastic.abs() + strained;
        let scale = if scale.is_finite() { scale } else { f64::MAX };
        // Without springs or ground contact nothing oscillates, so there is no step
        // limit to pass: what the energy does there is the integrator's drift under
        // steady forces (explicit Euler's `1/2 M g² h t` in free fall), not divergence.
        // Unless self-collision is on: thicker than bars allow (a rope's particles
        // two 0.1 m bars apart kept 0.5 m apart), it pushes against them, and each
        // push's `δ / h` pumps energy in (350 kJ in 500 steps); it gets
        // `UNBOUNDED_SLACK` times the scale, which the drift takes hours to fill.
        let allowed = if stability.omega_max > 0.0 {
            (SLACK + swing(p.integrator, stability.margin)) * scale
        } else if p.self_collides() {
            UNBOUNDED_SLACK * scale
        } else {
            f64::INFINITY
        };
        Self {
            base: energy.total(),
            scale,
            allowed,
            margin: stability.margin,
            broken: model.broken_springs,
            springs: model.springs.len(),
        }
    }

    /// The user did `work` (J) on the system without starting a new budget (a
    /// held particle moved): the energy may rise by that much more, and the
    /// energy the system may legitimately hold grows by its size, with the margin
    /// in proportion.
    pub fn add_work(&mut self, work: f64) {
        if !work.is_finite() {
            return;
        }
        let scale = self.scale + work.abs();
        if self.scale > 0.0 && self.allowed.is_finite() {
            self.allowed *= scale / self.scale;
        }
        self.base += work;
        self.scale = scale;
    }

    /// The most energy (J) the run may hold.
    pub fn limit(&self) -> f64 {
        self.base + self.allowed
    }

    /// Whether `energy` is within the budget; the divergence, with its numbers, if
    /// not. `time` and `step` say when.
    pub fn check(&self, energy: Energy, time: f64, step: u64) -> Result<(), Divergence> {
        let total = energy.total();
        if total <= self.limit() {
            return Ok(());
        }
        Err(Divergence::EnergyGrowth {
            time,
            step,
            rise: total - self.base,
            allowed: self.allowed,
        })
    }
}

/// How far the energy of a bounded run may rise above its start, as a multiple of
/// the scale, for `integrator` at `dt / dt_crit = r` (see the module doc): the
/// square of the linear swing `s = (1 + r) / (1 - r)` for symplectic Euler and
/// Verlet inside their limit, nothing otherwise (past the limit there is no
/// bounded swing to allow for).
///
/// The linear swing alone is the room of a linear system, whose energy stays
/// within `s` of the modified energy the step conserves. A nonlinearity the
/// linearisation does not see moves the state across those orbits and may take
/// another factor `s`: the mass on a spring past its anchor (the spring through
/// zero length, where its force turns over) at `omega h` = 1.97, 1.99 and 1.995
/// holds 10,000, 14,100 and 186,000 times its start energy, bounded over 30,000
/// steps, against `s` = 132, 399 and 799 and `s²` = 17,500, 159,000 and 638,000.
/// The square matters only near the limit: 1.2 times `s` at `r` = 0.1, and the
/// room of a diverging run is still passed geometrically fast.
pub fn swing(integrator: Integrator, r: f64) -> f64 {
    match integrator {
        Integrator::SymplecticEuler | Integrator::Verlet if r < 1.0 => {
            let linear = (1.0 + r) / (1.0 - r);
            linear * linear
        }
        _ => 0.0,
    }
}
