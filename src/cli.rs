//! The headless command line: `cloth run`, `cloth info`, `cloth scenes`.
//!
//! Exit codes: 0 ran, 2 bad input (with a message naming the field), 3 the
//! simulation diverged (with the time and a hint).

use std::io::Write;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};
use cloth_sandbox::scene::{Scene, SceneError, builtin_scenes};
use cloth_sandbox::sim::safe::{
    DEFAULT_MAX_SUBSTEPS, DEFAULT_SAFETY, added_stretch_limit, safe_step,
};
use cloth_sandbox::sim::{Divergence, Engine, Integrator, SpringKind, System, bounding_sphere};
use glam::DVec3;
use serde_json::json;

/// Exit code for bad input.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code for a diverged simulation.
pub const EXIT_DIVERGED: u8 = 3;

/// cloth-sandbox: an interactive mass-spring cloth simulator. Without a subcommand
/// it opens the desktop app.
#[derive(Parser, Debug)]
#[command(name = "cloth", version, about)]
pub struct Args {
    /// What to do (default: open the desktop app).
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Scene the desktop app opens: a built-in name or a scene TOML file.
    #[arg(long, value_name = "NAME")]
    pub scene: Option<String>,
    /// Override a scene parameter in the desktop app, e.g. `--set width=48`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// Scene selection and overrides shared by the subcommands.
#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// A built-in scene name (see `cloth scenes`) or a path to a scene TOML file.
    #[arg(long, default_value = "cloth")]
    pub scene: String,
    /// Override a scene parameter, e.g. `--set stiffness=500 --set wind=1,0,0`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

impl SceneArgs {
    /// Loads the scene and applies the overrides.
    pub fn load(&self) -> Result<Scene, SceneError> {
        let mut scene = Scene::load(&self.scene)?;
        scene.set_all(self.set.iter().map(String::as_str))?;
        Ok(scene)
    }
}

/// Subcommands.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run a scene headless and print what happened.
    Run(RunArgs),
    /// Describe a scene: particles, springs, force terms, parameters, stability.
    Info(InfoArgs),
    /// List the built-in scenes.
    Scenes,
    /// Render a scene after N steps to a PNG, off-screen (no window or display).
    Screenshot(crate::app::screenshot::ScreenshotArgs),
    /// Measure error against run time and stability of every integrator; write CSV,
    /// SVG plots and REPORT.md.
    Report(ReportArgs),
}

/// `cloth report`.
#[derive(clap::Args, Debug)]
pub struct ReportArgs {
    /// Output folder.
    #[arg(long, default_value = "report")]
    out: std::path::PathBuf,
    /// Smaller problems: a smoke run for CI (under 2 minutes).
    #[arg(long)]
    quick: bool,
}

/// `cloth run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Integrator: explicit-euler, symplectic-euler, verlet, rk2, rk4, implicit-euler, xpbd.
    #[arg(long)]
    integrator: Option<String>,
    /// Time step in seconds.
    #[arg(long, allow_hyphen_values = true)]
    dt: Option<String>,
    /// Simulated seconds to run (default 1).
    #[arg(long, conflicts_with = "steps", allow_hyphen_values = true)]
    duration: Option<f64>,
    /// Number of steps to run (0: just the initial state).
    #[arg(long, allow_hyphen_values = true)]
    steps: Option<u64>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Write the final positions as CSV `index,x,y,z`.
    #[arg(long, value_name = "FILE.csv")]
    dump: Option<std::path::PathBuf>,
    /// Safe stepping: split each step of dt into the fewest substeps that keep the
    /// step below half the integrator's critical step (Gershgorin estimate).
    #[arg(long)]
    safe: bool,
    /// Always use the general f64 engine (by default a plain grid cloth stepped by
    /// symplectic Euler runs on the f32 grid kernel; results agree to round-off).
    #[arg(long)]
    exact: bool,
    /// Untimed steps before the timed run, after which the start state is restored
    /// (as the peers' benchmarks warm up).
    #[arg(long, default_value_t = 0, value_name = "N")]
    warmup: u64,
}

