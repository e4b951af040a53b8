//! The window's GPU side: surface, device, the scene renderer and egui's renderer,
//! drawn into one frame (scene pass, then the panel on top).

use std::sync::Arc;

use anyhow::Context as _;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

use crate::render::{self, Renderer, SceneFrame, ViewOptions, gpu};
use cloth_sandbox::view::OrbitCamera;

/// Everything needed to draw into the window.
pub struct Gfx {
    pub window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    pub renderer: Renderer,
    pub egui_renderer: egui_wgpu::Renderer,
    pub adapter_name: String,
    /// Whether the adapter rasterises on the CPU (lavapipe, llvmpipe): its frames
    /// cost the cores the physics runs on.
    pub software: bool,
}

/// What came of trying to draw a frame.
pub enum FrameOutcome {
    /// Drawn and presented.
    Presented,
    /// Nothing drawn (minimised, occluded, timed out, surface reconfigured).
    Skipped,
}

impl Gfx {
    /// Opens the GPU for `window`. Errors are one sentence saying what is missing.
    pub fn new(event_loop: &ActiveEventLoop, window: Arc<Window>) -> anyhow::Result<Self> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = match instance.create_surface(window.clone()) {
            Ok(surface) => surface,
            Err(err) => {
                log::debug!("create_surface failed: {err}");
                // The surface error says nothing useful; an adapter request says what is missing.
                pollster::block_on(gpu::adapter(&instance, None))?;
                anyhow::bail!(
                    "cannot draw into the window: the graphics driver refused to create a surface ({err})"
                );
            }
        };
        let adapter = pollster::block_on(gpu::adapter(&instance, Some(&surface)))?;
        let adapter_name = gpu::describe(&adapter);
        log::info!("adapter: {adapter_name}");
        let (device, queue) = pollster::block_on(gpu::device(&adapter))?;

        let caps = surface.get_capabilities(&adapter);
        // egui-wgpu expects a non-sRGB target.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f,
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .or_else(|| caps.formats.iter().copied().find(|f| !f.is_srgb()))
            .or_else(|| caps.formats.first().copied())
            .context("the graphics adapter cannot present to this window")?;
        let size = window.inner_size();
        let (width, height) = surface_size(&device, size.width, size.height);
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: width.max(1),
            height: height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        if size.width > 0 && size.height > 0 {
            surface.configure(&device, &config);
        }
        // A software adapter (lavapipe) rasterises on the cores the physics
        // thread steps on: every frame without MSAA leaves it more of them.
        let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let samples = if software {
            1
        } else {
            render::pick_sample_count(&adapter, format)
        };
        log::info!("surface format {format:?}, MSAA x{samples}");
        let renderer = Renderer::new(
            &device,
            &queue,
            format,
            samples,
            (config.width, config.height),
        );
        let egui_renderer =
            egui_wgpu::Renderer::new(&device, format, egui_wgpu::RendererOptions::default());
        Ok(Self {
            window,
            surface,
            device,
            queue,
            config,
            renderer,
            egui_renderer,
            adapter_name,
            software,
        })
    }

    /// Size of the drawable area in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Follows a window resize; a zero size (minimised) is remembered as nothing to draw.
    pub fn resize(&mut self, width: u32, height: u32) {
        if width == 0 || height == 0 {
            return;
        }
        let (width, height) = surface_size(&self.device, width, height);
        self.config.width = width;
        self.config.height = height;
        self.surface.configure(&self.device, &self.config);
        self.renderer.resize(&self.device, (width, height));
    }

    /// Draws the scene and the panel and presents them.
    pub fn draw(
        &mut self,
        frame: &SceneFrame<'_>,
        camera: &OrbitCamera,
        options: &ViewOptions,
        egui_ctx: &egui::Context,
        ui: egui::FullOutput,
    ) -> FrameOutcome {
        // Texture uploads happen even on frames that are not drawn: egui sends each once.
        let mut delta = ui.textures_delta;
        for (id, images) in delta.set.drain() {
            for image in &images {
                self.egui_renderer
                    .update_texture(&self.device, &self.queue, id, image);
            }
        }
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            free_textures(&mut self.egui_renderer, delta);
            return FrameOutcome::Skipped;
        }
        if surface_size(&self.device, size.width, size.height) != self.size() {
            self.resize(size.width, size.height);
        }
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.device, &self.config);
                free_textures(&mut self.egui_renderer, delta);
                return FrameOutcome::Skipped;
            }
            other => {
                log::debug!("no surface texture this frame: {other:?}");
                free_textures(&mut self.egui_renderer, delta);
                return FrameOutcome::Skipped;
            }
        };
        let view = texture.texture.create_view(&Default::default());
        self.renderer
            .update(&self.device, &self.queue, frame, camera, options);

        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame encoder"),
            });
        self.renderer.render(&mut encoder, &view);

        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: ui.pixels_per_point,
        };
        let primitives = egui_ctx.tessellate(ui.shapes, ui.pixels_per_point);
        let extra = self.egui_renderer.update_buffers(
            &self.device,
            &self.queue,
            &mut encoder,
            &primitives,
            &screen,
        );
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("egui pass"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.egui_renderer.render(&mut pass, &primitives, &screen);
        }
        for id in delta.free.drain() {
            self.egui_renderer.free_texture(&id);
        }
        self.queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        self.window.pre_present_notify();
        self.queue.present(texture);
        FrameOutcome::Presented
    }
}

/// Frees the textures egui no longer needs, on a frame that is not drawn.
fn free_textures(renderer: &mut egui_wgpu::Renderer, mut delta: egui::TexturesDelta) {
    for id in delta.free.drain() {
        renderer.free_texture(&id);
    }
}

/// A window size clamped to the device's largest texture side: a window larger
/// than that is drawn at that size (stretched by the compositor) rather than
/// refused by the device.
fn surface_size(device: &wgpu::Device, width: u32, height: u32) -> (u32, u32) {
    let max = device.limits().max_texture_dimension_2d;
    (width.min(max), height.min(max))
}
