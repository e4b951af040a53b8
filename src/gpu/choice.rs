//! `--engine cpu|gpu|auto`: which engine steps a run. `cpu` is the CPU engines
//! as [`System::run`] picks them; `gpu` the [`GpuEngine`], or a clear refusal;
//! `auto` the GPU engine only where it can gain: on a hardware adapter (not a
//! CPU adapter such as lavapipe) and from [`AUTO_GPU_PARTICLES`] particles, and
//! the CPU otherwise, saying why when it had looked for a GPU.

use super::{GpuEngine, GpuError, GpuTime};
use crate::sim::{Divergence, System};

/// Particles from which `auto` looks for a GPU. Below it no adapter is opened
/// (that alone takes longer than a small run). 256² is not measured: no hardware
/// GPU was at hand to find where the GPU engine overtakes the CPU's, and the
/// figure is to be replaced by that measurement (`docs/gpu.md`).
pub const AUTO_GPU_PARTICLES: usize = 65_536;

/// The engine asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EngineChoice {
    /// The CPU engines.
    Cpu,
    /// The GPU engine, or a refusal.
    Gpu,
    /// The GPU where it gains, else the CPU.
    #[default]
    Auto,
}

impl EngineChoice {
    /// The names `--engine` takes.
    pub const NAMES: &'static str = "cpu, gpu or auto";
}

impl std::str::FromStr for EngineChoice {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "cpu" => Ok(Self::Cpu),
            "gpu" => Ok(Self::Gpu),
            "auto" => Ok(Self::Auto),
            _ => Err(format!("`{s}` is not an engine; use {}", Self::NAMES)),
        }
    }
}

/// Why `--engine gpu` cannot run: a scene the engine does not step or a cloth
/// over the device's limits (bad input), or no adapter (the machine).
#[derive(Debug)]
pub enum Refused {
    /// The scene or its size: exit code 2.
    Input(String),
    /// No adapter or device: exit code 1.
    Machine(String),
}

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (Self::Input(s) | Self::Machine(s)) = self;
        f.write_str(s)
    }
}

/// The engine a run steps on.
pub enum Stepper {
    /// [`System::run`].
    Cpu,
    /// [`GpuEngine::run`].
    Gpu(Box<GpuEngine>),
}

impl Stepper {
    /// Chooses for `system` as `choice` asks. `Ok` carries the stepper and,
    /// when `auto` looked for a GPU and took the CPU, the line that says why.
    pub fn choose(
        choice: EngineChoice,
        system: &System,
    ) -> Result<(Self, Option<String>), Refused> {
        match choice {
            EngineChoice::Cpu => Ok((Self::Cpu, None)),
            EngineChoice::Gpu => match GpuEngine::new(system) {
                Ok(engine) => Ok((Self::Gpu(Box::new(engine)), None)),
                Err(e @ (GpuError::NoAdapter | GpuError::Device(_))) => {
                    Err(Refused::Machine(format!("--engine gpu: {e}")))
                }
                Err(e) => Err(Refused::Input(format!("--engine gpu: {e}"))),
            },
            EngineChoice::Auto => Ok(Self::auto(system)),
        }
    }

    fn auto(system: &System) -> (Self, Option<String>) {
        let n = system.particle_count();
        if n < AUTO_GPU_PARTICLES {
            return (Self::Cpu, None);
        }
        let cpu = |why: String| {
            (
                Self::Cpu,
                Some(format!("--engine auto: the CPU engine, {why}")),
            )
        };
        if let Some(why) = GpuEngine::refusal(system.model()) {
            return cpu(format!("as the GPU engine cannot step this scene: {why}"));
        }
        // The adapter first: no device is opened on one that is not taken.
        let opened = match super::device::find() {
            Ok((adapter, _)) if adapter.software => {
                return cpu(format!(
                    "as the only adapter, {adapter}, is a CPU adapter and no faster"
                ));
            }
            found => found.and_then(super::device::open_found),
        };
        let opened = match opened {
            Ok(opened) => opened,
            Err(e) => return cpu(format!("as no GPU engine could start: {e}")),
        };
        match GpuEngine::on(opened, system) {
            Ok(engine) => (Self::Gpu(Box::new(engine)), None),
            Err(e) => cpu(format!("as no GPU engine could start: {e}")),
        }
    }

    /// Runs `n` steps of `system`; the outer error is the engine's, the inner
    /// one a divergence.
    pub fn run(&mut self, system: &mut System, n: u64) -> Result<Result<(), Divergence>, String> {
        match self {
            Self::Cpu => Ok(system.run(n)),
            Self::Gpu(engine) => engine.run(system, n).map_err(|e| e.to_string()),
        }
    }

    /// The GPU time of the steps so far, on the GPU engine with timestamps.
    pub fn gpu_time(&self) -> Option<GpuTime> {
        match self {
            Self::Cpu => None,
            Self::Gpu(engine) => engine.gpu_time(),
        }
    }

    /// Starts the GPU time afresh (after a warm-up).
    pub fn reset_gpu_time(&mut self) {
        if let Self::Gpu(engine) = self {
            engine.reset_gpu_time();
        }
    }

    /// The adapter, on the GPU engine.
    pub fn adapter(&self) -> Option<&super::Adapter> {
        match self {
            Self::Cpu => None,
            Self::Gpu(engine) => Some(engine.adapter()),
        }
    }
}
