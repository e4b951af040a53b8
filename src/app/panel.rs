//! The egui side panel: scene and integrator, parameter sliders (only those the
//! scene uses), play/pause/step/reset and speed, display toggles, live stats and
//! the divergence notice. It edits view options directly and returns every
//! change to the simulation as an `Action` for the app to apply; parameter changes
//! are typed [`Edit`]s.

use std::time::Instant;

use cloth_sandbox::scene::{Layout, PinPreset, Pins, Scene, builtin_scenes};
use cloth_sandbox::session::{Edit, Pace, Session};
use cloth_sandbox::sim::Integrator;
use egui::{Color32, RichText, Ui};

use crate::render::ViewOptions;

/// Something the user asked for in the panel (or by key).
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Quit the app (Esc).
    Quit,
    /// Frame the scene with the default camera.
    ResetView,
    /// Open another scene.
    LoadScene(String),
    /// Rebuild the scene with the current settings (R).
    Reset,
    /// Change a setting (a slider or dropdown).
    Edit(Edit),
    /// Change dt, keeping the speed (the dt slider).
    DtKeepingSpeed(f64),
    /// Pause or resume (Space).
    TogglePause,
    /// Run one step.
    Step,
    /// Turn safe stepping on or off.
    SafeStepping(bool),
    /// Pin exactly these particles (a preset, or none to unpin all).
    Pins(Pins),
    /// Turn the wind (and gusts) on or off.
    WindOn(bool),
    /// Save the setup as a scene file (Ctrl+S).
    Save,
    /// Write the cloth's surface as `cloth-<scene>-N.obj`.
    ExportObj,
    /// Save the view as `screenshot-N.png` (F12).
    Screenshot,
    /// Record this many seconds of the view as `cloth-<scene>-N.gif`.
    Record(f64),
    /// Show or hide the help overlay (F1, ?).
    ToggleHelp,
    /// Take back the last change of parameters or pins (Ctrl+Z).
    Undo,
    /// Do again the last change undone (Ctrl+Shift+Z).
    Redo,
    /// Restore the scene's own parameters and pins.
    Defaults,
}

/// Panel state that lives between frames.
#[derive(Default)]
pub struct PanelState {
    /// Colour springs by strain instead of kind.
    pub strain_colors: bool,
    /// Last error from a scene change, shown until the next success.
    pub error: Option<String>,
    /// Where the setup was last saved.
    pub saved: Option<String>,
    /// The last OBJ export, screenshot or recording: what was written where.
    pub wrote: Option<String>,
    /// Seconds the Record button records (4 until changed).
    pub record_seconds: f64,
    /// A recording under way: frames done and frames in all.
    pub recording: Option<(u64, u64)>,
    /// Whether the help overlay is open.
    pub help: bool,
    /// The readings the plots show.
    pub history: super::plots::History,
    frame_time: f64,
    frames_in_window: u64,
    window_start: Option<Instant>,
}

impl PanelState {
    /// Folds one frame's time (s, smoothed) into the stats.
    pub fn record(&mut self, frame_time: f64, pace: Pace) {
        self.frame_time = frame_time;
        self.frames_in_window += 1;
        let now = Instant::now();
        let start = *self.window_start.get_or_insert(now);
        let span = now.duration_since(start).as_secs_f64();
        if span >= 0.5 {
            // For measuring the app from outside (benches/xvfb_slider_drag.sh).
            log::debug!(
                target: "cloth::frames",
                "frame {:.2} ms, {:.1} frames/s, real-time factor {:.3} of {:.3} asked, physics busy {:.1}%, {:.0} steps/s",
                1e3 * self.frame_time,
                self.frames_in_window as f64 / span,
                pace.real_time_factor,
                pace.target,
                1e2 * pace.busy,
                pace.steps_per_second
            );
            self.frames_in_window = 0;
            self.window_start = Some(now);
        }
    }
}

/// A slider over `range` that reports a change the user made. A value the slider
/// did not touch is left as it is, even one outside `range` or with more decimals
/// than it shows (egui's default clamps and rounds every frame, which would edit
/// a scene's damping ratio or a 1024-wide grid the moment it opens).
fn slider(
    ui: &mut Ui,
    value: &mut f64,
    range: std::ops::RangeInclusive<f64>,
    label: &str,
    log: bool,
    tip: &str,
) -> bool {
    let (lo, hi) = (*range.start(), *range.end());
    let scale = if log { ", logarithmic" } else { "" };
    ui.add(
        egui::Slider::new(value, range)
            .logarithmic(log)
            .clamping(egui::SliderClamping::Edits)
            .text(label)
            .max_decimals(6),
    )
    .on_hover_text(format!(
        "{tip}\nSlider: {lo} to {hi}{scale}; type a value in the box for more"
    ))
    .changed()
}

