//! When a run counts as diverged, and why: the one check every engine's run ends
//! with (the fast engines copy their state back to the f64 state for it).

use glam::DVec3;

use super::State;

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
}

impl Divergence {
    /// Simulated time at which it happened, in s.
    pub fn time(&self) -> f64 {
        match *self {
            Self::NonFinite { time, .. } | Self::Runaway { time, .. } => time,
        }
    }
}

/// Speeds above this (m/s) count as a runaway: nothing in a cloth moves at 100 km/s.
pub const RUNAWAY_SPEED: f64 = 1e5;
/// Distances from the start above this many start extents (plus 1 km) count as a runaway.
pub const RUNAWAY_EXTENT: f64 = 1e4;

/// Checks `state` for non-finite values, speeds over [`RUNAWAY_SPEED`] and particles
/// farther than `far` (m) from `start_center`.
pub(crate) fn check(state: &State, start_center: DVec3, far: f64) -> Result<(), Divergence> {
    let (time, step) = (state.time, state.steps);
    let mut max_speed2: f64 = 0.0;
    let mut max_dist2: f64 = 0.0;
    for (x, v) in state.positions.iter().zip(&state.velocities) {
        if !(x.is_finite() && v.is_finite()) {
            return Err(Divergence::NonFinite { time, step });
        }
        max_speed2 = max_speed2.max(v.length_squared());
        max_dist2 = max_dist2.max((*x - start_center).length_squared());
    }
    if max_speed2 > RUNAWAY_SPEED * RUNAWAY_SPEED {
        return Err(Divergence::Runaway {
            time,
            step,
            what: "a particle passed 100 km/s",
        });
    }
    if max_dist2 > far * far {
        let what = "a particle flew 10,000 scene sizes from the start";
        return Err(Divergence::Runaway { time, step, what });
    }
    Ok(())
}
