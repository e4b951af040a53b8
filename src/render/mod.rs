//! The scene renderer (wgpu): the cloth as a lit, two-sided, textured mesh,
//! springs and wireframe as lines, particles as discs, ground and sphere.
//! It takes plain slices, owns its GPU buffers and never uploads a non-finite value.

pub mod geometry;
pub mod gpu;
pub mod offscreen;
mod solids;

use bytemuck::{Pod, Zeroable};
use cloth_sandbox::view::OrbitCamera;
use glam::{Vec2, Vec3};
use wgpu::util::DeviceExt;

use geometry::{LineVertex, MeshVertex, PointInstance};

/// Depth buffer format.
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The checker texture mapped on the cloth by its UVs.
const CHECKER_PNG: &[u8] = include_bytes!("../../assets/textures/checker.png");

/// What to draw this frame: plain slices, indices into `positions`.
/// Radius at which the sphere collider is drawn, as a fraction of its collision radius.
const SPHERE_SKIN: f32 = 0.97;

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
    /// Centre (m) and radius (m) of the sphere collider, if any.
    pub sphere: Option<(Vec3, f32)>,
    /// The other colliders, drawn where they are at `time`.
    pub colliders: &'a [cloth_sandbox::sim::Collider],
    /// Simulated time (s) of the frame.
    pub time: f64,
}

/// Display toggles and colours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewOptions {
    /// Draw the lit surface.
    pub mesh: bool,
    /// Draw the surface's triangle edges.
    pub wireframe: bool,
    /// Draw the springs as lines.
    pub springs: bool,
    /// Draw every particle as a disc.
    pub particles: bool,
    /// Mark pinned particles.
    pub pins: bool,
    /// Map the checker texture onto the cloth (otherwise plain front/back colours).
    pub textured: bool,
    /// Background colour (sRGB bytes).
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
            background: [38, 44, 56],
            particle_px: 7.0,
        }
    }
}

/// Camera and light uniforms; layout matches `Globals` in `shaders/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    light_dir: [f32; 4],
    back_tint: [f32; 4],
    viewport: [f32; 4],
}

/// A GPU buffer that grows (by doubling) when the data outgrows it, never past
/// the device's largest buffer (`max_buffer_size`).
struct DynBuffer {
    buffer: wgpu::Buffer,
    capacity: u64,
    /// The device's largest buffer in bytes.
    limit: u64,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl DynBuffer {
    fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages) -> Self {
        let usage = usage | wgpu::BufferUsages::COPY_DST;
        let capacity = 1024;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: capacity,
            usage,
            mapped_at_creation: false,
        });
        Self {
            buffer,
            capacity,
            limit: device.limits().max_buffer_size,
            usage,
            label,
        }
    }

    /// Most whole elements of `stride` bytes one buffer can hold on this device.
    fn max_elements(&self, stride: usize) -> usize {
        usize::try_from(self.limit / stride as u64).unwrap_or(usize::MAX)
    }

    /// Uploads `items` from offset 0, reallocating if too small, and returns how
    /// many were uploaded: all of them, or as many as the device's largest buffer
    /// holds (the caller draws that many and says what was left out).
    fn write<T: Pod>(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, items: &[T]) -> usize {
        let stride = std::mem::size_of::<T>().max(1);
        let count = items.len().min(self.max_elements(stride));
        let bytes: &[u8] = bytemuck::cast_slice(&items[..count]);
        let len = bytes.len() as u64;
        if len > self.capacity {
            self.capacity = len.next_power_of_two().min(self.limit);
            self.buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size: self.capacity,
                usage: self.usage,
                mapped_at_creation: false,
            });
        }
        if len > 0 {
            queue.write_buffer(&self.buffer, 0, bytes);
        }
        if count < items.len() {
            log::warn!(
                "{}: {} of {} items fit in the device's largest buffer ({} bytes); the rest are not drawn",
                self.label,
                count,
                items.len(),
                self.limit
            );
        }
        count
    }
}

/// Line vertices split over as many buffers as the device's buffer size limit
/// needs, each drawn with its own call: every line is drawn, however many.
struct LineBuffers {
    chunks: Vec<DynBuffer>,
    /// Vertices in each chunk, in order.
    counts: Vec<u32>,
}

impl LineBuffers {
    fn new(device: &wgpu::Device) -> Self {
        Self {
            chunks: vec![DynBuffer::new(
                device,
                "line vertices",
                wgpu::BufferUsages::VERTEX,
            )],
            counts: Vec::new(),
        }
    }

