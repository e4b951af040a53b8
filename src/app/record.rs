//! `cloth record`: run a scene for N simulated seconds and render it off-screen,
//! frame by frame, to an animated GIF or a numbered PNG sequence, with the app's
//! renderer (no window or display needed, as `cloth screenshot`).
//!
//! Frame i shows the simulation at `t = i / fps` (the step nearest to it), so
//! `--seconds 4 --fps 25` is 100 frames that play back in real time. The camera
//! frames the scene as it starts and stays put, so the motion shows.
//!
//! Where the frames go is read from `--out`, by one rule:
//! - a name ending in `.gif`: one animated GIF (each frame quantised to 256
//!   colours, looping);
//! - a `.png` name with `%d` or `%0Nd` in it (`frame-%04d.png`): one PNG per
//!   frame, numbered from 0;
//! - a folder (ending in `/`, or one that exists): `frame-0000.png`, ... in it;
//!   the folder is made if missing and must be empty (unless `--force`), so no
//!   earlier recording is mixed in or overwritten.
//!
//! Everything is checked before the simulation starts: the frame count and the
//! steps, the output path, and the graphics adapter.
//!
//! The app's "Record GIF" button runs the same frame loop ([`render_frames`]) on
//! a copy of the running system, on a thread of its own with the window's device
//! ([`Job`]), so the window keeps running while it records.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, mpsc};
use std::time::Instant;

use anyhow::{Context as _, anyhow};

use super::frame::{self, FrameData};
use super::screenshot::{Diverged, parse_size};
use crate::render::ViewOptions;
use crate::render::offscreen::{Offscreen, write_png};
use cloth_sandbox::limits::{self, PendingFile};
use cloth_sandbox::session::Session;
use cloth_sandbox::sim::System;
use cloth_sandbox::sim::safe::{StepWatch, follow_areas};
use cloth_sandbox::view::OrbitCamera;

/// Most frames one recording may have (at 25 fps, 400 s).
pub const MAX_FRAMES: u64 = 10_000;

/// Arguments of `cloth record`.
#[derive(Debug, Clone, clap::Args)]
pub struct RecordArgs {
    /// Scene to load (a built-in name or a scene file).
    #[arg(long, default_value = "cloth")]
    pub scene: String,
    /// Override a scene parameter (same keys as the panel and `--set` elsewhere); repeatable.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Simulated seconds to record.
    #[arg(long, default_value_t = 4.0, allow_hyphen_values = true)]
    pub seconds: f64,
    /// Frames per simulated second, which is also the playback rate: 1 to 50 (GIF
    /// players do not go faster).
    #[arg(
        long,
        default_value_t = 25,
        value_parser = clap::value_parser!(u32).range(1..=50),
        allow_hyphen_values = true
    )]
    pub fps: u32,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "640x400", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Where the frames go: `NAME.gif` writes an animated GIF; a `.png` name with
    /// `%d` or `%0Nd` for the frame number (e.g. `frame-%04d.png`) writes one PNG
    /// per frame, numbered from 0; a folder (`DIR/`, made if missing, and empty
    /// unless `--force`) gets `DIR/frame-0000.png`, `DIR/frame-0001.png`, ...
    #[arg(long, value_name = "FILE.gif|PATTERN.png|DIR/")]
    pub out: PathBuf,
    /// With `--out DIR/`: write into a folder that is not empty, replacing frames of
    /// the same names (without it, such a folder is refused before the recording).
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub engine: crate::cli::EngineArg,
    /// Camera yaw in degrees (0 looks along -z).
    #[arg(long, allow_negative_numbers = true)]
    pub yaw: Option<f32>,
    /// Camera pitch in degrees (positive looks down on the scene).
    #[arg(long, allow_negative_numbers = true)]
    pub pitch: Option<f32>,
}

/// Where the frames go, as `--out` says.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// One animated GIF.
    Gif(PathBuf),
    /// One PNG per frame, named by a pattern.
    Pattern(Sequence),
    /// One PNG per frame in a new or empty folder.
    Folder(Sequence),
}

/// Numbered PNG file names: `folder/{head}{i:0digits$}{tail}`.
#[derive(Debug, Clone, PartialEq)]
pub struct Sequence {
    folder: PathBuf,
    head: String,
    digits: usize,
    tail: String,
}

impl Sequence {
    /// The file of frame `i`.
    pub fn path(&self, i: u64) -> PathBuf {
        let digits = self.digits;
        self.folder
            .join(format!("{}{i:0digits$}{}", self.head, self.tail))
    }
}

