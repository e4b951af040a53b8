//! [`System`]: a model, its state and the scratch space a step needs, and the step
//! itself, read in one place ([`System::step`]): forces and integration
//! ([`super::integrators`]), then constraints ([`super::constraints`]), then the
//! speed limit and tearing ([`super::tearing`]), then the divergence check
//! ([`super::divergence`]).
//!
//! The system ties together parts that live in their own files: the [`Model`],
//! the [`State`] (with its [`super::VerletHistory`]), the [`Workspace`], the user's
//! [`Grab`], the runaway yardstick and the fast engines it hands runs to
//! ([`super::fast_path`]).

use std::sync::OnceLock;

use glam::{DVec2, DVec3};

use super::divergence::Runaway;
use super::energy_budget::ENERGY_CHECK_STEPS;
use super::{
    Bar, BarPairs, Collider, Divergence, Energy, EnergyBudget, ForceTerms, Grab, HAND_REACH,
    Integrator, Model, Params, Spring, SpringKind, SpringMaterial, Stability, State, Topology,
    Wind, constraints, fast_path, forces, grid_kernel, implicit, integrators, laws, springs,
    stability,
};

/// Scratch space for a step, sized once per model and integrator.
#[derive(Clone, Debug, Default)]
pub struct Workspace {
    pub(crate) spring_forces: Vec<DVec3>,
    pub(crate) accelerations: Vec<DVec3>,
    pub(crate) x_tmp: Vec<DVec3>,
    pub(crate) v_tmp: Vec<DVec3>,
    pub(crate) dx_sum: Vec<DVec3>,
    pub(crate) dv_sum: Vec<DVec3>,
    pub(crate) before_constraints: Vec<DVec3>,
    /// Positions at the start of the step (XPBD's damping, self-collision's friction).
    pub(crate) step_start: Vec<DVec3>,
    /// XPBD's multiplier of each spring in its pass ([`constraints::xpbd_pass`]).
    pub(crate) multipliers: Vec<f64>,
    /// The colliders' poses at the end of the step.
    pub(crate) collider_poses: Vec<super::Pose>,
    /// The self-collision pass's candidate pairs.
    pub(crate) self_collision: super::SelfCollision,
    pub(crate) implicit: implicit::ImplicitWorkspace,
}

impl Workspace {
    /// Sizes the f64 force evaluation's scratch for `model`, on its first use: a
    /// run on a fast engine never needs it, and on a big cloth a force per spring
    /// is the largest scratch there is.
    pub(crate) fn fit_forces(&mut self, model: &Model) {
        self.spring_forces.resize(model.springs.len(), DVec3::ZERO);
        self.accelerations.resize(model.mass.len(), DVec3::ZERO);
    }
}

/// A simulated system: model, state and scratch space.
#[derive(Clone, Debug)]
pub struct System {
    pub(super) model: Model,
    pub(super) state: State,
    pub(super) work: Workspace,
    /// Where the run started, for the runaway check.
    pub(super) runaway: Runaway,
    /// The energy the run may reach; `None` after an edit, until the next step
    /// sets it from the edited state.
    pub(super) budget: Option<EnergyBudget>,
    pub(super) grab: Option<Grab>,
    /// The fast engines runs are handed to, when allowed.
    pub(super) engines: fast_path::Engines,
    /// The step count and energy of the last full check, for [`Self::energy`].
    pub(super) checked_energy: Option<(u64, Energy)>,
    /// [`Self::stability`], until the next edit.
    stability: OnceLock<Stability>,
    /// Each particle's drag area at rest ([`stability::drag_areas`]), until the
    /// rest lengths or the springs change: most of the estimate's work on a grid,
    /// kept across edits of the stiffness, damping, mass or wind.
    rest_drag_areas: OnceLock<Vec<f64>>,
    /// The spectrum behind [`Self::stability`], scaled on a stiffness or mass edit.
    spectrum: super::spectrum::Cache,
    /// [`Self::edits`].
    edits: u64,
}

