//! [`Grab`]: the particle the user holds with the mouse, where the hand is, and
//! where the particle is held on its way there.

use glam::DVec3;

use super::State;

/// How far a held particle may move towards the hand in one step, in lengths of
/// the shortest spring or bar at it: a hand that jumps (a flick of the mouse, or
/// a slow frame) is followed over several steps rather than at once. Put 1.35 m
/// from its neighbours in one step, a particle of the fold scene's 4 cm cloth
/// threw one of them at 780 m/s through the cloth's layers, and the run ran away.
/// While the simulation is paused, each move of the hand moves the particle that
/// far; once it runs again, its steps take the particle the rest of the way, if
/// it is still held.
pub const HAND_REACH: f64 = 0.5;

/// A particle held at a position until released. While held it has zero inverse
/// mass (it moves only with the hand) and pulls its neighbours through their
/// springs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grab {
    /// The particle's index.
    pub particle: usize,
    /// Where the hand is, in m: where the particle goes.
    pub target: DVec3,
    /// Where the particle is held now, in m: the target, or on its way there
    /// ([`HAND_REACH`]).
    pub at: DVec3,
}

impl Grab {
    /// Holds `particle` at `target` at once.
    pub(super) fn new(particle: usize, target: DVec3) -> Self {
        Self {
            particle,
            target,
            at: target,
        }
    }

    /// Puts the particle where it is held, at rest, with no Verlet memory of how it
    /// got there (`h` is the step).
    pub(super) fn hold(self, state: &mut State, h: f64) {
        let i = self.particle;
        state.positions[i] = self.at;
        state.velocities[i] = DVec3::ZERO;
        state.verlet.forget_motion(i, self.at, DVec3::ZERO, h);
    }

    /// Whether the particle has yet to reach the hand.
    pub(super) fn trails(&self) -> bool {
        self.at != self.target
    }

    /// The place `reach` (m) closer to the target, or the target within reach.
    pub(super) fn towards_target(&self, reach: f64) -> DVec3 {
        let to_go = self.target - self.at;
        let distance = to_go.length();
        if distance <= reach {
            self.target
        } else {
            self.at + to_go * (reach / distance)
        }
    }
}