const OUT_RULE: &str = "give a name ending in .gif (an animated GIF), a .png name with %d or %04d \
    for the frame number such as frame-%04d.png, or a folder ending in / (frame-0000.png, ... in it)";

/// Reads `--out` by the rule in the module docs; the error says the rule.
pub fn parse_out(out: &Path) -> Result<Output, String> {
    let text = out.to_string_lossy();
    let shown = limits::echo(&text);
    let lower = text.to_lowercase();
    if text.ends_with('/') || out.is_dir() {
        return Ok(Output::Folder(Sequence {
            folder: out.to_path_buf(),
            head: "frame-".to_string(),
            digits: 4,
            tail: ".png".to_string(),
        }));
    }
    if lower.ends_with(".gif") {
        return Ok(Output::Gif(out.to_path_buf()));
    }
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    if !lower.ends_with(".png") {
        return Err(format!("--out {shown}: {OUT_RULE}"));
    }
    let Some(at) = name.find('%') else {
        return Err(format!(
            "--out {shown}: a PNG sequence needs the frame number in the name, e.g. frame-%04d.png; or {OUT_RULE}"
        ));
    };
    let (head, rest) = name.split_at(at);
    let rest = &rest[1..];
    let width: String = rest.chars().take_while(char::is_ascii_digit).collect();
    let Some(tail) = rest[width.len()..].strip_prefix('d') else {
        return Err(format!(
            "--out {shown}: the frame number is written %d or %0Nd (e.g. %04d), and a name has one of them"
        ));
    };
    if tail.contains('%') {
        return Err(format!(
            "--out {shown}: only one %d may stand for the frame number"
        ));
    }
    let digits = width.parse::<usize>().unwrap_or(0);
    if digits > 9 {
        return Err(format!(
            "--out {shown}: at most 9 digits for the frame number, got {digits}"
        ));
    }
    let folder = out.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok(Output::Pattern(Sequence {
        folder,
        head: head.to_string(),
        digits,
        tail: tail.to_string(),
    }))
}

/// Frames for `seconds` at `fps`: at least one, at most [`MAX_FRAMES`].
pub fn frame_count(seconds: f64, fps: u32) -> Result<u64, String> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(format!(
            "--seconds {} must be a number of seconds above 0",
            limits::number(seconds)
        ));
    }
    let frames = (seconds * f64::from(fps)).round().max(1.0);
    if frames > MAX_FRAMES as f64 {
        return Err(format!(
            "--seconds {} at --fps {fps} is {} frames: a recording has at most {MAX_FRAMES} frames",
            limits::number(seconds),
            limits::number(frames)
        ));
    }
    Ok(frames as u64)
}

/// The GIF delay of frame `i` in hundredths of a second: the rounding of each
/// frame is carried to the next, so the whole plays in `frames / fps` seconds even
/// when `100 / fps` is not whole.
pub fn gif_delay(i: u64, fps: u32) -> u16 {
    let at = |k: u64| (100 * k + u64::from(fps) / 2) / u64::from(fps);
    (at(i + 1) - at(i)) as u16
}

/// Where frames are written as they come.
enum Sink {
    Gif {
        file: PendingFile,
        encoder: Option<gif::Encoder<std::io::BufWriter<std::fs::File>>>,
        fps: u32,
    },
    Pngs {
        sequence: Sequence,
        /// The frames written so far.
        written: Vec<PathBuf>,
    },
}

impl Sink {
    /// A looping GIF of `size` pixels at `fps`, written to a file beside `path`
    /// and renamed over it when finished.
    fn gif(path: &Path, size: (u32, u32), fps: u32) -> anyhow::Result<Self> {
        let shown = path.display();
        let mut file = PendingFile::create(path).map_err(|e| anyhow!("{shown}: {e}"))?;
        let writer = file
            .writer()
            .try_clone()
            .with_context(|| format!("opening {shown}"))?;
        let mut encoder = gif::Encoder::new(
            std::io::BufWriter::new(writer),
            size.0 as u16,
            size.1 as u16,
            &[],
        )
        .with_context(|| format!("writing {shown}"))?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .with_context(|| format!("writing {shown}"))?;
        Ok(Sink::Gif {
            file,
            encoder: Some(encoder),
            fps,
        })
    }

