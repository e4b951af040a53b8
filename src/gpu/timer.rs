//! GPU timestamps around each submission's compute pass, where the device has
//! them (`Features::TIMESTAMP_QUERY`): the GPU time a step takes, which `cloth
//! run --engine gpu --json` reports beside the wall clock's steps/s. They are
//! read back with the state at the run's end, never inside the loop.

/// Submissions of a run that are timed (two queries each): a run's first
/// 65,536 steps.
pub(super) const TIMED_SUBMISSIONS: u32 = 64;

/// GPU time over the steps it timed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuTime {
    /// Steps timed.
    pub steps: u64,
    /// GPU seconds they took, from their passes' first timestamp to their last.
    pub seconds: f64,
}

impl GpuTime {
    /// Seconds a step, once any step was timed.
    pub fn per_step(&self) -> Option<f64> {
        (self.steps > 0).then(|| self.seconds / self.steps as f64)
    }
}

/// The query set and the buffer its timestamps resolve into.
pub(super) struct Timer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    /// Nanoseconds a timestamp tick.
    period_ns: f64,
}

impl Timer {
    /// Bytes the timestamps take in a readback.
    pub const BYTES: u64 = 16 * TIMED_SUBMISSIONS as u64;

    /// A timer on `device`, or `None` where it has no timestamp queries.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Option<Self> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("step timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * TIMED_SUBMISSIONS,
        });
        let resolved = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resolved timestamps"),
            size: Self::BYTES,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Some(Self {
            queries,
            resolved,
            period_ns: f64::from(queue.get_timestamp_period()),
        })
    }

    /// The timestamp writes of submission number `k` of a run, if it is timed.
    pub fn writes(&self, k: u64) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let k = u32::try_from(k).ok().filter(|&k| k < TIMED_SUBMISSIONS)?;
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        })
    }

    /// Resolves the first `submissions` timed passes' timestamps and copies them
    /// into `readback` at `offset`.
    pub fn resolve(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        submissions: u64,
        (readback, offset): (&wgpu::Buffer, u64),
    ) {
        let timed = submissions.min(u64::from(TIMED_SUBMISSIONS)) as u32;
        if timed == 0 {
            return;
        }
        encoder.resolve_query_set(&self.queries, 0..2 * timed, &self.resolved, 0);
        let bytes = 16 * u64::from(timed);
        encoder.copy_buffer_to_buffer(&self.resolved, 0, readback, offset, bytes);
    }

    /// The GPU seconds of the passes whose timestamps `bytes` hold (begin and
    /// end pairs, as [`Self::resolve`] copied them).
    pub fn seconds(&self, bytes: &[u8], submissions: u64) -> f64 {
        let timed = submissions.min(u64::from(TIMED_SUBMISSIONS)) as usize;
        let stamps: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes[..16 * timed]);
        let ticks: u64 = stamps
            .chunks_exact(2)
            .map(|pair| pair[1].saturating_sub(pair[0]))
            .sum();
        ticks as f64 * self.period_ns * 1e-9
    }
}
