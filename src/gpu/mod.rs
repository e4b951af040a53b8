//! The GPU engine: a cloth stepped by wgpu compute shaders
//! (`shaders/gpu/laws.wgsl`, the laws of `sim::laws` in WGSL, and
//! `shaders/gpu/step.wgsl`, one step of every particle). Each particle gathers
//! its own springs and triangles from a compressed adjacency (`layout.rs`), with
//! no atomics and no shared writes, so two runs give the same bits.
//!
//! The engine is a schedule, not a second state: [`GpuEngine::run`] takes the
//! [`System`]'s f64 state, runs `n` steps in as few submissions as the uniform
//! records allow (nothing read back between them), and puts the result back into
//! the system, which checks it as any run's end. Positions are two f32 (`x +
//! low`) from an origin at the cloth's centre, taken again at every run, so a
//! cloth that travels keeps its precision; velocities are f32.
//!
//! It steps symplectic Euler, explicit Euler, position Verlet and XPBD with
//! gravity, the applied force, damped springs, aero drag with wind and gusts, air
//! damping, the ground's penalty and friction, the sphere with friction, pins,
//! the stretch limit and the speed limit. XPBD and the stretch limit sweep the
//! springs in the model's constraint order, one dispatch for each run of springs
//! that share no particle (`shaders/gpu/constrain.wgsl`). A scene that needs more
//! (bars, self-collision, tearing, colliders, the other integrators, constraints
//! over springs whose order has no colour classes) is refused with its reasons
//! ([`GpuEngine::refusal`]).

mod choice;
#[cfg(test)]
mod conformance;
mod constraints;
mod device;
mod layout;
mod params;
mod pipeline;
mod timer;

pub use choice::{AUTO_GPU_PARTICLES, EngineChoice, Refused, Stepper};
pub use device::Adapter;
pub use timer::GpuTime;

use glam::DVec3;
use wgpu::util::DeviceExt as _;

use crate::sim::{Divergence, Integrator, Model, Stepped, System};
use layout::{Particle, RECORD_BYTES, StepRecord};
use params::StepParams;

/// Why the GPU engine cannot run.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all.
    #[error(
        "no GPU adapter found: install a Vulkan, Metal or DX12 driver (on Debian/Ubuntu `apt-get install mesa-vulkan-drivers libvulkan1` gives a software one), or use --engine cpu"
    )]
    NoAdapter,
    /// The adapter would not open a device, or the device failed.
    #[error("{0}")]
    Device(String),
    /// The scene needs something the engine does not step.
    #[error("the GPU engine does not step this scene: {0}")]
    Unsupported(String),
    /// A buffer the scene needs is over the device's limit.
    #[error(
        "the cloth is too big for this GPU: its {what} take {bytes} bytes, over the device's limit of {limit} bytes a buffer"
    )]
    TooLarge {
        /// Which buffer.
        what: &'static str,
        /// Its size.
        bytes: u64,
        /// The device's largest storage buffer.
        limit: u64,
    },
    /// The model's topology or its constraints changed since the engine was
    /// built (springs torn or cut, particles added, XPBD or the stretch limit
    /// turned on or off): build the engine again.
    #[error("the cloth's springs or constraints changed since the GPU engine was built")]
    Changed,
}

/// Particles a workgroup steps (the shader's `@workgroup_size`).
const WORKGROUP: u32 = 64;
/// Workgroups a dispatch dimension takes at most (WebGPU's limit; the shader's `ROW`).
const MAX_GROUPS: u32 = 65_535;
/// Steps encoded in one submission (their uniform records take 256 KiB).
const STEPS_PER_SUBMISSION: u64 = 1024;
/// Runs of springs a constraint sweeps at most, each a dispatch a step (a grid's
/// constraint order has 12, a lattice's 26).
const MOST_RUNS: usize = 256;