    /// Checks the output and makes it ready, before any work: no file it will
    /// write (the GIF, each of the `frames` frames) is one of the `inputs`, and
    /// without `--force` a PNG sequence replaces no frame that exists (an earlier
    /// recording's), as a folder must be empty.
    fn open(
        out: &Output,
        args: &RecordArgs,
        frames: u64,
        inputs: &limits::Inputs,
    ) -> anyhow::Result<Self> {
        let shown = args.out.display();
        let frames_of = |sequence: &Sequence| -> anyhow::Result<()> {
            for i in 0..frames {
                let path = sequence.path(i);
                inputs
                    .check(&format!("--out {shown} (frame {i})"), &path)
                    .map_err(|e| anyhow!(e))?;
            }
            Ok(())
        };
        match out {
            Output::Gif(path) => {
                inputs.check("--out", path).map_err(|e| anyhow!(e))?;
                Sink::gif(path, args.size, args.fps).map_err(|e| anyhow!("--out {e:#}"))
            }
            Output::Folder(sequence) => {
                limits::prepare_output_folder(&sequence.folder, args.force)
                    .map_err(|e| anyhow!("--out: {e}"))?;
                frames_of(sequence)?;
                Ok(Sink::pngs(sequence))
            }
            Output::Pattern(sequence) => {
                frames_of(sequence)?;
                if !args.force
                    && let Some(i) = (0..frames).find(|&i| sequence.path(i).exists())
                {
                    return Err(anyhow!(
                        "--out {shown}: {} exists (an earlier recording's frame?): give another \
                         name, or --force to replace the frames of the same names",
                        sequence.path(i).display()
                    ));
                }
                // The first frame's file, made and dropped: the folder exists and
                // can be written.
                PendingFile::create(&sequence.path(0))
                    .map_err(|e| anyhow!("--out {shown}: {e}"))?;
                Ok(Sink::pngs(sequence))
            }
        }
    }

    /// A PNG sequence that has written nothing yet.
    fn pngs(sequence: &Sequence) -> Self {
        Sink::Pngs {
            sequence: sequence.clone(),
            written: Vec::new(),
        }
    }

    /// After a failed write: removes the frames this recording wrote, so that no
    /// part of it is left (a GIF is written whole or not at all).
    fn abandon(self) {
        if let Sink::Pngs { written, .. } = self {
            for path in written {
                let _ = std::fs::remove_file(path);
            }
        }
    }

    /// Adds frame `i` (RGBA8 rows, top first).
    fn push(&mut self, i: u64, size: (u32, u32), mut rgba: Vec<u8>) -> anyhow::Result<()> {
        let (width, height) = size;
        match self {
            Sink::Gif { encoder, fps, .. } => {
                let encoder = encoder.as_mut().context("the GIF is already finished")?;
                // Opaque: an alpha of 0 would make a pixel transparent.
                for px in rgba.chunks_exact_mut(4) {
                    px[3] = 255;
                }
                let mut frame =
                    gif::Frame::from_rgba_speed(width as u16, height as u16, &mut rgba, 10);
                frame.delay = gif_delay(i, *fps);
                encoder.write_frame(&frame).context("writing a GIF frame")?;
            }
            Sink::Pngs { sequence, written } => {
                let path = sequence.path(i);
                let file = PendingFile::create(&path)
                    .map_err(|e| anyhow!("frame {i}, {}: {e}", path.display()))?;
                write_png(file, width, height, &rgba)
                    .with_context(|| format!("writing frame {i} to {}", path.display()))?;
                written.push(path);
            }
        }
        Ok(())
    }

    /// Finishes the GIF (its trailer) and renames it over the target.
    fn finish(self) -> anyhow::Result<()> {
        if let Sink::Gif {
            file, mut encoder, ..
        } = self
        {
            let encoder = encoder.take().context("the GIF is already finished")?;
            let mut writer = encoder.into_inner().context("finishing the GIF")?;
            writer.flush().context("finishing the GIF")?;
            drop(writer);
            file.commit().context("finishing the GIF")?;
        }
        Ok(())
    }
}

/// The camera and what to draw, fixed for a whole recording.
pub struct View {
    /// The camera.
    pub camera: OrbitCamera,
    /// Display options (mesh, overlays, background).
    pub options: ViewOptions,
    /// Springs coloured by strain rather than kind.
    pub by_strain: bool,
    /// The triangles to draw ([`cloth_sandbox::session::Session::surface`]).
    pub surface: Vec<[u32; 3]>,
}

