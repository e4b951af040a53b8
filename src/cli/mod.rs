//! The headless command line: `cloth run`, `cloth info`, `cloth scenes`.
//!
//! Exit codes: 0 ran, 2 bad input (with a message naming the field), 3 the
//! simulation diverged (with the time and a hint).

use std::io::Write;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};
use cloth_sandbox::limits::{self, PendingFile};
use cloth_sandbox::scene::{Scene, SceneError, builtin_scenes};
use cloth_sandbox::sim::grid_kernel::{Precision, SimdLevel};
use cloth_sandbox::sim::safe::{
    DEFAULT_MAX_SUBSTEPS, DEFAULT_SAFETY, StepWatch, added_stretch_limit, follow_areas,
    safe_step_below,
};
use cloth_sandbox::sim::{
    Divergence, Integrator, PrecisionRule, SpringKind, System, bounding_sphere,
};
use serde_json::json;

mod summary;
use cloth_sandbox::gpu::{EngineChoice, Refused, Stepper};
use summary::Summary;

/// Exit code for bad input.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Exit code when no graphics adapter or display can be had.
pub const EXIT_NO_ADAPTER: u8 = 1;
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
    #[command(flatten)]
    pub engine: EngineArg,
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
    /// Record N simulated seconds of a scene off-screen, as a GIF or numbered PNGs.
    ///
    /// `--out NAME.gif` writes an animated GIF, `--out frame-%04d.png` or `--out DIR/`
    /// one PNG per frame; no window or display is needed.
    Record(crate::app::record::RecordArgs),
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
    /// Write into an output folder that is not empty, replacing files of the same
    /// names (without it, a non-empty folder is refused before the study starts).
    #[arg(long)]
    force: bool,
}

/// The integrator and step, given as flags rather than `--set` (`cloth run` and
/// `cloth info`).
#[derive(clap::Args, Debug)]
pub struct StepArgs {
    /// Integrator: explicit-euler, symplectic-euler, verlet, rk2, rk4, implicit-euler, xpbd.
    #[arg(long)]
    integrator: Option<String>,
    /// Time step in seconds.
    #[arg(long, allow_hyphen_values = true)]
    dt: Option<String>,
}

/// `cloth run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    step: StepArgs,
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
    /// Write the cloth's surface at the end of the run as a Wavefront OBJ file:
    /// positions, texture coordinates and vertex normals (scenes without a surface,
    /// such as `chain`, are refused before the run).
    #[arg(long, value_name = "FILE.obj")]
    obj: Option<std::path::PathBuf>,
    /// Safe stepping: split each step of dt into the fewest substeps that keep the
    /// step below half the integrator's critical step (the stability estimate).
    #[arg(long)]
    safe: bool,
    /// Always use the general f64 engine, the reference (by default every scene runs
    /// on a fast engine, named by `--json` and `cloth info`, that agrees with it
    /// within stated tolerances; RK2, RK4 and implicit Euler always run on this one).
    #[arg(long)]
    exact: bool,
    /// Untimed steps before the timed run, after which the start state is restored
    /// (as the peers' benchmarks warm up).
    #[arg(
        long,
        default_value_t = 0,
        value_name = "N",
        allow_hyphen_values = true
    )]
    warmup: u64,
    /// Run the fast engines' loops at this SIMD level at most, to compare levels on
    /// one machine: avx512, avx2 or baseline (default: the best this CPU has; a
    /// level it lacks is refused).
    #[arg(long, value_name = "LEVEL")]
    simd: Option<String>,
    #[command(flatten)]
    engine: EngineArg,
}

/// `--engine`, on `cloth run`, `cloth info`, `cloth screenshot` and `cloth record`.
#[derive(clap::Args, Debug, Clone)]
pub struct EngineArg {
    /// Engine: cpu (the CPU engines), gpu (wgpu compute shaders; refused in one
    /// line where there is no adapter or the scene needs what it does not step),
    /// or auto (the GPU on a hardware adapter from 65,536 particles, else the CPU).
    #[arg(long, value_name = "ENGINE", default_value = "auto")]
    pub engine: String,
}

impl EngineArg {
    /// The engine asked for, or the message that names the choices.
    pub fn choice(&self) -> Result<EngineChoice, String> {
        self.engine.parse().map_err(|e| format!("--engine: {e}"))
    }