    /// Uploads `vertices` (pairs, one line each) in chunks of whole lines.
    fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, vertices: &[LineVertex]) {
        let per_chunk =
            lines_per_buffer(self.chunks[0].max_elements(std::mem::size_of::<LineVertex>()));
        self.counts.clear();
        for (i, chunk) in vertices.chunks(per_chunk.max(2)).enumerate() {
            if i == self.chunks.len() {
                self.chunks.push(DynBuffer::new(
                    device,
                    "line vertices",
                    wgpu::BufferUsages::VERTEX,
                ));
            }
            let written = self.chunks[i].write(device, queue, chunk);
            self.counts.push(draw_count(written));
        }
        // Buffers no longer needed are given back (one stays for next time).
        self.chunks.truncate(self.counts.len().max(1));
    }
}

/// Vertices of whole lines (an even number, and at most `u32::MAX`) that fit in
/// a buffer of `max_vertices` vertices.
fn lines_per_buffer(max_vertices: usize) -> usize {
    max_vertices.min(u32::MAX as usize) & !1
}

/// A count for a draw call: counts past `u32::MAX` draw `u32::MAX`.
fn draw_count(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
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
    globals: wgpu::Buffer,
    globals_bind: wgpu::BindGroup,
    texture_bind: wgpu::BindGroup,
    mesh_pipeline: wgpu::RenderPipeline,
    line_pipeline: wgpu::RenderPipeline,
    point_pipeline: wgpu::RenderPipeline,
    cloth_vertices: DynBuffer,
    cloth_indices: DynBuffer,
    cloth_index_count: u32,
    /// Whether the cloth vertex buffer holds this frame's vertices.
    mesh_visible: bool,
    extra_vertices: DynBuffer,
    extra_indices: DynBuffer,
    extra_index_count: u32,
    lines: LineBuffers,
    points: DynBuffer,
    point_count: u32,
    background: wgpu::Color,
    /// Topology last uploaded: triangles and vertex count; the index buffer and
    /// the wireframe edges are rebuilt only when these change.
    topology: Option<(Vec<[u32; 3]>, usize)>,
    /// Indices of the usable triangles, as uploaded.
    usable: Vec<u32>,
    /// The triangles as drawn (see `update`).
    wound: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    scratch_positions: Vec<Vec3>,
    scratch_valid: Vec<bool>,
    scratch_mesh: Vec<MeshVertex>,
    scratch_lines: Vec<LineVertex>,
    scratch_points: Vec<PointInstance>,
}