/// The GPU engine for one model's topology.
pub struct GpuEngine {
    adapter: Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipelines: pipeline::Pipelines,
    /// Particles in and out, ping-pong: step `k` reads `state[k % 2]`.
    state: [wgpu::Buffer; 2],
    /// Verlet's update velocities, likewise (16-byte stand-ins otherwise).
    u: [wgpu::Buffer; 2],
    /// `bind[k % 2]` binds step `k`'s input and output.
    bind: [wgpu::BindGroup; 2],
    topology: wgpu::BindGroup,
    records: wgpu::Buffer,
    constraints: constraints::Constraints,
    readback: wgpu::Buffer,
    /// Timestamps, where the device has them, and the GPU time they measured.
    timer: Option<timer::Timer>,
    gpu_time: GpuTime,
    particles: usize,
    springs: usize,
    triangles: usize,
}

impl GpuEngine {
    /// The reasons the engine cannot step `model` exactly, if any, in one line.
    pub fn refusal(model: &Model) -> Option<String> {
        Self::unsupported(model).or_else(|| Self::too_many_runs(model))
    }

    /// What the engine does not step in `model`, in one line, if anything.
    fn unsupported(model: &Model) -> Option<String> {
        let p = &model.params;
        let Some(params) = StepParams::of(model) else {
            return Some(format!(
                "it steps symplectic Euler, explicit Euler and Verlet, not {}",
                p.integrator
            ));
        };
        let mut reasons = Vec::new();
        if !model.bars.is_empty() && params.bar_iterations > 0 {
            reasons.push("bars".to_string());
        }
        if params.self_collision.is_some() {
            reasons.push("self-collision".to_string());
        }
        if params.tear_strain.is_some() {
            reasons.push("tearing".to_string());
        }
        if !model.colliders.is_empty() {
            reasons.push(format!(
                "colliders other than one fixed sphere ({})",
                model.colliders.len()
            ));
        }
        (!reasons.is_empty()).then(|| format!("it does not step {} yet", reasons.join(", ")))
    }

    /// Why the constraint sweeps of `model` would take too many dispatches, if
    /// they would: its springs' order has no colour classes (a mesh cloth).
    fn too_many_runs(model: &Model) -> Option<String> {
        let passes = constraints::Passes::of(&StepParams::of(model)?);
        if !passes.any() {
            return None;
        }
        let runs = layout::constraint_runs(model).len();
        let what = if passes.xpbd {
            "XPBD"
        } else {
            "the stretch limit"
        };
        (runs > MOST_RUNS).then(|| {
            format!(
                "{what} on this cloth, whose springs' constraint order falls into {runs} runs that share no particle where it sweeps at most {MOST_RUNS} (a grid's or a lattice's has colour classes)"
            )
        })
    }

    /// An engine for `system`'s model on the best adapter there is.
    pub fn new(system: &System) -> Result<Self, GpuError> {
        if let Some(reason) = Self::refusal(system.model()) {
            return Err(GpuError::Unsupported(reason));
        }
        Self::on(device::open()?, system)
    }

    /// An engine for `system`'s model on a device [`device::open`] gave. Its
    /// callers have found no [`Self::refusal`] before opening the device.
    fn on(
        (adapter, device, queue): (Adapter, wgpu::Device, wgpu::Queue),
        system: &System,
    ) -> Result<Self, GpuError> {
        let has = device.limits().max_storage_buffers_per_shader_stage;
        if has < pipeline::STORAGE_BUFFERS {
            return Err(GpuError::Device(format!(
                "{adapter} allows {has} storage buffers a shader stage, and the GPU engine binds {}",
                pipeline::STORAGE_BUFFERS
            )));
        }
        let pipelines = pipeline::Pipelines::new(&device);
        Self::build((adapter, device, queue, pipelines), system)
    }

