//! The parameter sliders and switches, only those the scene uses. Each change
//! is an [`Edit`]; dt keeps the speed. Ranges and scales come from the
//! session's table ([`Session::sliders`]).

use cloth_sandbox::scene::{Layout, MATERIALS, Resolved};
use cloth_sandbox::session::{Edit, Session, Slider};
use cloth_sandbox::sim::Params;
use egui::Ui;

use super::Action;

/// Draws `slider` (from the session's table, [`Session::sliders`]) and sends
/// its edit when the user moved it. A value the slider did not touch is left as
/// it is, even one outside its range or with more decimals than it shows (egui's
/// default clamps and rounds every frame, which would edit a scene's damping ratio
/// the moment it opens).
fn slider(ui: &mut Ui, s: &Slider, r: &Resolved, edit: &mut impl FnMut(Edit)) {
    let mut value = s.value(r);
    let moved = ui
        .add(
            egui::Slider::new(&mut value, s.range.clone())
                .logarithmic(s.log)
                .clamping(egui::SliderClamping::Edits)
                .text(&s.label)
                .max_decimals(6),
        )
        .on_hover_text(&s.tip)
        .changed();
    if moved {
        edit(s.edit(r, value));
    }
}

/// The table's slider `id`, drawn where the scene has it.
fn slider_of(ui: &mut Ui, table: &[Slider], id: &str, r: &Resolved, edit: &mut impl FnMut(Edit)) {
    if let Some(s) = table.iter().find(|s| s.id == id) {
        slider(ui, s, r, edit);
    }
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

/// The sliders and switches of the parameters the scene uses.
pub(super) fn parameters(ui: &mut Ui, session: &Session, actions: &mut Vec<Action>) {
    let r = session.settings();
    let p = r.params;
    let system = session.system();
    let has_springs = !system.springs().is_empty();
    let has_surface = !system.triangles().is_empty();
    let table = session.sliders();
    let mut wind_switch = None;
    // The panel's dt keeps the speed (see `Session::apply_dt_keeping_speed`).
    let mut edit = |e: Edit| {
        actions.push(match e {
            Edit::Dt(dt) => Action::DtKeepingSpeed(dt),
            e => Action::Edit(e),
        })
    };
    egui::CollapsingHeader::new("Parameters")
        .default_open(true)
        .show(ui, |ui| {
            if has_springs && system.bars().is_empty() {
                material(ui, session, &mut edit);
            }
            let mut draw = |ui: &mut Ui, id: &str| slider_of(ui, &table, id, r, &mut edit);
            for id in ["stiffness", "damping", "rest_length"] {
                draw(ui, id);
            }
            let keeps_size = session.scene().spec.size.is_some();
            size_sliders(ui, r, keeps_size, &mut edit);
            for id in ["particle_mass", "gravity_y"] {
                slider_of(ui, &table, id, r, &mut edit);
            }
            ui.label("Force on every particle").on_hover_text(
                "Seed 001's force vector: a force on every particle besides gravity, \
                 in the particle's weight, e.g. a push or a steady wind on the cloth of bars",
            );
            for id in ["force_x", "force_y", "force_z"] {
                slider_of(ui, &table, id, r, &mut edit);
            }
            if has_surface {
                wind_switch = wind(ui, session, &table, &mut edit);
            }
            slider_of(ui, &table, "dt", r, &mut edit);
            if !system.bars().is_empty() {
                let mut it = p.bar_iterations;
                if int_slider(ui, &mut it, 0..=64, "bar relaxation iterations", "Rigid-bar relaxation passes per step (seed 001: 4 to 10); more passes keep bars closer to their length") {
                    edit(Edit::BarIterations(it));
                }
            }
            if has_springs {
                stretch_limit(ui, &p, &mut edit);
                slider_of(ui, &table, "stretch_limit", r, &mut edit);
            }
            for id in ["friction", "thickness"] {
                slider_of(ui, &table, id, r, &mut edit);
            }
            if has_surface {
                self_collision(ui, &p, &mut edit);
            }
            if has_springs || system.broken_springs() > 0 {
                tearing(ui, &p, &mut edit);
                slider_of(ui, &table, "tear_strain", r, &mut edit);
            }
            speed_limit(ui, &p, &mut edit);
            slider_of(ui, &table, "max_speed", r, &mut edit);
        });
    if let Some(on) = wind_switch {
        actions.push(Action::WindOn(on));
    }
}

/// The material presets of a grid or mesh cloth; the scene's own values until
/// one is chosen, and "edited" once a slider changes one of its values.
fn material(ui: &mut Ui, session: &Session, edit: &mut impl FnMut(Edit)) {
    let spec = &session.scene().spec;
    if !matches!(spec.layout, Layout::Grid | Layout::Mesh) {
        return;
    }
    let chosen = spec.material.as_deref();
    let text = match chosen {
        Some(name) if spec.overrides_material() => format!("{name} (edited)"),
        Some(name) => name.to_string(),
        None => "the scene's own".to_string(),
    };
    egui::ComboBox::from_label("material")
        .selected_text(text)
        .show_ui(ui, |ui| {
            for m in &MATERIALS {
                let tip = format!(
                    "{}\n{} kg/m², k = {} N/m, b = {} N·s/m, bend {} k, drag {}",
                    m.about,
                    m.areal_density,
                    m.stiffness,
                    m.damping,
                    m.bend_scale,
                    m.drag_coefficient
                );
                if ui
                    .selectable_label(chosen == Some(m.name), m.name)
                    .on_hover_text(tip)
                    .clicked()
                {
                    edit(Edit::Material(m));
                }
            }
        })
        .response
        .on_hover_text(
            "A fabric's mass per area, stiffness, damping, bending and drag. It holds at \
             any spacing: the width slider then refines the same cloth over the same size",
        );
}

/// The particles across, down, deep or along, as the layout has them. A grid
/// that keeps its size in m (`size`, as a material does) refines with its width.
fn size_sliders(ui: &mut Ui, r: &Resolved, keeps_size: bool, edit: &mut impl FnMut(Edit)) {
    match r.layout {
        Layout::Grid | Layout::Lattice => {
            // Grids up to 512 x 512 run in real time on the grid kernel; a
            // lattice has 13 springs per particle and no fast path.
            let side = if r.layout == Layout::Grid {
                2..=512
            } else {
                2..=32
            };
            let mut w = r.width;
            if int_slider(
                ui,
                &mut w,
                side.clone(),
                "width (particles)",
                if keeps_size {
                    "Particles across the cloth's width in m: more refine the same cloth; rebuilds the scene keeping the other settings"
                } else {
                    "Particles across; rebuilds the scene keeping the other settings"
                },
            ) {
                edit(Edit::Width(w));
            }
            let mut h = r.height;
            if int_slider(
                ui,
                &mut h,
                side,
                "height (particles)",
                "Particles down; rebuilds the scene keeping the other settings",
            ) {
                edit(Edit::Height(h));
            }
            if r.layout == Layout::Lattice {
                let mut d = r.depth;
                if int_slider(
                    ui,
                    &mut d,
                    2..=32,
                    "depth (particles)",
                    "Particles deep; rebuilds the scene keeping the other settings",
                ) {
                    edit(Edit::Depth(d));
                }
            }
        }
        Layout::Chain | Layout::Rope => {
            let mut w = r.width;
            if int_slider(
                ui,
                &mut w,
                2..=200,
                "length (particles)",
                "Particles along the line; rebuilds the scene keeping the other settings",
            ) {
                edit(Edit::Width(w));
            }
        }
        Layout::Spring | Layout::Mesh => {}
    }
}

/// The wind switch, velocity and gusts; returns the switch if it was flipped.
fn wind(
    ui: &mut Ui,
    session: &Session,
    table: &[Slider],
    edit: &mut impl FnMut(Edit),
) -> Option<bool> {
    let r = session.settings();
    let p = r.params;
    let mut switch = None;
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
            switch = Some(on);
        }
        ui.label("Wind (m/s)").on_hover_text("Mean wind velocity in m/s, acting through the aerodynamic drag on each triangle; -20 to 20 here, up to 10000 m/s in scene files");
        for id in ["wind_x", "wind_y", "wind_z", "gust"] {
            slider_of(ui, table, id, r, edit);
        }
    })
    .response
    .on_disabled_hover_text(
        "This scene has no aerodynamic drag (drag_coefficient or air_density is 0, still air): wind would have no effect",
    );
    switch
}

/// Provot's stretch limit: its switch (the table has its tau).
fn stretch_limit(ui: &mut Ui, p: &Params, edit: &mut impl FnMut(Edit)) {
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
        edit(Edit::StretchLimit(
            on.then_some(p.stretch_limit.unwrap_or(0.1)),
        ));
    }
}

/// Self-collision's switch, where there is a surface.
fn self_collision(ui: &mut Ui, p: &Params, edit: &mut impl FnMut(Edit)) {
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

/// Tearing's switch (the table has the tear strain).
fn tearing(ui: &mut Ui, p: &Params, edit: &mut impl FnMut(Edit)) {
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
}

/// The speed limit's switch (the table has the speed).
fn speed_limit(ui: &mut Ui, p: &Params, edit: &mut impl FnMut(Edit)) {
    let mut limited = p.max_speed.is_some();
    if ui
        .checkbox(&mut limited, "speed limit")
        .on_hover_text(
            "Slow every particle faster than the limit down to it after each step \
             (seed 000's vLim): a last resort against runaways, off by default",
        )
        .changed()
    {
        edit(Edit::MaxSpeed(
            limited.then_some(p.max_speed.unwrap_or(10.0)),
        ));
    }
}
