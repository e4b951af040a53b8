//! The scene renderer (wgpu): the cloth as a lit, two-sided, textured mesh with
//! a front and a back colour, the colliders, a ground that fades into a gradient
//! sky, shadows from the key light, springs and wireframe as lines, particles as
//! discs (as lit spheres and tubes in scenes without a surface), and FXAA where
//! there is no MSAA. It takes plain slices, owns its GPU buffers and never
//! uploads a non-finite value. See docs/render.md.

mod buffers;
pub mod geometry;
pub mod gpu;
pub mod markers;
pub mod offscreen;
mod pipelines;
mod post;
pub mod shadow;
mod solids;
mod texture;
mod upload;

use bytemuck::{Pod, Zeroable};
use cloth_sandbox::view::OrbitCamera;
use glam::{Mat4, Vec2, Vec3};

use buffers::{DynBuffer, LineBuffers};
use geometry::{LineVertex, MeshVertex, PointInstance};

/// Depth buffer format.
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Radius at which the sphere collider is drawn, as a fraction of its collision radius.
const SPHERE_SKIN: f32 = 0.97;

/// Unit vector towards the key light (the light is high, about 63° up, so
/// shadows fall close under what casts them).
pub const LIGHT_DIR: Vec3 = Vec3::new(0.3, 0.9, 0.35);

/// What to draw this frame: plain slices, indices into `positions`.
#[derive(Clone, Copy, Debug, Default)]
pub struct SceneFrame<'a> {
    /// Particle positions (m).
    pub positions: &'a [Vec3],
    /// Surface triangles (may be empty: chains and ropes have none).
    pub triangles: &'a [[u32; 3]],
    /// Texture coordinates per particle (may be empty).
    pub uvs: &'a [Vec2],
    /// Spring endpoints.
    pub lines: &'a [[u32; 2]],
    /// Colour per spring (linear RGBA), same length as `lines`.
    pub line_colors: &'a [[f32; 4]],
    /// Pinned flag per particle (may be shorter than `positions`).
    pub pinned: &'a [bool],
    /// Particle to highlight (hovered or dragged).
    pub highlight: Option<usize>,
    /// Height of the ground plane (m), if the scene has one.
    pub ground: Option<f32>,
    /// Height (m) of a display-only floor for a scene without a ground (set once
    /// from the scene's bounds at load, so it stays put while the cloth moves);
    /// ignored when `ground` is set.
    pub floor: Option<f32>,
    /// Centre (m) and radius (m) of the sphere collider, if any.
    pub sphere: Option<(Vec3, f32)>,
    /// The other colliders, drawn where they are at `time`.
    pub colliders: &'a [cloth_sandbox::sim::Collider],
    /// Simulated time (s) of the frame.
    pub time: f64,
    /// The live reference's positions (m), drawn as a ghost wireframe over the
    /// same edges as the cloth; empty when it is off.
    pub ghost: &'a [Vec3],
}

/// Display toggles and colours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewOptions {
    /// Draw the lit surface.
    pub mesh: bool,
    /// Draw the surface's triangle edges.
    pub wireframe: bool,
    /// Draw the springs (lines; tubes in a scene without a surface).
    pub springs: bool,
    /// Draw every particle (discs; spheres in a scene without a surface).
    pub particles: bool,
    /// Mark pinned particles.
    pub pins: bool,
    /// Map the checker texture onto the cloth (otherwise plain front/back colours).
    pub textured: bool,
    /// Shadows from the key light.
    pub shadows: bool,
    /// The sky's colour at the horizon (sRGB bytes); the zenith is a deeper
    /// blue derived from it, and the area outside the viewport is cleared to it.
    pub background: [u8; 3],
    /// Particle disc diameter (px).
    pub particle_px: f32,
}

impl Default for ViewOptions {
    fn default() -> Self {
        Self {
            mesh: true,
            wireframe: false,
            springs: false,
            particles: false,
            pins: true,
            textured: true,
            shadows: true,
            background: [200, 208, 218],
            particle_px: 7.0,
        }
    }
}

/// The sky's zenith colour for a horizon colour: darker, and bluer.
pub fn zenith_of(horizon: Vec3) -> Vec3 {
    horizon * Vec3::new(0.42, 0.55, 0.78)
}

/// Camera, light, sky, ground and shadow uniforms; layout matches `Globals` in
/// `shaders/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    inv_view_proj: [[f32; 4]; 4],
    light_view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light_dir: [f32; 4],
    viewport: [f32; 4],
    zenith: [f32; 4],
    horizon: [f32; 4],
    ground: [f32; 4],
    ground_fade: [f32; 4],
    shadow: [f32; 4],
}