/// The simulation step, counted from the start, that frame `i` shows at `fps`:
/// the one nearest `i / fps` seconds, at the step `dt` that runs.
fn step_at(i: u64, fps: u32, dt: f64) -> f64 {
    (i as f64 / f64::from(fps) / dt).round()
}

/// Checks that `frames` frames at `fps` from `system`'s state are a run within
/// the work limits; the error gives the limit.
pub fn check_steps(system: &System, fps: u32, frames: u64) -> Result<(), String> {
    let dt = system.params().dt;
    let last = step_at(frames.saturating_sub(1), fps, dt);
    if !(last.is_finite() && last <= limits::MAX_STEPS as f64) {
        return Err(format!(
            "{frames} frames at {fps} fps and dt = {} s are {} steps; a run may take at most {} steps",
            limits::number(dt),
            limits::number(last),
            limits::MAX_STEPS
        ));
    }
    limits::total_steps(last as u64, 1, limits::StepWork::of(system.model())).map(|_| ())
}

/// Steps `system` with `stepper` from its state and renders `frames` frames at `fps` (frame i
/// at `i / fps` seconds after the start), handing each to `each` as RGBA8 rows.
/// With `scene_dt` (the session it came from steps safely, splitting its scene's
/// step of that many seconds: [`Session::safe_scene_step`]) it keeps safe stepping's watch
/// on the drag's areas after each frame, as the app does ([`follow_areas`]).
/// A divergence stops it with [`Diverged`], which says at which frame.
pub fn render_frames(
    (system, stepper): (&mut System, &mut cloth_sandbox::gpu::Stepper),
    scene_dt: Option<f64>,
    view: &View,
    fps: u32,
    frames: u64,
    offscreen: &mut Offscreen,
    mut each: impl FnMut(u64, Vec<u8>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    // The step that runs (safe stepping may have made it smaller than the scene's),
    // and the frame and step it took over from (where the watch last chose it).
    let mut dt = system.params().dt;
    let mut from = (0, system.steps_taken());
    let mut watch = StepWatch::default();
    let mut data = FrameData::default();
    for i in 0..frames {
        let target = from.1 + (step_at(i, fps, dt) - step_at(from.0, fps, dt)).max(0.0) as u64;
        let due = target.saturating_sub(system.steps_taken());
        if let Err(d) = stepper.run(system, due).map_err(|e| anyhow!(e))? {
            return Err(Diverged {
                steps: target,
                frame: i,
                message: format!("{d} (at frame {i} of {frames})"),
            }
            .into());
        }
        if let Some(scene_dt) = scene_dt
            && follow_areas(system, &mut watch, scene_dt).is_some()
        {
            dt = system.params().dt;
            from = (i, system.steps_taken());
        }
        data.build(system, &view.surface, &view.options, view.by_strain);
        let frame = data.scene_frame(None);
        let pixels = offscreen.render(&frame, &view.camera, &view.options)?;
        each(i, pixels)?;
    }
    Ok(())
}

/// Records `seconds` of `system` from its state as a GIF at `path` (a file there,
/// such as a name reserved with `create_new`, is replaced whole at the end) at
/// `fps`, on `offscreen`; `progress` gets the frames done so far and can stop it.
/// The app's "Record" button runs it on a thread of its own.
#[allow(clippy::too_many_arguments)]
pub fn record_gif(
    mut system: System,
    scene_dt: Option<f64>,
    view: &View,
    seconds: f64,
    fps: u32,
    offscreen: &mut Offscreen,
    path: &Path,
    progress: &Progress,
) -> anyhow::Result<()> {
    let frames = frame_count(seconds, fps).map_err(|e| anyhow!(e))?;
    check_steps(&system, fps, frames).map_err(|e| anyhow!(e))?;
    let size = offscreen.size();
    let mut sink = Sink::gif(path, size, fps)?;
    render_frames(
        (&mut system, &mut cloth_sandbox::gpu::Stepper::Cpu),
        scene_dt,
        view,
        fps,
        frames,
        offscreen,
        |i, pixels| {
            if progress.cancel.load(Ordering::Relaxed) {
                anyhow::bail!("the recording was cancelled");
            }
            sink.push(i, size, pixels)?;
            progress.frames_done.store(i + 1, Ordering::Relaxed);
            Ok(())
        },
    )?;
    sink.finish()
}

/// The longest side of a recording made in the app, in pixels: the view is
/// scaled down to it (GIFs of the full window are large and slow to quantise).
pub const APP_MAX_SIDE: u32 = 640;

/// A GIF being recorded on a thread of its own, from the app: the window keeps
/// running while it steps a copy of the system and renders on the window's
/// device.
pub struct Job {
    /// Where the GIF goes.
    pub path: PathBuf,
    /// Frames in all.
    pub frames: u64,
    progress: Arc<Progress>,
    done: mpsc::Receiver<anyhow::Result<()>>,
    thread: Option<std::thread::JoinHandle<()>>,
}

/// How far a recording has got, and a request to stop it.
#[derive(Default)]
pub struct Progress {
    /// Frames written so far.
    pub frames_done: AtomicU64,
    /// Set to stop the recording at the next frame (its file is then removed).
    pub cancel: AtomicBool,
}

/// The GPU a [`Job`] renders with: the window's device.
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter, in words.
    pub adapter_name: String,
    /// MSAA samples per pixel.
    pub samples: u32,
}

