//! What `cloth run` prints: the run's figures, as text or one JSON object.

use cloth_sandbox::sim::{Engine, Integrator, System, max_speed};
use glam::DVec3;
use serde_json::json;

/// What `cloth run` prints.
pub(super) struct Summary {
    steps: u64,
    time: f64,
    wall: f64,
    particles: usize,
    springs: usize,
    /// Springs broken (torn or cut) during the run.
    broken_springs: usize,
    energy: cloth_sandbox::sim::Energy,
    min: DVec3,
    max: DVec3,
    max_speed: f64,
    engine: Engine,
    /// The adapter, when the GPU engine ran ([`Self::on_gpu`]).
    adapter: Option<String>,
    /// GPU seconds a step, from its timestamps, where the adapter has them.
    gpu_seconds_per_step: Option<f64>,
    threads: usize,
    integrator: Integrator,
    /// The step the run ended on (safe stepping may have split the scene's).
    dt: f64,
    /// Conjugate-gradient iterations of the last step, for implicit Euler.
    solver_iterations: Option<usize>,
    /// What the limiters hold at the end, where the scene has any.
    pub(super) limiters: Option<cloth_sandbox::sim::LimiterActivity>,
}

impl Summary {
    pub(super) fn of(system: &System, wall: f64, engine: Engine) -> Self {
        let positions = system.positions();
        let (min, max) = positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        // A state with a non-finite value has no finite maximum or bounds: NaN
        // (JSON null), never a number that looks like one.
        let max_speed = max_speed(system.velocities());
        let (min, max) = if positions.iter().all(|p| p.is_finite()) {
            (min, max)
        } else {
            (DVec3::NAN, DVec3::NAN)
        };
        Self {
            steps: system.steps_taken(),
            time: system.time(),
            wall,
            particles: system.particle_count(),
            springs: system.springs().len(),
            broken_springs: system.broken_springs(),
            energy: system.energy(),
            min,
            max,
            max_speed,
            engine,
            adapter: None,
            gpu_seconds_per_step: None,
            threads: system.engine_threads(),
            integrator: system.params().integrator,
            dt: system.params().dt,
            solver_iterations: (system.params().integrator == Integrator::ImplicitEuler)
                .then(|| system.solver_iterations()),
            limiters: {
                let p = system.params();
                (p.max_speed.is_some() || p.stretch_limit.is_some() || p.tear_strain.is_some())
                    .then(|| system.limiter_activity())
            },
        }
    }

    /// The run was the GPU engine's, on `adapter`, taking `gpu_time` by its
    /// timestamps.
    pub(super) fn on_gpu(
        self,
        adapter: Option<&cloth_sandbox::gpu::Adapter>,
        gpu_time: Option<cloth_sandbox::gpu::GpuTime>,
    ) -> Self {
        Self {
            adapter: adapter.map(ToString::to_string),
            gpu_seconds_per_step: gpu_time.and_then(|t| t.per_step()),
            ..self
        }
    }

    pub(super) fn steps_per_second(&self) -> f64 {
        if self.wall > 0.0 {
            self.steps as f64 / self.wall
        } else {
            0.0
        }
    }

    pub(super) fn to_json(&self) -> serde_json::Value {
        let sps = self.steps_per_second();
        json!({
            "steps": self.steps,
            "simulated_time": self.time,
            "wall_time": self.wall,
            "steps_per_second": sps,
            "particle_steps_per_second": sps * self.particles as f64,
            "spring_steps_per_second": sps * self.springs as f64,
            "particles": self.particles,
            "springs": self.springs,
            "broken_springs": self.broken_springs,
            "energy": {
                "kinetic": self.energy.kinetic,
                "gravity": self.energy.gravity,
                "elastic": self.energy.elastic,
                "total": self.energy.total(),
            },
            "bounding_box": { "min": [self.min.x, self.min.y, self.min.z], "max": [self.max.x, self.max.y, self.max.z] },
            "max_speed": self.max_speed,
            "engine": if self.adapter.is_some() { "gpu" } else { self.engine.name() },
            "adapter": self.adapter,
            "gpu_seconds_per_step": self.gpu_seconds_per_step,
            "simd": self.adapter.is_none().then(|| self.engine.simd_level().name()),
            "threads": self.adapter.is_none().then_some(self.threads),
            "integrator": self.integrator.name(),
            "dt": self.dt,
            "cg_iterations_last_step": self.solver_iterations,
            "limiters": self.limiters.map(|a| {
                let pair = |(n, of): (usize, usize)| json!({ "holding": n, "of": of });
                json!({
                    "torn_springs": pair(a.torn),
                    "particles_at_speed_cap": pair(a.at_speed_cap),
                    "springs_at_stretch_limit": pair(a.at_stretch_limit),
                    "warning": a.warning(),
                })
            }),
        })
    }

    pub(super) fn print(&self) {
        let sps = self.steps_per_second();
        println!("steps           {}", self.steps);
        println!("simulated time  {:.6} s", self.time);
        println!("wall time       {:.6} s", self.wall);
        println!(
            "steps/s         {sps:.1}  ({:.3e} particle-steps/s, {:.3e} spring-steps/s)",
            sps * self.particles as f64,
            sps * self.springs as f64
        );
        println!(
            "energy          {:.6e} J  (kinetic {:.6e}, gravity {:.6e}, elastic {:.6e})",
            self.energy.total(),
            self.energy.kinetic,
            self.energy.gravity,
            self.energy.elastic
        );
        println!(
            "bounding box    ({:.4}, {:.4}, {:.4}) to ({:.4}, {:.4}, {:.4}) m",
            self.min.x, self.min.y, self.min.z, self.max.x, self.max.y, self.max.z
        );
        println!("max speed       {:.4} m/s", self.max_speed);
        match &self.adapter {
            Some(adapter) => println!("engine          gpu, on {adapter}"),
            None => println!("engine          {}", self.engine.label(self.threads)),
        }
        if let Some(t) = self.gpu_seconds_per_step {
            println!("gpu time        {:.3} us a step (its timestamps)", t * 1e6);
        }
        println!("integrator      {}, dt {:.4e} s", self.integrator, self.dt);
        if let Some(n) = self.solver_iterations {
            println!("cg iterations   {n} (last step)");
        }
        if self.broken_springs > 0 {
            println!("broken springs  {}", self.broken_springs);
        }
        if let Some(a) = &self.limiters {
            let held: Vec<String> = a.working().map(|(l, n, of)| l.holding(n, of)).collect();
            if !held.is_empty() {
                println!("limiters        hold {}", held.join(", "));
            }
        }
    }
}
