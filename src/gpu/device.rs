//! The GPU engine's adapter and device, with one clear sentence when none can be had.

use super::GpuError;

/// The adapter the engine runs on, as `cloth info`, `--json` and the panel name it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Adapter {
    /// The adapter's name (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)").
    pub name: String,
    /// The graphics API wgpu reaches it through (Vulkan, Metal, DX12, GL).
    pub backend: String,
    /// Whether it is a CPU adapter (lavapipe, WARP, SwiftShader): correct, but no
    /// faster than the CPU engines.
    pub software: bool,
}

impl std::fmt::Display for Adapter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = if self.software { ", software" } else { "" };
        write!(f, "{} ({}{kind})", self.name, self.backend)
    }
}

/// The highest-performance adapter wgpu finds (`WGPU_BACKEND` chooses the API,
/// as everywhere in wgpu), described, with no device opened on it yet: `auto`
/// turns a CPU adapter down before it costs a device.
pub(super) fn find() -> Result<(Adapter, wgpu::Adapter), GpuError> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let options = wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: None,
        apply_limit_buckets: false,
    };
    let adapter = pollster::block_on(instance.request_adapter(&options)).map_err(|e| {
        log::debug!("request_adapter failed: {e}");
        GpuError::NoAdapter
    })?;
    let info = adapter.get_info();
    let described = Adapter {
        name: info.name.clone(),
        backend: format!("{:?}", info.backend),
        software: info.device_type == wgpu::DeviceType::Cpu,
    };
    Ok((described, adapter))
}

/// Opens [`find`]'s adapter and a device with every limit it has: a big cloth
/// needs its largest storage buffers.
pub(super) fn open() -> Result<(Adapter, wgpu::Device, wgpu::Queue), GpuError> {
    open_found(find()?)
}

/// Opens a device on an adapter [`find`] gave.
pub(super) fn open_found(
    (described, adapter): (Adapter, wgpu::Adapter),
) -> Result<(Adapter, wgpu::Device, wgpu::Queue), GpuError> {
    // Timestamps where the adapter has them: the GPU time a step takes.
    let descriptor = wgpu::DeviceDescriptor {
        label: Some("cloth GPU engine"),
        required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
        required_limits: adapter.limits(),
        ..Default::default()
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&descriptor))
        .map_err(|e| GpuError::Device(format!("{described} refused to open a device: {e}")))?;
    Ok((described, device, queue))
}
