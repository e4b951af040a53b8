//! The step's compute pipeline and its bind groups, as `shaders/gpu/step.wgsl`
//! declares them.

use std::num::NonZeroU64;

use super::layout::RECORD_BYTES;

/// The step shader: the laws, then the pass that calls them.
pub(super) const STEP_SHADER: &str = concat!(
    include_str!("../../shaders/gpu/laws.wgsl"),
    include_str!("../../shaders/gpu/step.wgsl")
);

/// The pipeline and its two bind group layouts (handles: a clone shares them).
#[derive(Clone)]
pub(super) struct Pipelines {
    pub pipeline: wgpu::ComputePipeline,
    step: wgpu::BindGroupLayout,
    topology: wgpu::BindGroupLayout,
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
        let step = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("step: records and particles"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: NonZeroU64::new(RECORD_BYTES),
                    },
                    count: None,
                },
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
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("step"),
            bind_group_layouts: &[Some(&step), Some(&topology)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("step particles"),
            layout: Some(&layout),
            module: &module,
            entry_point: Some("step_particles"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self {
            pipeline,
            step,
            topology,
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
            layout: &self.step,
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
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}