/// `cloth info`.
#[derive(clap::Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs a subcommand and returns the process exit code.
pub fn run_command(command: Command) -> ExitCode {
    let result = match command {
        Command::Run(args) => run(args),
        Command::Info(args) => info(args),
        Command::Scenes => {
            scenes();
            Ok(ExitCode::SUCCESS)
        }
        Command::Screenshot(args) => crate::app::screenshot::run(&args)
            .map(|()| ExitCode::SUCCESS)
            .map_err(|e| format!("{e:#}")),
        Command::Report(args) => report(args),
    };
    result.unwrap_or_else(|message| {
        eprintln!("error: {message}");
        ExitCode::from(EXIT_BAD_INPUT)
    })
}

fn report(args: ReportArgs) -> Result<ExitCode, String> {
    let options = cloth_sandbox::report::Options {
        out: args.out,
        quick: args.quick,
        ..Default::default()
    };
    let start = Instant::now();
    let mut progress = |line: &str| eprintln!("[{:6.1} s] {line}", start.elapsed().as_secs_f64());
    cloth_sandbox::report::run(&options, &mut progress)?;
    eprintln!(
        "done in {:.1} s: {}",
        start.elapsed().as_secs_f64(),
        options.out.join("REPORT.md").display()
    );
    Ok(ExitCode::SUCCESS)
}

fn scenes() {
    for builtin in builtin_scenes() {
        let description = Scene::load(builtin.name)
            .ok()
            .and_then(|s| s.spec.description)
            .unwrap_or_default();
        println!("{:<11} {description}", builtin.name);
    }
}

/// Loads a scene with the run's `--integrator` and `--dt` applied as overrides.
fn load_run_scene(args: &RunArgs) -> Result<Scene, String> {
    let mut scene = args.scene.load().map_err(|e| e.to_string())?;
    // The flags are scene keys; errors name the flag as the user typed it.
    let flag = |scene: &mut Scene, key: &str, value: &str, shown: &str| {
        scene.set(key, value).map_err(|e| match e {
            SceneError::Invalid { field, message, .. } => {
                format!("--{shown}: `{field}` {message}")
            }
            SceneError::Parse { message, .. } => format!("--{shown}: {message}"),
            other => other.to_string(),
        })
    };
    if let Some(integrator) = &args.integrator {
        flag(
            &mut scene,
            "integrator",
            &format!("\"{integrator}\""),
            &format!("integrator {integrator}"),
        )?;
    }
    if let Some(dt) = &args.dt {
        flag(&mut scene, "dt", dt, &format!("dt {dt}"))?;
    }
    Ok(scene)
}