impl Job {
    /// Starts recording `seconds` of `system` from its state as `view` shows it,
    /// at `fps`, `size` pixels, into `cloth-<scene>-N.gif` in `dir` (the name is
    /// taken now, so no file is replaced). Errors that need no work (the length,
    /// the folder) come back at once; the rest from [`Job::finished`].
    #[allow(clippy::too_many_arguments)]
    pub fn start(
        system: System,
        scene_dt: Option<f64>,
        view: View,
        seconds: f64,
        fps: u32,
        gpu: Gpu,
        size: (u32, u32),
        dir: &Path,
        scene: &str,
    ) -> anyhow::Result<Job> {
        let frames = frame_count(seconds, fps).map_err(|e| anyhow!(e))?;
        check_steps(&system, fps, frames).map_err(|e| anyhow!(e))?;
        let stem = format!("cloth-{}", cloth_sandbox::export::scene_stem(scene));
        let (path, reserved) = cloth_sandbox::export::create_numbered(dir, &stem, "gif")?;
        drop(reserved);
        let progress = Arc::new(Progress::default());
        let (send, done) = mpsc::channel();
        let mut job = Job {
            path: path.clone(),
            frames,
            progress: progress.clone(),
            done,
            thread: None,
        };
        let thread = std::thread::Builder::new()
            .name("record".to_string())
            .spawn(move || {
                let result = Offscreen::with_device(
                    gpu.device,
                    gpu.queue,
                    gpu.adapter_name,
                    gpu.samples,
                    size.0,
                    size.1,
                )
                .and_then(|mut offscreen| {
                    record_gif(
                        system,
                        scene_dt,
                        &view,
                        seconds,
                        fps,
                        &mut offscreen,
                        &path,
                        &progress,
                    )
                });
                if result.is_err() {
                    // Not the reserved, empty name left looking like a recording.
                    let _ = std::fs::remove_file(&path);
                }
                let _ = send.send(result);
            })
            .context("starting the recording thread")?;
        job.thread = Some(thread);
        Ok(job)
    }

    /// Frames rendered so far.
    pub fn frames_done(&self) -> u64 {
        self.progress.frames_done.load(Ordering::Relaxed)
    }

    /// The outcome once the recording is over; `None` while it runs.
    pub fn finished(&self) -> Option<anyhow::Result<()>> {
        match self.done.try_recv() {
            Ok(result) => Some(result),
            Err(mpsc::TryRecvError::Empty) => None,
            Err(mpsc::TryRecvError::Disconnected) => Some(Err(anyhow!(
                "the recording thread stopped without a result"
            ))),
        }
    }
}

