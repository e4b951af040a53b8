//! The mesh engine's glue: the systems the grid and lattice kernels leave, stepped
//! by the f64 mesh engine.

use glam::DVec3;

use super::chunks::{FastEngine, copy_state_back, load_state};
use super::{Ahead, pool_threads};
use crate::sim::mesh_kernel::{MeshKernel, MeshParams};
use crate::sim::{Divergence, System};

/// The mesh engine and whether it holds the f64 state.
#[derive(Debug)]
pub(super) struct MeshPath {
    pub(super) kernel: MeshKernel,
    /// Whether the engine holds the same state as the f64 arrays.
    pub(super) in_sync: bool,
}

impl System {
    /// Runs `n` steps on the mesh engine if allowed and it models the system
    /// exactly; `None` when the general path must run them. Call after
    /// [`Self::run_on_grid`] and [`Self::run_on_lattice`] declined.
    pub(in crate::sim) fn run_on_mesh(
        &mut self,
        n: u64,
        settle: bool,
    ) -> Option<Result<(), Divergence>> {
        if !self.engines.allowed {
            return None;
        }
        let params = MeshParams::of(&self.model)?;
        if (self.engines.mesh.as_ref()).is_some_and(|mesh| mesh.kernel.has_torn()) {
            // The engine ran ahead and tore springs: the model breaks them too
            // before the two are compared.
            self.catch_up();
        }
        let reused = self.engines.mesh.take().map(|mut mesh| {
            // Coefficients, masses and pins are taken in place; a new topology or
            // integrator needs a new engine (on the same threads).
            if !mesh.kernel.refresh(&self.model, params) {
                mesh.kernel.rebuild(&self.model, params);
                mesh.in_sync = false;
            }
            mesh
        });
        let mut mesh = match reused {
            Some(mesh) => mesh,
            None => {
                let mut kernel = MeshKernel::new(&self.model, params);
                kernel.set_threads(pool_threads());
                MeshPath {
                    kernel,
                    in_sync: false,
                }
            }
        };
        if !mesh.in_sync {
            load_state(&mut mesh.kernel, self);
            mesh.in_sync = true;
        }
        // Float64 positions: the mesh engine runs every step.
        let result = self.run_in_chunks(n, &mut mesh, settle).map(|_| ());
        self.engines.mesh = Some(mesh);
        Some(result)
    }
}

impl FastEngine for MeshPath {
    const KIND: Ahead = Ahead::Mesh;
    fn advance(&mut self, system: &System, steps: usize) {
        self.kernel.set_time(system.state.time);
        self.kernel.steps(steps);
    }
    fn extremes(&self, center: DVec3) -> (f64, f64) {
        self.kernel.extremes(center)
    }
    fn copy_back(&mut self, system: &mut System) {
        let torn = self.kernel.take_torn();
        if !torn.is_empty() {
            // The kernel broke them itself, by the same rule at the same steps:
            // the model breaks them too, and then has the kernel's springs.
            system.break_springs(|s| torn.binary_search(&(s.a, s.b)).is_ok());
        }
        copy_state_back(&self.kernel, &[], system);
    }
    fn load(&mut self, system: &System) {
        load_state(&mut self.kernel, system);
    }
    fn outgrown_unit(&self, _dt: f64) -> Option<f64> {
        None // float64 positions
    }
}