    /// The stepper for `system`, saying on stderr when `auto` fell back; a
    /// refusal is an error with its exit code.
    pub fn stepper(&self, system: &System) -> Result<Stepper, EngineRefused> {
        let refused = |message, code| EngineRefused { message, code };
        let choice = self.choice().map_err(|e| refused(e, EXIT_BAD_INPUT))?;
        match Stepper::choose(choice, system) {
            Ok((stepper, note)) => {
                if let Some(note) = note {
                    eprintln!("{note}");
                }
                Ok(stepper)
            }
            Err(Refused::Input(e)) => Err(refused(e, EXIT_BAD_INPUT)),
            Err(Refused::Machine(e)) => Err(refused(e, EXIT_NO_ADAPTER)),
        }
    }
}

/// `--engine` refused: the message, and the exit code (2 for the scene, 1 for
/// the machine).
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct EngineRefused {
    message: String,
    code: u8,
}

impl EngineRefused {
    /// Says it and gives its exit code.
    fn exit(&self) -> ExitCode {
        eprintln!("error: {}", self.message);
        ExitCode::from(self.code)
    }
}

/// `cloth info`.
#[derive(clap::Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    step: StepArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    engine: EngineArg,
}

/// A screenshot's or a recording's end as an exit code: an engine refused and a
/// divergence say their own line; any other error is bad input.
fn offscreen(result: anyhow::Result<()>) -> Result<ExitCode, String> {
    let Err(e) = result else {
        return Ok(ExitCode::SUCCESS);
    };
    if let Some(refused) = e.downcast_ref::<EngineRefused>() {
        return Ok(refused.exit());
    }
    if e.is::<crate::app::screenshot::Diverged>() {
        eprintln!("error: {e:#}");
        return Ok(ExitCode::from(EXIT_DIVERGED));
    }
    Err(format!("{e:#}"))
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
        Command::Screenshot(args) => offscreen(crate::app::screenshot::run(&args)),
        Command::Record(args) => offscreen(crate::app::record::run(&args)),
        Command::Report(args) => report(args),
    };
    result.unwrap_or_else(|message| {
        eprintln!("error: {message}");
        ExitCode::from(EXIT_BAD_INPUT)
    })
}

fn report(args: ReportArgs) -> Result<ExitCode, String> {
    // Checked before the study, which takes minutes: a folder that cannot take
    // the results, or one holding other files, is refused now.
    limits::prepare_output_folder(&args.out, args.force).map_err(|e| format!("--out: {e}"))?;
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

/// Runs `steps` steps of `system`'s step, or with `recheck` (safe stepping on a
/// model with drag; the step of dt it splits) the simulated time they cover, in
/// frames of 1/60 s simulated, choosing the step again after each frame where
/// the drag's areas have outgrown it ([`follow_areas`]: the app's rule, every
/// frame), and saying so. Stops early at step `until`, if given (the replay to the
/// state before a divergence, which takes the same steps). The error is a run that
/// its new steps would make longer than [`limits::total_steps`] allows.
fn run_checked(
    stepper: &mut Stepper,
    system: &mut System,
    steps: u64,
    recheck: Option<f64>,
    until: Option<u64>,
) -> Result<Result<(), Divergence>, String> {
    let until = until.unwrap_or(u64::MAX);
    let Some(scene_dt) = recheck else {
        return stepper.run(
            system,
            steps.min(until.saturating_sub(system.steps_taken())),
        );
    };
    let end = system.time() + steps as f64 * system.params().dt;
    let work = limits::StepWork::of(system.model());
    let mut watch = StepWatch::default();
    loop {
        let dt = system.params().dt;
        let left = ((end - system.time()) / dt).round().max(0.0) as u64;
        let left = left.min(until.saturating_sub(system.steps_taken()));
        if left == 0 {
            return Ok(Ok(()));
        }
        let frame = ((1.0 / 60.0) / dt).ceil().max(1.0) as u64;
        if let Err(d) = stepper.run(system, left.min(frame))? {
            return Ok(Err(d));
        }
        if let Some(choice) = follow_areas(system, &mut watch, scene_dt) {
            let left = ((end - system.time()) / choice.dt).round().max(0.0) as u64;
            limits::total_steps(system.steps_taken() + left, 1, work).map_err(|e| {
                format!("run too long after safe stepping chose a smaller step: {e}")
            })?;
            eprintln!(
                "safe stepping at t = {:.4} s: the cloth's drag areas have {}, so {} substeps of {:.4e} s per step of {scene_dt:.4e} s",
                system.time(),
                if choice.dt < dt {
                    "grown"
                } else {
                    "shrunk back"
                },
                choice.substeps,
                choice.dt,
            );
        }
    }
}

/// Loads a scene with `--integrator` and `--dt` applied as overrides.
fn load_scene(scene: &SceneArgs, args: &StepArgs) -> Result<Scene, String> {
    let mut scene = scene.load().map_err(|e| e.to_string())?;
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
            &format!("integrator {}", limits::echo(integrator)),
        )?;
    }
    if let Some(dt) = &args.dt {
        flag(&mut scene, "dt", dt, &format!("dt {}", limits::echo(dt)))?;
    }
    Ok(scene)
}