    /// An engine for `system`'s model (edited, or another) on this one's device
    /// and pipeline: only the buffers are made again.
    pub fn rebuilt(&self, system: &System) -> Result<Self, GpuError> {
        if let Some(reason) = Self::refusal(system.model()) {
            return Err(GpuError::Unsupported(reason));
        }
        let gpu = (
            self.adapter.clone(),
            self.device.clone(),
            self.queue.clone(),
        );
        Self::build((gpu.0, gpu.1, gpu.2, self.pipelines.clone()), system)
    }

    fn build(
        (adapter, device, queue, pipelines): (
            Adapter,
            wgpu::Device,
            wgpu::Queue,
            pipeline::Pipelines,
        ),
        system: &System,
    ) -> Result<Self, GpuError> {
        let model = system.model();
        let adjacency = layout::Adjacency::of(model);
        let n = model.mass.len();
        let verlet = model.params.integrator == Integrator::Verlet;
        let particle_bytes = (n * size_of::<Particle>()) as u64;
        let u_bytes = if verlet { (n * 16) as u64 } else { 16 };
        let limit = {
            let l = device.limits();
            l.max_storage_buffer_binding_size.min(l.max_buffer_size)
        };
        let fits = |what, bytes: u64| match bytes <= limit {
            true => Ok(()),
            false => Err(GpuError::TooLarge { what, bytes, limit }),
        };
        fits("particles", particle_bytes)?;
        fits("spring links", (adjacency.links.len() * 16) as u64)?;
        fits("triangle links", (adjacency.triangles.len() * 16) as u64)?;
        let storage = |label, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let state = [
            storage("particles a", particle_bytes),
            storage("particles b", particle_bytes),
        ];
        let u = [
            storage("verlet u a", u_bytes),
            storage("verlet u b", u_bytes),
        ];
        let init = |label, contents: &[u8]| {
            let padded;
            let contents = if contents.is_empty() {
                padded = [0u8; 16];
                &padded[..]
            } else {
                contents
            };
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let offsets = init("offsets", bytemuck::cast_slice(&adjacency.offsets));
        let links = init("spring links", bytemuck::cast_slice(&adjacency.links));
        let triangle_links = init("triangle links", bytemuck::cast_slice(&adjacency.triangles));
        let records = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("step records"),
            size: STEPS_PER_SUBMISSION * RECORD_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let timer = timer::Timer::new(&device, &queue);
        let timer_bytes = if timer.is_some() {
            timer::Timer::BYTES
        } else {
            0
        };
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: particle_bytes.max(16) + u_bytes + timer_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = [0, 1].map(|k| pipelines.step_group(&device, &records, &state, &u, k));
        let topology = pipelines.topology_group(&device, [&offsets, &links, &triangle_links]);
        let passes = constraints::Passes::of(&StepParams::of(model).expect("refusal() passed"));
        let constraints =
            constraints::Constraints::new((&device, &pipelines), model, passes, fits)?;
        Ok(Self {
            adapter,
            device,
            queue,
            pipelines,
            state,
            u,
            bind,
            topology,
            records,
            constraints,
            readback,
            timer,
            gpu_time: GpuTime::default(),
            particles: n,
            springs: model.springs.len(),
            triangles: model.triangles.len(),
        })
    }

    /// The adapter the engine runs on.
    pub fn adapter(&self) -> &Adapter {
        &self.adapter
    }

    /// The GPU time the steps took since the engine was built or
    /// [`Self::reset_gpu_time`], from timestamps; `None` where the device has
    /// none.
    pub fn gpu_time(&self) -> Option<GpuTime> {
        self.timer.as_ref().map(|_| self.gpu_time)
    }

    /// Starts the GPU time afresh (after a warm-up).
    pub fn reset_gpu_time(&mut self) {
        self.gpu_time = GpuTime::default();
    }

    /// Runs `n` steps of `system` on the GPU, then checks the state as a run's end
    /// ([`System::run`]'s check). The outer error is the engine's; the inner one a
    /// divergence of the physics.
    pub fn run(&mut self, system: &mut System, n: u64) -> Result<Result<(), Divergence>, GpuError> {
        let model = system.model();
        if model.mass.len() != self.particles
            || model.springs.len() != self.springs
            || model.triangles.len() != self.triangles
        {
            return Err(GpuError::Changed);
        }
        // The laws only: the constraint runs were counted when the engine was built.
        if let Some(reason) = Self::unsupported(model) {
            return Err(GpuError::Unsupported(reason));
        }
        let params = StepParams::of(model).expect("unsupported() passed");
        if constraints::Passes::of(&params) != self.constraints.passes {
            return Err(GpuError::Changed);
        }
        system.run_outside(n, |system| self.advance(system, n))
    }

    /// The state `n` steps after `system`'s.
    fn advance(&mut self, system: &System, n: u64) -> Result<Stepped, GpuError> {
        let model = system.model();
        let params = StepParams::of(model).expect("refusal() passed");
        let state = system.state();
        let origin = centroid(&state.positions);
        let particles: Vec<Particle> = (state.positions.iter().zip(&state.velocities))
            .zip(&model.inv_mass)
            .map(|((&x, &v), &w)| Particle::new(x, origin, v, w))
            .collect();
        self.queue
            .write_buffer(&self.state[0], 0, bytemuck::cast_slice(&particles));
        let verlet = system.verlet_update_velocities();
        if let Some(u) = &verlet {
            let u: Vec<[f32; 4]> = u
                .iter()
                .map(|u| u.as_vec3().extend(0.0).to_array())
                .collect();
            self.queue
                .write_buffer(&self.u[0], 0, bytemuck::cast_slice(&u));
        }
        let mut time = state.time;
        let (mut done, mut submissions, mut timed_steps) = (0, 0, 0);
        while done < n {
            let chunk = STEPS_PER_SUBMISSION.min(n - done);
            let records: Vec<StepRecord> = (0..chunk)
                .map(|_| {
                    let record = step_record(&params, origin, time, self.particles);
                    time += params.dt;
                    record
                })
                .collect();
            self.queue
                .write_buffer(&self.records, 0, bytemuck::cast_slice(&records));
            let mut encoder = self.device.create_command_encoder(&Default::default());
            {
                let timestamp_writes = self.timer.as_ref().and_then(|t| t.writes(submissions));
                if timestamp_writes.is_some() {
                    timed_steps += chunk;
                }
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("step particles"),
                    timestamp_writes,
                });
                pass.set_bind_group(1, &self.topology, &[]);
                let (x, y) = dispatch_size(self.particles);
                for k in 0..chunk {
                    let parity = ((done + k) % 2) as usize;
                    pass.set_pipeline(&self.pipelines.step);
                    pass.set_bind_group(0, &self.bind[parity], &[(k * RECORD_BYTES) as u32]);
                    self.constraints.bind(&mut pass);
                    pass.dispatch_workgroups(x, y, 1);
                    (self.constraints).encode(&mut pass, &self.pipelines, self.particles);
                }
            }
            self.queue.submit([encoder.finish()]);
            done += chunk;
            submissions += 1;
        }
        let last = (n % 2) as usize;
        let (particles, u, seconds) = self.read_back(last, verlet.is_some(), submissions)?;
        if let Some(seconds) = seconds {
            self.gpu_time.steps += timed_steps;
            self.gpu_time.seconds += seconds;
        }
        Ok(Stepped {
            positions: particles.iter().map(|p| p.position(origin)).collect(),
            velocities: particles.iter().map(Particle::velocity).collect(),
            update_velocities: u,
        })
    }

    /// The particles (and Verlet's update velocities) in `state[which]`, and the
    /// GPU seconds of the run's first timed `submissions`, where there is a timer.
    #[allow(clippy::type_complexity)]
    fn read_back(
        &self,
        which: usize,
        verlet: bool,
        submissions: u64,
    ) -> Result<(Vec<Particle>, Option<Vec<DVec3>>, Option<f64>), GpuError> {
        let particle_bytes = (self.particles * size_of::<Particle>()) as u64;
        let u_bytes = (self.particles * 16) as u64;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.state[which], 0, &self.readback, 0, particle_bytes);
        if verlet {
            encoder.copy_buffer_to_buffer(
                &self.u[which],
                0,
                &self.readback,
                particle_bytes,
                u_bytes,
            );
        }
        // The timestamps, last in the readback.
        let stamps_at = (self.readback.size()).saturating_sub(timer::Timer::BYTES);
        if let Some(timer) = &self.timer {
            timer.resolve(&mut encoder, submissions, (&self.readback, stamps_at));
        }
        self.queue.submit([encoder.finish()]);
        let slice = self.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        let lost = |e: &dyn std::fmt::Display| {
            GpuError::Device(format!("the GPU failed while stepping: {e}"))
        };
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| lost(&e))?;
        rx.recv().map_err(|e| lost(&e))?.map_err(|e| lost(&e))?;
        let mapped = slice.get_mapped_range().map_err(|e| lost(&e))?;
        let bytes = &mapped[..];
        let particles: Vec<Particle> =
            bytemuck::pod_collect_to_vec(&bytes[..particle_bytes as usize]);
        let u = verlet.then(|| {
            let u: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(
                &bytes[particle_bytes as usize..(particle_bytes + u_bytes) as usize],
            );
            u.iter()
                .map(|u| glam::Vec3::from_slice(&u[..3]).as_dvec3())
                .collect()
        });
        let seconds = (self.timer.as_ref())
            .map(|timer| timer.seconds(&bytes[stamps_at as usize..], submissions));
        drop(mapped);
        self.readback.unmap();
        Ok((particles, u, seconds))
    }
}

