//! The step's compute pipelines and their bind groups, as `shaders/gpu/step.wgsl`
//! and `shaders/gpu/constrain.wgsl` declare them: the step of every particle, the
//! constraint passes over runs of springs, and the end of a constrained step.

use std::num::NonZeroU64;

use super::layout::RECORD_BYTES;

/// The step's shaders: the laws, then the passes that call them.
pub(super) const STEP_SHADER: &str = concat!(
    include_str!("../../shaders/gpu/laws.wgsl"),
    include_str!("../../shaders/gpu/step.wgsl"),
    include_str!("../../shaders/gpu/constrain.wgsl")
);

/// Storage buffers the pipelines bind in one stage: four of the particles (in
/// and out, and Verlet's update velocities), three of the adjacency and three of
/// the constraints. That is over WebGPU's default of 8: a device with fewer is
/// refused before any pipeline is made.
pub(super) const STORAGE_BUFFERS: u32 = 10;

/// The pipelines and their three bind group layouts (handles: a clone shares
/// them).
#[derive(Clone)]
pub(super) struct Pipelines {
    /// `step_particles`.
    pub step: wgpu::ComputePipeline,
    /// `xpbd_run`.
    pub xpbd: wgpu::ComputePipeline,
    /// `stretch_limit_run`.
    pub stretch_limit: wgpu::ComputePipeline,
    /// `end_step`.
    pub end: wgpu::ComputePipeline,
    records: wgpu::BindGroupLayout,
    topology: wgpu::BindGroupLayout,
    constraints: wgpu::BindGroupLayout,
}

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl Pipelines {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("step.wgsl"),
            source: wgpu::ShaderSource::Wgsl(STEP_SHADER.into()),
        });
        let records = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("step: records and particles"),
            entries: &[
                record(0),
                storage(1, true),
                storage(2, true),
                storage(3, false),
                storage(4, false),
            ],
        });
        let topology = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("step: adjacency"),
            entries: &[storage(0, true), storage(1, true), storage(2, true)],
        });
        let constraints = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("step: constraints"),
            entries: &[
                record(0),
                storage(1, false),
                storage(2, true),
                storage(3, false),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("step"),
            bind_group_layouts: &[Some(&records), Some(&topology), Some(&constraints)],
            immediate_size: 0,
        });
        let pipeline = |entry_point| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry_point),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry_point),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        Self {
            step: pipeline("step_particles"),
            xpbd: pipeline("xpbd_run"),
            stretch_limit: pipeline("stretch_limit_run"),
            end: pipeline("end_step"),
            records,
            topology,
            constraints,
        }
    }

    /// The bind group of a step `k` with `k % 2 == parity`: it reads
    /// `state[parity]` and writes the other.
    pub fn step_group(
        &self,
        device: &wgpu::Device,
        records: &wgpu::Buffer,
        state: &[wgpu::Buffer; 2],
        u: &[wgpu::Buffer; 2],
        parity: usize,
    ) -> wgpu::BindGroup {
        let (from, to) = (parity, 1 - parity);
        let record = wgpu::BufferBinding {
            buffer: records,
            offset: 0,
            size: NonZeroU64::new(RECORD_BYTES),
        };
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("step"),
            layout: &self.records,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(record),
                },
                entry(1, &state[from]),
                entry(2, &u[from]),
                entry(3, &state[to]),
                entry(4, &u[to]),
            ],
        })
    }

    /// The bind group of the adjacency: offsets, spring links, triangle links.
    pub fn topology_group(
        &self,
        device: &wgpu::Device,
        buffers: [&wgpu::Buffer; 3],
    ) -> wgpu::BindGroup {
        let entries: Vec<_> = (0..3).map(|i| entry(i as u32, buffers[i])).collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("adjacency"),
            layout: &self.topology,
            entries: &entries,
        })
    }

    /// The bind group of the constraint passes: the run records, the positions
    /// before the constraints, the springs in order, the multipliers.
    pub fn constraint_group(
        &self,
        device: &wgpu::Device,
        runs: &wgpu::Buffer,
        buffers: [&wgpu::Buffer; 3],
    ) -> wgpu::BindGroup {
        let run = wgpu::BufferBinding {
            buffer: runs,
            offset: 0,
            size: NonZeroU64::new(RECORD_BYTES),
        };
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::Buffer(run),
        }];
        entries.extend((0..3).map(|i| entry(i as u32 + 1, buffers[i])));
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("constraints"),
            layout: &self.constraints,
            entries: &entries,
        })
    }
}

/// A uniform binding of one 256-byte record, at a dynamic offset.
fn record(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: true,
            min_binding_size: NonZeroU64::new(RECORD_BYTES),
        },
        count: None,
    }
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}