fn run(args: RunArgs) -> Result<ExitCode, String> {
    let scene = load_run_scene(&args)?;
    let mut system = scene.build().map_err(|e| e.to_string())?;
    let dt = system.params().dt;
    let mut steps = match (args.steps, args.duration) {
        (Some(n), _) => n,
        (None, Some(d)) if d.is_finite() && d >= 0.0 => (d / dt).round() as u64,
        (None, Some(d)) => {
            return Err(format!(
                "--duration {d} must be a finite number of seconds >= 0"
            ));
        }
        (None, None) => (1.0 / dt).round() as u64,
    };
    if args.safe {
        let choice = safe_step(system.model(), dt, DEFAULT_SAFETY, DEFAULT_MAX_SUBSTEPS);
        let mut params = *system.params();
        params.dt = choice.dt;
        let added_limit = added_stretch_limit(system.model(), params.stretch_limit);
        params.stretch_limit = params.stretch_limit.or(added_limit);
        system.set_params(params);
        if let Some(tau) = added_limit {
            eprintln!(
                "safe stepping: the wind is strong for these springs, so a {:.0}% stretch limit is added (as in the app)",
                100.0 * tau
            );
        }
        steps *= choice.substeps as u64;
        eprintln!(
            "safe stepping: {} substeps of {:.4e} s per step of {dt:.4e} s{}",
            choice.substeps,
            choice.dt,
            if choice.safe {
                ""
            } else {
                " (not enough: the integrator has no stable step here, or the cap was hit)"
            }
        );
    }
    system.set_fast_path(!args.exact);
    let engine = system.engine();
    // Setup is not timed: zero steps build the engine's buffers (and thread pool),
    // and warm-up steps run from the start state, which is then put back.
    let start_state = system.state().clone();
    if system.run(args.warmup).is_err() {
        system.set_state(start_state.clone());
    }
    system.set_state(start_state);
    let start = Instant::now();
    let outcome = system.run(steps);
    let wall = start.elapsed().as_secs_f64();
    let summary = Summary::of(&system, wall, engine);
    if let Some(path) = &args.dump {
        dump_csv(&system, path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    if args.json {
        let mut value = summary.to_json();
        if let Err(d) = &outcome {
            value["diverged"] =
                json!({ "time": d.time(), "message": d.to_string(), "hint": hint(&system) });
        }
        println!("{value}");
    } else {
        summary.print();
    }
    match outcome {
        Ok(()) => Ok(ExitCode::SUCCESS),
        Err(divergence) => {
            report_divergence(&system, &divergence);
            Ok(ExitCode::from(EXIT_DIVERGED))
        }
    }
}

fn hint(system: &System) -> String {
    let stability = system.stability();
    let margin = if stability.margin.is_finite() {
        format!("dt / dt_crit = {:.3}", stability.margin)
    } else {
        format!(
            "{} has no stable step without damping",
            system.params().integrator
        )
    };
    let safe_dt = stability
        .dt_critical
        .filter(|c| c.is_finite())
        .map(|c| format!(" (e.g. --dt {:.3e})", 0.5 * c))
        .unwrap_or_default();
    format!(
        "{margin}; try a smaller dt{safe_dt}, a lower stiffness, or --integrator implicit-euler"
    )
}

fn report_divergence(system: &System, divergence: &Divergence) {
    eprintln!("error: the simulation diverged: {divergence}");
    eprintln!("hint: {}", hint(system));
}

fn dump_csv(system: &System, path: &std::path::Path) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(out, "index,x,y,z")?;
    for (i, p) in system.positions().iter().enumerate() {
        writeln!(out, "{i},{},{},{}", p.x, p.y, p.z)?;
    }
    out.flush()
}

/// What `cloth run` prints.
struct Summary {
    steps: u64,
    time: f64,
    wall: f64,
    particles: usize,
    springs: usize,
    energy: cloth_sandbox::sim::Energy,
    min: DVec3,
    max: DVec3,
    max_speed: f64,
    engine: Engine,
    threads: usize,
    /// Conjugate-gradient iterations of the last step, for implicit Euler.
    solver_iterations: Option<usize>,
}

impl Summary {
    fn of(system: &System, wall: f64, engine: Engine) -> Self {
        let positions = system.positions();
        let (min, max) = positions
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let max_speed = system
            .velocities()
            .iter()
            .map(|v| v.length())
            .fold(0.0, f64::max);
        Self {
            steps: system.steps_taken(),
            time: system.time(),
            wall,
            particles: system.particle_count(),
            springs: system.springs().len(),
            energy: system.energy(),
            min,
            max,
            max_speed,
            engine,
            threads: rayon::current_num_threads(),
            solver_iterations: (system.params().integrator == Integrator::ImplicitEuler)
                .then(|| system.solver_iterations()),
        }
    }

    fn steps_per_second(&self) -> f64 {
        if self.wall > 0.0 {
            self.steps as f64 / self.wall
        } else {
            0.0
        }
    }

    fn to_json(&self) -> serde_json::Value {
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
            "energy": {
                "kinetic": self.energy.kinetic,
                "gravity": self.energy.gravity,
                "elastic": self.energy.elastic,
                "total": self.energy.total(),
            },
            "bounding_box": { "min": [self.min.x, self.min.y, self.min.z], "max": [self.max.x, self.max.y, self.max.z] },
            "max_speed": self.max_speed,
            "engine": self.engine.name(),
            "threads": self.threads,
            "cg_iterations_last_step": self.solver_iterations,
        })
    }

    fn print(&self) {
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
        println!(
            "engine          {} ({} threads)",
            self.engine.name(),
            self.threads
        );
        if let Some(n) = self.solver_iterations {
            println!("cg iterations   {n} (last step)");
        }
    }
}