/// Builds a shader module from `common.wgsl` followed by `source`.
fn shader(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    let code = format!("{}\n{}", include_str!("../../shaders/common.wgsl"), source);
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
    /// with `sample_count` MSAA samples (1 for none).
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
        let (texture_layout, texture_bind) = texture_bind_group(device, queue);
        let [mesh_pipeline, line_pipeline, point_pipeline] = pipelines(
            device,
            format,
            sample_count,
            &globals_layout,
            &texture_layout,
        );
        let vertex = wgpu::BufferUsages::VERTEX;
        let index = wgpu::BufferUsages::INDEX;
        let size = (size.0.max(1), size.1.max(1));
        Self {
            format,
            sample_count,
            size,
            viewport: [0.0, 0.0, size.0 as f32, size.1 as f32],
            targets: make_targets(device, format, sample_count, size),
            globals,
            globals_bind,
            texture_bind,
            mesh_pipeline,
            line_pipeline,
            point_pipeline,
            cloth_vertices: DynBuffer::new(device, "cloth vertices", vertex),
            cloth_indices: DynBuffer::new(device, "cloth indices", index),
            cloth_index_count: 0,
            mesh_visible: false,
            extra_vertices: DynBuffer::new(device, "collider vertices", vertex),
            extra_indices: DynBuffer::new(device, "collider indices", index),
            extra_index_count: 0,
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
    }

    /// Uploads this frame's geometry and camera.
    pub fn update(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        camera: &OrbitCamera,
        options: &ViewOptions,
    ) {
        self.upload_globals(queue, camera, options);
        let mut positions = std::mem::take(&mut self.scratch_positions);
        let mut valid = std::mem::take(&mut self.scratch_valid);
        geometry::sanitize_all(frame.positions, &mut positions, &mut valid);
        self.upload_surface(device, queue, frame, &positions, &valid, options);
        self.upload_colliders(device, queue, frame, &positions);
        self.upload_lines(device, queue, frame, &positions, &valid, options);
        self.upload_points(device, queue, frame, &positions, &valid, options);
        self.scratch_positions = positions;
        self.scratch_valid = valid;
    }

    /// The camera and light uniforms, and the background colour.
    fn upload_globals(&mut self, queue: &wgpu::Queue, camera: &OrbitCamera, options: &ViewOptions) {
        let viewport = Vec2::new(self.viewport[2], self.viewport[3]);
        let mut globals = Globals {
            view_proj: camera.view_proj(viewport).to_cols_array_2d(),
            eye: camera.eye().extend(1.0).to_array(),
            light_dir: Vec3::new(0.35, 0.85, 0.45)
                .normalize()
                .extend(0.0)
                .to_array(),
            back_tint: Vec3::from(geometry::BACK_TINT).extend(1.0).to_array(),
            viewport: [viewport.x, viewport.y, (camera.fov_y * 0.5).tan(), 0.0],
        };
        if !bytemuck::cast_slice::<_, f32>(std::slice::from_ref(&globals))
            .iter()
            .all(|x| x.is_finite())
        {
            // A broken camera must not reach the GPU: fall back to the default view.
            let cam = OrbitCamera::default();
            globals.view_proj = cam.view_proj(viewport).to_cols_array_2d();
            globals.eye = cam.eye().extend(1.0).to_array();
            globals.viewport[2] = (cam.fov_y * 0.5).tan();
        }
        queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&globals));
        let [r, g, b] = options.background.map(|c| f64::from(c) / 255.0);
        self.background = wgpu::Color { r, g, b, a: 1.0 };
    }

    /// The surface: indices only when the topology changes, vertices every frame.
    fn upload_surface(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        positions: &[Vec3],
        valid: &[bool],
        options: &ViewOptions,
    ) {
        let n = positions.len();
        let changed = match &self.topology {
            Some((tris, count)) => *count != n || tris.as_slice() != frame.triangles,
            None => true,
        };
        if changed {
            self.topology = Some((frame.triangles.to_vec(), n));
            self.edges = geometry::triangle_edges(frame.triangles);
            // The core winds its cloth so that the side facing the default camera is
            // clockwise; draw it the other way round so that side is the front.
            self.wound.clear();
            self.wound
                .extend(frame.triangles.iter().map(|&[a, b, c]| [a, c, b]));
            self.usable.clear();
            self.usable.extend(
                self.wound
                    .iter()
                    .filter(|t| t.iter().all(|&i| (i as usize) < n))
                    .flatten(),
            );
            let written = self.cloth_indices.write(device, queue, &self.usable);
            self.cloth_index_count = draw_count(written - written % 3);
        }
        let all_valid = valid.iter().all(|&v| v);
        self.mesh_visible = options.mesh && self.cloth_index_count > 0;
        if self.mesh_visible && self.cloth_index_count > 0 {
            let normals = geometry::vertex_normals(positions, &self.wound, valid);
            let mut mesh = std::mem::take(&mut self.scratch_mesh);
            geometry::cloth_vertices(positions, &normals, frame.uvs, options.textured, &mut mesh);
            if self.cloth_vertices.write(device, queue, &mesh) < mesh.len() {
                // Indices would reach past the vertices uploaded: no surface.
                self.mesh_visible = false;
            }
            self.scratch_mesh = mesh;
            if !all_valid {
                // Rare: drop triangles touching a non-finite particle this frame.
                let idx: Vec<u32> = self
                    .wound
                    .iter()
                    .filter(|t| geometry::usable_triangle(t, valid))
                    .flatten()
                    .copied()
                    .collect();
                let written = self.cloth_indices.write(device, queue, &idx);
                self.cloth_index_count = draw_count(written - written % 3);
                self.topology = None;
            }
        }
    }

    /// The ground and the sphere, sized to the cloth's bounds.
    fn upload_colliders(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        positions: &[Vec3],
    ) {
        let mut extra = Vec::new();
        let mut extra_idx = Vec::new();
        let (centre, half) = match cloth_sandbox::view::bounds(positions) {
            Some((lo, hi)) => ((lo + hi) * 0.5, ((hi - lo).length() * 1.5).max(6.0)),
            None => (Vec3::ZERO, 10.0),
        };
        if let Some(y) = frame.ground.filter(|y| y.is_finite()) {
            geometry::ground_mesh(y.clamp(-1e4, 1e4), centre, half, &mut extra, &mut extra_idx);
        }
        if let Some((c, r)) = frame.sphere
            && let Some(c) = geometry::sanitize(c)
            && r.is_finite()
            && r > 0.0
        {
            // Drawn a little inside its collision radius: cloth resting on the sphere
            // has its particles on the surface and its flat triangles as chords
            // inside it, through which the full-size sphere would show.
            geometry::sphere_mesh(c, SPHERE_SKIN * r.min(1e4), &mut extra, &mut extra_idx);
        }
        for collider in frame.colliders {
            let skin = f64::from(SPHERE_SKIN);
            solids::push_collider(collider, frame.time, skin, &mut extra, &mut extra_idx);
        }
        let extra_index_count = if self.extra_vertices.write(device, queue, &extra) < extra.len() {
            0
        } else {
            let written = self.extra_indices.write(device, queue, &extra_idx);
            written - written % 3
        };
        self.extra_index_count = draw_count(extra_index_count);
    }

    /// Lines: springs, then wireframe.
    fn upload_lines(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        positions: &[Vec3],
        valid: &[bool],
        options: &ViewOptions,
    ) {
        let mut lines = std::mem::take(&mut self.scratch_lines);
        lines.clear();
        if options.springs {
            let colors = frame.line_colors;
            geometry::push_lines(
                positions,
                valid,
                frame.lines,
                |k| colors.get(k).copied().unwrap_or(geometry::WIRE_COLOR),
                &mut lines,
            );
        }
        if options.wireframe {
            // Dark over the lit surface, light on the background without it.
            let color = match options.mesh {
                true => geometry::WIRE_COLOR,
                false => geometry::WIRE_ALONE_COLOR,
            };
            geometry::push_lines(positions, valid, &self.edges, |_| color, &mut lines);
        }
        self.lines.write(device, queue, &lines);
        self.scratch_lines = lines;
    }

    /// Points: free particles, then pins and the highlight on top.
    fn upload_points(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        positions: &[Vec3],
        valid: &[bool],
        options: &ViewOptions,
    ) {
        let mut points = std::mem::take(&mut self.scratch_points);
        points.clear();
        let size = options.particle_px.clamp(1.0, 64.0);
        for (i, p) in positions.iter().enumerate() {
            if !valid[i] {
                continue;
            }
            let pinned = frame.pinned.get(i).copied().unwrap_or(false);
            let highlighted = frame.highlight == Some(i);
            let (color, size) = if highlighted && pinned && options.pins {
                (geometry::PIN_COLOR, size * 1.6 + 2.0)
            } else if highlighted {
                (geometry::HIGHLIGHT_COLOR, size * 1.6 + 2.0)
            } else if pinned && options.pins {
                (geometry::PIN_COLOR, size * 1.4 + 1.0)
            } else if options.particles {
                (geometry::PARTICLE_COLOR, size)
            } else {
                continue;
            };
            points.push(PointInstance {
                position: p.to_array(),
                size,
                color,
            });
        }
        // Draw order = depth ties: later instances win, so put highlights last.
        points.sort_by(|a, b| a.size.total_cmp(&b.size));
        self.point_count = draw_count(self.points.write(device, queue, &points));
        self.scratch_points = points;
    }

    /// Records the scene pass into `encoder`, clearing and drawing into `target`
    /// (a view of a texture in this renderer's format and size).
    pub fn render(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
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
        pass.set_bind_group(1, &self.texture_bind, &[]);
        pass.set_pipeline(&self.mesh_pipeline);
        if self.mesh_visible && self.cloth_index_count > 0 {
            pass.set_vertex_buffer(0, self.cloth_vertices.buffer.slice(..));
            pass.set_index_buffer(
                self.cloth_indices.buffer.slice(..),
                wgpu::IndexFormat::Uint32,
            );
            pass.draw_indexed(0..self.cloth_index_count, 0, 0..1);
        }
        if self.extra_index_count > 0 {
            pass.set_vertex_buffer(0, self.extra_vertices.buffer.slice(..));
            pass.set_index_buffer(
                self.extra_indices.buffer.slice(..),
                wgpu::IndexFormat::Uint32,
            );
            pass.draw_indexed(0..self.extra_index_count, 0, 0..1);
        }
        if self.lines.counts.iter().any(|&n| n > 0) {
            pass.set_pipeline(&self.line_pipeline);
            for (chunk, &count) in self.lines.chunks.iter().zip(&self.lines.counts) {
                pass.set_vertex_buffer(0, chunk.buffer.slice(..));
                pass.draw(0..count, 0..1);
            }
        }
        if self.point_count > 0 {
            pass.set_pipeline(&self.point_pipeline);
            pass.set_vertex_buffer(0, self.points.buffer.slice(..));
            pass.draw(0..6, 0..self.point_count);
        }
    }
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

