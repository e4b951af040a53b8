//! Getting a graphics adapter and device, with one clear sentence when none can be had.

use anyhow::{Context as _, anyhow};

/// How to get a software adapter on Debian/Ubuntu, appended to adapter errors.
const HINT: &str = "install Mesa's Vulkan driver (e.g. `apt-get install mesa-vulkan-drivers libvulkan1`) \
or run on a machine with a working GPU driver";

/// An adapter for `surface` (or for off-screen use when `None`), or an error that
/// says what is missing.
pub async fn adapter(
    instance: &wgpu::Instance,
    surface: Option<&wgpu::Surface<'_>>,
) -> anyhow::Result<wgpu::Adapter> {
    let options = wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: surface,
        apply_limit_buckets: false,
    };
    match instance.request_adapter(&options).await {
        Ok(adapter) => Ok(adapter),
        Err(err) => {
            log::debug!("request_adapter failed: {err}");
            Err(anyhow!("no graphics adapter found: {HINT}"))
        }
    }
}

/// A device and queue with the adapter's default limits (downlevel-friendly).
pub async fn device(adapter: &wgpu::Adapter) -> anyhow::Result<(wgpu::Device, wgpu::Queue)> {
    adapter
        .request_device(&wgpu::DeviceDescriptor {
            label: Some("cloth device"),
            required_features: wgpu::Features::empty(),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            ..Default::default()
        })
        .await
        .with_context(|| {
            format!(
                "the graphics adapter {:?} refused to open a device",
                adapter.get_info().name
            )
        })
}

/// One line describing the adapter, for the log and the panel.
pub fn describe(adapter: &wgpu::Adapter) -> String {
    let info = adapter.get_info();
    format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
}
