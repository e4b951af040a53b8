//! The desktop app: a winit window with the scene drawn by wgpu and an egui side
//! panel. Input goes to egui first; what egui does not use drives the camera and
//! the picking. Dependencies point one way: app -> render -> (library) session/sim.

mod colliders;
pub mod frame;
pub mod gfx;
pub mod help;
pub mod input;
mod keys;
mod overlay;
pub mod panel;
pub mod physics;
pub mod plots;
pub mod record;
pub mod screenshot;

use std::sync::Arc;
use std::time::Instant;

use anyhow::Context as _;
use glam::Vec2;
use winit::application::ApplicationHandler;
use winit::dpi::LogicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, ModifiersState, PhysicalKey};
use winit::window::{Window, WindowId};

use cloth_sandbox::session::{Edit, Session};
use cloth_sandbox::view::{FlyKeys, OrbitCamera, any_in_view, pick_particle, springs_crossed};

use crate::render::ViewOptions;
use frame::FrameData;
use gfx::Gfx;
use input::{Button, Mouse, MouseAction};
use panel::{Action, PanelState};
use physics::SharedSession;

/// Window title (the Xvfb test finds the window by it).
pub const TITLE: &str = "cloth-sandbox";

/// Most of the wall-clock time frames may take on a software adapter once the
/// physics falls short of the speed asked for: the frames wait so that the cores
/// they share keep the rest.
/// A 256² cloth on lavapipe otherwise draws back to back and leaves the physics
/// under half of what it runs headless.
const SOFTWARE_FRAME_SHARE: f64 = 0.5;

/// The physics' share of wall time (see [`Pace::busy`]) below which frames on a
/// software adapter stop being spaced out: the physics keeps up with room to spare.
///
/// [`Pace::busy`]: cloth_sandbox::session::Pace::busy
const RELAXED_PHYSICS: f64 = 0.5;

/// Seconds with no particle in view before the camera frames the scene again.
const OUT_OF_VIEW_S: f64 = 1.0;

/// Pick radius around the cursor, in logical pixels.
const PICK_RADIUS: f32 = 12.0;

/// Options for the desktop app.
#[derive(Debug, Clone)]
pub struct AppOptions {
    /// Scene to open (built-in name or file); the default cloth when `None`.
    pub scene: Option<String>,
    /// `key=value` overrides applied to the scene.
    pub set: Vec<String>,
    /// `--engine`: the GPU engine, the CPU's, or the GPU where it gains.
    pub engine: crate::cli::EngineArg,
}