fn run(args: RunArgs) -> Result<ExitCode, String> {
    if let Some(name) = &args.simd {
        cap_simd(name)?;
    }
    let scene = load_scene(&args.scene, &args.step)?;
    let inputs = scene.inputs(&args.scene.scene);
    let mut system = scene.build().map_err(|e| e.to_string())?;
    let dt = system.params().dt;
    let steps = requested_steps(&args, dt)?;
    let substeps = if args.safe {
        safe_stepping(&mut system, dt)
    } else {
        1
    };
    // The whole run is checked before any of it starts: nothing the user asks for
    // may run for ever, and the results must have somewhere to go.
    let work = limits::StepWork::of(system.model());
    let steps =
        limits::total_steps(steps, substeps, work).map_err(|e| format!("run too long: {e}"))?;
    limits::total_steps(args.warmup, 1, work).map_err(|e| format!("--warmup: {e}"))?;
    let dump = match &args.dump {
        Some(path) => Some(prepare_dump(path, &inputs)?),
        None => None,
    };
    let obj = match &args.obj {
        Some(path) => Some(prepare_obj(&system, path, &args, &inputs)?),
        None => None,
    };
    system.set_fast_path(!args.exact);
    let engine = system.engine();
    if args.exact && args.engine.choice()? == EngineChoice::Gpu {
        return Err("--exact runs the f64 reference engine, not --engine gpu: give one".into());
    }
    let mut stepper = match args.exact {
        true => Stepper::Cpu,
        false => match args.engine.stepper(&system) {
            Ok(stepper) => stepper,
            Err(refused) => return Ok(refused.exit()),
        },
    };
    // Setup is not timed: warm-up steps build the engine's buffers (and thread
    // pool) and run from the start state, which is then put back; then a run of no
    // steps sets the energy budget from it and copies it into the engine. (Timed,
    // those two took 5 to 9 ms of the 32³ jelly's run, the time of 20 to 35 of its
    // steps: a short run's rate said more about them than about the steps.)
    // The start state is kept only where it is needed: on a big cloth it is
    // tens of megabytes.
    let replay = dump.is_some() || obj.is_some();
    let start_state = (args.warmup > 0 || replay).then(|| system.state().clone());
    if let Some(start) = start_state.as_ref().filter(|_| args.warmup > 0) {
        // A warm-up that diverges has served its purpose: the run starts over.
        let _ = stepper.run(&mut system, args.warmup)?;
        system.set_state(start.clone());
        stepper.reset_gpu_time();
    }
    system.run(0).map_err(|e| e.to_string())?;
    let start_params = *system.params();
    // Safe stepping on a cloth in the air checks its step as the app does.
    let recheck = (args.safe && system.model().terms.aero).then_some(dt);
    let start = Instant::now();
    let outcome = run_checked(&mut stepper, &mut system, steps, recheck, None)?;
    let wall = start.elapsed().as_secs_f64();
    let summary = Summary::of(&system, wall, engine).on_gpu(stepper.adapter(), stepper.gpu_time());
    let mut dumped = None;
    if let (Err(d), Some(start_state)) = (&outcome, start_state) {
        // The state at the divergence is not finite (or ran away): the CSV and
        // the OBJ hold the last state before it, which the run then replays to.
        system.set_params(start_params);
        system.set_state(start_state);
        let _ = run_checked(
            &mut stepper,
            &mut system,
            steps,
            recheck,
            Some(d.step().saturating_sub(1)),
        )?;
        dumped = Some((system.steps_taken(), system.time()));
    }
    write_outputs(&system, &args, dump, obj, outcome.is_err())?;
    print_summary(&system, &args, &summary, &outcome, dumped);
    if outcome.is_ok()
        && let Some(warning) = summary.limiters.and_then(|a| a.warning())
    {
        eprintln!("warning: {warning}");
    }
    match outcome {
        Ok(()) => Ok(ExitCode::SUCCESS),
        Err(divergence) => {
            report_divergence(&system, &divergence, args.safe);
            divergence_notes(&system, &args, dumped);
            Ok(ExitCode::from(EXIT_DIVERGED))
        }
    }
}

