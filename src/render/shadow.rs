//! Shadow mapping from the key light: a Depth32Float map drawn from a directional
//! light through an orthographic frustum fitted to the scene's casters and the
//! ground they shadow, read back through a comparison sampler (PCF in
//! `shaders/shadow_sample.wgsl`).

use glam::{Mat4, Vec3, Vec4Swizzles};

use super::geometry::MeshVertex;

/// Shadow map format.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Shadow map side (texels).
pub const SIZE: u32 = 2048;
/// PCF disc radius (texels).
pub const PCF_RADIUS: f32 = 2.5;
/// Normal offset of a receiver before its lookup, in shadow texels.
const NORMAL_OFFSET_TEXELS: f32 = 1.5;

/// The shadow map, the main pass's view of it, and the depth-only pipeline.
pub struct ShadowMap {
    /// The map as the shadow pass's depth attachment.
    pub attachment: wgpu::TextureView,
    /// Bind group 1 of the lit pipelines: the map and its comparison sampler.
    pub bind: wgpu::BindGroup,
    /// Its layout.
    pub layout: wgpu::BindGroupLayout,
    /// Meshes into the map, depth only.
    pub pipeline: wgpu::RenderPipeline,
}

/// The light's frustum for one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightFit {
    /// World to the light's clip space.
    pub view_proj: Mat4,
    /// World size (m) of a shadow texel.
    pub texel: f32,
}

impl LightFit {
    /// Normal offset (m) the receivers apply.
    pub fn normal_offset(&self) -> f32 {
        self.texel * NORMAL_OFFSET_TEXELS
    }
}

impl ShadowMap {
    /// Creates the map and its pipeline; `globals_layout` is bind group 0.
    pub fn new(device: &wgpu::Device, globals_layout: &wgpu::BindGroupLayout) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow map"),
            size: wgpu::Extent3d {
                width: SIZE,
                height: SIZE,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let attachment = texture.create_view(&Default::default());
        let sampled = texture.create_view(&Default::default());
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadow comparison sampler"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
            ],
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadow bind group"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&sampled),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
            ],
        });
        let pipeline = depth_pipeline(device, globals_layout);
        Self {
            attachment,
            bind,
            layout,
            pipeline,
        }
    }

    /// Records the shadow pass: clears the map, then draws each `(vertices,
    /// indices, count)` mesh into it.
    pub fn render(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        globals: &wgpu::BindGroup,
        meshes: &[(&wgpu::Buffer, &wgpu::Buffer, u32)],
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.attachment,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, globals, &[]);
        for &(vertices, indices, count) in meshes {
            if count == 0 {
                continue;
            }
            pass.set_vertex_buffer(0, vertices.slice(..));
            pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..count, 0, 0..1);
        }
    }
}

/// The depth-only pipeline: positions through `light_view_proj`, both sides,
/// with a slope-scaled depth bias (more bias where a surface is steep to the
/// light, where one texel spans the most depth).
fn depth_pipeline(
    device: &wgpu::Device,
    globals_layout: &wgpu::BindGroupLayout,
) -> wgpu::RenderPipeline {
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadow pipeline layout"),
        bind_group_layouts: &[Some(globals_layout)],
        immediate_size: 0,
    });
    let module = super::shader(
        device,
        "shadow.wgsl",
        &[include_str!("../../shaders/shadow.wgsl")],
    );
    let attrs = wgpu::vertex_attr_array![0 => Float32x3];
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("shadow pipeline"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<MeshVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &attrs,
            })],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::LessEqual),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState {
                constant: 2,
                slope_scale: 2.0,
                clamp: 0.0,
            },
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: None,
        multiview_mask: None,
        cache: None,
    })
}

/// The light's frustum for casters inside `lo..hi` lit along `-light` (`light`
/// a unit vector towards the light): an orthographic box around the casters
/// across the light, and deep enough along it to reach the ground at `ground`
/// (where the casters' shadows fall). Its side is rounded up to a step of
/// 2^(1/4) and its centre to whole texels, so a cloth moving inside it does not
/// make the shadows' edges crawl. `None` for empty or non-finite bounds.
pub fn fit(light: Vec3, lo: Vec3, hi: Vec3, ground: Option<f32>) -> Option<LightFit> {
    if !(lo.is_finite() && hi.is_finite() && light.is_finite()) || lo.cmpgt(hi).any() {
        return None;
    }
    let light = light.try_normalize()?;
    let up = if light.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    // Rotation only: light space is the same frame to frame.
    let view = glam::camera::rh::view::look_at_mat4(light, Vec3::ZERO, up);
    let mut points: Vec<Vec3> = (0..8)
        .map(|k| {
            Vec3::new(
                [lo.x, hi.x][k & 1],
                [lo.y, hi.y][(k >> 1) & 1],
                [lo.z, hi.z][k >> 2],
            )
        })
        .collect();
    if let Some(g) = ground.filter(|g| g.is_finite())
        && light.y > 1e-3
    {
        // Where each corner's shadow lands on the ground: c - light (c.y - g) / light.y.
        let landed: Vec<Vec3> = (points.iter())
            .map(|&c| c - light * ((c.y - g).max(0.0) / light.y))
            .collect();
        points.extend(landed);
    }
    let local: Vec<Vec3> = points
        .iter()
        .map(|&p| (view * p.extend(1.0)).xyz())
        .collect();
    let (min, max) = cloth_sandbox::view::bounds(&local)?;
    let span = (max.x - min.x).max(max.y - min.y).max(1e-3) * 1.02;
    let side = 2f32.powf((span.log2() * 4.0).ceil() / 4.0);
    let texel = side / SIZE as f32;
    let centre = ((min.truncate() + max.truncate()) * 0.5 / texel).round() * texel;
    let half = side * 0.5;
    // View space looks down -z: near and far are distances along it.
    let depth_pad = 0.05 * (max.z - min.z).max(side) + 1e-3;
    let proj = glam::camera::rh::proj::directx::orthographic(
        centre.x - half,
        centre.x + half,
        centre.y - half,
        centre.y + half,
        -max.z - depth_pad,
        -min.z + depth_pad,
    );
    let view_proj = proj * view;
    (view_proj.is_finite() && texel.is_finite() && texel > 0.0)
        .then_some(LightFit { view_proj, texel })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_holds_the_casters_and_their_shadow_on_the_ground() {
        let light = Vec3::new(0.3, 0.9, 0.35).normalize();
        let (lo, hi) = (Vec3::new(-1.0, 1.0, -1.0), Vec3::new(1.0, 3.0, 1.0));
        let f = fit(light, lo, hi, Some(0.0)).unwrap();
        let inside = |p: Vec3| {
            let c = f.view_proj * p.extend(1.0);
            let n = c.xyz() / c.w;
            n.x.abs() <= 1.0 && n.y.abs() <= 1.0 && (0.0..=1.0).contains(&n.z)
        };
        assert!(inside(lo) && inside(hi));
        // Below the box's centre on the ground, along the light.
        let c = (lo + hi) * 0.5;
        assert!(inside(c - light * (c.y / light.y)));
        assert!(fit(light, hi, lo, None).is_none());
        assert!(fit(light, Vec3::NAN, hi, None).is_none());
    }
}
