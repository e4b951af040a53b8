//! Off-screen rendering: the same `Renderer` drawing into a texture that is
//! copied back to memory, for `cloth screenshot`, `cloth record`, the app's
//! screenshots (F12) and the render tests. No window, no display.

use anyhow::{Context as _, bail};
use cloth_sandbox::view::OrbitCamera;

use super::{Renderer, SceneFrame, ViewOptions, gpu};

/// Output format: egui and the window use a non-sRGB target, so this matches them.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// A device with a renderer for images of one size.
pub struct Offscreen {
    device: wgpu::Device,
    queue: wgpu::Queue,
    renderer: Renderer,
    texture: wgpu::Texture,
    adapter_name: String,
}

impl Offscreen {
    /// Opens an adapter (no surface) and prepares `width × height` targets, with
    /// as many MSAA samples as the adapter allows.
    pub fn new(width: u32, height: u32) -> anyhow::Result<Self> {
        Self::with_samples(width, height, None)
    }

    /// [`Offscreen::new`] with `samples` MSAA samples where given (1: no MSAA,
    /// so FXAA), else the adapter's most.
    pub fn with_samples(width: u32, height: u32, samples: Option<u32>) -> anyhow::Result<Self> {
        check_image_range(width, height)?;
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(gpu::adapter(&instance, None))?;
        let adapter_name = gpu::describe(&adapter);
        log::info!("off-screen adapter: {adapter_name}");
        let (device, queue) = pollster::block_on(gpu::device(&adapter))?;
        let samples = samples.unwrap_or_else(|| super::pick_sample_count(&adapter, FORMAT));
        Self::with_device(device, queue, adapter_name, samples, width, height)
    }

    /// Prepares `width × height` targets on a device already open (the window's,
    /// for a screenshot of the view), with `samples` MSAA samples.
    pub fn with_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        adapter_name: String,
        samples: u32,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Self> {
        check_image_range(width, height)?;
        check_image_size(&device.limits(), width, height)?;
        let renderer = Renderer::new(&device, &queue, FORMAT, samples, (width, height));
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("off-screen colour"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        Ok(Self {
            device,
            queue,
            renderer,
            texture,
            adapter_name,
        })
    }

    /// Image size in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.renderer.size()
    }

    /// The adapter in use, in words.
    pub fn adapter_name(&self) -> &str {
        &self.adapter_name
    }

    /// Renders `frame` and returns tightly packed RGBA8 rows, top row first.
    pub fn render(
        &mut self,
        frame: &SceneFrame<'_>,
        camera: &OrbitCamera,
        options: &ViewOptions,
    ) -> anyhow::Result<Vec<u8>> {
        let (width, height) = self.renderer.size();
        self.renderer
            .update(&self.device, &self.queue, frame, camera, options);
        let view = self.texture.create_view(&Default::default());
        let row = width * 4;
        let padded =
            row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("off-screen readback"),
            size: u64::from(padded) * u64::from(height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("off-screen encoder"),
            });
        self.renderer.render(&mut encoder, &view);
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
        self.queue.submit([encoder.finish()]);
        let slice = readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .context("waiting for the GPU")?;
        rx.recv()
            .context("the GPU dropped the readback")?
            .context("mapping the readback buffer")?;
        let mapped = slice
            .get_mapped_range()
            .context("reading the readback buffer")?;
        let mut pixels = Vec::with_capacity((row * height) as usize);
        for y in 0..height as usize {
            let start = y * padded as usize;
            pixels.extend_from_slice(&mapped[start..start + row as usize]);
        }
        drop(mapped);
        readback.unmap();
        Ok(pixels)
    }
}

/// Refuses an empty image, or one over 8192 pixels a side, before any GPU work.
fn check_image_range(width: u32, height: u32) -> anyhow::Result<()> {
    if width == 0 || height == 0 || width > 8192 || height > 8192 {
        bail!("image size {width}x{height} is out of range (1..=8192 on each side)");
    }
    Ok(())
}

/// Refuses an image the device cannot hold: a side over its largest texture, or
/// a read-back buffer (rows padded for the copy) over its largest buffer.
fn check_image_size(limits: &wgpu::Limits, width: u32, height: u32) -> anyhow::Result<()> {
    let max_side = limits.max_texture_dimension_2d;
    if width > max_side || height > max_side {
        bail!(
            "image size {width}x{height} is too large for this graphics adapter: each side must be at most {max_side} pixels"
        );
    }
    let padded = u64::from(width * 4).div_ceil(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT))
        * u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let bytes = padded * u64::from(height);
    if bytes > limits.max_buffer_size {
        bail!(
            "image size {width}x{height} needs a {bytes}-byte read-back buffer, over this graphics adapter's largest buffer of {} bytes: choose a smaller --size",
            limits.max_buffer_size
        );
    }
    Ok(())
}

/// Writes RGBA8 pixels as a PNG file into the prepared output file, then renames
/// it over the target (never a half-written picture).
pub fn write_png(
    mut out: cloth_sandbox::limits::PendingFile,
    width: u32,
    height: u32,
    rgba: &[u8],
) -> anyhow::Result<()> {
    let mut encoder = png::Encoder::new(out.writer(), width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(rgba)?;
    writer.finish()?;
    out.commit()?;
    Ok(())
}