/// Integer slider; like [`slider`], it leaves a value it did not touch alone.
fn int_slider(
    ui: &mut Ui,
    value: &mut u32,
    range: std::ops::RangeInclusive<u32>,
    label: &str,
    tip: &str,
) -> bool {
    let (lo, hi) = (*range.start(), *range.end());
    ui.add(
        egui::Slider::new(value, range)
            .logarithmic(true)
            .clamping(egui::SliderClamping::Edits)
            .text(label),
    )
    .on_hover_text(format!("{tip}\nSlider: {lo} to {hi}"))
    .changed()
}

/// The pin presets the layout has (a grid's corners and edges, a line's ends) and
/// "unpin all".
fn pin_presets(ui: &mut Ui, layout: Layout, pinned: usize, actions: &mut Vec<Action>) {
    let presets: &[(&str, PinPreset, &str)] = match layout {
        Layout::Grid => &[
            (
                "corners",
                PinPreset::Corners,
                "Pin the four corners (seed 000)",
            ),
            (
                "top corners",
                PinPreset::TopCorners,
                "Pin the two top corners",
            ),
            ("top edge", PinPreset::TopEdge, "Pin the whole top row"),
            (
                "left edge",
                PinPreset::LeftEdge,
                "Pin the whole left column (a flag on its pole)",
            ),
            (
                "left every 4th",
                PinPreset::LeftEdgeEveryFourth,
                "Pin every fourth particle of the left column (seed 001's cloth)",
            ),
        ],
        Layout::Lattice => &[(
            "ends",
            PinPreset::Corners,
            "Pin the first and the last particle",
        )],
        _ => &[
            ("first", PinPreset::First, "Pin the first particle only"),
            (
                "both ends",
                PinPreset::Corners,
                "Pin the first and the last particle",
            ),
        ],
    };
    ui.horizontal_wrapped(|ui| {
        ui.label(format!("Pins ({pinned}):"))
            .on_hover_text("Pinned particles stay where they are. Click a particle in the view to pin or unpin it.");
        for &(label, preset, tip) in presets {
            if ui.button(label).on_hover_text(tip).clicked() {
                actions.push(Action::Pins(Pins::Preset(preset)));
            }
        }
        if ui
            .button("unpin all")
            .on_hover_text("Free every particle: the cloth falls")
            .clicked()
        {
            actions.push(Action::Pins(Pins::Preset(PinPreset::None)));
        }
    });
}

/// Draws the panel; returns what the user asked for and the rectangle (points)
/// left for the scene.
pub fn show(
    ui: &mut Ui,
    state: &mut PanelState,
    session: &Session,
    view: &mut ViewOptions,
    adapter: &str,
) -> (Vec<Action>, egui::Rect) {
    let mut actions = Vec::new();
    super::help::show(ui.ctx(), &mut state.help);
    egui::Panel::left("controls")
        .resizable(false)
        .exact_size(PANEL_WIDTH)
        .show(ui, |ui| {
            header(ui, &mut actions);
            status(ui, state, session, &mut actions);
            ui.separator();
            egui::ScrollArea::vertical().show(ui, |ui| {
                contents(ui, state, session, view, adapter, &mut actions);
            });
        });
    (actions, ui.available_rect_before_wrap())
}

/// The strain colours' key: compressed blue, at rest grey, stretched red to
/// pale yellow, saturating at 10%.
fn strain_legend(ui: &mut Ui) {
    let (rect, _) = ui.allocate_exact_size(
        egui::vec2(ui.available_width().min(240.0), 10.0),
        egui::Sense::hover(),
    );
    let painter = ui.painter_at(rect);
    let steps = 48;
    for i in 0..steps {
        let strain = -0.12 + 0.24 * (i as f32 + 0.5) / steps as f32;
        let [r, g, b, _] = crate::render::geometry::strain_color(strain);
        let linear = egui::Rgba::from_rgb(r, g, b);
        let x0 = rect.left() + rect.width() * i as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / steps as f32;
        let cell = egui::Rect::from_x_y_ranges(x0..=x1, rect.y_range());
        painter.rect_filled(cell, 0.0, Color32::from(linear));
    }
    ui.horizontal(|ui| {
        ui.label(RichText::new("-10% compressed").small());
        ui.label(RichText::new("· 0 ·").small());
        ui.label(RichText::new("+10% stretched").small());
    });
}