/// Runs the desktop app; on failure prints one `error:` line and returns 1.
pub fn main(options: AppOptions) -> std::process::ExitCode {
    // Bad input exits 2, as on the command line; a missing display or adapter, 1.
    let scene = options.scene.as_deref().unwrap_or("cloth");
    let mut session = match Session::load_with(scene, &options.set) {
        Ok(session) => session,
        Err(err) => {
            eprintln!("error: {err}");
            return std::process::ExitCode::from(2);
        }
    };
    // `auto` takes the GPU where `cloth run` would; `gpu` asks for it whatever
    // the adapter, and a machine without one is refused as on the command line.
    let gpu = match options.engine.choice() {
        Ok(cloth_sandbox::gpu::EngineChoice::Cpu) => false,
        Ok(cloth_sandbox::gpu::EngineChoice::Gpu) => true,
        Ok(cloth_sandbox::gpu::EngineChoice::Auto) => {
            matches!(options.engine.stepper(session.system()), Ok(s) if s.adapter().is_some())
        }
        Err(e) => {
            eprintln!("error: {e}");
            return std::process::ExitCode::from(2);
        }
    };
    if gpu && let Err(e) = session.set_gpu(true) {
        eprintln!("error: --engine gpu: {e}");
        return std::process::ExitCode::from(1);
    }
    match run(session) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Opens the window on `session` and runs until the user quits. Returns an error (one
/// sentence) when there is no display or no graphics adapter.
pub fn run(session: Session) -> anyhow::Result<()> {
    let event_loop = new_event_loop()?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App::new(session).context("cannot start the physics thread")?;
    event_loop
        .run_app(&mut app)
        .context("the window system stopped the event loop")?;
    match app.fatal.take() {
        Some(err) => Err(err),
        None => Ok(()),
    }
}

/// `EventLoop::new`, with winit's panics (a missing libxkbcommon-x11) and errors
/// (no display) turned into one clear sentence.
fn new_event_loop() -> anyhow::Result<EventLoop<()>> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let result = std::panic::catch_unwind(|| {
        let mut builder = EventLoop::builder();
        // Without a Wayland display, X11 straight away: trying Wayland first makes
        // libwayland print "XDG_RUNTIME_DIR is invalid" on every launch.
        #[cfg(all(unix, not(target_os = "macos")))]
        if std::env::var_os("WAYLAND_DISPLAY").is_none() && std::env::var_os("DISPLAY").is_some() {
            use winit::platform::x11::EventLoopBuilderExtX11 as _;
            builder.with_x11();
        }
        builder.build()
    });
    std::panic::set_hook(hook);
    match result {
        Ok(Ok(event_loop)) => Ok(event_loop),
        Ok(Err(err)) => {
            let text = err.to_string();
            if text.contains("DISPLAY") || text.contains("WAYLAND") {
                anyhow::bail!(
                    "no display to open a window on: neither DISPLAY nor WAYLAND_DISPLAY is set; run it in an X11 or Wayland session (or under Xvfb), or use `cloth screenshot` for off-screen images"
                )
            }
            anyhow::bail!("cannot connect to the window system: {text}")
        }
        Err(panic) => {
            let text = panic_text(panic.as_ref());
            anyhow::bail!(
                "cannot start the window system: {text} (on Debian/Ubuntu: apt-get install libxkbcommon-x11-0 libx11-xcb1 libxcursor1 libxi6)"
            )
        }
    }
}

/// What a caught panic said (its `String` or `&str` payload).
fn panic_text(panic: &(dyn std::any::Any + Send)) -> &str {
    panic
        .downcast_ref::<String>()
        .map(String::as_str)
        .or_else(|| panic.downcast_ref::<&str>().copied())
        .unwrap_or("unknown failure")
}

/// The running app: window, GPU, panel and session.
struct App {
    /// The session, stepped on the physics thread; each window event holds it
    /// while it runs (see [`physics`]).
    session: SharedSession,
    gfx: Option<Gfx>,
    egui_ctx: egui::Context,
    egui_state: Option<egui_winit::State>,
    camera: OrbitCamera,
    view: ViewOptions,
    panel: PanelState,
    mouse: Mouse,
    fly: FlyKeys,
    modifiers: ModifiersState,
    frame_data: FrameData,
    last_frame: Instant,
    /// Smoothed frame time (s).
    frame_time: f64,
    /// Smoothed wall time (s) the window's thread spends on one frame.
    draw_time: f64,
    /// When the next frame may start (see [`SOFTWARE_FRAME_SHARE`]).
    next_frame: Instant,
    /// Whether frames are spaced out for the physics' sake: from when it falls
    /// short of the speed asked for until it is busy less than [`RELAXED_PHYSICS`].
    spacing_frames: bool,
    /// Since when no particle has been in view, if none is.
    out_of_view_since: Option<Instant>,
    hovered: Option<usize>,
    /// The last points (px) of the cut the mouse is drawing (Ctrl + left drag).
    cut_path: Vec<Vec2>,
    /// The collider the mouse moves (Shift + left drag), if any.
    moving: Option<colliders::Moving>,
    /// A GIF being recorded (the panel's Record button).
    recording: Option<record::Job>,
    fatal: Option<anyhow::Error>,
}

/// An egui context whose text reads at 1x: body and buttons at 14 points,
/// small text at 12 (egui's defaults are 12.5 and 9).
fn readable_context() -> egui::Context {
    use egui::{FontFamily, FontId, TextStyle};
    let ctx = egui::Context::default();
    ctx.all_styles_mut(|style| {
        let sizes = [
            (TextStyle::Small, 12.0, FontFamily::Proportional),
            (TextStyle::Body, 14.0, FontFamily::Proportional),
            (TextStyle::Button, 14.0, FontFamily::Proportional),
            (TextStyle::Heading, 19.0, FontFamily::Proportional),
            (TextStyle::Monospace, 13.0, FontFamily::Monospace),
        ];
        for (text, size, family) in sizes {
            style.text_styles.insert(text, FontId::new(size, family));
        }
    });
    ctx
}

impl App {
    fn new(session: Session) -> std::io::Result<Self> {
        let mut app = Self {
            session: SharedSession::start(session)?,
            gfx: None,
            egui_ctx: readable_context(),
            egui_state: None,
            camera: OrbitCamera::default(),
            view: ViewOptions::default(),
            panel: PanelState::default(),
            mouse: Mouse::default(),
            fly: FlyKeys::default(),
            modifiers: ModifiersState::empty(),
            frame_data: FrameData::default(),
            last_frame: Instant::now(),
            frame_time: 1.0 / 60.0,
            draw_time: 0.0,
            next_frame: Instant::now(),
            spacing_frames: false,
            out_of_view_since: None,
            hovered: None,
            cut_path: Vec::new(),
            moving: None,
            recording: None,
            fatal: None,
        };
        app.scene_loaded();
        app.session.release();
        Ok(app)
    }

    /// After a scene (re)load: frame it and pick sensible display defaults.
    fn scene_loaded(&mut self) {
        self.frame_camera();
        // A cloth shows its surface; a lattice its faces; a chain or rope its
        // springs and particles.
        let has_surface = !self.session.surface().is_empty();
        self.view.mesh = has_surface;
        self.view.particles = !has_surface;
        self.view.springs = !has_surface;
    }

    /// "Reset view": the default orientation, framed on the scene.
    fn frame_camera(&mut self) {
        self.camera = OrbitCamera::default();
        let (lo, hi) = frame::scene_bounds(&self.session);
        self.camera.frame(lo, hi);
    }

    /// Frames the scene again when no particle has been in view for
    /// [`OUT_OF_VIEW_S`] (a soft cloth stretched past the view, one blown away, one
    /// unpinned that fell), unless the user is moving the camera or a particle.
    fn follow_the_scene(&mut self, now: Instant) {
        let in_view = any_in_view(&self.camera, self.viewport(), &self.frame_data.positions);
        if in_view || self.mouse.gesture != input::Gesture::Idle {
            self.out_of_view_since = None;
            return;
        }
        let since = *self.out_of_view_since.get_or_insert(now);
        if now.duration_since(since).as_secs_f64() >= OUT_OF_VIEW_S {
            log::info!("the scene left the view: framing it again");
            self.frame_camera();
            self.panel.wrote = Some("The scene left the view: framed again (F frames it).".into());
            self.out_of_view_since = None;
        }
    }

    /// Origin and size (px) of the scene's part of the window.
    fn scene_rect(&self) -> (Vec2, Vec2) {
        self.gfx
            .as_ref()
            .map_or((Vec2::ZERO, Vec2::ONE), |g| g.renderer.viewport())
    }

    /// Size (px) of the scene's part of the window.
    fn viewport(&self) -> Vec2 {
        self.scene_rect().1
    }

    /// A window position (px) in the scene's coordinates.
    fn to_scene(&self, window: Vec2) -> Vec2 {
        window - self.scene_rect().0
    }

    fn pixels_per_point(&self) -> f32 {
        self.gfx
            .as_ref()
            .map_or(1.0, |g| g.window.scale_factor() as f32)
    }

    /// Whether the cursor is over the panel or an egui popup, or egui is using
    /// the pointer (dragging a slider). Decided from the cursor's position, not
    /// from egui's last frame, so a quick move from the panel followed by a click
    /// on the scene still reaches the scene.
    fn over_ui(&self) -> bool {
        if self.egui_ctx.egui_is_using_pointer() {
            return true;
        }
        let Some(cursor) = self.mouse.cursor else {
            return false;
        };
        let (origin, size) = self.scene_rect();
        let local = cursor - origin;
        if local.x < 0.0 || local.y < 0.0 || local.x >= size.x || local.y >= size.y {
            return true;
        }
        let ppp = self.pixels_per_point();
        let pos = egui::pos2(cursor.x / ppp, cursor.y / ppp);
        self.egui_ctx
            .layer_id_at(pos)
            .is_some_and(|layer| layer.order != egui::Order::Background)
    }

    /// The particle under `cursor`, if any, where the last frame drew it: what the
    /// user points at, and no reason to take the session from the physics thread.
    fn pick(&self, cursor: Vec2) -> Option<usize> {
        pick_particle(
            &self.camera,
            self.viewport(),
            self.to_scene(cursor),
            &self.frame_data.positions,
            PICK_RADIUS * self.pixels_per_point(),
        )
    }

    fn apply_mouse(&mut self, action: MouseAction) {
        if !matches!(action, MouseAction::Orbit(_) | MouseAction::Pan(_)) {
            self.session.hold();
        }
        match action {
            MouseAction::TogglePin(i) => {
                let pinned = self.session.system().is_pinned(i);
                self.session.toggle_pin(i);
                log::info!(
                    "{} particle {i}",
                    if pinned { "unpinned" } else { "pinned" }
                );
            }
            MouseAction::Drag { particle, cursor } => {
                let anchor = match self.session.system().grabbed() {
                    Some((j, target)) if j == particle => target,
                    _ => self
                        .session
                        .system()
                        .positions()
                        .get(particle)
                        .copied()
                        .unwrap_or_default(),
                };
                let anchor = anchor.as_vec3();
                if let Some(target) =
                    self.camera
                        .drag_point(self.to_scene(cursor), self.viewport(), anchor)
                    && target.is_finite()
                {
                    if self.session.system().grabbed().is_none() {
                        log::info!("dragging particle {particle}");
                    }
                    self.session.system_mut().grab(particle, target.as_dvec3());
                }
            }
            MouseAction::Release => {
                if let Some((i, _)) = self.session.system().grabbed() {
                    log::info!("released particle {i}");
                }
                self.session.system_mut().release();
            }
            MouseAction::MoveCollider { index, cursor } => self.move_collider(index, cursor),
            MouseAction::ReleaseCollider(index) => self.release_collider(index),
            MouseAction::Orbit(d) => self.camera.orbit(d),
            MouseAction::Pan(d) => self.camera.pan(d, self.viewport()),
            MouseAction::Cut(from, to) => {
                // The path's last few points: a spring the moving cloth carried
                // across a joint between two moves is still cut.
                const CUT_PATH_POINTS: usize = 8;
                let continues = self.cut_path.last() == Some(&from);
                if !continues {
                    self.cut_path.clear();
                    self.cut_path.push(from);
                }
                self.cut_path.push(to);
                let keep = self.cut_path.len().saturating_sub(CUT_PATH_POINTS);
                self.cut_path.drain(..keep);
                self.frame_data.refresh_positions(self.session.system());
                let system = self.session.system();
                let springs = system
                    .springs()
                    .iter()
                    .map(|s| (s.a as usize, s.b as usize));
                let path: Vec<Vec2> = self.cut_path.iter().map(|&p| self.to_scene(p)).collect();
                let (positions, viewport) = (&self.frame_data.positions, self.viewport());
                let crossed = springs_crossed(&self.camera, viewport, &path, positions, springs);
                if !crossed.is_empty() {
                    let cut = self.session.cut(&crossed, continues);
                    log::info!("cut {cut} springs");
                }
            }
        }
    }

    fn apply(&mut self, action: Action, event_loop: &ActiveEventLoop) {
        self.session.hold();
        match action {
            Action::Quit => {
                log::info!("quit");
                event_loop.exit();
            }
            Action::ResetView => self.frame_camera(),
            Action::LoadScene(name) => match self.session.load_scene(&name) {
                Ok(()) => {
                    log::info!("loaded scene {name}");
                    // Messages about the last scene's files do not carry over.
                    (self.panel.error, self.panel.saved, self.panel.wrote) = (None, None, None);
                    self.mouse.cancel();
                    self.scene_loaded();
                }
                Err(e) => self.panel.error = Some(e.to_string()),
            },
            Action::Reset => {
                log::info!("scene reset");
                self.mouse.cancel();
                if let Err(e) = self.session.reset() {
                    self.panel.error = Some(e.to_string());
                }
            }
            Action::Edit(edit) => match self.session.apply(edit) {
                Ok(()) => {
                    log::debug!("edit {edit:?}");
                    self.panel.error = None;
                    // A new shape or size of cloth is framed anew.
                    if edit.rebuilds() {
                        self.mouse.cancel();
                        self.frame_camera();
                    } else if matches!(edit, Edit::RestLength(_)) {
                        self.frame_camera();
                    }
                }
                Err(e) => {
                    log::warn!("{e}");
                    self.panel.error = Some(e.to_string());
                }
            },
            Action::DtKeepingSpeed(dt) => match self.session.apply_dt_keeping_speed(dt) {
                Ok(()) => self.panel.error = None,
                Err(e) => self.panel.error = Some(e.to_string()),
            },
            Action::Colliders(list) => match self.session.set_colliders(list) {
                Ok(()) => self.panel.error = None,
                Err(e) => self.panel.error = Some(e.to_string()),
            },
            Action::Pins(pins) => match self.session.set_pins(pins) {
                Ok(()) => self.panel.error = None,
                Err(e) => self.panel.error = Some(e.to_string()),
            },
            Action::WindOn(on) => match self.session.set_wind_on(on) {
                Ok(()) => self.panel.error = None,
                Err(e) => self.panel.error = Some(e.to_string()),
            },
            Action::Save => self.save(),
            Action::ExportObj => self.export_obj(),
            Action::Screenshot => self.screenshot(),
            Action::Record(seconds) => self.record(seconds),
            Action::UndoDivergence => match self.session.undo_divergence() {
                Ok(done) => {
                    log::info!(
                        "undo that edit: {}",
                        if done { "done" } else { "nothing to undo" }
                    );
                    self.panel.error = None;
                }
                Err(e) => self.panel.error = Some(e.to_string()),
            },
            Action::Undo | Action::Redo | Action::Defaults => {
                let particles = self.session.system().particle_count();
                let done = match action {
                    Action::Undo => self.session.undo(),
                    Action::Redo => self.session.redo(),
                    _ => self.session.restore_defaults().map(|()| true),
                };
                match done {
                    Ok(true) => {
                        log::info!("{action:?} done");
                        self.panel.error = None;
                        if self.session.system().particle_count() != particles {
                            self.mouse.cancel();
                            self.frame_camera();
                        }
                    }
                    Ok(false) => log::info!("{action:?}: nothing to do"),
                    Err(e) => self.panel.error = Some(e.to_string()),
                }
            }
            Action::TogglePanel => {
                self.panel.hidden = !self.panel.hidden;
                log::info!(
                    "panel {}",
                    if self.panel.hidden { "hidden" } else { "shown" }
                );
            }
            Action::ToggleReadout => self.panel.readout_hidden = !self.panel.readout_hidden,
            Action::ToggleHelp => {
                self.panel.help = !self.panel.help;
                log::info!("help {}", if self.panel.help { "shown" } else { "hidden" });
            }
            Action::TogglePause => {
                let paused = self.session.paused();
                self.session.set_paused(!paused);
            }
            Action::SafeStepping(on) => self.session.set_safe_stepping(on),
            Action::SlowMotion(factor) => self.session.set_slow_motion(factor),
            Action::Reference(on) => match self.session.set_reference(on) {
                Ok(()) => log::info!("reference {}", if on { "on" } else { "off" }),
                Err(e) => self.panel.error = Some(format!("Could not start the reference: {e}")),
            },
            Action::Gpu(on) => match self.session.set_gpu(on) {
                Ok(()) => log::info!("engine {}", if on { "gpu" } else { "cpu" }),
                Err(e) => self.panel.error = Some(format!("No GPU engine: {e}")),
            },
            Action::RestartReference => {
                if let Err(e) = self.session.restart_reference() {
                    self.panel.error = Some(format!("Could not start the reference: {e}"));
                }
            }
            Action::Step => {
                self.session.step_frame();
            }
        }
    }

    /// Saves the setup as a scene file in the working directory and says where in
    /// the panel.
    fn save(&mut self) {
        let dir = std::env::current_dir().unwrap_or_else(|_| ".".into());
        match self.session.save_in(&dir) {
            Ok(path) => {
                log::info!("saved the setup to {}", path.display());
                self.panel.error = None;
                self.panel.saved = Some(path.display().to_string());
            }
            Err(e) => {
                let text = format!("cannot save the setup in {}: {e}", dir.display());
                log::warn!("{text}");
                self.panel.error = Some(text);
            }
        }
    }

    /// Writes the cloth's surface as `cloth-<scene>-N.obj` in the working
    /// directory and says where in the panel.
    fn export_obj(&mut self) {
        let dir = std::env::current_dir().unwrap_or_else(|_| ".".into());
        let scene = self.session.name();
        match cloth_sandbox::export::export_obj_in(self.session.system(), scene, &dir) {
            Ok(path) => {
                log::info!("exported the cloth to {}", path.display());
                self.panel.error = None;
                self.panel.wrote = Some(format!("Exported the cloth to {}", path.display()));
            }
            Err(e) => {
                let text = format!("cannot export OBJ in {}: {e}", dir.display());
                log::warn!("{text}");
                self.panel.error = Some(text);
            }
        }
    }

    /// Renders the view (the scene without the panel, at its size in pixels) to
    /// `screenshot-N.png` in the working directory and says where in the panel.
    fn screenshot(&mut self) {
        let dir = std::env::current_dir().unwrap_or_else(|_| ".".into());
        match self.write_screenshot(&dir) {
            Ok(path) => {
                log::info!("saved a screenshot to {}", path.display());
                self.panel.error = None;
                self.panel.wrote = Some(format!("Screenshot saved to {}", path.display()));
            }
            Err(e) => {
                let text = format!("cannot save a screenshot in {}: {e:#}", dir.display());
                log::warn!("{text}");
                self.panel.error = Some(text);
            }
        }
    }

    /// Starts recording `seconds` of the scene from now, as the view shows it, to
    /// `cloth-<scene>-N.gif` in the working directory, on a thread of its own.
    fn record(&mut self, seconds: f64) {
        if self.recording.is_some() {
            return;
        }
        let Some(gfx) = self.gfx.as_ref() else {
            return;
        };
        let dir = std::env::current_dir().unwrap_or_else(|_| ".".into());
        let (_, size) = gfx.renderer.viewport();
        let size = record::fit(
            (size.x.round() as u32, size.y.round() as u32),
            record::APP_MAX_SIDE,
        );
        let gpu = record::Gpu {
            device: gfx.device.clone(),
            queue: gfx.queue.clone(),
            adapter_name: gfx.adapter_name.clone(),
            samples: gfx.renderer.sample_count(),
        };
        let view = record::View {
            camera: self.camera,
            options: self.view,
            by_strain: self.panel.strain_colors,
            surface: self.session.surface().to_vec(),
        };
        let system = self.session.system().clone();
        let scene = self.session.name();
        let scene_dt = self.session.safe_scene_step();
        match record::Job::start(system, scene_dt, view, seconds, 25, gpu, size, &dir, scene) {
            Ok(job) => {
                log::info!("recording {seconds} s to {}", job.path.display());
                self.panel.error = None;
                self.panel.recording = Some((0, job.frames));
                self.recording = Some(job);
            }
            Err(e) => {
                let text = format!("cannot record in {}: {e:#}", dir.display());
                log::warn!("{text}");
                self.panel.error = Some(text);
            }
        }
    }

    /// Follows a recording: its progress in the panel, and where it went.
    fn poll_recording(&mut self) {
        let Some(job) = &self.recording else {
            return;
        };
        self.panel.recording = Some((job.frames_done(), job.frames));
        let Some(result) = job.finished() else {
            return;
        };
        match result {
            Ok(()) => {
                log::info!("recorded to {}", job.path.display());
                self.panel.wrote = Some(format!("Recorded to {}", job.path.display()));
            }
            Err(e) => {
                let text = format!("the recording failed: {e:#}");
                log::warn!("{text}");
                self.panel.error = Some(text);
            }
        }
        self.panel.recording = None;
        self.recording = None;
    }

    fn write_screenshot(&mut self, dir: &std::path::Path) -> anyhow::Result<std::path::PathBuf> {
        let Some(gfx) = self.gfx.as_ref() else {
            anyhow::bail!("the window is not drawn yet");
        };
        let (_, size) = gfx.renderer.viewport();
        let (width, height) = (
            size.x.round().max(1.0) as u32,
            size.y.round().max(1.0) as u32,
        );
        let mut offscreen = crate::render::offscreen::Offscreen::with_device(
            gfx.device.clone(),
            gfx.queue.clone(),
            gfx.adapter_name.clone(),
            gfx.renderer.sample_count(),
            width,
            height,
        )?;
        self.frame_data.build(
            self.session.system(),
            self.session.surface(),
            &self.view,
            self.panel.strain_colors,
        );
        (self.frame_data).set_ghost(self.session.reference().map(|r| r.ghost()));
        let frame = self.frame_data.scene_frame(None);
        let pixels = offscreen.render(&frame, &self.camera, &self.view)?;
        // The name is taken first (never replacing a file), then the picture is
        // written beside it and renamed over it whole.
        let (path, reserved) = cloth_sandbox::export::create_numbered(dir, "screenshot", "png")?;
        drop(reserved);
        let written = cloth_sandbox::limits::PendingFile::create(&path)
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
            .and_then(|file| crate::render::offscreen::write_png(file, width, height, &pixels));
        if let Err(e) = written {
            let _ = std::fs::remove_file(&path);
            return Err(e);
        }
        Ok(path)
    }

    /// One frame: the panel, its actions, and the scene copied from the session;
    /// then the session goes back to the physics thread while the frame is drawn.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        self.session.hold();
        self.steer_collider();
        let now = Instant::now();
        let elapsed = now.duration_since(self.last_frame).as_secs_f64().min(0.25);
        self.last_frame = now;
        self.frame_time = self.frame_time * 0.9 + elapsed * 0.1;

        if self.fly.any() {
            self.camera.fly(self.fly, elapsed as f32);
        }
        self.panel.record(self.frame_time, self.session.pace());
        self.panel.history.record(self.session.system());
        if let Some(failure) = self.session.failure() {
            self.panel.error = Some(failure);
        }
        self.poll_recording();

        let (Some(gfx), Some(egui_state)) = (self.gfx.as_mut(), self.egui_state.as_mut()) else {
            return;
        };
        let raw = egui_state.take_egui_input(&gfx.window);
        let mut actions = Vec::new();
        let mut free = egui::Rect::NOTHING;
        let adapter = gfx.adapter_name.clone();
        let ui_output = self.egui_ctx.run_ui(raw, |ui| {
            (actions, free) =
                panel::show(ui, &mut self.panel, &self.session, &mut self.view, &adapter);
        });
        let ppp = ui_output.pixels_per_point;
        if free.is_positive() {
            gfx.renderer.set_viewport(
                Vec2::new(free.min.x, free.min.y) * ppp,
                Vec2::new(free.width(), free.height()) * ppp,
            );
        }
        egui_state.handle_platform_output(&gfx.window, ui_output.platform_output.clone());

        for action in actions {
            self.apply(action, event_loop);
        }
        // A slider let go: its next edit is a new undo step.
        if !self.egui_ctx.egui_is_using_pointer() {
            self.session.end_edit_group();
        }
        self.frame_data.build(
            self.session.system(),
            self.session.surface(),
            &self.view,
            self.panel.strain_colors,
        );
        (self.frame_data).set_ghost(self.session.reference().map(|r| r.ghost()));
        self.follow_the_scene(now);
        let pace = self.session.pace();
        if pace.behind && pace.real_time_factor < 0.97 * pace.target {
            self.spacing_frames = true;
        } else if pace.busy < RELAXED_PHYSICS {
            self.spacing_frames = false;
        }
        self.session.release();

        let Some(gfx) = self.gfx.as_mut() else {
            return;
        };
        let highlight = self.mouse.dragged().or(self.hovered);
        let frame = self.frame_data.scene_frame(highlight);
        gfx.draw(&frame, &self.camera, &self.view, &self.egui_ctx, ui_output);

        let took = now.elapsed().as_secs_f64();
        self.draw_time = 0.8 * self.draw_time + 0.2 * took;
        let wait = if gfx.software && self.spacing_frames {
            (self.draw_time / SOFTWARE_FRAME_SHARE - took).clamp(0.0, 0.25)
        } else {
            0.0
        };
        self.next_frame = Instant::now() + std::time::Duration::from_secs_f64(wait);
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        self.session.hold();
        self.open_window(event_loop);
        self.session.release();
    }

    /// Takes the session from the physics thread only for what reads or edits it
    /// (a frame, an action, a grab or a pin): the cursor moving over the panel or
    /// the camera does not, and taking it for each move (50 a second in a slider
    /// drag) cost the simulation half its pace on a 256 x 256 cloth.
    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        self.handle(event_loop, event);
        self.session.release();
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(gfx) = &self.gfx else {
            return;
        };
        if Instant::now() >= self.next_frame {
            event_loop.set_control_flow(ControlFlow::Poll);
            gfx.window.request_redraw();
        } else {
            event_loop.set_control_flow(ControlFlow::WaitUntil(self.next_frame));
        }
    }
}

