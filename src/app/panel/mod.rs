//! The egui side panel: scene and integrator, parameter sliders (only those the
//! scene uses), play/pause/step/reset and speed, display toggles, live stats and
//! the divergence notice. It edits view options directly and returns every
//! change to the simulation as an `Action` for the app to apply; parameter changes
//! are typed [`Edit`]s.

mod accuracy;
mod colliders;
mod controls;
mod display;
mod parameters;
mod stats;

use std::time::Instant;

use cloth_sandbox::scene::Pins;
use cloth_sandbox::session::{Edit, Pace, Session};
use egui::{Color32, RichText, Ui};

use crate::render::ViewOptions;
use controls::{outputs, pin_presets, run_buttons, scene_and_integrator, speed};
use display::display;
use parameters::parameters;
pub(crate) use stats::engine_label;
use stats::stats;

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
    /// Set the slow-motion factor.
    SlowMotion(f64),
    /// Turn the live reference (the error against RK4 at a finer step) on or off.
    Reference(bool),
    /// Start the live reference again from the state now.
    RestartReference,
    /// Step on the GPU engine (or the CPU's).
    Gpu(bool),
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
    /// Hide or show the panel (Tab).
    TogglePanel,
    /// Hide or show the view's corner readout (F2).
    ToggleReadout,
    /// Take back the last change of parameters or pins (Ctrl+Z).
    Undo,
    /// Do again the last change undone (Ctrl+Shift+Z).
    Redo,
    /// After a divergence: take back the edit before it and run on from the last
    /// good state.
    UndoDivergence,
    /// Restore the scene's own parameters and pins.
    Defaults,
    /// Replace the colliders with these.
    Colliders(Vec<cloth_sandbox::scene::ColliderSpec>),
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
    /// Whether Tab has hidden the panel.
    pub hidden: bool,
    /// Whether the view's corner readout is hidden (F2 toggles it).
    pub readout_hidden: bool,
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

/// Draws the panel (unless Tab hid it) and the view's corner readout; returns
/// what the user asked for and the rectangle (points) left for the scene.
pub fn show(
    ui: &mut Ui,
    state: &mut PanelState,
    session: &Session,
    view: &mut ViewOptions,
    adapter: &str,
) -> (Vec<Action>, egui::Rect) {
    let mut actions = Vec::new();
    super::help::show(ui.ctx(), &mut state.help);
    if state.hidden {
        let corner = ui.max_rect().left_top() + egui::vec2(8.0, 8.0);
        egui::Area::new(egui::Id::unique("show the panel"))
            .fixed_pos(corner)
            .show(ui.ctx(), |ui| {
                if ui
                    .button("» Panel (Tab)")
                    .on_hover_text("Show the panel again")
                    .clicked()
                {
                    actions.push(Action::TogglePanel);
                }
            });
    } else {
        // At most about half a small window, so the view keeps room.
        let widest = (0.5 * ui.max_rect().width()).max(MIN_PANEL_WIDTH);
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(PANEL_WIDTH.min(widest))
            .size_range(MIN_PANEL_WIDTH..=widest.max(MIN_PANEL_WIDTH))
            .show(ui, |ui| {
                header(ui, &mut actions);
                status(ui, state, session, &mut actions);
                egui::ScrollArea::vertical().show(ui, |ui| {
                    contents(ui, state, session, view, adapter, &mut actions);
                });
            });
    }
    let free = ui.available_rect_before_wrap();
    if !state.readout_hidden {
        super::overlay::show(ui.ctx(), free, session, state.frame_time);
    }
    (actions, free)
}

/// Width of the panel (points) when the app opens, and the narrowest it is
/// dragged to.
const PANEL_WIDTH: f32 = 340.0;
const MIN_PANEL_WIDTH: f32 = 220.0;

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
            "Click a particle: pin · drag it: move · drag elsewhere: orbit · Tab: hide panel · F1 or ?: all keys",
        )
        .small(),
    );
    ui.separator();
}

/// The status box: a divergence in full, the last error, what was written
/// where. It takes no room when there is nothing to say (the pace is drawn in
/// the view's corner).
fn status(ui: &mut Ui, state: &PanelState, session: &Session, actions: &mut Vec<Action>) {
    let any = session.divergence().is_some()
        || session.paused()
        || state.error.is_some()
        || state.saved.is_some()
        || state.wrote.is_some();
    if !any {
        return;
    }
    if let Some(d) = session.divergence() {
        divergence(ui, d, session.can_undo(), actions);
    } else if session.paused() {
        ui.label("Paused (Space or Play resumes).");
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
    ui.separator();
}

/// A divergence in full: its cause, the edit before it, and the ways back.
fn divergence(
    ui: &mut Ui,
    d: &cloth_sandbox::session::DivergenceReport,
    can_undo: bool,
    actions: &mut Vec<Action>,
) {
    ui.colored_label(Color32::from_rgb(255, 110, 90), "Diverged and paused.");
    ui.horizontal(|ui| {
        if let Some((what, _)) = &d.edit
            && can_undo
            && ui
                .button("Undo that edit")
                .on_hover_text(format!(
                    "Take back {what} and run on from the last good frame"
                ))
                .clicked()
        {
            actions.push(Action::UndoDivergence);
        }
        if ui
            .button("Reset scene")
            .on_hover_text("Start the scene again from its setup (R)")
            .clicked()
        {
            actions.push(Action::Reset);
        }
    });
    ui.label(&d.cause);
    if let Some((what, ago)) = &d.edit {
        ui.label(format!("Last edit: {what}, {ago:.2} s before."));
    }
    ui.label(format!(
        "Showing the last good frame, t = {:.3} s.",
        d.shown_time
    ));
    ui.label(RichText::new(&d.message).small());
}

/// The panel below the status box, section by section; each folds away and
/// stays folded (egui keeps a header's state by its name).
fn contents(
    ui: &mut Ui,
    state: &mut PanelState,
    session: &Session,
    view: &mut ViewOptions,
    adapter: &str,
    actions: &mut Vec<Action>,
) {
    egui::CollapsingHeader::new("Scene and run")
        .default_open(true)
        .show(ui, |ui| {
            scene_and_integrator(ui, session, actions);
            controls::engine(ui, session, actions);
            run_buttons(ui, session, actions);
            speed(ui, session, actions);
        });
    egui::CollapsingHeader::new("Pins")
        .default_open(true)
        .show(ui, |ui| {
            pin_presets(ui, session.settings().layout, session.pins().len(), actions);
        });
    accuracy::accuracy(ui, session, actions);
    parameters(ui, session, actions);
    colliders::colliders(ui, session, actions);
    egui::CollapsingHeader::new("Files: save, export, record")
        .default_open(false)
        .show(ui, |ui| outputs(ui, state, session, actions));
    egui::CollapsingHeader::new("Plots")
        .default_open(false)
        .show(ui, |ui| state.history.show(ui))
        .header_response
        .on_hover_text(format!(
            "Energy and dt / dt_crit over the last {} s of simulated time",
            super::plots::WINDOW_S
        ));
    stats(ui, state, session, adapter);
    display(ui, state, view, actions);
}
