//! What every fast engine's run shares ([`FastEngine`]): steps in chunks with the
//! divergence check between them, the held particles, and the state copied into
//! the engine and back.

use glam::DVec3;

use super::{Ahead, CHUNK};
use crate::sim::energy_budget::ENERGY_CHECK_STEPS;
use crate::sim::grid_kernel::lattice::LatticeKernel;
use crate::sim::grid_kernel::{GridCloth, Precision, SpringNoise};
use crate::sim::{Divergence, Integrator, System};

impl System {
    /// The particles held in place (pinned or grabbed: inverse mass 0) with their
    /// positions exactly as the f64 state has them, after telling an engine which
    /// particles are held (`set_pinned(i, held)` for every particle): a float32
    /// engine holds them only to its precision, and puts them back on copying out.
    pub(super) fn held(&self, mut set_pinned: impl FnMut(usize, bool)) -> Vec<(usize, DVec3)> {
        let mut held = Vec::new();
        for (i, &w) in self.model.inv_mass.iter().enumerate() {
            set_pinned(i, w == 0.0);
            if w == 0.0 {
                held.push((i, self.state.positions[i]));
            }
        }
        held
    }

    /// Runs `n` steps on a fast engine in chunks of [`CHUNK`]. Simulated time
    /// advances by whole steps, as in the general path. After each chunk a cheap scan
    /// of the engine's own arrays; the f64 state and the full check (with the
    /// energy budget, and the message) every [`ENERGY_CHECK_STEPS`] steps (counted
    /// across runs), when the scan finds trouble, and at the end when `settle`.
    /// Without `settle` the engine may end the run ahead of the f64 state: see
    /// [`System::run_ahead`].
    ///
    /// When the scan finds a non-finite or runaway state, the steps since the f64
    /// state was last brought up to date (a full check, or [`System::settle`]) are
    /// run again one at a time from it, so that the divergence is reported at the
    /// step where it happened rather than at the end of its chunk.
    ///
    /// Returns the steps run: fewer than `n` when the engine's body outgrew its
    /// fixed-point unit ([`FastEngine::outgrown_unit`]), with the f64 state up to
    /// date; the caller runs the rest on the engine chosen again.
    pub(super) fn run_in_chunks<E: FastEngine>(
        &mut self,
        n: u64,
        engine: &mut E,
        settle: bool,
    ) -> Result<u64, Divergence> {
        let dt = self.model.params.dt;
        let mut done = 0;
        let mut from = match self.engines.ahead.take() {
            Some((_, time, steps)) => (time, steps),
            None => (self.state.time, self.state.steps),
        };
        if from.1 == self.state.steps
            && let Some(unit) = engine.outgrown_unit(dt)
        {
            // Loaded with a body spread past its unit (the f64 state is the
            // engine's): none of the run on it.
            self.engines.outgrown_unit = Some(unit);
            return Ok(0);
        }
        while done < n {
            let chunk = CHUNK.min(n - done);
            engine.advance(self, chunk as usize);
            done += chunk;
            self.engines.unchecked += chunk;
            for _ in 0..chunk {
                self.state.time += dt;
            }
            self.state.steps += chunk;
            let (speed2, dist2) = engine.extremes(self.runaway.center);
            let plausible = self.runaway.plausible(speed2, dist2);
            if !plausible && self.state.steps - from.1 > 1 {
                self.replay_one_by_one(engine, from);
            }
            let outgrown = engine.outgrown_unit(dt);
            let check = (settle && done == n) || self.engines.unchecked >= ENERGY_CHECK_STEPS;
            if check || !plausible || outgrown.is_some() {
                self.engines.unchecked = 0;
                engine.copy_back(self);
                self.check()?;
                from = (self.state.time, self.state.steps);
            }
            if outgrown.is_some() {
                // The body spread past what its fixed-point unit holds, and the
                // coarser unit is too noisy: the rest of the run goes to the kernel
                // the precision rule now chooses, from the state just copied back.
                self.engines.outgrown_unit = outgrown;
                break;
            }
        }
        if from.1 != self.state.steps {
            self.engines.ahead = Some((E::KIND, from.0, from.1));
        }
        Ok(done)
    }

    /// Brings the f64 state up to the fast engine's, if the engine ran ahead.
    pub(in crate::sim) fn catch_up(&mut self) {
        let Some((ahead, _, _)) = self.engines.ahead.take() else {
            return;
        };
        match ahead {
            Ahead::Grid => {
                if let Some(mut fast) = self.engines.grid.take() {
                    fast.copy_back(self);
                    self.engines.grid = Some(fast);
                }
            }
            Ahead::Lattice => {
                if let Some(mut lattice) = self.engines.lattice.take() {
                    lattice.copy_back(self);
                    self.engines.lattice = Some(lattice);
                }
            }
        }
    }