/// Where the staging goes this frame: the casters' bounds and the ground.
#[derive(Clone, Copy, Debug, Default)]
struct Stage {
    /// Bounds (m) of everything that casts a shadow.
    bounds: Option<(Vec3, Vec3)>,
    /// Height (m) of the ground drawn, if any.
    ground: Option<f32>,
}

/// Render targets that depend on the output size.
struct Targets {
    depth: wgpu::TextureView,
    msaa: Option<wgpu::TextureView>,
}

/// The scene renderer. `new`, then per frame `update` and `render`; `resize`
/// when the output size changes.
pub struct Renderer {
    format: wgpu::TextureFormat,
    sample_count: u32,
    size: (u32, u32),
    /// Sub-rectangle of the output the scene is drawn in: x, y, width, height (px).
    viewport: [f32; 4],
    targets: Targets,
    /// FXAA into the target, when there is no MSAA.
    post: Option<post::Fxaa>,
    globals: wgpu::Buffer,
    globals_bind: wgpu::BindGroup,
    texture_bind: wgpu::BindGroup,
    shadow: shadow::ShadowMap,
    pipelines: pipelines::Pipelines,
    /// Whether this frame draws the shadow pass, and the ground.
    shadows_on: bool,
    ground_on: bool,
    cloth_vertices: DynBuffer,
    cloth_indices: DynBuffer,
    cloth_index_count: u32,
    /// Whether the cloth vertex buffer holds this frame's vertices.
    mesh_visible: bool,
    extra_vertices: DynBuffer,
    extra_indices: DynBuffer,
    extra_index_count: u32,
    marker_vertices: DynBuffer,
    marker_indices: DynBuffer,
    marker_index_count: u32,
    lines: LineBuffers,
    points: DynBuffer,
    point_count: u32,
    background: wgpu::Color,
    /// Topology last uploaded: triangles and vertex count; the index buffer and
    /// the wireframe edges are rebuilt only when these change.
    topology: Option<(Vec<[u32; 3]>, usize)>,
    /// Indices of the usable triangles, as uploaded.
    usable: Vec<u32>,
    /// The triangles as drawn (see `upload_surface`).
    wound: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    scratch_positions: Vec<Vec3>,
    scratch_valid: Vec<bool>,
    scratch_mesh: Vec<MeshVertex>,
    scratch_lines: Vec<LineVertex>,
    scratch_points: Vec<PointInstance>,
}

/// Builds a shader module from `common.wgsl` followed by `parts`.
fn shader(device: &wgpu::Device, label: &str, parts: &[&str]) -> wgpu::ShaderModule {
    let mut code = include_str!("../../shaders/common.wgsl").to_string();
    for part in parts {
        code.push('\n');
        code.push_str(part);
    }
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(code.into()),
    })
}

/// Largest MSAA sample count (4 at most) usable for both `format` and depth.
pub fn pick_sample_count(adapter: &wgpu::Adapter, format: wgpu::TextureFormat) -> u32 {
    let color = adapter.get_texture_format_features(format).flags;
    let depth = adapter.get_texture_format_features(DEPTH_FORMAT).flags;
    [4, 2]
        .into_iter()
        .find(|&n| color.sample_count_supported(n) && depth.sample_count_supported(n))
        .unwrap_or(1)
}

