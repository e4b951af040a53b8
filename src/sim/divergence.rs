//! When a run counts as diverged, and why: the one check every engine's run ends
//! with (the fast engines copy their state back to the f64 state for it).

use glam::DVec3;

use super::State;
use super::limiters::Limiter;

/// Why a simulation was stopped.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Divergence {
    /// A position or velocity became NaN or infinite.
    #[error("a position or velocity became non-finite at t = {time:.4} s (step {step})")]
    NonFinite {
        /// Simulated time in s.
        time: f64,
        /// Step count.
        step: u64,
    },
    /// Something flew off: a speed or distance beyond any plausible motion.
    #[error("the motion ran away at t = {time:.4} s (step {step}): {what}")]
    Runaway {
        /// Simulated time in s.
        time: f64,
        /// Step count.
        step: u64,
        /// Which limit was passed.
        what: &'static str,
    },
    /// The mechanical energy rose past anything the forces and the step could
    /// supply (`super::energy_budget`).
    #[error(
        "the energy rose {how_far} at t = {time:.4} s (step {step}): {rise:.3e} J above the start or the last edit, where the forces and the step can add {allowed:.3e} J",
        how_far = past_budget(*rise, *allowed)
    )]
    EnergyGrowth {
        /// Simulated time in s.
        time: f64,
        /// Step count.
        step: u64,
        /// How far the energy rose above the budget's base, in J.
        rise: f64,
        /// How far it may rise, in J.
        allowed: f64,
    },
    /// The step is past the stability limit and a limiter holds back the blow-up
    /// (`super::limiters`).
    #[error(
        "{name} held back a blow-up at t = {time:.4} s (step {step}): the step is past the stability limit ({past}) and the limiter holds {held}",
        name = limiter_name(*limiter),
        past = past_limit(*margin),
        held = limiter.holding(*count, *of)
    )]
    HeldBack {
        /// Simulated time in s.
        time: f64,
        /// Step count.
        step: u64,
        /// The limiter holding the largest share.
        limiter: Limiter,
        /// What it holds: particles or springs.
        count: usize,
        /// Of how many.
        of: usize,
        /// `dt / dt_crit` (infinite: no step is stable).
        margin: f64,
    },
}

/// "tearing", "the speed limit", "the stretch limit".
fn limiter_name(limiter: Limiter) -> &'static str {
    match limiter {
        Limiter::Tearing => "tearing",
        Limiter::SpeedLimit => "the speed limit",
        Limiter::StretchLimit => "the stretch limit",
    }
}

/// "dt / dt_crit = 3.125", or that no step is stable.
fn past_limit(margin: f64) -> String {
    if margin.is_finite() {
        format!("dt / dt_crit = {margin:.3}")
    } else {
        "no step of this integrator is stable here".to_string()
    }
}

impl Divergence {
    /// Step count at which it happened.
    pub fn step(&self) -> u64 {
        match *self {
            Self::NonFinite { step, .. }
            | Self::Runaway { step, .. }
            | Self::EnergyGrowth { step, .. }
            | Self::HeldBack { step, .. } => step,
        }
    }

    /// Simulated time at which it happened, in s.
    pub fn time(&self) -> f64 {
        match *self {
            Self::NonFinite { time, .. }
            | Self::Runaway { time, .. }
            | Self::EnergyGrowth { time, .. }
            | Self::HeldBack { time, .. } => time,
        }
    }
}

/// Speeds above this (m/s) count as a runaway: nothing in a cloth moves at 100 km/s.
pub const RUNAWAY_SPEED: f64 = 1e5;
/// Distances from the start above this many start extents (plus 1 km) count as a runaway.
pub const RUNAWAY_EXTENT: f64 = 1e4;

/// Where a run started and how big it was: the yardstick for runaways.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Runaway {
    /// Centre of the start positions, in m.
    pub center: DVec3,
    /// Radius of the start positions about `center`, in m.
    pub extent: f64,
}