/// Caps the fast engines' loops at the SIMD level `--simd` names.
fn cap_simd(name: &str) -> Result<(), String> {
    let names = SimdLevel::ALL.map(SimdLevel::name).join(", ");
    let level = SimdLevel::from_name(name)
        .ok_or_else(|| format!("--simd: `{name}` is not a SIMD level; use one of {names}"))?;
    SimdLevel::cap(level).map_err(|e| format!("--simd {name}: {e}"))
}

/// The steps of `dt` that `--steps` or `--duration` asks for (1 s by default).
fn requested_steps(args: &RunArgs, dt: f64) -> Result<u64, String> {
    match (args.steps, args.duration) {
        (Some(n), _) => Ok(n),
        (None, Some(d)) => {
            limits::steps_for_duration(d, dt).map_err(|e| format!("--duration: {e}"))
        }
        (None, None) => limits::steps_for_duration(1.0, dt)
            .map_err(|e| format!("the default --duration of 1 s: {e}")),
    }
}

/// `--safe`: sets `system`'s step below half its critical step, with the stretch
/// limit the app adds in a strong wind, says so, and returns the substeps each
/// step of `dt` is split into.
fn safe_stepping(system: &mut System, dt: f64) -> u64 {
    let choice = safe_step_below(
        system.stability().dt_critical,
        dt,
        DEFAULT_SAFETY,
        DEFAULT_MAX_SUBSTEPS,
    );
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
    u64::from(choice.substeps)
}

