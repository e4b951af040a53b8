//! The session on the GPU engine (`cloth --engine gpu`, the panel's engine
//! choice): a frame's steps go to the [`GpuEngine`] while it can step the scene,
//! and to the CPU engines, with the reason shown, while it cannot (an
//! integrator or constraint it does not step yet). The engine is built again,
//! on the same device, after every edit ([`System::edits`]) and rebuild, so it
//! always steps the setup the panel shows.

use crate::gpu::{Adapter, GpuEngine, GpuError};
use crate::sim::{Divergence, System};

/// The GPU engine a session steps on, and why it does not step now.
pub(super) struct OnGpu {
    engine: Option<GpuEngine>,
    /// What `engine` was built from: the session's build, the system's edits
    /// and its springs (a tear changes them).
    key: Option<(u64, u64, usize)>,
    /// Why the steps run on the CPU now.
    problem: Option<String>,
}

impl OnGpu {
    fn key(build: u64, system: &System) -> (u64, u64, usize) {
        (build, system.edits(), system.springs().len())
    }

    /// The engine for `system` now, built again if it was edited since; `None`
    /// (with the reason kept) where it cannot step it.
    fn engine_for(&mut self, build: u64, system: &System) -> Option<&mut GpuEngine> {
        let key = Self::key(build, system);
        if self.key != Some(key) {
            self.key = Some(key);
            let built = match &self.engine {
                Some(engine) => engine.rebuilt(system),
                None => GpuEngine::new(system),
            };
            match built {
                Ok(engine) => {
                    self.engine = Some(engine);
                    self.problem = None;
                }
                Err(e) => self.problem = Some(e.to_string()),
            }
        }
        if self.problem.is_some() {
            return None;
        }
        self.engine.as_mut()
    }
}

impl super::Session {
    /// Steps on the GPU engine (`true`) or the CPU engines. Turning it on opens
    /// the adapter and builds the engine: without an adapter that is refused
    /// with the reason, and the session stays on the CPU; a scene the engine does
    /// not step turns it on all the same, running on the CPU (and saying why,
    /// [`Self::gpu_problem`]) until an edit makes it one it steps.
    pub fn set_gpu(&mut self, on: bool) -> Result<(), String> {
        if !on {
            self.gpu = None;
            return Ok(());
        }
        if self.gpu.is_some() {
            return Ok(());
        }
        let mut gpu = OnGpu {
            engine: None,
            key: None,
            problem: None,
        };
        self.system.settle().map_err(|d| d.to_string())?;
        let built = gpu.engine_for(self.builds, &self.system).is_some();
        if !built && self.gpu_can_step() {
            // The scene is one it steps: the machine has no engine to give.
            return Err(gpu.problem.take().unwrap_or_default());
        }
        self.gpu = Some(gpu);
        Ok(())
    }

    /// Whether the GPU engine would step this scene (so that a failure to build
    /// it is the machine's, not the scene's).
    fn gpu_can_step(&self) -> bool {
        GpuEngine::refusal(self.system.model()).is_none()
    }

    /// Whether the session steps on the GPU engine (when it can).
    pub fn on_gpu(&self) -> bool {
        self.gpu.is_some()
    }

    /// The adapter the GPU engine runs on, once built.
    pub fn gpu_adapter(&self) -> Option<&Adapter> {
        self.gpu.as_ref()?.engine.as_ref().map(GpuEngine::adapter)
    }

    /// Why the session, on the GPU engine, steps on the CPU engines now.
    pub fn gpu_problem(&self) -> Option<&str> {
        self.gpu.as_ref()?.problem.as_deref()
    }

    /// Runs `steps` on the GPU engine, if the session is on it and it can step
    /// the scene now; `None` where the CPU engines are to run them.
    pub(super) fn run_on_gpu(&mut self, steps: u32) -> Option<Result<(), Divergence>> {
        let build = self.builds;
        let engine = self.gpu.as_mut()?.engine_for(build, &self.system)?;
        let e = match engine.run(&mut self.system, u64::from(steps)) {
            Ok(outcome) => return Some(outcome),
            Err(e) => e,
        };
        let gpu = self.gpu.as_mut()?;
        // A model the engine no longer fits is built for again at the next
        // steps; a device that failed stays failed until an edit.
        if matches!(e, GpuError::Changed | GpuError::Unsupported(_)) {
            gpu.key = None;
        }
        gpu.problem = Some(e.to_string());
        None
    }
}
