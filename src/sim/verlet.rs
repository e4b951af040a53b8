//! [`VerletHistory`]: what position Verlet remembers between steps, and how it is
//! started, kept honest when the user moves a particle, and exchanged with the
//! fast engines (which keep it as the update velocity `u = (x - x_prev) / h`).

use glam::DVec3;

use super::{Model, Workspace};

/// Position Verlet's memory: the previous positions and accelerations. Empty for
/// the other integrators.
#[derive(Clone, Debug, Default)]
pub struct VerletHistory {
    /// Positions one step ago, in m.
    pub positions: Vec<DVec3>,
    /// Accelerations of the previous step, in m/s².
    pub accelerations: Vec<DVec3>,
}

impl VerletHistory {
    /// Whether there is a history for `n` particles.
    pub fn covers(&self, n: usize) -> bool {
        self.positions.len() == n && self.accelerations.len() == n
    }

    /// Forgets the history (for the other integrators).
    pub(super) fn clear(&mut self) {
        *self = Self::default();
    }

    /// A history consistent with velocities `v` at positions `x` and time `t`:
    /// `x_prev = x - h v + h²/2 a`, so that Verlet's velocity estimate
    /// `(x - x_prev)/h + h/2 a_prev` starts equal to `v`.
    pub(super) fn restart(
        &mut self,
        model: &Model,
        x: &[DVec3],
        v: &[DVec3],
        t: f64,
        work: &mut Workspace,
    ) {
        let h = model.params.dt;
        work.fit_forces(model);
        let a = &mut work.accelerations;
        model.accelerations(x, v, t, &mut work.spring_forces, a);
        self.positions = (x.iter().zip(v).zip(a.iter()))
            .map(|((&x, &v), &a)| x - h * v + 0.5 * h * h * a)
            .collect();
        self.accelerations.clone_from(a);
    }

    /// After the user moved, pinned or released particle `i` (now at `x` with
    /// velocity `v`), its history must not remember the old motion.
    pub(super) fn forget_motion(&mut self, i: usize, x: DVec3, v: DVec3, h: f64) {
        if let Some(prev) = self.positions.get_mut(i) {
            *prev = x - h * v;
            self.accelerations[i] = DVec3::ZERO;
        }
    }

    /// The update velocities `(x - x_prev) / h` the fast engines keep, or `None`
    /// without a history for `x`.
    pub(super) fn update_velocities(&self, x: &[DVec3], h: f64) -> Option<Vec<DVec3>> {
        if !self.covers(x.len()) {
            return None;
        }
        Some(
            (x.iter().zip(&self.positions))
                .map(|(&x, &prev)| (x - prev) / h)
                .collect(),
        )
    }

    /// The history from a fast engine's update velocities `u` (which `fill`
    /// writes): `x_prev = x - h u`, and the last acceleration from the velocity
    /// estimate `v = u + h/2 a`. Does nothing without a history for `x`.
    pub(super) fn set_from_update_velocities(
        &mut self,
        x: &[DVec3],
        v: &[DVec3],
        h: f64,
        fill: impl FnOnce(&mut [DVec3]),
    ) {
        if !self.covers(x.len()) {
            return;
        }
        let u = &mut self.accelerations;
        fill(u);
        for i in 0..x.len() {
            self.positions[i] = x[i] - h * u[i];
            u[i] = (v[i] - u[i]) * (2.0 / h);
        }
    }
}