/// The checker texture and its repeating sampler as a bind group, and its layout.
fn texture_bind_group(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("cloth texture layout"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ],
    });
    let texture_view = checker_texture(device, queue);
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("cloth sampler"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("cloth texture bind group"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&texture_view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::Sampler(&sampler),
            },
        ],
    });
    (layout, bind)
}

/// The mesh, line and point pipelines, for output in `format` with
/// `sample_count` samples: each depth-tested and writing depth, with its shader's
/// `vs_main` and `fs_main`.
fn pipelines(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    sample_count: u32,
    globals_layout: &wgpu::BindGroupLayout,
    texture_layout: &wgpu::BindGroupLayout,
) -> [wgpu::RenderPipeline; 3] {
    let mesh_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("mesh pipeline layout"),
        bind_group_layouts: &[Some(globals_layout), Some(texture_layout)],
        immediate_size: 0,
    });
    let overlay_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("overlay pipeline layout"),
        bind_group_layouts: &[Some(globals_layout)],
        immediate_size: 0,
    });
    let targets = [Some(wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState::REPLACE),
        write_mask: wgpu::ColorWrites::ALL,
    })];
    let pipeline = |label: &str,
                    layout: &wgpu::PipelineLayout,
                    shader: &wgpu::ShaderModule,
                    buffer: wgpu::VertexBufferLayout<'_>,
                    primitive: wgpu::PrimitiveState| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module: shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(buffer)],
            },
            primitive,
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: sample_count,
                mask: !0,
                alpha_to_coverage_enabled: false,
            },
            fragment: Some(wgpu::FragmentState {
                module: shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    };

    let mesh_shader = shader(device, "mesh.wgsl", include_str!("../../shaders/mesh.wgsl"));
    let mesh_attrs =
        wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4];
    let mesh = pipeline(
        "mesh pipeline",
        &mesh_layout,
        &mesh_shader,
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &mesh_attrs,
        },
        wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        },
    );

    let line_shader = shader(
        device,
        "lines.wgsl",
        include_str!("../../shaders/lines.wgsl"),
    );
    let line_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4];
    let line = pipeline(
        "line pipeline",
        &overlay_layout,
        &line_shader,
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<LineVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &line_attrs,
        },
        wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::LineList,
            ..Default::default()
        },
    );

    let point_shader = shader(
        device,
        "points.wgsl",
        include_str!("../../shaders/points.wgsl"),
    );
    let point_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32x4];
    let point = pipeline(
        "point pipeline",
        &overlay_layout,
        &point_shader,
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<PointInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &point_attrs,
        },
        wgpu::PrimitiveState::default(),
    );
    [mesh, line, point]
}

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