impl App {
    /// Opens the window and its GPU surface on the first `resumed`.
    fn open_window(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        let attributes = Window::default_attributes()
            .with_title(format!("{TITLE} — {}", self.session.name()))
            .with_inner_size(LogicalSize::new(1200.0, 760.0))
            .with_min_inner_size(LogicalSize::new(320.0, 240.0));
        let window = match event_loop.create_window(attributes) {
            Ok(w) => Arc::new(w),
            Err(e) => {
                self.fatal = Some(anyhow::anyhow!("cannot open a window: {e}"));
                event_loop.exit();
                return;
            }
        };
        match Gfx::new(event_loop, window.clone()) {
            Ok(gfx) => {
                log::info!("drawing with {}", gfx.adapter_name);
                let max_side = gfx.device.limits().max_texture_dimension_2d as usize;
                self.egui_state = Some(egui_winit::State::new(
                    self.egui_ctx.clone(),
                    egui::ViewportId::ROOT,
                    &window,
                    Some(window.scale_factor() as f32),
                    None,
                    Some(max_side),
                ));
                self.gfx = Some(gfx);
                self.last_frame = Instant::now();
                // R, Space and Esc work at once, without a click first.
                window.focus_window();
                window.request_redraw();
            }
            Err(e) => {
                self.fatal = Some(e);
                event_loop.exit();
            }
        }
    }