impl Renderer {
    /// Creates pipelines and buffers for output in `format`, `size` pixels,
    /// with `sample_count` MSAA samples (1 for none: then FXAA).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        format: wgpu::TextureFormat,
        sample_count: u32,
        size: (u32, u32),
    ) -> Self {
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("scene globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (globals_layout, globals_bind) = globals_bind_group(device, &globals);
        let (texture_layout, texture_bind) = texture::texture_bind_group(device, queue);
        let shadow = shadow::ShadowMap::new(device, &globals_layout);
        let layouts = pipelines::Layouts {
            globals: &globals_layout,
            shadow: &shadow.layout,
            texture: &texture_layout,
        };
        let pipelines = pipelines::Pipelines::new(device, format, sample_count, &layouts);
        let vertex = wgpu::BufferUsages::VERTEX;
        let index = wgpu::BufferUsages::INDEX;
        let size = (size.0.max(1), size.1.max(1));
        Self {
            format,
            sample_count,
            size,
            viewport: [0.0, 0.0, size.0 as f32, size.1 as f32],
            targets: make_targets(device, format, sample_count, size),
            post: (sample_count <= 1).then(|| post::Fxaa::new(device, format, size)),
            globals,
            globals_bind,
            texture_bind,
            shadow,
            pipelines,
            shadows_on: false,
            ground_on: false,
            cloth_vertices: DynBuffer::new(device, "cloth vertices", vertex),
            cloth_indices: DynBuffer::new(device, "cloth indices", index),
            cloth_index_count: 0,
            mesh_visible: false,
            extra_vertices: DynBuffer::new(device, "collider vertices", vertex),
            extra_indices: DynBuffer::new(device, "collider indices", index),
            extra_index_count: 0,
            marker_vertices: DynBuffer::new(device, "marker vertices", vertex),
            marker_indices: DynBuffer::new(device, "marker indices", index),
            marker_index_count: 0,
            lines: LineBuffers::new(device),
            points: DynBuffer::new(device, "point instances", vertex),
            point_count: 0,
            background: wgpu::Color::BLACK,
            topology: None,
            usable: Vec::new(),
            wound: Vec::new(),
            edges: Vec::new(),
            scratch_positions: Vec::new(),
            scratch_valid: Vec::new(),
            scratch_mesh: Vec::new(),
            scratch_lines: Vec::new(),
            scratch_points: Vec::new(),
        }
    }

    /// Output size in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// MSAA samples per pixel (1 for none).
    pub fn sample_count(&self) -> u32 {
        self.sample_count
    }

    /// Draws the scene only in the rectangle at `origin` (px) of `size` (px),
    /// clamped to the output (the rest is still cleared to the background).
    pub fn set_viewport(&mut self, origin: Vec2, size: Vec2) {
        let out = Vec2::new(self.size.0 as f32, self.size.1 as f32);
        let lo = origin.clamp(Vec2::ZERO, out - 1.0);
        let hi = (origin + size).clamp(lo + 1.0, out);
        self.viewport = if lo.is_finite() && hi.is_finite() {
            [lo.x, lo.y, hi.x - lo.x, hi.y - lo.y]
        } else {
            [0.0, 0.0, out.x, out.y]
        };
    }

    /// The scene rectangle: origin and size (px).
    pub fn viewport(&self) -> (Vec2, Vec2) {
        let [x, y, w, h] = self.viewport;
        (Vec2::new(x, y), Vec2::new(w, h))
    }

    /// Recreates the size-dependent targets. Zero sizes (a minimised window) are
    /// ignored: there is nothing to draw until the window comes back.
    pub fn resize(&mut self, device: &wgpu::Device, size: (u32, u32)) {
        if size.0 == 0 || size.1 == 0 || size == self.size {
            return;
        }
        self.size = size;
        let (origin, extent) = self.viewport();
        self.set_viewport(origin, extent);
        self.targets = make_targets(device, self.format, self.sample_count, size);
        if let Some(post) = &mut self.post {
            post.resize(device, self.format, size);
        }
    }

    /// Uploads this frame's geometry, camera, light and staging.
    pub fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        camera: &OrbitCamera,
        options: &ViewOptions,
    ) {
        let mut positions = std::mem::take(&mut self.scratch_positions);
        let mut valid = std::mem::take(&mut self.scratch_valid);
        geometry::sanitize_all(frame.positions, &mut positions, &mut valid);
        self.upload_surface(device, queue, frame, &positions, &valid, options);
        self.upload_colliders(device, queue, frame);
        self.upload_markers(device, queue, frame, &positions, &valid, options);
        self.upload_lines(device, queue, frame, &positions, &valid, options);
        self.upload_points(device, queue, frame, &positions, &valid, options);
        let stage = stage(frame, &positions, &valid);
        self.upload_globals(queue, camera, options, &stage);
        self.scratch_positions = positions;
        self.scratch_valid = valid;
    }

    /// The camera, light, sky, ground and shadow uniforms, and the clear colour.
    fn upload_globals(
        &mut self,
        queue: &wgpu::Queue,
        camera: &OrbitCamera,
        options: &ViewOptions,
        stage: &Stage,
    ) {
        let viewport = Vec2::new(self.viewport[2], self.viewport[3]);
        let mut cam = *camera;
        let finite = |cam: &OrbitCamera| {
            let m = cam.view_proj(viewport);
            m.is_finite() && m.determinant().abs() > 0.0 && cam.eye().is_finite()
        };
        if !finite(&cam) {
            // A broken camera must not reach the GPU: fall back to the default view.
            cam = OrbitCamera::default();
        }
        let view_proj = cam.view_proj(viewport);
        let light = LIGHT_DIR.normalize();
        let horizon = Vec3::from(options.background.map(|c| f32::from(c) / 255.0));
        let (centre, radius) = match stage.bounds {
            Some((lo, hi)) => ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).clamp(0.5, 1e5)),
            None => (Vec3::ZERO, 5.0),
        };
        let fit = (stage.bounds)
            .filter(|_| {
                options.shadows
                    && (self.mesh_visible
                        || self.extra_index_count > 0
                        || self.marker_index_count > 0)
            })
            .and_then(|(lo, hi)| shadow::fit(light, lo, hi, stage.ground));
        self.shadows_on = fit.is_some();
        self.ground_on = stage.ground.is_some();
        // Grid cells of a power of ten, at most 0.8 of the scene's radius.
        let cell = 10f32.powf((radius * 0.8).log10().floor()).clamp(1e-3, 1e4);
        let mut globals = Globals {
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            light_view_proj: fit
                .map_or(Mat4::IDENTITY, |f| f.view_proj)
                .to_cols_array_2d(),
            eye: cam.eye().extend(1.0).to_array(),
            light_dir: light.extend(0.0).to_array(),
            viewport: [viewport.x, viewport.y, (cam.fov_y * 0.5).tan(), 0.0],
            zenith: zenith_of(horizon).extend(1.0).to_array(),
            horizon: horizon.extend(1.0).to_array(),
            ground: [
                stage.ground.unwrap_or(0.0),
                f32::from(u8::from(self.ground_on)),
                centre.x,
                centre.z,
            ],
            ground_fade: [2.5 * radius, 10.0 * radius, cell, 10.5 * radius],
            shadow: [
                1.0 / shadow::SIZE as f32,
                fit.map_or(0.0, |f| f.normal_offset()),
                f32::from(u8::from(self.shadows_on)),
                shadow::PCF_RADIUS,
            ],
        };
        if !bytemuck::cast_slice::<_, f32>(std::slice::from_ref(&globals))
            .iter()
            .all(|x| x.is_finite())
        {
            // Whatever is not finite (a degenerate inverse): no shadows, no ground,
            // an identity where a matrix broke.
            log::debug!("non-finite scene uniforms: drawing without staging");
            for m in [&mut globals.inv_view_proj, &mut globals.light_view_proj] {
                if !m.iter().flatten().all(|x| x.is_finite()) {
                    *m = Mat4::IDENTITY.to_cols_array_2d();
                }
            }
            globals.ground = [0.0; 4];
            globals.ground_fade = [1.0, 2.0, 1.0, 1.0];
            globals.shadow = [1.0 / shadow::SIZE as f32, 0.0, 0.0, shadow::PCF_RADIUS];
            self.shadows_on = false;
            self.ground_on = false;
        }
        queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&globals));
        let [r, g, b] = options.background.map(|c| f64::from(c) / 255.0);
        self.background = wgpu::Color { r, g, b, a: 1.0 };
    }

    /// Records the frame into `encoder`: the shadow pass, then the scene,
    /// clearing and drawing into `target` (a view of a texture in this renderer's
    /// format and size), through FXAA when there is no MSAA.
    pub fn render(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        if self.shadows_on {
            let meshes = [
                (
                    &self.cloth_vertices.buffer,
                    &self.cloth_indices.buffer,
                    if self.mesh_visible {
                        self.cloth_index_count
                    } else {
                        0
                    },
                ),
                (
                    &self.extra_vertices.buffer,
                    &self.extra_indices.buffer,
                    self.extra_index_count,
                ),
                (
                    &self.marker_vertices.buffer,
                    &self.marker_indices.buffer,
                    self.marker_index_count,
                ),
            ];
            self.shadow.render(encoder, &self.globals_bind, &meshes);
        }
        match &self.post {
            Some(post) => {
                self.scene_pass(encoder, &post.scene);
                post.render(encoder, target);
            }
            None => self.scene_pass(encoder, target),
        }
    }

    /// The main pass into `target`: sky, ground, meshes, lines, discs.
    fn scene_pass(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        let (view, resolve) = match &self.targets.msaa {
            Some(msaa) => (msaa, Some(target)),
            None => (target, None),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: resolve,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(self.background),
                    store: if resolve.is_some() {
                        wgpu::StoreOp::Discard
                    } else {
                        wgpu::StoreOp::Store
                    },
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.targets.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let [x, y, w, h] = self.viewport;
        pass.set_viewport(x, y, w, h, 0.0, 1.0);
        pass.set_bind_group(0, &self.globals_bind, &[]);
        pass.set_bind_group(1, &self.shadow.bind, &[]);
        pass.set_bind_group(2, &self.texture_bind, &[]);
        pass.set_pipeline(&self.pipelines.sky);
        pass.draw(0..3, 0..1);
        if self.ground_on {
            pass.set_pipeline(&self.pipelines.ground);
            pass.draw(0..6, 0..1);
        }
        pass.set_pipeline(&self.pipelines.mesh);
        let meshes = [
            (
                &self.cloth_vertices,
                &self.cloth_indices,
                if self.mesh_visible {
                    self.cloth_index_count
                } else {
                    0
                },
            ),
            (
                &self.extra_vertices,
                &self.extra_indices,
                self.extra_index_count,
            ),
            (
                &self.marker_vertices,
                &self.marker_indices,
                self.marker_index_count,
            ),
        ];
        for (vertices, indices, count) in meshes {
            if count > 0 {
                pass.set_vertex_buffer(0, vertices.buffer.slice(..));
                pass.set_index_buffer(indices.buffer.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..count, 0, 0..1);
            }
        }
        if self.lines.counts.iter().any(|&n| n > 0) {
            pass.set_pipeline(&self.pipelines.line);
            for (chunk, &count) in self.lines.chunks.iter().zip(&self.lines.counts) {
                pass.set_vertex_buffer(0, chunk.buffer.slice(..));
                pass.draw(0..count, 0..1);
            }
        }
        if self.point_count > 0 {
            pass.set_pipeline(&self.pipelines.point);
            pass.set_vertex_buffer(0, self.points.buffer.slice(..));
            pass.draw(0..6, 0..self.point_count);
        }
    }
}