impl System {
    /// Builds a system from particle masses, start positions, pinned particles,
    /// topology and parameters. Velocities start at zero.
    pub fn new(
        masses: Vec<f64>,
        positions: Vec<DVec3>,
        pinned: &[usize],
        topology: Topology,
        params: Params,
    ) -> Self {
        let Topology {
            mut springs,
            materials,
            mut bars,
            mut triangles,
            uvs,
            grid,
            lattice,
        } = topology;
        let n = positions.len();
        assert_eq!(masses.len(), n, "one mass per particle");
        springs::canonicalize(&mut springs);
        // A builder's pushes leave up to half its capacity spare; a system keeps
        // its lists for its life.
        springs.shrink_to_fit();
        bars.shrink_to_fit();
        triangles.shrink_to_fit();
        let mut pinned_flags = vec![false; n];
        for &i in pinned {
            if i < n {
                pinned_flags[i] = true;
            }
        }
        let wind = Wind::new(params.wind, params.gust, params.seed);
        let mut model = Model {
            inv_mass: vec![0.0; n],
            mass: masses,
            pinned: pinned_flags,
            springs,
            materials,
            adjacency: OnceLock::new(),
            constraint_order: OnceLock::new(),
            broken_springs: 0,
            bar_pairs: BarPairs::new(&bars),
            bars,
            triangles,
            uvs,
            grid,
            lattice,
            params,
            terms: ForceTerms::default(),
            wind,
            colliders: Vec::new(),
        };
        model.refresh_terms();
        model.refresh_inv_mass(None);
        let runaway = Runaway::around(&positions);
        let state = State {
            velocities: vec![DVec3::ZERO; n],
            positions,
            ..State::default()
        };
        let mut system = Self {
            model,
            state,
            work: Workspace::default(),
            runaway,
            budget: None,
            grab: None,
            engines: fast_path::Engines::default(),
            checked_energy: None,
            stability: OnceLock::new(),
            rest_drag_areas: OnceLock::new(),
            spectrum: Default::default(),
            edits: 0,
        };
        system.engines.stencil_springs = fast_path::StencilSprings::of(&system.model);
        system.prepare_integrator();
        system
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.state.positions.len()
    }
    /// Positions in m.
    pub fn positions(&self) -> &[DVec3] {
        &self.state.positions
    }
    /// Velocities in m/s.
    pub fn velocities(&self) -> &[DVec3] {
        &self.state.velocities
    }
    /// Particle masses in kg.
    pub fn masses(&self) -> &[f64] {
        &self.model.mass
    }
    /// Inverse masses (0 for pinned or grabbed particles).
    pub fn inv_masses(&self) -> &[f64] {
        &self.model.inv_mass
    }
    /// Springs.
    pub fn springs(&self) -> &[Spring] {
        &self.model.springs
    }
    /// Rigid bars.
    pub fn bars(&self) -> &[Bar] {
        &self.model.bars
    }
    /// Surface triangles (empty without a surface).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.model.triangles
    }
    /// Texture coordinates, one per particle (empty without a surface).
    pub fn uvs(&self) -> &[DVec2] {
        &self.model.uvs
    }
    /// Parameters in effect.
    pub fn params(&self) -> &Params {
        &self.model.params
    }
    /// Force terms that run.
    pub fn force_terms(&self) -> ForceTerms {
        self.model.terms
    }
    /// The model (topology and parameters).
    pub fn model(&self) -> &Model {
        &self.model
    }
    /// The state.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// Puts back a state taken from this system with [`Self::state`] (e.g. to rerun
    /// from the start). Ignored if its particle count differs.
    pub fn set_state(&mut self, state: State) {
        let n = self.particle_count();
        if state.positions.len() != n || state.velocities.len() != n {
            return;
        }
        self.mark_edited();
        self.state = state;
        if self.model.params.integrator == Integrator::Verlet && !self.state.verlet.covers(n) {
            self.restart_verlet_history();
        }
    }
    /// How many changes were made to the system from outside its steps since it
    /// was built (an edit, a pin, a grab or a move of the hand, a collider moved,
    /// a state put back): whoever mirrors the run, as the live reference does,
    /// starts again from the state when this changes.
    pub fn edits(&self) -> u64 {
        self.edits
    }
    /// Simulated time in s.
    pub fn time(&self) -> f64 {
        self.state.time
    }
    /// Steps taken.
    pub fn steps_taken(&self) -> u64 {
        self.state.steps
    }
    /// Conjugate-gradient iterations of the last implicit-Euler step (0 for other integrators).
    pub fn solver_iterations(&self) -> usize {
        self.work.implicit.last_iterations
    }
    /// The particle the user holds, if any, and where the hand holds it (the
    /// particle may trail it for a few steps: [`Grab::at`]).
    pub fn grabbed(&self) -> Option<(usize, DVec3)> {
        self.grab.map(|g| (g.particle, g.target))
    }

    /// Whether particle `i` is pinned (by the scene or the user).
    pub fn is_pinned(&self, i: usize) -> bool {
        self.model.pinned.get(i).copied().unwrap_or(false)
    }

    /// Pins or unpins particle `i` (ignored if out of range). A pinned particle stops.
    pub fn set_pinned(&mut self, i: usize, pinned: bool) {
        self.mark_edited();
        if i >= self.particle_count() {
            return;
        }
        self.model.pinned[i] = pinned;
        if pinned {
            self.state.velocities[i] = DVec3::ZERO;
        }
        self.model.refresh_inv_mass(self.grab.map(|g| g.particle));
        self.forget_motion(i);
    }

    /// Holds particle `i` at `target` (m) until [`Self::release`]: it moves with the
    /// hand and pulls its neighbours through their springs. Grabbed anew, it is put
    /// at `target` at once; held already, it follows the hand at most
    /// [`HAND_REACH`] of its shortest link a step. Non-finite targets are ignored.
    pub fn grab(&mut self, i: usize, target: DVec3) {
        if i < self.particle_count()
            && target.is_finite()
            && self.grab.is_some_and(|g| g.particle == i)
        {
            self.move_grab(target);
            return;
        }
        self.mark_edited();
        if i >= self.particle_count() || !target.is_finite() {
            return;
        }
        if self.grab.is_some_and(|g| g.particle != i) {
            self.release();
        }
        let grab = Grab::new(i, target);
        grab.hold(&mut self.state, self.model.params.dt);
        self.grab = Some(grab);
        self.model.refresh_inv_mass(Some(i));
    }

    /// The hand holding the particle moved to `target` (the mouse moved): the
    /// particle follows it ([`Self::follow_hand`]).
    fn move_grab(&mut self, target: DVec3) {
        self.edits += 1;
        if let Some(grab) = self.grab.as_mut() {
            grab.target = target;
        }
        self.follow_hand();
    }

    /// Moves the held particle towards the hand, at most [`HAND_REACH`] of its
    /// shortest spring or bar: on each move of the hand, and before each step
    /// until it gets there. No inverse mass changes, so the stability estimate
    /// stays; the energy budget takes the hand's work on the particle's springs
    /// ([`EnergyBudget::add_work`]), and the engines take the one particle.
    fn follow_hand(&mut self) {
        let Some(mut grab) = self.grab.filter(Grab::trails) else {
            return;
        };
        self.catch_up();
        let i = grab.particle;
        grab.at = grab.towards_target(HAND_REACH * self.shortest_link_at(i));
        self.grab = Some(grab);
        let before = self.model.energy_of_springs_at(i, &self.state.positions);
        grab.hold(&mut self.state, self.model.params.dt);
        if let Some(budget) = &mut self.budget {
            budget.add_work(self.model.energy_of_springs_at(i, &self.state.positions) - before);
        }
        self.held_particle_moved(i, grab.at);
    }

    /// Length (m) of the shortest spring or bar at particle `i`; infinite with
    /// none.
    fn shortest_link_at(&self, i: usize) -> f64 {
        let springs =
            (self.model.adjacency().springs_of(i)).map(|(s, _)| self.model.springs[s].rest);
        let bars = (self.model.bars.iter())
            .filter(|b| b.a as usize == i || b.b as usize == i)
            .map(|b| b.length);
        springs
            .chain(bars)
            .filter(|l| *l > 0.0)
            .fold(f64::INFINITY, f64::min)
    }

    /// Lets go of the held particle: it is free again unless pinned.
    pub fn release(&mut self) {
        self.mark_edited();
        if let Some(Grab { particle: i, .. }) = self.grab.take() {
            self.state.velocities[i] = DVec3::ZERO;
            self.model.refresh_inv_mass(None);
            self.forget_motion(i);
        }
    }

    /// Changes parameters that need no rebuild (k and b go through
    /// [`Self::set_spring_stiffness`]); recomputes which force terms run.
    pub fn set_params(&mut self, params: Params) {
        self.mark_edited();
        let integrator_changed = params.integrator != self.model.params.integrator;
        let dt_changed = params.dt != self.model.params.dt;
        self.model.params = params;
        self.model.wind = Wind::new(params.wind, params.gust, params.seed);
        self.model.refresh_terms();
        if integrator_changed {
            self.prepare_integrator();
        } else if dt_changed && params.integrator == Integrator::Verlet {
            self.restart_verlet_history();
        }
    }

    /// The colliders besides the ground and the scene's sphere.
    pub fn colliders(&self) -> &[Collider] {
        &self.model.colliders
    }

    /// Replaces the colliders (`super::colliders`); their poses are taken as
    /// of their own `since` times.
    pub fn set_colliders(&mut self, colliders: Vec<Collider>) {
        self.mark_edited();
        self.model.colliders = colliders;
    }

    /// Moves collider `i` to `center` (m) now, moving on at `velocity` (m/s) at
    /// most its [`Collider::speed_limit`], so that it cannot pass through a
    /// particle in one step. The user's work starts a new energy budget.
    pub fn move_collider(&mut self, i: usize, center: DVec3, velocity: DVec3) {
        self.catch_up();
        let (t, dt) = (self.state.time, self.model.params.dt);
        let Some(collider) = self.model.colliders.get_mut(i) else {
            return;
        };
        let limit = collider.speed_limit(dt);
        let velocity = velocity.clamp_length_max(limit);
        if center.is_finite() && velocity.is_finite() {
            collider.move_to(center, velocity, t);
            self.budget = None;
            self.edits += 1;
        }
    }

    /// Sets the stiffness (N/m) of every spring of `kind`.
    pub fn set_spring_stiffness(&mut self, kind: SpringKind, stiffness: f64) {
        self.set_stiffness_by_kind(|k| (k == kind).then_some(stiffness));
    }

    /// Sets the damping (N·s/m) of every spring of `kind`.
    pub fn set_spring_damping(&mut self, kind: SpringKind, damping: f64) {
        self.set_damping_by_kind(|k| (k == kind).then_some(damping));
    }

    /// Sets the stiffness (N/m) of the springs of each kind that `stiffness` gives
    /// one for (a grid's three kinds on a slider drag).
    pub fn set_stiffness_by_kind(&mut self, stiffness: impl Fn(SpringKind) -> Option<f64>) {
        self.edit_springs_by_kind(stiffness, |m, k| m.stiffness = k, |c, k| c.k = k);
    }

    /// Sets the damping (N·s/m) of the springs of each kind that `damping` gives one
    /// for.
    pub fn set_damping_by_kind(&mut self, damping: impl Fn(SpringKind) -> Option<f64>) {
        self.edit_springs_by_kind(damping, |m, b| m.damping = b, |c, b| c.b = b);
    }

    /// Sets one coefficient of the springs of each kind `value` gives one for: in
    /// the model's materials (`material`) and, a whole kind changing together so
    /// that the grid stays a grid with no rescan, in the engines' stencil
    /// (`stencil`).
    fn edit_springs_by_kind(
        &mut self,
        value: impl Fn(SpringKind) -> Option<f64>,
        material: impl Fn(&mut SpringMaterial, f64),
        stencil: impl Fn(&mut grid_kernel::SpringCoefficients, f64),
    ) {
        self.coefficients_edited();
        for kind in SpringKind::ALL {
            if let Some(v) = value(kind) {
                material(&mut self.model.materials[kind.index()], v);
                (self.engines).edit_stencil_springs(&self.model, kind, |c| stencil(c, v));
            }
        }
    }

    /// Multiplies every spring's and bar's rest length by `factor` (the rest-length slider).
    pub fn scale_rest_lengths(&mut self, factor: f64) {
        self.coefficients_edited();
        if !(factor.is_finite() && factor >= 0.0) {
            return;
        }
        for s in &mut self.model.springs {
            s.rest *= factor;
        }
        self.forget_rest_drag_areas();
        for b in &mut self.model.bars {
            b.length *= factor;
        }
        self.engines.stencil_springs = fast_path::StencilSprings::of(&self.model);
    }

    /// Scales the whole system by `factor`: rest lengths, bar lengths and positions
    /// about the centroid of the pinned particles (of all particles if none is
    /// pinned). Strains and velocities are unchanged, so no energy is injected: this
    /// is how a rest-length edit applies to a running cloth.
    pub fn rescale(&mut self, factor: f64) {
        self.mark_edited();
        if !(factor.is_finite() && factor > 0.0) {
            return;
        }
        let anchors: Vec<DVec3> = (0..self.particle_count())
            .filter(|&i| self.model.pinned[i])
            .map(|i| self.state.positions[i])
            .collect();
        let points = if anchors.is_empty() {
            &self.state.positions[..]
        } else {
            &anchors[..]
        };
        let center = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
        let scale = |p: &mut DVec3| *p = center + (*p - center) * factor;
        self.state.positions.iter_mut().for_each(scale);
        self.state.verlet.positions.iter_mut().for_each(scale);
        if let Some(grab) = &mut self.grab {
            scale(&mut grab.target);
            scale(&mut grab.at);
        }
        self.scale_rest_lengths(factor);
        self.runaway = Runaway::around(&self.state.positions);
    }

    /// Sets every particle's mass (kg), keeping pins.
    pub fn set_particle_mass(&mut self, mass: f64) {
        self.coefficients_edited();
        if !(mass.is_finite() && mass > 0.0) {
            return;
        }
        self.model.mass.fill(mass);
        self.model.refresh_inv_mass(self.grab.map(|g| g.particle));
        self.engines.stencil_springs = fast_path::StencilSprings::of(&self.model);
    }

    /// Energy now (as the last full check found it, when that was at this step).
    pub fn energy(&self) -> Energy {
        match self.checked_energy {
            Some((steps, energy)) if steps == self.state.steps => energy,
            _ => self
                .model
                .energy(&self.state.positions, &self.state.velocities),
        }
    }

    /// Stability estimate for the current parameters (computed once per edit).
    pub fn stability(&self) -> Stability {
        *self.stability.get_or_init(|| {
            let areas = (self.model.terms.aero).then(|| {
                (self.rest_drag_areas)
                    .get_or_init(|| stability::drag_areas(&self.model))
                    .as_slice()
            });
            let at = (&self.state.positions[..], &self.spectrum);
            stability::estimate_with(&self.model, Some(at), areas)
        })
    }

    /// The critical step of [`System::stability`] with the drag also taken on the
    /// triangles' areas now ([`stability::dt_critical_at`]), for safe stepping.
    pub fn dt_critical_now(&self) -> Option<f64> {
        let at_rest = self.stability().dt_critical;
        stability::dt_critical_at(&self.model, self.positions(), at_rest)
    }

    /// Advances one step of `dt`, then checks the state. On divergence the state is
    /// left as it is (the caller decides to reset). A held particle that trails
    /// the hand first moves towards it ([`HAND_REACH`]).
    pub fn step(&mut self) -> Result<(), Divergence> {
        self.follow_hand();
        self.step_hand_still()
    }

    /// [`Self::step`] with the held particle left where it is (the run's loop
    /// moves it towards the hand before each step itself).
    fn step_hand_still(&mut self) -> Result<(), Divergence> {
        self.mark_changed();
        self.budget();
        if let Some(grab) = self.grab {
            grab.hold(&mut self.state, self.model.params.dt);
        }
        integrators::step(&self.model, &mut self.state, &mut self.work);
        if self.has_constraints() {
            self.work
                .before_constraints
                .clone_from(&self.state.positions);
            constraints::apply(&self.model, &mut self.state, &mut self.work);
        }
        if let Some(max_speed) = self.model.params.max_speed {
            self.limit_speed(max_speed);
        }
        if let Some(tau) = self.model.params.tear_strain {
            self.tear(tau);
        }
        self.state.time += self.model.params.dt;
        self.state.steps += 1;
        if self.state.steps.is_multiple_of(ENERGY_CHECK_STEPS) {
            self.check()
        } else {
            self.runaway.check(&self.state)
        }
    }

    /// Runs `n` steps, stopping at the first divergence; the energy budget is
    /// checked every [`ENERGY_CHECK_STEPS`] steps and at the end. A model big enough for the
    /// threaded force path runs its whole loop on a pool thread, so the parallel loops
    /// inside go through worker-local queues and allocate nothing per step.
    pub fn run(&mut self, n: u64) -> Result<(), Divergence> {
        self.run_settling(n, true)
    }

    /// [`Self::run`] for a caller that reads the state less often than it steps
    /// (the app's physics thread runs a few steps at a time): a fast engine may
    /// keep the latest state in its own arrays, and the full check at the end is
    /// left out, so that a short run costs its steps and not a copy and a check of
    /// the whole cloth. The state's positions and velocities may lag behind its
    /// time until [`Self::settle`], which the caller must run before it reads
    /// them; every edit through `&mut self` settles first. Non-finite and runaway
    /// states are still caught at once, and the energy budget every
    /// [`ENERGY_CHECK_STEPS`] steps.
    pub fn run_ahead(&mut self, n: u64) -> Result<(), Divergence> {
        self.run_settling(n, false)
    }

    /// Runs `n` steps; while a held particle trails the hand, one step at a time,
    /// each after a move towards it ([`Self::follow_hand`]).
    fn run_settling(&mut self, n: u64, settle: bool) -> Result<(), Divergence> {
        let mut left = n;
        while left > 0 && self.grab.is_some_and(|g| g.trails()) {
            self.follow_hand();
            self.run_on_an_engine(1, settle && left == 1)?;
            left -= 1;
        }
        // A run of no steps still goes to the engines, which settle it.
        if left > 0 || n == 0 {
            self.run_on_an_engine(left, settle)?;
        }
        Ok(())
    }

    /// Runs `n` steps on the fastest engine that models the system.
    pub(super) fn run_on_an_engine(&mut self, n: u64, settle: bool) -> Result<(), Divergence> {
        self.budget();
        if let Some(result) = self.run_on_grid(n, settle) {
            return result;
        }
        if let Some(result) = self.run_on_lattice(n, settle) {
            return result;
        }
        self.mark_changed();
        let steps = |system: &mut Self| (0..n).try_for_each(|_| system.step_hand_still());
        if forces::uses_threads(&self.model) {
            let mut result = Ok(());
            rayon::scope(|_| result = steps(self));
            result?;
        } else {
            steps(self)?;
        }
        // A run ends checked in full, as the fast engines' runs do; a run ahead
        // leaves the check of its last steps to `settle`.
        if settle && n > 0 && !self.state.steps.is_multiple_of(ENERGY_CHECK_STEPS) {
            self.check()?;
        }
        self.engines.unchecked = match settle {
            true => 0,
            false => self.state.steps % ENERGY_CHECK_STEPS,
        };
        Ok(())
    }

    /// Whether anything is enforced after integration.
    pub fn has_constraints(&self) -> bool {
        let p = &self.model.params;
        (!self.model.bars.is_empty() && p.bar_iterations > 0)
            || (p.integrator == Integrator::Xpbd && !self.model.springs.is_empty())
            || (p.stretch_limit.is_some() && !self.model.springs.is_empty())
            || laws::Contact::of(p).is_active()
            || p.self_collides()
            || !self.model.colliders.is_empty()
    }

    /// Checks for non-finite values and runaways (`super::divergence`), then the
    /// energy against its budget (`super::energy_budget`).
    pub fn check(&mut self) -> Result<(), Divergence> {
        self.runaway.check(&self.state)?;
        self.checked_energy = None;
        let energy = self.energy();
        self.checked_energy = Some((self.state.steps, energy));
        let budget = self.budget();
        budget.check(energy, self.state.time, self.state.steps)?;
        super::limiters::check(&self.model, &self.state, &budget)
    }

    /// The energy budget in effect; `None` after an edit until the next step sets
    /// it.
    pub fn energy_budget(&self) -> Option<EnergyBudget> {
        self.budget
    }

    /// Something outside the run changed the system (a grab, a pin, a parameter):
    /// the engines must take the new state, and the energy budget starts again from
    /// it, so that the edit's own work is not counted against the run.
    pub(super) fn mark_edited(&mut self) {
        self.edits += 1;
        self.mark_changed();
        self.budget = None;
        self.stability = OnceLock::new();
    }

    /// A coefficient changed (stiffness, damping, rest length, mass): the state
    /// stays, the engines take the new coefficients in place, and the energy
    /// budget and stability estimate start again.
    fn coefficients_edited(&mut self) {
        self.edits += 1;
        self.catch_up();
        self.budget = None;
        self.stability = OnceLock::new();
        self.checked_energy = None;
    }

    /// The energy budget, set from the state now if an edit cleared it.
    pub(super) fn budget(&mut self) -> EnergyBudget {
        if let Some(budget) = self.budget {
            return budget;
        }
        let energy = (self.model).energy(&self.state.positions, &self.state.velocities);
        let budget = EnergyBudget::new(
            &self.model,
            &self.state.positions,
            energy,
            &self.stability(),
        );
        self.budget = Some(budget);
        budget
    }

    /// The springs' rest lengths or the triangles changed: the drag areas at rest
    /// are found again with the next stability estimate.
    pub(super) fn forget_rest_drag_areas(&mut self) {
        self.rest_drag_areas = OnceLock::new();
    }

    pub(super) fn prepare_integrator(&mut self) {
        let n = self.particle_count();
        let m = self.model.springs.len();
        let w = &mut self.work;
        let multistage = matches!(
            self.model.params.integrator,
            Integrator::Rk2 | Integrator::Rk4
        );
        let len = if multistage { n } else { 0 };
        w.x_tmp.resize(len, DVec3::ZERO);
        w.v_tmp.resize(len, DVec3::ZERO);
        let len = if self.model.params.integrator == Integrator::Rk4 {
            n
        } else {
            0
        };
        w.dx_sum.resize(len, DVec3::ZERO);
        w.dv_sum.resize(len, DVec3::ZERO);
        if self.model.params.integrator == Integrator::ImplicitEuler {
            w.implicit.resize(n, m);
        } else {
            w.implicit = Default::default();
        }
        if self.model.params.integrator == Integrator::Verlet {
            self.restart_verlet_history();
        } else {
            self.state.verlet.clear();
        }
    }

    /// Verlet needs a history consistent with the current velocities
    /// ([`super::VerletHistory::restart`]).
    pub(super) fn restart_verlet_history(&mut self) {
        let State {
            positions,
            velocities,
            time,
            verlet,
            ..
        } = &mut self.state;
        verlet.restart(&self.model, positions, velocities, *time, &mut self.work);
    }

    /// The speed limit ([`laws::speed_limit`]): every particle faster than
    /// `max_speed` is slowed to it, and under Verlet its history with it.
    fn limit_speed(&mut self, max_speed: f64) {
        let State {
            positions,
            velocities,
            verlet,
            ..
        } = &mut self.state;
        for (i, v) in velocities.iter_mut().enumerate() {
            let factor = laws::speed_limit(*v, max_speed);
            if factor < 1.0 {
                *v *= factor;
                if let Some(prev) = verlet.positions.get_mut(i) {
                    *prev = positions[i] - (positions[i] - *prev) * factor;
                }
            }
        }
    }

    /// After the user moves, pins or releases particle `i`, its Verlet history must
    /// not remember the old motion.
    fn forget_motion(&mut self, i: usize) {
        let (x, v) = (self.state.positions[i], self.state.velocities[i]);
        (self.state.verlet).forget_motion(i, x, v, self.model.params.dt);
    }
}