/// Decodes the checker PNG (any 8-bit colour type) into an RGBA8 texture; a
/// procedural checker stands in if the file cannot be decoded.
fn checker_texture(device: &wgpu::Device, queue: &wgpu::Queue) -> wgpu::TextureView {
    let (w, h, rgba) = decode_png_rgba(CHECKER_PNG).unwrap_or_else(|| {
        log::warn!("checker texture could not be decoded; using a procedural one");
        let n = 64u32;
        let rgba = (0..n * n)
            .flat_map(|i| {
                let v = if ((i % n) / 8 + (i / n) / 8).is_multiple_of(2) {
                    235
                } else {
                    150
                };
                [v, v, v, 255]
            })
            .collect();
        (n, n, rgba)
    });
    let texture = device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("cloth checker texture"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &rgba,
    );
    texture.create_view(&Default::default())
}

/// Width, height and RGBA8 pixels of an 8-bit PNG.
fn decode_png_rgba(bytes: &[u8]) -> Option<(u32, u32, Vec<u8>)> {
    let mut decoder = png::Decoder::new(bytes);
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().ok()?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).ok()?;
    if info.bit_depth != png::BitDepth::Eight {
        return None;
    }
    let px = &buf[..info.buffer_size()];
    let rgba = match info.color_type {
        png::ColorType::Rgba => px.to_vec(),
        png::ColorType::Rgb => px
            .chunks_exact(3)
            .flat_map(|c| [c[0], c[1], c[2], 255])
            .collect(),
        png::ColorType::GrayscaleAlpha => px
            .chunks_exact(2)
            .flat_map(|c| [c[0], c[0], c[0], c[1]])
            .collect(),
        png::ColorType::Grayscale => px.iter().flat_map(|&v| [v, v, v, 255]).collect(),
        png::ColorType::Indexed => return None,
    };
    Some((info.width, info.height, rgba))
}
