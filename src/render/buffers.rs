//! GPU buffers that grow with the data but never past the device's limits.

use bytemuck::Pod;

use super::geometry::LineVertex;

/// A GPU buffer that grows (by doubling) when the data outgrows it, never past
/// the device's largest buffer (`max_buffer_size`).
pub struct DynBuffer {
    pub buffer: wgpu::Buffer,
    capacity: u64,
    /// The device's largest buffer in bytes.
    limit: u64,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl DynBuffer {
    pub fn new(device: &wgpu::Device, label: &'static str, usage: wgpu::BufferUsages) -> Self {
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
    pub fn max_elements(&self, stride: usize) -> usize {
        usize::try_from(self.limit / stride as u64).unwrap_or(usize::MAX)
    }

    /// Uploads `items` from offset 0, reallocating if too small, and returns how
    /// many were uploaded: all of them, or as many as the device's largest buffer
    /// holds (the caller draws that many and says what was left out).
    pub fn write<T: Pod>(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        items: &[T],
    ) -> usize {
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
pub struct LineBuffers {
    pub chunks: Vec<DynBuffer>,
    /// Vertices in each chunk, in order.
    pub counts: Vec<u32>,
}

impl LineBuffers {
    pub fn new(device: &wgpu::Device) -> Self {
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
    pub fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, vertices: &[LineVertex]) {
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
pub fn draw_count(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}