impl Drop for Job {
    /// Quitting the app during a recording stops it at the next frame and waits
    /// for the thread, which removes the unfinished file.
    fn drop(&mut self) {
        self.progress.cancel.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

/// `size` scaled down, keeping its shape, so that no side is over `max` pixels.
pub fn fit(size: (u32, u32), max: u32) -> (u32, u32) {
    let longest = size.0.max(size.1).max(1);
    if longest <= max {
        return (size.0.max(1), size.1.max(1));
    }
    let scale = f64::from(max) / f64::from(longest);
    let side = |s: u32| ((f64::from(s) * scale).round() as u32).clamp(1, max);
    (side(size.0), side(size.1))
}

/// Runs the scene and writes the frames.
pub fn run(args: &RecordArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let (width, height) = args.size;
    let output = parse_out(&args.out).map_err(|e| anyhow!(e))?;
    let frames = frame_count(args.seconds, args.fps).map_err(|e| anyhow!(e))?;
    let mut session = Session::load_with(&args.scene, &args.set).map_err(|e| anyhow!("{e}"))?;
    check_steps(session.system(), args.fps, frames).map_err(|e| anyhow!("--seconds: {e}"))?;
    // The output and the adapter before the simulation: whatever is missing is
    // said before any work.
    let mut stepper = args.engine.stepper(session.system())?;
    let inputs = session.scene().inputs(&args.scene);
    let mut sink = Sink::open(&output, args, frames, &inputs)?;
    let mut offscreen = Offscreen::new(width, height)?;

    let surfaceless = session.surface().is_empty();
    let options = ViewOptions {
        springs: surfaceless,
        particles: surfaceless,
        ..ViewOptions::default()
    };
    let camera = frame::framed_camera(&session, args.yaw, args.pitch);
    let view = View {
        camera,
        options,
        by_strain: false,
        surface: session.surface().to_vec(),
    };
    let scene_dt = session.safe_scene_step();
    let outcome = render_frames(
        (session.system_mut(), &mut stepper),
        scene_dt,
        &view,
        args.fps,
        frames,
        &mut offscreen,
        |i, pixels| sink.push(i, args.size, pixels),
    );
    if let Err(e) = outcome {
        let Some(diverged) = e.downcast_ref::<Diverged>() else {
            // A failed write (a full disk): no part of the recording is left.
            sink.abandon();
            return Err(e.context("the frames written before it were removed"));
        };
        let frame = diverged.frame;
        // What a user finds of the recording: a GIF is all or nothing.
        let kept = match (&output, frame) {
            (Output::Gif(_), _) | (_, 0) => "nothing was written".to_string(),
            (Output::Pattern(s) | Output::Folder(s), i) => format!(
                "frames 0 to {} were written, from {}",
                i - 1,
                s.path(0).display()
            ),
        };
        return Err(Diverged {
            steps: diverged.steps,
            frame,
            message: format!("{}; {kept}", diverged.message),
        }
        .into());
    }
    sink.finish()?;
    let written = match &output {
        Output::Gif(path) => path.display().to_string(),
        Output::Pattern(sequence) | Output::Folder(sequence) => format!(
            "{} to {}",
            sequence.path(0).display(),
            sequence.path(frames - 1).display()
        ),
    };
    eprintln!(
        "wrote {written}: {frames} frames of {width}x{height} at {} fps, t = 0 to {:.3} s, in {:.1} s (adapter {})",
        args.fps,
        session.system().time(),
        started.elapsed().as_secs_f64(),
        offscreen.adapter_name()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_add_up_to_the_recording() {
        for fps in [1, 7, 24, 25, 30, 50] {
            let total: u64 = (0..fps as u64 * 3)
                .map(|i| u64::from(gif_delay(i, fps)))
                .sum();
            assert_eq!(total, 300, "fps {fps}");
        }
        assert_eq!(gif_delay(0, 25), 4);
    }

    #[test]
    fn fit_keeps_the_shape() {
        assert_eq!(fit((894, 760), 640), (640, 544));
        assert_eq!(fit((320, 200), 640), (320, 200));
        assert_eq!(fit((4000, 1), 640), (640, 1));
    }

    #[test]
    fn out_rule() {
        assert_eq!(
            parse_out(Path::new("a/b.GIF")),
            Ok(Output::Gif("a/b.GIF".into()))
        );
        let Ok(Output::Pattern(s)) = parse_out(Path::new("shots/f-%03d.png")) else {
            panic!("a pattern")
        };
        assert_eq!(s.path(7), Path::new("shots/f-007.png"));
        let Ok(Output::Pattern(s)) = parse_out(Path::new("x%d.png")) else {
            panic!("a pattern")
        };
        assert_eq!(s.path(12), Path::new("x12.png"));
        let Ok(Output::Folder(s)) = parse_out(Path::new("new-folder/")) else {
            panic!("a folder")
        };
        assert_eq!(s.path(3), Path::new("new-folder/frame-0003.png"));
        for bad in [
            "a.png",
            "a.mp4",
            "a-%x.png",
            "a-%d-%d.png",
            "a-%012d.png",
            "a",
        ] {
            assert!(parse_out(Path::new(bad)).is_err(), "{bad}");
        }
    }
}
