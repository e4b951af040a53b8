//! The panel's top: the scene and integrator, the run buttons, what can be
//! written out, the speed and safe stepping, and the pin presets.

use cloth_sandbox::scene::{Layout, PinPreset, Pins, Scene, builtin_scenes};
use cloth_sandbox::session::{Edit, Session};
use cloth_sandbox::sim::Integrator;
use egui::{Color32, Ui};

use super::{Action, PanelState};

/// The pin presets the layout has (a grid's corners and edges, a line's ends) and
/// "unpin all".
pub(super) fn pin_presets(ui: &mut Ui, layout: Layout, pinned: usize, actions: &mut Vec<Action>) {
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

/// The scene and integrator dropdowns.
pub(super) fn scene_and_integrator(ui: &mut Ui, session: &Session, actions: &mut Vec<Action>) {
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
    let p = session.settings().params;
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
}

/// Play/pause, step, reset and save; undo, redo and defaults.
/// The engine choice: the GPU engine (wgpu compute) or the CPU's, and why the
/// GPU engine steps on the CPU where it cannot step the scene.
pub(super) fn engine(ui: &mut Ui, session: &Session, actions: &mut Vec<Action>) {
    let mut on = session.on_gpu();
    let hover = "Step on the GPU engine (wgpu compute shaders), built again after every edit; \
                 scenes it does not step yet run on the CPU, saying why.";
    let toggle = ui.checkbox(&mut on, "GPU engine").on_hover_text(hover);
    if toggle.changed() {
        actions.push(Action::Gpu(on));
    }
    if let Some(problem) = session.gpu_problem() {
        let text = format!("{problem}: running on the CPU.");
        ui.colored_label(Color32::from_rgb(255, 200, 60), text);
    }
}

pub(super) fn run_buttons(ui: &mut Ui, session: &Session, actions: &mut Vec<Action>) {
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
}

/// What can be written out: the OBJ, a screenshot, a GIF recording.
pub(super) fn outputs(
    ui: &mut Ui,
    state: &mut PanelState,
    session: &Session,
    actions: &mut Vec<Action>,
) {
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
}

/// The steps per frame, the speed they make, and safe stepping with what it
/// chose.
pub(super) fn speed(ui: &mut Ui, session: &Session, actions: &mut Vec<Action>) {
    let r = session.settings();
    let p = r.params;
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
    let mut slow = session.slow_motion();
    let range = cloth_sandbox::session::SLOW_MOTION;
    if ui
        .add(
            egui::Slider::new(&mut slow, range)
                .logarithmic(true)
                .text("slow motion (× speed)"),
        )
        .on_hover_text("Watch fast events (a tear, a fling) slowly: 1 runs at the scene's speed, 0.05 twenty times slower, with the same steps. Not part of the scene")
        .changed()
    {
        actions.push(Action::SlowMotion(slow));
    }
    ui.label(format!(
        "speed {:.2}x real time ({} x {:.3e} s per 1/60 s{})",
        session.speed(),
        r.substeps,
        p.dt,
        if slow < 1.0 { format!(", slowed {slow:.2}x") } else { String::new() }
    ))
    .on_hover_text("Simulated seconds per wall-clock second asked for. The corner of the view says what the physics thread reaches.");
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
}