fn info(args: InfoArgs) -> Result<ExitCode, String> {
    let scene = args.scene.load().map_err(|e| e.to_string())?;
    let resolved = scene.resolve().map_err(|e| e.to_string())?;
    let mut system = resolved.build();
    // The engine `cloth run` uses (without `--exact`).
    system.set_fast_path(true);
    let engine = system.engine().name();
    let p = system.params();
    let mut per_kind = serde_json::Map::new();
    for kind in SpringKind::ALL {
        let n = system.springs().iter().filter(|s| s.kind == kind).count();
        per_kind.insert(kind.name().to_string(), json!(n));
    }
    let mut constraints = Vec::new();
    if p.integrator == Integrator::Xpbd && !system.springs().is_empty() {
        constraints.push("springs as XPBD distance constraints (compliance 1/k)".to_string());
    }
    if !system.bars().is_empty() && p.bar_iterations > 0 {
        constraints.push(format!("rigid bars ({} passes per step)", p.bar_iterations));
    }
    if let Some(tau) = p.stretch_limit {
        constraints.push(format!("stretch limit ({:.0}%)", tau * 100.0));
    }
    if let Some(s) = p.sphere {
        constraints.push(format!(
            "sphere collider (centre {:?}, radius {} m)",
            s.center.to_array(),
            s.radius
        ));
    }
    let stability = system.stability();
    let (_, extent) = bounding_sphere(system.positions());
    let value = json!({
        "scene": scene.origin,
        "description": scene.spec.description,
        "particles": system.particle_count(),
        "pinned": (0..system.particle_count()).filter(|&i| system.is_pinned(i)).count(),
        "springs": system.springs().len(),
        "springs_per_kind": per_kind,
        "bars": system.bars().len(),
        "triangles": system.triangles().len(),
        "force_terms": system.force_terms().names(),
        "constraints": constraints,
        "engine": engine,
        "parameters": {
            "layout": format!("{:?}", resolved.layout).to_lowercase(),
            "width": resolved.width,
            "height": resolved.height,
            "depth": resolved.depth,
            "rest_length": resolved.rest_length,
            "particle_mass": resolved.particle_mass,
            "stiffness": resolved.stiffness,
            "damping": resolved.damping,
            "shear_scale": resolved.shear_scale,
            "bend_scale": resolved.bend_scale,
            "gravity": p.gravity.to_array(),
            "wind": p.wind.to_array(),
            "gust": p.gust,
            "air_density": p.air_density,
            "drag_coefficient": p.drag_coefficient,
            "air_damping": p.air_damping,
            "ground": p.ground.map(|g| json!({"height": g.height, "stiffness": g.stiffness, "damping": g.damping})),
            "integrator": p.integrator.name(),
            "dt": p.dt,
            "substeps": resolved.substeps,
            "seed": p.seed,
            "bar_iterations": p.bar_iterations,
            "stretch_limit": p.stretch_limit,
        },
        "extent": 2.0 * extent,
        "stability": {
            "omega_max_bound": stability.omega_max,
            "damping_ratio": stability.zeta,
            "dt_critical": stability.dt_critical.map(|c| if c.is_finite() { json!(c) } else { json!("unlimited") }),
            "dt_over_dt_critical": if stability.margin.is_finite() { json!(stability.margin) } else { json!("unstable at any dt") },
        },
    });
    if args.json {
        println!("{value}");
    } else {
        print_info(&value);
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints the info object as indented `key: value` lines.
fn print_info(value: &serde_json::Value) {
    fn walk(value: &serde_json::Value, indent: usize) {
        if let serde_json::Value::Object(map) = value {
            for (k, v) in map {
                match v {
                    serde_json::Value::Object(_) => {
                        println!("{:indent$}{k}:", "");
                        walk(v, indent + 2);
                    }
                    _ => println!("{:indent$}{k}: {}", "", compact(v)),
                }
            }
        }
    }
    fn compact(v: &serde_json::Value) -> String {
        match v {
            serde_json::Value::String(s) => s.clone(),
            serde_json::Value::Null => "none".to_string(),
            serde_json::Value::Array(items) => {
                items.iter().map(compact).collect::<Vec<_>>().join(", ")
            }
            other => other.to_string(),
        }
    }
    walk(value, 0);
}