impl Runaway {
    /// The yardstick for a run starting at `positions`.
    pub fn around(positions: &[DVec3]) -> Self {
        let (center, extent) = bounding_sphere(positions);
        Self { center, extent }
    }

    /// Distance from the start (m) past which a particle counts as a runaway.
    pub fn distance(&self) -> f64 {
        RUNAWAY_EXTENT * (self.extent + 0.1) + 1000.0
    }

    /// Whether the largest squared speed and squared distance from `center` of a
    /// state are within bounds (the fast engines' cheap scan; false on NaN).
    pub fn plausible(&self, speed2: f64, dist2: f64) -> bool {
        speed2 <= RUNAWAY_SPEED * RUNAWAY_SPEED && dist2 <= self.distance().powi(2)
    }

    /// Checks `state` for non-finite values, speeds over [`RUNAWAY_SPEED`] and
    /// particles farther than [`Self::distance`] from the start.
    pub fn check(&self, state: &State) -> Result<(), Divergence> {
        let (time, step) = (state.time, state.steps);
        let mut max_speed2: f64 = 0.0;
        let mut max_dist2: f64 = 0.0;
        for (x, v) in state.positions.iter().zip(&state.velocities) {
            if !(x.is_finite() && v.is_finite()) {
                return Err(Divergence::NonFinite { time, step });
            }
            max_speed2 = max_speed2.max(v.length_squared());
            max_dist2 = max_dist2.max((*x - self.center).length_squared());
        }
        if max_speed2 > RUNAWAY_SPEED * RUNAWAY_SPEED {
            return Err(Divergence::Runaway {
                time,
                step,
                what: "a particle passed 100 km/s",
            });
        }
        if max_dist2 > self.distance().powi(2) {
            let what = "a particle flew 10,000 scene sizes from the start";
            return Err(Divergence::Runaway { time, step, what });
        }
        Ok(())
    }
}

/// The largest speed (m/s) among `velocities`; NaN when any is not finite, so
/// that a broken state never reads as a plausible number (0 when empty).
pub fn max_speed(velocities: &[DVec3]) -> f64 {
    if velocities.iter().all(|v| v.is_finite()) {
        velocities.iter().map(|v| v.length()).fold(0.0, f64::max)
    } else {
        f64::NAN
    }
}

/// Centre and radius (m) of a sphere around the points, for runaway detection and framing.
pub fn bounding_sphere(points: &[DVec3]) -> (DVec3, f64) {
    let Some(&first) = points.first() else {
        return (DVec3::ZERO, 0.0);
    };
    let (lo, hi) = points
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let center = (lo + hi) * 0.5;
    (center, (hi - lo).length() * 0.5)
}

/// How far past its budget an energy rise of `rise` J went when `allowed` J were
/// allowed: "8.5x as far as its budget allows", or "past its budget" where the
/// ratio means nothing (a budget of 0 J: a body built at a point, with no size for
/// gravity or the wind to work over).
fn past_budget(rise: f64, allowed: f64) -> String {
    let ratio = rise / allowed;
    if allowed > 0.0 && ratio.is_finite() {
        format!("{ratio:.1}x as far as its budget allows")
    } else {
        "past its budget".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The message gives the ratio where there is one, and no "inf" or "NaN" where
    /// the budget was 0 J (the drape built at rest length 0 on XPBD read "rose infx").
    #[test]
    fn an_energy_growth_reads_as_a_ratio_or_past_a_budget_of_nothing() {
        let growth = |rise, allowed| {
            Divergence::EnergyGrowth {
                time: 0.2,
                step: 200,
                rise,
                allowed,
            }
            .to_string()
        };
        let some = growth(3.853e3, 1.478e2);
        assert!(some.contains("26.1x as far as its budget allows"), "{some}");
        for none in [growth(4.2e7, 0.0), growth(0.0, 0.0)] {
            assert!(none.contains("rose past its budget"), "{none}");
            assert!(!none.contains("inf") && !none.contains("NaN"), "{none}");
        }
    }
}