    /// After [`System::run_ahead`]: brings the f64 state up to the fast engine's
    /// and checks it in full, as [`System::run`] leaves it. Does nothing when the
    /// state was checked at this step already.
    pub fn settle(&mut self) -> Result<(), Divergence> {
        if self.engines.ahead.is_none() && self.engines.unchecked == 0 {
            return Ok(());
        }
        self.catch_up();
        self.engines.unchecked = 0;
        self.check()
    }

    /// The f64 state is about to change or be read outside the fast engines:
    /// brings it up to date first, and has the engines copy it in again before
    /// they next run.
    pub(in crate::sim) fn mark_changed(&mut self) {
        self.catch_up();
        self.engines.mark_stale();
        self.checked_energy = None;
    }

    /// The held particle `i` was put at `position`, at rest, in the f64 state (a
    /// grab moved by the mouse): the grid kernel, when it holds the f64 state,
    /// takes that one particle, so that dragging a particle does not reload the
    /// whole cloth at every move; the other engines, and Verlet (whose update
    /// velocities the hold resets), copy the whole state in again.
    pub(in crate::sim) fn held_particle_moved(&mut self, i: usize, position: DVec3) {
        let verlet = self.model.params.integrator == Integrator::Verlet;
        let moved_in_place = match &mut self.engines.grid {
            Some(grid) if grid.in_sync && !verlet => {
                match grid.held.iter_mut().find(|(j, _)| *j == i) {
                    Some(held) => {
                        held.1 = position;
                        grid.kernel.set_particle(i, position, DVec3::ZERO);
                        true
                    }
                    None => false,
                }
            }
            _ => false,
        };
        self.engines.mark_stale();
        if let Some(grid) = self.engines.grid.as_mut().filter(|_| moved_in_place) {
            grid.in_sync = true;
        }
        self.checked_energy = None;
    }

    /// Runs the steps from the last full check (`checked`: its time and step count,
    /// with its positions and velocities still in the f64 state) up to the current
    /// step again, one at a time, stopping at the first whose scan fails: the
    /// engine and the step count are left at that step.
    pub(super) fn replay_one_by_one(&mut self, engine: &mut impl FastEngine, from: (f64, u64)) {
        let dt = self.model.params.dt;
        let last = self.state.steps;
        (self.state.time, self.state.steps) = from;
        engine.load(self);
        while self.state.steps < last {
            engine.advance(self, 1);
            self.state.time += dt;
            self.state.steps += 1;
            let (speed2, dist2) = engine.extremes(self.runaway.center);
            if !self.runaway.plausible(speed2, dist2) {
                break;
            }
        }
    }

    /// Position Verlet's update velocities `(x - x_prev) / h` for a fast engine
    /// (`None` for the other integrators).
    pub(crate) fn verlet_update_velocities(&self) -> Option<Vec<DVec3>> {
        if self.model.params.integrator != Integrator::Verlet {
            return None;
        }
        let state = &self.state;
        (state.verlet).update_velocities(&state.positions, self.model.params.dt)
    }

    /// The f64 Verlet history from a fast engine's update velocities (which `fill`
    /// writes).
    pub(crate) fn set_verlet_history(&mut self, fill: impl FnOnce(&mut [DVec3])) {
        if self.model.params.integrator != Integrator::Verlet {
            return;
        }
        let state = &mut self.state;
        let h = self.model.params.dt;
        (state.verlet).set_from_update_velocities(&state.positions, &state.velocities, h, fill);
    }
}

#[cfg(feature = "gpu")]
impl System {
    /// Runs `n` steps on an engine outside the CPU's (the GPU engine): `advance`
    /// takes the system at the run's start and returns the state `n` steps of `dt`
    /// later. The held particles stay exactly where the f64 state has them, time
    /// advances by whole steps as in the general path, and the state is checked in
    /// full (the energy budget from the start state). Divergence is found at the
    /// end of the run, not at its step: the caller runs a frame at a time.
    pub(crate) fn run_outside<E>(
        &mut self,
        n: u64,
        advance: impl FnOnce(&System) -> Result<Stepped, E>,
    ) -> Result<Result<(), Divergence>, E> {
        self.mark_changed();
        self.budget();
        let stepped = advance(self)?;
        let dt = self.model.params.dt;
        for _ in 0..n {
            self.state.time += dt;
        }
        self.state.steps += n;
        let held: Vec<(usize, DVec3)> = self.held(|_, _| {});
        self.state.positions = stepped.positions;
        self.state.velocities = stepped.velocities;
        for (i, position) in held {
            self.state.positions[i] = position;
        }
        if let Some(u) = stepped.update_velocities {
            self.set_verlet_history(|out| out.copy_from_slice(&u));
        }
        self.engines.unchecked = 0;
        Ok(self.check())
    }
}

