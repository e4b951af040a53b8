//! Fixed-step clock: wall time goes into an accumulator, physics comes out in whole
//! steps of `dt`, at most `max_steps` per frame. When a frame cannot keep up, the
//! excess time is dropped (the simulation runs slower than real time) instead of
//! piling up into ever longer frames (the "spiral of death"). The physics never
//! sees the frame rate.

/// Accumulator of wall time not yet simulated.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clock {
    accumulator: f64,
}

/// What one frame should simulate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSteps {
    /// Whole steps to run now.
    pub steps: u32,
    /// Simulated seconds dropped this frame because of the cap (0 when keeping up).
    pub dropped: f64,
}

impl Clock {
    /// Adds `elapsed` seconds (times `speed`) and returns the whole steps of `dt` due,
    /// at most `max_steps`.
    pub fn advance(&mut self, elapsed: f64, speed: f64, dt: f64, max_steps: u32) -> FrameSteps {
        if !(dt > 0.0 && elapsed.is_finite() && speed.is_finite()) {
            return FrameSteps {
                steps: 0,
                dropped: 0.0,
            };
        }
        self.accumulator += elapsed.max(0.0) * speed.max(0.0);
        let due = (self.accumulator / dt).floor();
        let steps = due.min(max_steps as f64);
        self.accumulator -= steps * dt;
        let mut dropped = 0.0;
        if due > steps {
            dropped = self.accumulator;
            self.accumulator = 0.0;
        }
        FrameSteps {
            steps: steps as u32,
            dropped,
        }
    }

    /// Puts `steps` steps of `dt` back as due: taken from [`Clock::advance`] but
    /// not run yet.
    pub fn defer(&mut self, steps: u32, dt: f64) {
        if dt > 0.0 {
            self.accumulator += f64::from(steps) * dt;
        }
    }

    /// Forgets unsimulated time (after a pause or reset).
    pub fn reset(&mut self) {
        self.accumulator = 0.0;
    }
}
