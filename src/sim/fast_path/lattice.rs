//! The lattice kernel's glue: whether a system is a lattice block the kernel
//! models exactly (`lattice_spec`), and its runs.

use glam::DVec3;

use super::chunks::{FastEngine, copy_state_back, load_state, outgrown};
use super::{Ahead, pool_threads, uniform_acceleration};
use crate::sim::grid_kernel::Precision;
use crate::sim::grid_kernel::lattice::{LatticeKernel, LatticeSpec};
use crate::sim::{Divergence, System};

/// The lattice kernel, and whether it holds the f64 state.
#[derive(Debug)]
pub(super) struct LatticePath {
    pub(super) kernel: LatticeKernel,
    /// Whether the kernel holds the same state as the f64 arrays.
    pub(super) in_sync: bool,
    /// Positions of the particles held in place, exactly as the f64 state had them.
    pub(super) held: Vec<(usize, DVec3)>,
}

impl System {
    /// Runs `n` steps on the lattice kernel if allowed and it models the system;
    /// `None` when another engine must run them. Call after [`Self::run_on_grid`]
    /// declined.
    pub(in crate::sim) fn run_on_lattice(
        &mut self,
        n: u64,
        settle: bool,
    ) -> Option<Result<(), Divergence>> {
        if !self.engines.allowed {
            return None;
        }
        self.run_choosing(n, settle, Self::lattice_spec, |system, spec, n| {
            system.run_lattice_once(spec, n, settle)
        })
    }

    /// [`Self::run_on_lattice`]'s run of up to `n` steps on a lattice kernel for
    /// `spec`, the one built before when it can take the spec: the steps run
    /// ([`Self::run_in_chunks`]).
    pub(super) fn run_lattice_once(
        &mut self,
        spec: LatticeSpec,
        n: u64,
        settle: bool,
    ) -> Result<u64, Divergence> {
        let reused = self.engines.lattice.take().and_then(|mut lattice| {
            if *lattice.kernel.spec() != spec {
                // A live edit of a coefficient: updated in place (pins are set
                // again below); a new shape, integrator or precision needs a new
                // kernel.
                if !lattice.kernel.respec(spec.clone()) {
                    return None;
                }
                lattice.in_sync = false;
            }
            Some(lattice)
        });
        let mut lattice = match reused {
            Some(lattice) => lattice,
            None => {
                self.engines.builds += 1;
                let mut kernel = LatticeKernel::new(spec);
                kernel.set_threads(pool_threads());
                LatticePath {
                    kernel,
                    in_sync: false,
                    held: Vec::new(),
                }
            }
        };
        if !lattice.in_sync {
            lattice.load(self);
            lattice.held = self.held(|i, pinned| lattice.kernel.set_pinned(i, pinned));
            lattice.in_sync = true;
        }
        let result = self.run_in_chunks(n, &mut lattice, settle);
        self.engines.lattice = Some(lattice);
        result
    }

    /// The lattice kernel's description of this system, if it models it: a
    /// lattice whose springs are checked to be its stencil's, one mass, gravity and
    /// the applied force, air damping, a penalty ground and a sphere with or
    /// without friction, symplectic Euler, explicit Euler or Verlet, in the
    /// precision the precision rule asks for.
    ///
    /// Every parameter is named here (no `..`): a new one fails to compile until
    /// it is either passed to the kernel or made a reason to refuse it.
    pub(in crate::sim) fn lattice_spec(&self) -> Option<LatticeSpec> {
        let model = &self.model;
        if self.engines.lattice_refused || !model.colliders.is_empty() {
            return None;
        }
        let (shape, springs) = (model.lattice?, self.engines.stencil_springs?);
        let crate::sim::Params {
            gravity,
            force,
            wind: _,             // only the aerodynamic drag uses it (refused below)
            gust: _,             // likewise
            air_density: _,      // likewise
            drag_coefficient: _, // likewise
            air_damping,
            ground,
            sphere,
            integrator,
            dt: _,             // given to each run
            bar_iterations: _, // bars are refused below
            stretch_limit,
            tear_strain,
            max_speed,
            friction,
            thickness: _, // already in `ground` and `sphere`
            self_collision,
            seed: _, // only the gusts use it
        } = model.params;
        let crate::sim::ForceTerms {
            gravity: gravity_on,
            springs: _, // the kernel always evaluates the stencil
            aero,
            air_damping: air_damping_on,
            ground: _, // `ground` itself says
            applied,
        } = model.terms;
        let bars = !model.bars.is_empty() && model.params.bar_iterations > 0;
        let others = aero || self_collision || tear_strain.is_some() || max_speed.is_some();
        if !springs.lattice || bars || others || !LatticeSpec::supports(integrator) {
            return None;
        }
        let mut spec = LatticeSpec {
            shape,
            spacing: springs.spacing,
            particle_mass: springs.mass,
            kinds: springs.coefficients,
            gravity: uniform_acceleration(
                gravity_on.then_some(gravity),
                applied.then_some(force),
                springs.mass,
            ),
            air_damping: if air_damping_on { air_damping } else { 0.0 },
            ground,
            sphere,
            friction,
            stretch_limit: stretch_limit.filter(|_| !model.springs.is_empty()),
            integrator,
            precision: Precision::Single,
        };
        let precision = Precision::cheapest(self.noise_rule(&spec).1, self.float32_reach());
        spec.precision = precision;
        Some(spec)
    }
}

impl FastEngine for LatticePath {
    const KIND: Ahead = Ahead::Lattice;
    fn advance(&mut self, system: &System, steps: usize) {
        self.kernel.steps(system.model.params.dt, steps);
    }
    fn extremes(&self, center: DVec3) -> (f64, f64) {
        self.kernel.extremes(center)
    }
    fn copy_back(&mut self, system: &mut System) {
        copy_state_back(&self.kernel, &self.held, system);
    }
    fn load(&mut self, system: &System) {
        load_state(&mut self.kernel, system);
    }
    fn outgrown_unit(&self, dt: f64) -> Option<f64> {
        outgrown(self.kernel.position_unit(), self.kernel.spec(), dt)
    }
}
