//! [`Grab`]: the particle the user holds with the mouse, and where.

use glam::DVec3;

use super::State;

/// A particle held at a target position until released. While held it has zero
/// inverse mass (it moves only with the hand) and pulls its neighbours through
/// their springs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grab {
    /// The particle's index.
    pub particle: usize,
    /// Where the hand holds it, in m.
    pub target: DVec3,
}

impl Grab {
    /// Puts the particle at the target, at rest, with no Verlet memory of how it
    /// got there (`h` is the step).
    pub(super) fn hold(self, state: &mut State, h: f64) {
        let i = self.particle;
        state.positions[i] = self.target;
        state.velocities[i] = DVec3::ZERO;
        state.verlet.forget_motion(i, self.target, DVec3::ZERO, h);
    }
}