/// Writes `system` into the prepared `--dump` and `--obj` files. After a
/// divergence the exit code says so, and an OBJ that cannot be written is a note.
fn write_outputs(
    system: &System,
    args: &RunArgs,
    dump: Option<PendingFile>,
    obj: Option<PendingFile>,
    diverged: bool,
) -> Result<(), String> {
    if let (Some(file), Some(path)) = (dump, &args.dump) {
        write_csv(system, file).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    if let (Some(file), Some(path)) = (obj, &args.obj) {
        let scene = &args.scene.scene;
        match write_obj(system, scene, file) {
            Ok(()) => eprintln!(
                "wrote {} ({} vertices, {} triangles, t = {:.4} s)",
                path.display(),
                system.particle_count(),
                system.triangles().len(),
                system.time()
            ),
            // The note tells why there is no file.
            Err(e) if diverged => eprintln!("note: {} not written: {e}", path.display()),
            Err(e) => return Err(format!("cannot write {}: {e}", path.display())),
        }
    }
    Ok(())
}

/// Prints the summary: as text, or as JSON with the divergence, its hint and the
/// state the dump holds.
fn print_summary(
    system: &System,
    args: &RunArgs,
    summary: &Summary,
    outcome: &Result<(), Divergence>,
    dumped: Option<(u64, f64)>,
) {
    if args.json {
        let mut value = summary.to_json();
        if let Err(d) = outcome {
            value["diverged"] = json!({
                "time": d.time(),
                "step": d.step(),
                "message": d.to_string(),
                "hint": hint(system, args.safe),
                "dump": dumped.map(|(step, time)| json!({ "step": step, "time": time })),
            });
        }
        println!("{value}");
    } else {
        summary.print();
    }
}

/// After a divergence: the state the `--dump` and `--obj` files hold, the last
/// before it (`dumped`: its step and time).
fn divergence_notes(system: &System, args: &RunArgs, dumped: Option<(u64, f64)>) {
    let finite = system.positions().iter().all(|p| p.is_finite());
    if let (Some((step, time)), Some(path)) = (dumped, &args.dump) {
        eprintln!(
            "note: {} holds the last state before the divergence, at step {step} (t = {time:.4} s){}",
            path.display(),
            if finite {
                ""
            } else {
                ", and even it is not finite"
            }
        );
    }
    if let (Some((step, time)), Some(path), true) = (dumped, &args.obj, finite) {
        eprintln!(
            "note: {} holds the last state before the divergence, at step {step} (t = {time:.4} s)",
            path.display(),
        );
    }
}

/// The `--dump` file made ready before the run, so that a path that cannot be
/// written is found before the work rather than after it: none of the run's
/// inputs (the scene file, its mesh, however spelled), not a folder, not a device
/// or pipe (`/dev/stdout` would mix the CSV into the summary), in a folder that
/// can be written.
fn prepare_dump(path: &Path, inputs: &limits::Inputs) -> Result<PendingFile, String> {
    inputs.check("--dump", path)?;
    PendingFile::create(path).map_err(|e| format!("--dump {}: {e}", path.display()))
}

/// The `--obj` file made ready before the run, as `--dump` is: the scene must have
/// a surface, and the path must be writable, none of the run's inputs and not the
/// `--dump` file.
fn prepare_obj(
    system: &System,
    path: &Path,
    args: &RunArgs,
    inputs: &limits::Inputs,
) -> Result<PendingFile, String> {
    let shown = path.display();
    inputs.check("--obj", path)?;
    cloth_sandbox::export::check_surface(system, &args.scene.scene)
        .map_err(|e| format!("--obj {shown}: {e}"))?;
    let same = |dump: &Path| {
        dump == path
            || limits::output_target(dump).is_some_and(|d| Some(d) == limits::output_target(path))
    };
    if args.dump.as_deref().is_some_and(same) {
        return Err(format!(
            "--obj {shown} is also the --dump file: give them different names"
        ));
    }
    PendingFile::create(path).map_err(|e| format!("--obj {shown}: {e}"))
}

/// Writes the surface as OBJ into the prepared file and renames it over the target.
fn write_obj(
    system: &System,
    scene: &str,
    mut file: PendingFile,
) -> Result<(), cloth_sandbox::export::ExportError> {
    cloth_sandbox::export::write_obj(system, scene, file.writer())?;
    file.commit()?;
    Ok(())
}

/// What to try after a divergence of `system` (`safe`: the run already had safe
/// stepping, so it is not suggested).
fn hint(system: &System, safe: bool) -> String {
    let stability = system.stability();
    let integrator = system.params().integrator;
    let other_integrator = if integrator == Integrator::ImplicitEuler {
        ""
    } else {
        ", or --integrator implicit-euler"
    };
    match stability.dt_critical {
        None => {
            let why = if stability.zeta > 0.0 {
                "here"
            } else {
                "without damping"
            };
            let others: Vec<_> = [
                Integrator::SymplecticEuler,
                Integrator::Rk4,
                Integrator::ImplicitEuler,
            ]
            .into_iter()
            .filter(|&i| i != integrator)
            .map(|i| i.name())
            .collect();
            format!(
                "{integrator} has no stable step {why}; try --integrator {}",
                others.join(" or ")
            )
        }
        Some(c) if stability.margin >= 1.0 => format!(
            "dt / dt_crit = {:.3}: the step is over the stability limit; try a smaller dt (e.g. --dt {:.3e}), a lower stiffness or damping{other_integrator}",
            stability.margin,
            0.5 * c
        ),
        // XPBD's springs set no step limit, and safe stepping and implicit Euler
        // leave the other forces as explicit as XPBD does.
        Some(_) if integrator == Integrator::Xpbd => "xpbd's springs set no step limit, so a \
             force it steps explicitly ran away (wind drag on light particles, gravity, a \
             collider's push): try a smaller dt or more steps per frame, or less wind"
            .to_string(),
        // The estimate takes the springs at their rest length and the drag on the
        // triangles' rest areas: a cloth stretched far past them (a soft one under
        // its own weight or in the wind) may need a smaller step than it says.
        Some(_) => format!(
            "dt / dt_crit = {:.3}: the step is within the estimated stability limit, which takes the \
             springs {}; stretched far past rest, or pushed hard (wind, gravity, a collider, \
             constraints), the system may need a smaller step: try --dt {:.3e}{}{other_integrator}",
            stability.margin,
            if safe {
                "at rest (safe stepping followed the drag's areas)"
            } else {
                "and the drag areas at rest"
            },
            0.5 * system.params().dt,
            if safe { "" } else { ", --safe" },
        ),
    }
}

/// Prints the divergence and what to try (`safe`: the run already had safe stepping).
fn report_divergence(system: &System, divergence: &Divergence, safe: bool) {
    eprintln!("error: the simulation diverged: {divergence}");
    eprintln!("hint: {}", hint(system, safe));
}

/// Writes the positions as CSV `index,x,y,z` into the prepared file and renames it
/// over the target.
fn write_csv(system: &System, mut file: PendingFile) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(file.writer());
    writeln!(out, "index,x,y,z")?;
    for (i, p) in system.positions().iter().enumerate() {
        writeln!(out, "{i},{},{},{}", p.x, p.y, p.z)?;
    }
    out.flush()?;
    drop(out);
    file.commit()
}