#[cfg(feature = "gpu")]
/// The state an outside engine's run ends in ([`System::run_outside`]).
pub(crate) struct Stepped {
    /// Positions in m.
    pub positions: Vec<DVec3>,
    /// Velocities in m/s.
    pub velocities: Vec<DVec3>,
    /// Position Verlet's update velocities `(x - x_prev) / h` (Verlet only).
    pub update_velocities: Option<Vec<DVec3>>,
}

/// What [`System::run_in_chunks`] needs of a fast engine.
pub(super) trait FastEngine {
    /// Which engine this is.
    const KIND: Ahead;
    /// `steps` steps of the system's `dt`, from the system's time.
    fn advance(&mut self, system: &System, steps: usize);
    /// The largest squared speed and squared distance from `center` (infinite on
    /// NaN).
    fn extremes(&self, center: DVec3) -> (f64, f64);
    /// The engine's state into the system's f64 state (and springs it broke into
    /// the model).
    fn copy_back(&mut self, system: &mut System);
    /// The system's f64 state into the engine (the reverse of `copy_back`).
    fn load(&mut self, system: &System);
    /// The unit (m) of the engine's fixed-point positions when the body has spread
    /// past what its spec's unit holds and the float32 noise at the unit it took
    /// instead is over [`Precision::NOISE_LIMIT`] (steps of `dt` s): the precision
    /// rule must then choose again.
    fn outgrown_unit(&self, dt: f64) -> Option<f64>;
}

/// [`FastEngine::outgrown_unit`] of a kernel keeping positions in `unit` (if fixed
/// point) for `spec`, at steps of `dt` s.
pub(super) fn outgrown(unit: Option<f64>, spec: &impl SpringNoise, dt: f64) -> Option<f64> {
    let noisy = |unit| spec.spring_noise(Err(unit), dt) > Precision::NOISE_LIMIT;
    unit.filter(|&unit| unit > spec.fixed_unit() && noisy(unit))
}

/// How a fast engine's state goes in and out: the same calls on each kernel.
pub(super) trait KernelState {
    fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]);
    fn set_update_velocities(&mut self, u: &[DVec3]);
    fn positions_into(&self, out: &mut [DVec3]);
    fn velocities_into(&self, out: &mut [DVec3]);
    fn update_velocities_into(&self, out: &mut [DVec3]);
}

macro_rules! kernel_state {
    ($($kernel:ty),*) => {$(
        impl KernelState for $kernel {
            fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) {
                <$kernel>::set_state(self, positions, velocities);
            }
            fn set_update_velocities(&mut self, u: &[DVec3]) {
                <$kernel>::set_update_velocities(self, u);
            }
            fn positions_into(&self, out: &mut [DVec3]) {
                <$kernel>::positions_into(self, out);
            }
            fn velocities_into(&self, out: &mut [DVec3]) {
                <$kernel>::velocities_into(self, out);
            }
            fn update_velocities_into(&self, out: &mut [DVec3]) {
                <$kernel>::update_velocities_into(self, out);
            }
        }
    )*};
}

kernel_state!(GridCloth, LatticeKernel);

/// The system's f64 state (and Verlet's update velocities) into `kernel`.
pub(super) fn load_state(kernel: &mut impl KernelState, system: &System) {
    let state = &system.state;
    kernel.set_state(&state.positions, &state.velocities);
    if let Some(u) = system.verlet_update_velocities() {
        kernel.set_update_velocities(&u);
    }
}

/// `kernel`'s state into the system's f64 state, the `held` particles put back
/// exactly where the f64 state had them.
pub(super) fn copy_state_back(
    kernel: &impl KernelState,
    held: &[(usize, DVec3)],
    system: &mut System,
) {
    kernel.positions_into(&mut system.state.positions);
    kernel.velocities_into(&mut system.state.velocities);
    for &(i, position) in held {
        system.state.positions[i] = position;
    }
    system.set_verlet_history(|u| kernel.update_velocities_into(u));
}