    /// One window event; what reads or edits the session takes it first
    /// ([`Self::redraw`], [`Self::apply`], [`Self::apply_mouse`]).
    fn handle(&mut self, event_loop: &ActiveEventLoop, event: WindowEvent) {
        // Tab is the panel's key unless a text field is being typed in: egui
        // would take it to move its focus to a widget, which then holds the keys.
        let panel_key = matches!(&event, WindowEvent::KeyboardInput { event, .. }
            if event.physical_key == PhysicalKey::Code(KeyCode::Tab))
            && !self.egui_ctx.egui_wants_keyboard_input();
        let consumed = match (&mut self.egui_state, &self.gfx) {
            (Some(state), Some(gfx)) if !panel_key => {
                state.on_window_event(&gfx.window, &event).consumed
            }
            _ => false,
        };
        let over_ui = self.over_ui();
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gfx) = self.gfx.as_mut() {
                    gfx.resize(size.width, size.height);
                }
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            // A scene file dropped on the window (e.g. one saved with Ctrl+S) opens.
            WindowEvent::DroppedFile(path) => {
                self.apply(
                    Action::LoadScene(path.to_string_lossy().into_owned()),
                    event_loop,
                );
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::Focused(false) => {
                self.fly = FlyKeys::default();
                if let Some(a) = self.mouse.cancel() {
                    self.apply_mouse(a);
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let released = event.state == ElementState::Released;
                if released || !(consumed || self.egui_ctx.egui_wants_keyboard_input()) {
                    self.key(&event, event_loop);
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = Vec2::new(position.x as f32, position.y as f32);
                if let Some(a) = self.mouse.moved(p) {
                    self.apply_mouse(a);
                }
                self.hovered = if self.mouse.gesture == input::Gesture::Idle && !self.over_ui() {
                    self.pick(p)
                } else {
                    None
                };
            }
            WindowEvent::CursorLeft { .. } => {
                self.hovered = None;
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let button = match button {
                    MouseButton::Left => Button::Left,
                    MouseButton::Right => Button::Right,
                    MouseButton::Middle => Button::Middle,
                    _ => return,
                };
                match state {
                    ElementState::Pressed if !over_ui => {
                        let m = self.modifiers;
                        if let (Button::Left, true, Some(c)) =
                            (button, m.shift_key(), self.mouse.cursor)
                            && self.grab_collider(c)
                        {
                            return;
                        }
                        let picked = match (button, self.mouse.cursor) {
                            (Button::Left, Some(c)) => self.pick(c),
                            _ => None,
                        };
                        if let Some(a) =
                            self.mouse
                                .press(button, (m.shift_key(), m.control_key()), picked)
                        {
                            self.apply_mouse(a);
                        }
                    }
                    ElementState::Pressed => {}
                    ElementState::Released => {
                        if let Some(a) = self.mouse.release(button) {
                            self.apply_mouse(a);
                        }
                    }
                }
            }
            WindowEvent::MouseWheel { delta, .. } if !over_ui => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.camera.zoom(steps);
            }
            _ => {}
        }
    }
}