/// Width of the panel (points): the same in every scene.
const PANEL_WIDTH: f32 = 320.0;

/// Height of the status box (points): messages come and go inside it, and the
/// controls below never move.
const STATUS_HEIGHT: f32 = 104.0;

fn header(ui: &mut Ui, actions: &mut Vec<Action>) {
    ui.horizontal(|ui| {
        ui.heading("cloth-sandbox");
        if ui
            .button("Help")
            .on_hover_text("Every key and mouse binding (F1 or ?)")
            .clicked()
        {
            actions.push(Action::ToggleHelp);
        }
    });
    ui.label(
        RichText::new(
            "Click a particle: pin · drag it: move · drag elsewhere: orbit · F1 or ?: all keys",
        )
        .small(),
    );
    ui.separator();
}

/// The status box: how the run keeps up, a divergence, the last error, what was
/// written where. Fixed height, scrolling when a message is long.
fn status(ui: &mut Ui, state: &PanelState, session: &Session, actions: &mut Vec<Action>) {
    egui::ScrollArea::vertical()
        .id_salt("status")
        .max_height(STATUS_HEIGHT)
        .show(ui, |ui| {
            ui.set_min_height(STATUS_HEIGHT);
            ui.set_width(ui.available_width());
            status_lines(ui, state, session, actions);
        });
}

fn status_lines(ui: &mut Ui, state: &PanelState, session: &Session, actions: &mut Vec<Action>) {
    if let Some(d) = session.divergence() {
        ui.horizontal(|ui| {
            ui.colored_label(Color32::from_rgb(255, 110, 90), "Diverged and paused.");
            if ui
                .button("Reset scene")
                .on_hover_text("Start the scene again from its setup (R)")
                .clicked()
            {
                actions.push(Action::Reset);
            }
        });
        ui.label(format!(
            "Showing the last good frame, t = {:.3} s.",
            d.shown_time
        ));
        ui.label("Lower dt or the stiffness, or try another integrator, then reset.");
        match d.margin {
            Some(m) => ui.label(format!("At t = {:.3} s, dt / dt_crit = {m:.2}:", d.time)),
            None => ui.label(format!("At t = {:.3} s:", d.time)),
        };
        ui.label(RichText::new(&d.message).small());
    } else if session.paused() {
        ui.label("Paused (Space or Play resumes).");
    } else {
        let pace = session.pace();
        let factor = format!(
            "{:.2} s simulated per s (asked {:.2})",
            pace.real_time_factor, pace.target
        );
        // A backlog dropped once (a long pause of the window's thread) is not
        // "slower": only a factor short of the one asked for is.
        if pace.behind && pace.real_time_factor < 0.97 * pace.target {
            ui.colored_label(
                Color32::from_rgb(255, 200, 60),
                format!("Slower than asked: {factor}"),
            )
            .on_hover_text("The physics cannot run every step due: it is busy all the time on its own thread. Fewer particles, a larger dt or fewer steps per frame make it keep up.");
        } else {
            ui.label(format!("Keeping up: {factor}"))
                .on_hover_text("The physics runs on its own thread, at the speed asked for whatever the frame rate.");
        }
    }
    if let Some(e) = &state.error {
        ui.colored_label(Color32::from_rgb(255, 170, 60), e);
    }
    if let Some(path) = &state.saved {
        ui.label(RichText::new(format!("Saved to {path}")).small());
    }
    if let Some(text) = &state.wrote {
        ui.label(RichText::new(text).small());
    }
}

