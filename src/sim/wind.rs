//! Wind: a constant air velocity (m/s) plus optional gusts.
//!
//! Gusts are a sum of a few sinusoids whose frequencies, phases and directions are
//! drawn once from `rand` with the scene's seed, so the wind is a pure function of
//! time: the same seed gives the same run, and multi-stage integrators (RK2, RK4)
//! see a consistent wind at their intermediate times.

use glam::DVec3;
use rand::{Rng, SeedableRng, rngs::StdRng};

const GUST_MODES: usize = 4;

/// Air velocity as a function of time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wind {
    /// Mean air velocity in m/s.
    pub base: DVec3,
    /// Gust amplitude in m/s (0: steady wind).
    pub gust: f64,
    modes: [(f64, f64, DVec3); GUST_MODES],
}

impl Wind {
    /// A wind of mean velocity `base` with gusts of amplitude `gust`, drawn from `seed`.
    pub fn new(base: DVec3, gust: f64, seed: u64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed);
        let modes = std::array::from_fn(|_| {
            let frequency = rng.random_range(0.2..1.5); // Hz: slow swells, like real gusts
            let phase = rng.random_range(0.0..std::f64::consts::TAU);
            let direction = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-0.3..0.3),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or_zero();
            (frequency, phase, direction)
        });
        Self { base, gust, modes }
    }

    /// Air velocity at time `t` (s).
    pub fn at(&self, t: f64) -> DVec3 {
        if self.gust == 0.0 {
            return self.base;
        }
        let scale = self.gust / GUST_MODES as f64;
        self.modes.iter().fold(self.base, |w, &(f, phase, dir)| {
            w + dir * (scale * (std::f64::consts::TAU * f * t + phase).sin())
        })
    }
}