/// The mean of `positions` (the origin of the engine's positions), or 0.
fn centroid(positions: &[DVec3]) -> DVec3 {
    let sum: DVec3 = positions.iter().sum();
    let mean = sum / positions.len().max(1) as f64;
    if mean.is_finite() { mean } else { DVec3::ZERO }
}

/// Workgroups in x and y for `n` particles.
fn dispatch_size(n: usize) -> (u32, u32) {
    let groups = (n as u32).div_ceil(WORKGROUP).max(1);
    (groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS))
}

/// The step at `time` of `params`, with positions from `origin`.
fn step_record(params: &StepParams, origin: DVec3, time: f64, particles: usize) -> StepRecord {
    let v4 = |v: DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
    let (wind, half_rho_cd) = match params.drag {
        Some(drag) => (drag.wind.at(time), drag.half_rho_cd),
        None => (DVec3::ZERO, 0.0),
    };
    let mut flags = 0;
    if params.spring_forces {
        flags |= layout::SPRINGS;
    }
    if constraints::Passes::of(params).any() {
        flags |= layout::CONSTRAINED;
    }
    let ground = params.ground.map_or([0.0; 4], |g| {
        flags |= layout::GROUND;
        [
            (g.height - origin.y) as f32,
            g.stiffness as f32,
            g.damping as f32,
            g.friction as f32,
        ]
    });
    let sphere = params.sphere.map_or([0.0; 4], |s| {
        flags |= layout::SPHERE;
        v4(s.center - origin, s.radius)
    });
    let method = match params.integrator {
        Integrator::ExplicitEuler => layout::EXPLICIT_EULER,
        Integrator::Verlet => layout::VERLET,
        _ => layout::SYMPLECTIC_EULER,
    };
    StepRecord {
        gravity: v4(params.gravity, params.dt),
        force: v4(params.force, -params.air_damping),
        wind: v4(wind, half_rho_cd),
        ground,
        sphere,
        limits: [
            params.friction as f32,
            params.max_speed.unwrap_or(0.0) as f32,
            params.stretch_limit.unwrap_or(0.0) as f32,
            0.0,
        ],
        // The last is the shader's opaque zero (`opaque` in step.wgsl).
        flags: [method, particles as u32, flags, 0],
        _pad: [0; 36],
    }
}