fn contents(
    ui: &mut Ui,
    state: &mut PanelState,
    session: &Session,
    view: &mut ViewOptions,
    adapter: &str,
    actions: &mut Vec<Action>,
) {
    // Scene and integrator.
    let mut scene = session.name().to_string();
    egui::ComboBox::from_label("Scene")
        .selected_text(scene.as_str())
        .show_ui(ui, |ui| {
            for b in builtin_scenes() {
                let description = Scene::parse(b.toml, b.name)
                    .ok()
                    .and_then(|s| s.spec.description)
                    .unwrap_or_default();
                ui.selectable_value(&mut scene, b.name.to_string(), b.name)
                    .on_hover_text(description);
            }
        })
        .response
        .on_hover_text(format!(
            "{}\nOpening another scene drops your edits (save them first with Ctrl+S); a scene file dropped on the window opens too",
            session.scene().spec.description.as_deref().unwrap_or("The running scene")
        ));
    if scene != session.name() {
        actions.push(Action::LoadScene(scene));
    }
    let r = session.settings();
    let p = r.params;
    let mut integrator = p.integrator;
    egui::ComboBox::from_label("Integrator")
        .selected_text(integrator.name())
        .show_ui(ui, |ui| {
            for i in Integrator::ALL {
                ui.selectable_value(&mut integrator, i, i.name());
            }
        })
        .response
        .on_hover_text("How each step advances the particles: explicit Euler, symplectic Euler, position Verlet, RK2, RK4 (explicit, stable below a critical dt), implicit Euler (stable at any dt, damps), XPBD (constraints, any stiffness)");
    if integrator != p.integrator {
        actions.push(Action::Edit(Edit::Integrator(integrator)));
    }

    // Run controls.
    ui.horizontal(|ui| {
        let label = if session.paused() { "Play" } else { "Pause" };
        if ui.button(label).on_hover_text("Pause or resume (Space)").clicked() {
            actions.push(Action::TogglePause);
        }
        if ui
            .add_enabled(session.paused(), egui::Button::new("Step"))
            .on_hover_text(format!(
                "Run one frame: {} steps of dt, {:.4} s (. key)",
                session.substeps(),
                f64::from(session.substeps()) * session.system().params().dt
            ))
            .on_disabled_hover_text("Pause first: Step runs one frame (the steps of 1/60 s)")
            .clicked()
        {
            actions.push(Action::Step);
        }
        if ui
            .button("Reset")
            .on_hover_text("Start the scene again from its setup, keeping your edits and pins (R)")
            .clicked()
        {
            actions.push(Action::Reset);
        }
        if ui
            .button("Save")
            .on_hover_text("Save the scene, every parameter and the pins as saved-<scene>-N.toml in the working directory (Ctrl+S); open it with `cloth --scene FILE`, `cloth run --scene FILE`, or by dropping it on the window")
            .clicked()
        {
            actions.push(Action::Save);
        }
    });
    ui.horizontal(|ui| {
        if ui
            .add_enabled(session.can_undo(), egui::Button::new("Undo"))
            .on_hover_text("Take back the last change of a parameter or the pins (Ctrl+Z)")
            .clicked()
        {
            actions.push(Action::Undo);
        }
        if ui
            .add_enabled(session.can_redo(), egui::Button::new("Redo"))
            .on_hover_text("Do again the last change undone (Ctrl+Shift+Z)")
            .clicked()
        {
            actions.push(Action::Redo);
        }
        if ui
            .button("Defaults")
            .on_hover_text("Restore the scene's own parameters and pins, as it was opened (with any --set), in place; R then starts it again from there. Can be undone")
            .clicked()
        {
            actions.push(Action::Defaults);
        }
    });
    ui.horizontal(|ui| {
        let surface = !session.system().triangles().is_empty();
        if ui
            .add_enabled(surface, egui::Button::new("Export OBJ"))
            .on_hover_text("Write the cloth as it is now (positions, texture coordinates, normals) as cloth-<scene>-N.obj in the working directory, for Blender or any 3D tool")
            .on_disabled_hover_text("This scene has no surface (no triangles) to export")
            .clicked()
        {
            actions.push(Action::ExportObj);
        }
        if ui
            .button("Screenshot")
            .on_hover_text("Save the view as screenshot-N.png in the working directory (F12)")
            .clicked()
        {
            actions.push(Action::Screenshot);
        }
    });
    ui.horizontal(|ui| match state.recording {
        Some((done, all)) => {
            ui.add(
                egui::ProgressBar::new(done as f32 / all.max(1) as f32)
                    .text(format!("recording frame {done} of {all}")),
            );
        }
        None => {
            if state.record_seconds <= 0.0 {
                state.record_seconds = 4.0;
            }
            if ui
                .button("Record GIF")
                .on_hover_text("Record the next seconds of the simulation from now, as the view shows it, at 25 frames per second, as cloth-<scene>-N.gif in the working directory (at most 640 pixels a side). A copy of the scene is stepped on its own thread, so the window keeps running; `cloth record` does the same from the command line")
                .clicked()
            {
                actions.push(Action::Record(state.record_seconds));
            }
            ui.add(
                egui::DragValue::new(&mut state.record_seconds)
                    .range(0.5..=60.0)
                    .speed(0.1)
                    .suffix(" s"),
            )
            .on_hover_text("Simulated seconds the recording lasts, 0.5 to 60");
        }
    });
    // The scene's own steps per frame (its speed); safe stepping may run more,
    // smaller steps over the same simulated time.
    let mut substeps = r.substeps;
    if ui
        .add(
            egui::Slider::new(&mut substeps, 1..=2000)
                .logarithmic(true)
                .clamping(egui::SliderClamping::Edits)
                .text("steps of dt per frame"),
        )
        .on_hover_text("The scene's steps of dt per 1/60 s of wall time: the simulation's speed (steps x dt x 60 simulated seconds per second). Safe stepping may split them into more, smaller steps over the same simulated time. Slider: 1 to 2000, logarithmic")
        .changed()
    {
        actions.push(Action::Edit(Edit::Substeps(substeps)));
    }
    ui.label(format!(
        "speed {:.2}x real time ({} x {:.3e} s per 1/60 s)",
        session.speed(),
        r.substeps,
        p.dt
    ))
    .on_hover_text("Simulated seconds per wall-clock second asked for. The status above says what the physics thread reaches.");
    let mut safe = session.safe_stepping();
    if ui
        .checkbox(&mut safe, "safe stepping")
        .on_hover_text(
            "Keep dt below half the integrator's critical step (dt_crit), with more substeps per frame so that the simulated time per frame stays the same",
        )
        .changed()
    {
        actions.push(Action::SafeStepping(safe));
    }
    match session.step_choice() {
        Some(c) if c.safe => {
            let limit = (c.stretch_limit)
                .map(|t| format!(", stretch <= {:.0}%", t * 100.0))
                .unwrap_or_default();
            let text = if c.substeps == r.substeps && c.dt == p.dt {
                format!("safe: dt is below half of dt_crit{limit}")
            } else {
                format!(
                    "safe: runs them as {} steps of {:.3e} s{limit}",
                    c.substeps, c.dt
                )
            };
            ui.label(text);
        }
        Some(_) => {
            ui.colored_label(
                Color32::from_rgb(255, 170, 60),
                format!(
                    "{} has no stable step here without more damping",
                    p.integrator
                ),
            );
        }
        None => {
            ui.label("unchecked: dt and steps as set");
        }
    }

    // Pins.
    ui.separator();
    pin_presets(ui, r.layout, session.pins().len(), actions);

    // Parameters the scene uses.
    let system = session.system();
    let has_springs = !system.springs().is_empty();
    let has_surface = !system.triangles().is_empty();
    let mut wind_switch = None;
    // The panel's dt keeps the speed (see `Session::apply_dt_keeping_speed`).
    let mut edit = |e: Edit| {
        actions.push(match e {
            Edit::Dt(dt) => Action::DtKeepingSpeed(dt),
            e => Action::Edit(e),
        })
    };
    ui.separator();
    egui::CollapsingHeader::new("Parameters")
        .default_open(true)
        .show(ui, |ui| {
            if has_springs {
                let mut k = r.stiffness;
                // XPBD is stable at any stiffness: its slider reaches the scene
                // files' limit.
                let k_max = if system.params().integrator == Integrator::Xpbd {
                    1e9
                } else {
                    100_000.0
                };
                if slider(ui, &mut k, 0.01..=k_max, "stiffness k (N/m)", true, "Spring stiffness k in N/m: force per metre of stretch (shear and bend springs keep their multiples of it)") {
                    edit(Edit::Stiffness(k));
                }
                let mut b = r.damping;
                if slider(ui, &mut b, 0.0..=100.0, "damping b (N·s/m)", true, "Spring damping b in N·s/m: force per m/s of stretching speed along the spring") {
                    edit(Edit::Damping(b));
                }
            }
            let mut rest = r.rest_length;
            if slider(ui, &mut rest, 0.001..=5.0, "rest length (m)", true, "Spacing between neighbouring particles in m; the cloth grows or shrinks about its pins") {
                edit(Edit::RestLength(rest));
            }
            match r.layout {
                Layout::Grid | Layout::Lattice => {
                    // Grids up to 512 x 512 run in real time on the grid kernel; a
                    // lattice has 13 springs per particle and no fast path.
                    let side = if r.layout == Layout::Grid {
                        1..=512
                    } else {
                        2..=32
                    };
                    let mut w = r.width;
                    if int_slider(ui, &mut w, side.clone(), "width (particles)", "Particles across; rebuilds the scene keeping the other settings") {
                        edit(Edit::Width(w));
                    }
                    let mut h = r.height;
                    if int_slider(ui, &mut h, side, "height (particles)", "Particles down; rebuilds the scene keeping the other settings") {
                        edit(Edit::Height(h));
                    }
                    if r.layout == Layout::Lattice {
                        let mut d = r.depth;
                        if int_slider(ui, &mut d, 2..=32, "depth (particles)", "Particles deep; rebuilds the scene keeping the other settings") {
                            edit(Edit::Depth(d));
                        }
                    }
                }
                Layout::Chain | Layout::Rope => {
                    let mut w = r.width;
                    if int_slider(ui, &mut w, 2..=200, "length (particles)", "Particles along the line; rebuilds the scene keeping the other settings") {
                        edit(Edit::Width(w));
                    }
                }
                Layout::Spring | Layout::Mesh => {}
            }
            let mut m = r.particle_mass;
            if slider(ui, &mut m, 0.000_001..=10.0, "particle mass (kg)", true, "Mass of each particle in kg") {
                edit(Edit::ParticleMass(m));
            }
            let mut g = p.gravity;
            if slider(ui, &mut g.y, -30.0..=10.0, "gravity y (m/s²)", false, "Gravitational acceleration along y in m/s² (negative is down; Earth: -9.81)") {
                edit(Edit::Gravity(g));
            }
            // Seed 001's force vector: a force on every particle, in every scene.
            // The sliders reach a few times the particle's weight (or the force set).
            let mut f = p.force;
            let reach = (20.0 * m * 9.81).max(2.0 * p.force.abs().max_element()).min(1e6);
            ui.label("Force on every particle (N)").on_hover_text(
                "Seed 001's force vector: a force in N on every particle besides gravity, \
                 e.g. a push or a steady wind on the cloth of bars",
            );
            let mut changed = false;
            for (value, axis) in [(&mut f.x, "x"), (&mut f.y, "y"), (&mut f.z, "z")] {
                let tip = format!("Force along {axis} in N on every particle");
                changed |= slider(ui, value, -reach..=reach, &format!("force {axis} (N)"), false, &tip);
            }
            if changed {
                edit(Edit::Force(f));
            }
            if has_surface {
                // Wind acts through the aerodynamic drag only: without it (seed
                // 002's still air) the controls would do nothing, so they are off.
                let aero = p.drag_coefficient > 0.0 && p.air_density > 0.0;
                ui.add_enabled_ui(aero, |ui| {
                    let mut on = session.wind_on();
                    if ui
                        .checkbox(&mut on, "wind")
                        .on_hover_text("Wind on or off (seed 004): off sets the wind and gusts to zero and remembers them for turning it back on")
                        .changed()
                    {
                        wind_switch = Some(on);
                    }
                    let mut w = p.wind;
                    let tip = "Mean wind velocity in m/s, acting through the aerodynamic drag on each triangle; -20 to 20 here, up to 10000 m/s in scene files";
                    ui.label("Wind (m/s)").on_hover_text(tip);
                    let mut changed = slider(ui, &mut w.x, -20.0..=20.0, "x", false, "Wind velocity along x in m/s");
                    changed |= slider(ui, &mut w.y, -20.0..=20.0, "y", false, "Wind velocity along y in m/s");
                    changed |= slider(ui, &mut w.z, -20.0..=20.0, "z", false, "Wind velocity along z in m/s (towards the viewer)");
                    if changed {
                        edit(Edit::Wind(w));
                    }
                    let mut gust = p.gust;
                    if slider(ui, &mut gust, 0.0..=10.0, "gust (m/s)", false, "Gust amplitude in m/s: random variation of the wind about its mean") {
                        edit(Edit::Gust(gust));
                    }
                })
                .response
                .on_disabled_hover_text(
                    "This scene has no aerodynamic drag (drag_coefficient or air_density is 0, still air): wind would have no effect",
                );
            }
            let mut dt = p.dt;
            if slider(ui, &mut dt, 0.000_01..=0.05, "dt (s)", true, "Time step in s, 1e-5 to 0.05. The speed stays: the steps per frame change with it, so a larger dt means coarser steps, not a faster run. Safe stepping may run smaller steps over the same simulated time") {
                edit(Edit::Dt(dt));
            }
            if !system.bars().is_empty() {
                let mut it = p.bar_iterations;
                if int_slider(ui, &mut it, 0..=64, "bar relaxation iterations", "Rigid-bar relaxation passes per step (seed 001: 4 to 10); more passes keep bars closer to their length") {
                    edit(Edit::BarIterations(it));
                }
            }
            if has_springs {
                let mut on = p.stretch_limit.is_some();
                if ui
                    .checkbox(&mut on, "stretch limit")
                    .on_hover_text(
                        "Provot's stretch limit (seed 004): after each step, every spring \
                         longer than (1 + tau) times its rest length is pulled back to it, \
                         so that a soft cloth does not stretch like taffy",
                    )
                    .changed()
                {
                    edit(Edit::StretchLimit(on.then_some(p.stretch_limit.unwrap_or(0.1))));
                }
                if let Some(mut tau) = p.stretch_limit
                    && slider(ui, &mut tau, 0.0..=1.0, "max stretch (tau)", false, "Maximum stretch tau (Provot): springs are kept no longer than (1 + tau) times their rest length; 0.1 = 10% (0 to 100)")
                {
                    edit(Edit::StretchLimit(Some(tau)));
                }
            }
            let surface = !system.triangles().is_empty();
            if p.ground.is_some() || p.sphere.is_some() || surface {
                let mut mu = p.friction;
                if slider(ui, &mut mu, 0.0..=2.0, "friction μ", false, "Coulomb friction coefficient μ of the ground and the sphere (no unit); 0 is frictionless") {
                    edit(Edit::Friction(mu));
                }
                let mut t = p.thickness;
                if slider(ui, &mut t, 0.0..=0.1, "thickness (m)", false, "Contact thickness in m: how far above the ground and outside the sphere the cloth rests") {
                    edit(Edit::Thickness(t));
                }
            }
            if surface {
                let mut on = p.self_collision;
                if ui
                    .checkbox(&mut on, "self-collision")
                    .on_hover_text(
                        "Keep the cloth's particles a thickness apart, so that its layers \
                         fold onto each other instead of passing through",
                    )
                    .changed()
                {
                    edit(Edit::SelfCollision(on));
                }
            }
            if !system.springs().is_empty() || system.broken_springs() > 0 {
                let mut on = p.tear_strain.is_some();
                if ui
                    .checkbox(&mut on, "tearing")
                    .on_hover_text(
                        "Springs break for good when stretched past the tear strain; \
                         Ctrl + left drag cuts the cloth along the mouse's path either way",
                    )
                    .changed()
                {
                    edit(Edit::TearStrain(on.then_some(p.tear_strain.unwrap_or(0.5))));
                }
                if let Some(mut tau) = p.tear_strain
                    && slider(ui, &mut tau, 0.01..=2.0, "tear strain", true, "A spring breaks when longer than (1 + strain) times its rest length: 0.5 = 50% stretched (0.01 to 100)")
                {
                    edit(Edit::TearStrain(Some(tau)));
                }
            }
            let mut limited = p.max_speed.is_some();
            if ui
                .checkbox(&mut limited, "speed limit")
                .on_hover_text(
                    "Slow every particle faster than the limit down to it after each step \
                     (seed 000's vLim): a last resort against runaways, off by default",
                )
                .changed()
            {
                edit(Edit::MaxSpeed(limited.then_some(p.max_speed.unwrap_or(10.0))));
            }
            if let Some(mut v) = p.max_speed
                && slider(ui, &mut v, 0.1..=100.0, "max speed (m/s)", true, "Speed limit in m/s: no particle leaves a step faster than this (above 0, up to 1e6)")
            {
                edit(Edit::MaxSpeed(Some(v)));
            }
        });

    if let Some(on) = wind_switch {
        actions.push(Action::WindOn(on));
    }

    // Stats.
    egui::CollapsingHeader::new("Plots")
        .default_open(false)
        .show(ui, |ui| state.history.show(ui))
        .header_response
        .on_hover_text(format!(
            "Energy and dt / dt_crit over the last {} s of simulated time",
            super::plots::WINDOW_S
        ));
    egui::CollapsingHeader::new("Stats")
        .default_open(true)
        .show(ui, |ui| {
            ui.label(format!(
                "particles {} · springs {} · bars {} · triangles {}",
                system.particle_count(),
                system.springs().len(),
                system.bars().len(),
                system.triangles().len()
            ));
            let pace = session.pace();
            ui.label(format!(
                "physics {:.3} ms/step · {:.0} steps/s · busy {:.0}%",
                session.ms_per_step(),
                pace.steps_per_second,
                pace.busy * 100.0
            ))
            .on_hover_text("The physics thread's cost: wall time per step, steps per wall second, and the share of wall time it spends stepping.");
            ui.label(format!(
                "frame {:.1} ms ({:.0} frames/s)",
                state.frame_time * 1e3,
                1.0 / state.frame_time.max(1e-6)
            ));
            ui.label(format!(
                "t = {:.3} s · step {}",
                system.time(),
                system.steps_taken()
            ));
            let e = system.energy();
            ui.label(format!(
                "energy {:.4} J (kinetic {:.4}, gravity {:.4}, elastic {:.4})",
                e.total(),
                e.kinetic,
                e.gravity,
                e.elastic
            ));
            let s = system.stability();
            let margin = s.margin;
            let color = if !margin.is_finite() || margin >= 1.0 {
                Color32::from_rgb(255, 90, 80)
            } else if margin >= 0.7 {
                Color32::from_rgb(255, 200, 60)
            } else {
                Color32::from_rgb(120, 220, 120)
            };
            match s.dt_critical {
                Some(c) if c.is_infinite() => {
                    let why = if s.omega_max == 0.0 {
                        "nothing here oscillates on a step: bars and constraints only \
                         (XPBD's springs are constraints)"
                    } else {
                        "this integrator is stable at any dt"
                    };
                    ui.label(format!("stability: no step limit ({why})"));
                }
                Some(c) => {
                    ui.colored_label(
                        color,
                        format!("stability dt / dt_crit = {margin:.3} (dt_crit {c:.3e} s)"),
                    );
                }
                None => {
                    ui.colored_label(
                        color,
                        format!("stability: {} has no stable step here without damping", p.integrator),
                    );
                }
            }
            if let Some(budget) = system.energy_budget() {
                // How much of the energy rise the budget allows is used.
                let used = (e.total() - budget.base) / budget.allowed;
                let color = if used >= 0.5 {
                    Color32::from_rgb(255, 200, 60)
                } else {
                    Color32::from_rgb(120, 220, 120)
                };
                ui.colored_label(
                    color,
                    format!("energy budget used {:.0}%", 100.0 * used.max(0.0)),
                )
                .on_hover_text(format!(
                    "The run counts as diverged when its energy rises more than {:.3e} J \
                         above the {:.3e} J it had at the start or the last edit",
                    budget.limit() - budget.base,
                    budget.base
                ));
            }
            if system.broken_springs() > 0 {
                ui.label(format!("broken springs {}", system.broken_springs()));
            }
            if p.max_speed.is_some() || p.stretch_limit.is_some() || p.tear_strain.is_some() {
                let activity = system.limiter_activity();
                let held: Vec<String> = (activity.working())
                    .map(|(l, n, of)| l.holding(n, of))
                    .collect();
                if !held.is_empty() {
                    ui.label(format!("limiters hold {}", held.join(", ")));
                }
                if let Some(warning) = activity.warning() {
                    ui.colored_label(Color32::from_rgb(255, 200, 60), warning);
                }
            }
            if p.self_collision {
                ui.label(format!(
                    "self-collision contacts {}",
                    system.self_collision_contacts()
                ));
            }
            let engine = system.engine().label(system.engine_threads());
            ui.label(format!("engine {engine}"));
            ui.label(RichText::new(format!("adapter: {adapter}")).small());
        });
    // Display.
    egui::CollapsingHeader::new("Display")
        .default_open(true)
        .show(ui, |ui| {
            ui.horizontal_wrapped(|ui| {
                ui.checkbox(&mut view.mesh, "mesh")
                    .on_hover_text("Draw the cloth surface, lit");
                ui.checkbox(&mut view.wireframe, "wireframe")
                    .on_hover_text("Draw the triangles' edges");
                ui.checkbox(&mut view.textured, "texture")
                    .on_hover_text("A checker texture on the surface, to show how it moves");
            });
            ui.horizontal_wrapped(|ui| {
                ui.checkbox(&mut view.springs, "springs")
                    .on_hover_text("Draw the springs as lines, coloured by kind");
                ui.checkbox(&mut state.strain_colors, "by strain")
                    .on_hover_text(
                        "Colour springs by strain (stretch over rest length) instead of kind",
                    );
            });
            if view.springs && state.strain_colors {
                strain_legend(ui);
            }
            ui.horizontal_wrapped(|ui| {
                ui.checkbox(&mut view.particles, "particles")
                    .on_hover_text("Draw every particle as a dot");
                ui.checkbox(&mut view.pins, "pins")
                    .on_hover_text("Mark the pinned particles in red");
            });
            ui.add(egui::Slider::new(&mut view.particle_px, 2.0..=20.0).text("particle size (px)"))
                .on_hover_text("Diameter of the particle dots in screen pixels, 2 to 20");
            ui.horizontal(|ui| {
                ui.label("background");
                ui.color_edit_button_srgb(&mut view.background)
                    .on_hover_text("Background colour of the view");
                if ui
                    .button("Reset view")
                    .on_hover_text("Frame the scene with the default camera (F or Home)")
                    .clicked()
                {
                    actions.push(Action::ResetView);
                }
            });
        });
}
