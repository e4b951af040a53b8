//! What advances: positions and velocities (and Verlet's history), and its energy.

use glam::DVec3;

use super::VerletHistory;

/// The state that advances: positions, velocities and, for Verlet, its history.
#[derive(Clone, Debug, Default)]
pub struct State {
    /// Positions in m.
    pub positions: Vec<DVec3>,
    /// Velocities in m/s.
    pub velocities: Vec<DVec3>,
    /// Position Verlet's memory (empty for the other integrators).
    pub verlet: VerletHistory,
    /// Simulated time in s.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
}

/// Energy in J, relative to the start positions for gravity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Energy {
    /// Kinetic energy `sum 1/2 m v²`.
    pub kinetic: f64,
    /// Gravitational potential `-sum m g·x`.
    pub gravity: f64,
    /// Elastic energy of springs `sum 1/2 k (l - L)²` and of ground contact.
    pub elastic: f64,
}

impl Energy {
    /// Kinetic plus potential.
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravity + self.elastic
    }
}
