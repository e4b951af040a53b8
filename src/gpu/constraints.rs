//! The GPU engine's constraint passes (`shaders/gpu/constrain.wgsl`): XPBD's
//! springs and the stretch limit, each a sweep over the springs in the model's
//! constraint order, as the f64 engine's (`sim::constraints::apply`). The order
//! is cut into runs that share no particle (`layout::constraint_runs`); a run is
//! one dispatch, a step's runs are dispatched in order, and `end_step` closes
//! the step.

use wgpu::util::DeviceExt as _;

use super::layout::{self, ConstraintSpring, RECORD_BYTES, RunRecord};
use super::params::StepParams;
use super::pipeline::Pipelines;
use super::{GpuError, dispatch_size};
use crate::sim::constraints::xpbd_sweeps_back;
use crate::sim::{Integrator, Model};

/// Which constraint passes a step runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Passes {
    pub xpbd: bool,
    pub stretch_limit: bool,
}

impl Passes {
    /// The passes `params` ask for.
    pub fn of(params: &StepParams) -> Self {
        Self {
            xpbd: params.integrator == Integrator::Xpbd,
            stretch_limit: params.stretch_limit.is_some(),
        }
    }

    /// Whether a step has constraints, and ends in `end_step`.
    pub fn any(self) -> bool {
        self.xpbd || self.stretch_limit
    }
}

/// One dispatch of a step's constraint passes: a run of springs through XPBD's
/// pass (else the stretch limit's), its record the dispatch's place in the run
/// records.
#[derive(Clone, Copy, Debug)]
struct Dispatch {
    xpbd: bool,
    /// Springs in the run.
    count: u32,
}

/// The constraint passes of one model: their bind group and a step's dispatches
/// (none without constraints, when the group binds stand-ins).
pub(super) struct Constraints {
    group: wgpu::BindGroup,
    dispatches: Vec<Dispatch>,
    /// What they were built for.
    pub passes: Passes,
}

impl Constraints {
    /// The passes `passes` of `model` on `device`; `fits` refuses a buffer over
    /// the device's limit.
    pub fn new(
        (device, pipelines): (&wgpu::Device, &Pipelines),
        model: &Model,
        passes: Passes,
        fits: impl Fn(&'static str, u64) -> Result<(), GpuError>,
    ) -> Result<Self, GpuError> {
        let Passes {
            xpbd,
            stretch_limit: stretch,
        } = passes;
        let constrained = passes.any();
        let runs = match constrained {
            true => layout::constraint_runs(model),
            false => Vec::new(),
        };
        let back = xpbd && xpbd_sweeps_back(model.lattice);
        let mut records = Vec::new();
        let mut dispatches = Vec::new();
        let mut sweep =
            |pass_xpbd: bool, sweep: u32, runs: &mut dyn Iterator<Item = &(u32, u32)>| {
                for &(start, count) in runs {
                    dispatches.push(Dispatch {
                        xpbd: pass_xpbd,
                        count,
                    });
                    records.push(RunRecord {
                        start,
                        count,
                        sweep,
                        _pad: [0; 61],
                    });
                }
            };
        if xpbd {
            let forward = if back {
                layout::FORWARD_KEPT
            } else {
                layout::FORWARD
            };
            sweep(true, forward, &mut runs.iter());
            if back {
                sweep(true, layout::BACK, &mut runs.iter().rev());
            }
        }
        if stretch {
            sweep(false, layout::FORWARD, &mut runs.iter());
        }
        let springs = match constrained {
            true => layout::constraint_springs(model),
            false => Vec::new(),
        };
        let n = model.mass.len();
        let before_bytes = if constrained { n as u64 * 32 } else { 16 };
        let spring_bytes = (springs.len() * size_of::<ConstraintSpring>()) as u64;
        let multiplier_bytes = if back { springs.len() as u64 * 4 } else { 4 };
        fits("positions before the constraints", before_bytes)?;
        fits("constraint springs", spring_bytes)?;
        fits("XPBD multipliers", multiplier_bytes)?;
        let empty = |label, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let before = empty("positions before the constraints", before_bytes);
        let multipliers = empty("XPBD multipliers", multiplier_bytes);
        let springs = filled(
            device,
            "constraint springs",
            &springs,
            wgpu::BufferUsages::STORAGE,
        );
        let records = filled(
            device,
            "constraint runs",
            &records,
            wgpu::BufferUsages::UNIFORM,
        );
        let group = pipelines.constraint_group(device, &records, [&before, &springs, &multipliers]);
        Ok(Self {
            group,
            dispatches,
            passes,
        })
    }

    /// Binds the group for a step's first pass (`step_particles` writes the
    /// positions before the constraints through it).
    pub fn bind(&self, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_bind_group(2, &self.group, &[0]);
    }

    /// Encodes the step's constraint dispatches and its end (`end_step`), after
    /// `step_particles`, for `particles` particles; nothing without constraints,
    /// whose end `step_particles` makes.
    pub fn encode(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        pipelines: &Pipelines,
        particles: usize,
    ) {
        if !self.passes.any() {
            return;
        }
        for (record, d) in self.dispatches.iter().enumerate() {
            let pipeline = if d.xpbd {
                &pipelines.xpbd
            } else {
                &pipelines.stretch_limit
            };
            pass.set_pipeline(pipeline);
            pass.set_bind_group(2, &self.group, &[(record as u64 * RECORD_BYTES) as u32]);
            let (x, y) = dispatch_size(d.count as usize);
            pass.dispatch_workgroups(x, y, 1);
        }
        pass.set_pipeline(&pipelines.end);
        let (x, y) = dispatch_size(particles);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// A buffer holding `items`, or one zeroed item where there are none (a
/// binding takes at least one).
fn filled<T: bytemuck::Pod>(
    device: &wgpu::Device,
    label: &str,
    items: &[T],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let stand_in = [T::zeroed()];
    let items = if items.is_empty() {
        &stand_in[..]
    } else {
        items
    };
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(items),
        usage,
    })
}