/// The casters' bounds (valid particles, the sphere, the colliders where they
/// are at the frame's time) and the ground's height: the scene's own, else its
/// display floor; clamped to a range the shaders handle.
fn stage(frame: &SceneFrame<'_>, positions: &[Vec3], valid: &[bool]) -> Stage {
    let mut bounds: Option<(Vec3, Vec3)> = None;
    let mut grow = |lo: Vec3, hi: Vec3| {
        if lo.is_finite() && hi.is_finite() {
            bounds = Some(match bounds {
                None => (lo, hi),
                Some((a, b)) => (a.min(lo), b.max(hi)),
            });
        }
    };
    for (p, _) in positions.iter().zip(valid).filter(|(_, v)| **v) {
        grow(*p, *p);
    }
    if let Some((c, r)) = frame.sphere
        && r.is_finite()
        && r > 0.0
        && let Some(c) = geometry::sanitize(c)
    {
        let r = Vec3::splat(r.min(1e4));
        grow(c - r, c + r);
    }
    for collider in frame.colliders {
        let (centre, _) = collider.pose_at(frame.time);
        let r = collider.shape.bounding_radius();
        if centre.is_finite() && centre.abs().max_element() < 1e4 && r.is_finite() && r < 1e4 {
            let (c, r) = (centre.as_vec3(), Vec3::splat(r as f32));
            grow(c - r, c + r);
        }
    }
    let ground = (frame.ground.or(frame.floor))
        .filter(|y| y.is_finite())
        .map(|y| y.clamp(-1e4, 1e4));
    Stage { bounds, ground }
}

/// The camera and light uniforms' bind group, and its layout.
fn globals_bind_group(
    device: &wgpu::Device,
    globals: &wgpu::Buffer,
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene globals layout"),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene globals bind group"),
        layout: &layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: globals.as_entire_binding(),
        }],
    });
    (layout, bind)
}

/// The depth buffer and, with MSAA, the multisampled colour target.
fn make_targets(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    sample_count: u32,
    size: (u32, u32),
) -> Targets {
    let extent = wgpu::Extent3d {
        width: size.0.max(1),
        height: size.1.max(1),
        depth_or_array_layers: 1,
    };
    let depth = device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("scene depth"),
            size: extent,
            mip_level_count: 1,
            sample_count,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&Default::default());
    let msaa = (sample_count > 1).then(|| {
        device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("scene msaa colour"),
                size: extent,
                mip_level_count: 1,
                sample_count,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&Default::default())
    });
    Targets { depth, msaa }
}
