//! `cloth screenshot`: run a scene for N steps and render it off-screen to a PNG
//! with the app's renderer, no window or display needed.

use std::path::PathBuf;

use anyhow::Context as _;

use super::frame::{self, FrameData};
use crate::render::ViewOptions;
use crate::render::offscreen::{Offscreen, write_png};
use cloth_sandbox::limits::{self, PendingFile};
use cloth_sandbox::session::Session;

/// Arguments of `cloth screenshot`.
#[derive(Debug, Clone, clap::Args)]
pub struct ScreenshotArgs {
    /// Scene to load (a built-in name or a scene file).
    #[arg(long, default_value = "cloth")]
    pub scene: String,
    /// Simulation steps to run before rendering.
    #[arg(long, default_value_t = 0, allow_hyphen_values = true)]
    pub steps: u64,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "960x640", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Override a scene parameter (same keys as the panel and `--set` elsewhere); repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Output PNG file.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub engine: crate::cli::EngineArg,
    /// Draw the triangle edges.
    #[arg(long)]
    pub wireframe: bool,
    /// Draw the springs as lines, coloured by kind.
    #[arg(long)]
    pub springs: bool,
    /// Draw the springs coloured by strain instead of kind (implies --springs).
    #[arg(long)]
    pub strain: bool,
    /// Draw every particle.
    #[arg(long)]
    pub particles: bool,
    /// Do not draw the surface.
    #[arg(long)]
    pub no_mesh: bool,
    /// Plain front/back colours instead of the checker texture.
    #[arg(long)]
    pub no_texture: bool,
    /// Camera yaw in degrees (0 looks along -z).
    #[arg(long, allow_negative_numbers = true)]
    pub yaw: Option<f32>,
    /// Camera pitch in degrees (positive looks down on the scene).
    #[arg(long, allow_negative_numbers = true)]
    pub pitch: Option<f32>,
}

/// Parses `WIDTHxHEIGHT`.
pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got {s:?}"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in {s:?}"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in {s:?}"))?;
    if !(1..=8192).contains(&w) || !(1..=8192).contains(&h) {
        return Err(format!("size {s:?} out of range (1..=8192 each side)"));
    }
    Ok((w, h))
}

/// The simulation diverged before the picture could be taken (exit code 3, as
/// `cloth run`).
#[derive(Debug, thiserror::Error)]
#[error("the simulation diverged before step {steps}: {message}")]
pub struct Diverged {
    /// Steps asked for.
    pub steps: u64,
    /// The frame being made (0 for a screenshot).
    pub frame: u64,
    /// The core's description (what and when).
    pub message: String,
}

/// Runs the scene and writes the picture.
pub fn run(args: &ScreenshotArgs) -> anyhow::Result<()> {
    let (width, height) = args.size;
    let mut session =
        Session::load_with(&args.scene, &args.set).map_err(|e| anyhow::anyhow!("{e}"))?;
    let work = limits::StepWork::of(session.system().model());
    limits::total_steps(args.steps, 1, work).map_err(|e| anyhow::anyhow!("--steps: {e}"))?;
    // The output file is checked before the steps, which may take long: none of
    // the inputs, and writable.
    (session.scene().inputs(&args.scene))
        .check("--out", &args.out)
        .map_err(|e| anyhow::anyhow!(e))?;
    let mut stepper = args.engine.stepper(session.system())?;
    let out = PendingFile::create(&args.out)
        .map_err(|e| anyhow::anyhow!("--out {}: {e}", args.out.display()))?;
    let diverged = |message| Diverged {
        steps: args.steps,
        frame: 0,
        message,
    };
    if stepper.adapter().is_some() {
        // The GPU engine runs the steps in one go, the session's dt and all.
        let run = stepper.run(session.system_mut(), args.steps);
        if let Err(d) = run.map_err(|e| anyhow::anyhow!(e))? {
            return Err(diverged(d.to_string()).into());
        }
    }
    for _ in session.system().steps_taken()..args.steps {
        session.single_step();
        if let Some(d) = session.divergence() {
            return Err(diverged(d.message.clone()).into());
        }
    }
    // Scenes without a surface (spring, chain, rope) draw as springs and particles.
    let surfaceless = session.surface().is_empty();
    let options = ViewOptions {
        mesh: !args.no_mesh,
        wireframe: args.wireframe,
        springs: args.springs || args.strain || surfaceless,
        particles: args.particles || surfaceless,
        textured: !args.no_texture,
        ..ViewOptions::default()
    };
    let camera = frame::framed_camera(&session, args.yaw, args.pitch);
    let mut data = FrameData::default();
    data.build(session.system(), session.surface(), &options, args.strain);
    let frame = data.scene_frame(None);
    let mut off = Offscreen::new(width, height)?;
    let pixels = off.render(&frame, &camera, &options)?;
    write_png(out, width, height, &pixels)
        .with_context(|| format!("writing the screenshot to {}", args.out.display()))?;
    let engine = (stepper.adapter()).map_or("the CPU engines".into(), |a| {
        format!("the GPU engine on {a}")
    });
    eprintln!(
        "wrote {} ({width}x{height}, adapter {}, stepped by {engine})",
        args.out.display(),
        off.adapter_name()
    );
    Ok(())
}
