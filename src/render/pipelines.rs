//! The main pass's pipelines: sky, ground, lit meshes, lines and particle discs,
//! for output in one format with one MSAA sample count.

use super::geometry::{LineVertex, MeshVertex, PointInstance};
use super::{DEPTH_FORMAT, shader};

/// The main pass's pipelines.
pub struct Pipelines {
    pub sky: wgpu::RenderPipeline,
    pub ground: wgpu::RenderPipeline,
    pub mesh: wgpu::RenderPipeline,
    pub line: wgpu::RenderPipeline,
    pub point: wgpu::RenderPipeline,
}

/// Bind group layouts: 0 the globals, 1 the shadow map, 2 the cloth texture.
pub struct Layouts<'a> {
    pub globals: &'a wgpu::BindGroupLayout,
    pub shadow: &'a wgpu::BindGroupLayout,
    pub texture: &'a wgpu::BindGroupLayout,
}

/// What differs between the pipelines.
struct Spec<'a> {
    label: &'a str,
    layout: &'a wgpu::PipelineLayout,
    shader: &'a wgpu::ShaderModule,
    buffer: Option<wgpu::VertexBufferLayout<'a>>,
    primitive: wgpu::PrimitiveState,
    /// Writes and tests depth (the sky does neither).
    depth: bool,
}

const COMMON: &str = include_str!("../../shaders/shadow_sample.wgsl");

impl Pipelines {
    /// Every pipeline for output in `format` with `samples` samples per pixel.
    pub fn new(
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        samples: u32,
        layouts: &Layouts<'_>,
    ) -> Self {
        let layout = |label: &str, groups: &[Option<&wgpu::BindGroupLayout>]| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: groups,
                immediate_size: 0,
            })
        };
        let lit = layout(
            "mesh pipeline layout",
            &[
                Some(layouts.globals),
                Some(layouts.shadow),
                Some(layouts.texture),
            ],
        );
        let shadowed = layout(
            "ground pipeline layout",
            &[Some(layouts.globals), Some(layouts.shadow)],
        );
        let plain = layout("overlay pipeline layout", &[Some(layouts.globals)]);
        let build = |spec: Spec<'_>| build(device, format, samples, spec);
        let triangles = wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        };

        let sky_shader = shader(
            device,
            "sky.wgsl",
            &[include_str!("../../shaders/sky.wgsl")],
        );
        let sky = build(Spec {
            label: "sky pipeline",
            layout: &plain,
            shader: &sky_shader,
            buffer: None,
            primitive: triangles,
            depth: false,
        });
        let ground_shader = shader(
            device,
            "ground.wgsl",
            &[COMMON, include_str!("../../shaders/ground.wgsl")],
        );
        let ground = build(Spec {
            label: "ground pipeline",
            layout: &shadowed,
            shader: &ground_shader,
            buffer: None,
            primitive: triangles,
            depth: true,
        });
        let mesh_shader = shader(
            device,
            "mesh.wgsl",
            &[COMMON, include_str!("../../shaders/mesh.wgsl")],
        );
        let mesh_attrs = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4, 4 => Float32x4
        ];
        let mesh = build(Spec {
            label: "mesh pipeline",
            layout: &lit,
            shader: &mesh_shader,
            buffer: Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<MeshVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &mesh_attrs,
            }),
            primitive: triangles,
            depth: true,
        });
        let line_shader = shader(
            device,
            "lines.wgsl",
            &[include_str!("../../shaders/lines.wgsl")],
        );
        let line_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4];
        let line = build(Spec {
            label: "line pipeline",
            layout: &plain,
            shader: &line_shader,
            buffer: Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<LineVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &line_attrs,
            }),
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::LineList,
                ..Default::default()
            },
            depth: true,
        });
        let point_shader = shader(
            device,
            "points.wgsl",
            &[include_str!("../../shaders/points.wgsl")],
        );
        let point_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32x4];
        let point = build(Spec {
            label: "point pipeline",
            layout: &plain,
            shader: &point_shader,
            buffer: Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<PointInstance>() as u64,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &point_attrs,
            }),
            primitive: wgpu::PrimitiveState::default(),
            depth: true,
        });
        Self {
            sky,
            ground,
            mesh,
            line,
            point,
        }
    }
}

/// One pipeline with `vs_main` and `fs_main` of its shader, replacing colour.
fn build(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    samples: u32,
    spec: Spec<'_>,
) -> wgpu::RenderPipeline {
    let buffers = [spec.buffer];
    let buffers: &[Option<wgpu::VertexBufferLayout<'_>>] =
        if buffers[0].is_some() { &buffers } else { &[] };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(spec.layout),
        vertex: wgpu::VertexState {
            module: spec.shader,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers,
        },
        primitive: spec.primitive,
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(spec.depth),
            depth_compare: Some(if spec.depth {
                wgpu::CompareFunction::LessEqual
            } else {
                wgpu::CompareFunction::Always
            }),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: samples,
            mask: !0,
            alpha_to_coverage_enabled: false,
        },
        fragment: Some(wgpu::FragmentState {
            module: spec.shader,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format,
                blend: Some(wgpu::BlendState::REPLACE),
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}