/// The precision rule's reasons, as `cloth info` shows them: the positions the
/// kernel keeps, and the float32 noise on each kind of positions against the limit.
fn precision_json(rule: PrecisionRule) -> serde_json::Value {
    let positions = match rule.precision {
        Precision::Single => "float32".to_string(),
        Precision::Mixed => format!(
            "fixed point, unit 2^{} m ({:.3e} m)",
            rule.unit.log2().round(),
            rule.unit
        ),
        Precision::Double => "float64".to_string(),
    };
    json!({
        "positions": positions,
        "float32_noise_m_per_s2": {
            "on_float32_positions": rule.float32_positions,
            "on_fixed_point_positions": rule.fixed_point,
            "limit": Precision::NOISE_LIMIT,
        },
    })
}

fn info(args: InfoArgs) -> Result<ExitCode, String> {
    let scene = load_scene(&args.scene, &args.step)?;
    let resolved = scene.resolve().map_err(|e| e.to_string())?;
    let mut system = resolved.build();
    // The engine `cloth run` uses (without `--exact`).
    system.set_fast_path(true);
    let engine = system.engine();
    let stepper = match args.engine.stepper(&system) {
        Ok(stepper) => stepper,
        Err(refused) => return Ok(refused.exit()),
    };
    let adapter = stepper.adapter().map(ToString::to_string);
    let p = system.params();
    let mut per_kind = serde_json::Map::new();
    for kind in SpringKind::ALL {
        let n = system.springs().iter().filter(|s| s.kind == kind).count();
        per_kind.insert(kind.name().to_string(), json!(n));
    }
    let constraints = constraints(&system);
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
        "engine": if adapter.is_some() { "gpu" } else { engine.name() },
        "adapter": adapter,
        "simd": adapter.is_none().then(|| engine.simd_level().name()),
        "precision": system.precision_rule().filter(|_| adapter.is_none()).map(precision_json),
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
            "ground": p.ground.map(|g| json!({"height": g.height - p.thickness, "stiffness": g.stiffness, "damping": g.damping, "friction": g.friction})),
            "sphere": p.sphere.map(|s| json!({"center": s.center.to_array(), "radius": s.radius - p.thickness})),
            "friction": p.friction,
            "thickness": p.thickness,
            "self_collision": p.self_collision,
            "integrator": p.integrator.name(),
            "dt": p.dt,
            "substeps": resolved.substeps,
            "seed": p.seed,
            "bar_iterations": p.bar_iterations,
            "stretch_limit": p.stretch_limit,
            "tear_strain": p.tear_strain,
            "max_speed": p.max_speed,
        },
        "extent": 2.0 * extent,
        "stability": {
            "omega_max": stability.omega_max,
            "omega_max_bound": stability.omega_bound,
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

/// The constraints, limiters and contacts `system` applies after its forces, as
/// `cloth info` lists them.
fn constraints(system: &System) -> Vec<String> {
    let p = system.params();
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
            "sphere collider (centre {:?}, radius {} m, touched at {} m)",
            s.center.to_array(),
            s.radius - p.thickness,
            s.radius
        ));
    }
    if p.self_collides() {
        constraints.push(format!(
            "self-collision (particles {} m apart, friction {})",
            p.thickness, p.friction
        ));
    }
    if let Some(max_speed) = p.max_speed {
        constraints.push(format!("speed limit ({max_speed} m/s)"));
    }
    if let Some(tau) = p.tear_strain {
        constraints.push(format!(
            "tearing (a spring breaks past {:.0}% stretch)",
            tau * 100.0
        ));
    }
    let surfaces = [
        ("sphere", p.sphere.map(|_| p.friction)),
        ("ground", p.ground.map(|g| g.friction)),
    ];
    for (surface, mu) in surfaces {
        if let Some(mu) = mu.filter(|&mu| mu > 0.0) {
            constraints.push(format!("Coulomb friction (mu = {mu}) on the {surface}"));
        }
    }
    constraints
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
            serde_json::Value::Array(items) if items.is_empty() => "none".to_string(),
            serde_json::Value::Array(items) => {
                items.iter().map(compact).collect::<Vec<_>>().join(", ")
            }
            other => other.to_string(),
        }
    }
    walk(value, 0);
}
