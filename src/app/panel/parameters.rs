//! The parameter sliders and switches, only those the scene uses. Each change
//! is an [`Edit`]; dt keeps the speed.

use cloth_sandbox::scene::{Layout, Resolved};
use cloth_sandbox::session::{Edit, Session};
use cloth_sandbox::sim::{Integrator, Params, System};
use egui::Ui;

use super::Action;

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

/// The sliders and switches of the parameters the scene uses.
pub(super) fn parameters(ui: &mut Ui, session: &Session, actions: &mut Vec<Action>) {
    let r = session.settings();
    let p = r.params;
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
    egui::CollapsingHeader::new("Parameters")
        .default_open(true)
        .show(ui, |ui| {
            if has_springs {
                spring_sliders(ui, r, system, &mut edit);
            }
            let mut rest = r.rest_length;
            if slider(ui, &mut rest, 0.001..=5.0, "rest length (m)", true, "Spacing between neighbouring particles in m; the cloth grows or shrinks about its pins") {
                edit(Edit::RestLength(rest));
            }
            size_sliders(ui, r, &mut edit);
            mass_and_forces(ui, r, &mut edit);
            if has_surface {
                wind_switch = wind(ui, session, &mut edit);
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
                stretch_limit(ui, &p, &mut edit);
            }
            contact(ui, &p, has_surface, &mut edit);
            if !system.springs().is_empty() || system.broken_springs() > 0 {
                tearing(ui, &p, &mut edit);
            }
            speed_limit(ui, &p, &mut edit);
        });
    if let Some(on) = wind_switch {
        actions.push(Action::WindOn(on));
    }
}

/// Spring stiffness and damping.
fn spring_sliders(ui: &mut Ui, r: &Resolved, system: &System, edit: &mut impl FnMut(Edit)) {
    let mut k = r.stiffness;
    // XPBD is stable at any stiffness: its slider reaches the scene
    // files' limit.
    let k_max = if system.params().integrator == Integrator::Xpbd {
        1e9
    } else {
        100_000.0
    };
    if slider(
        ui,
        &mut k,
        0.01..=k_max,
        "stiffness k (N/m)",
        true,
        "Spring stiffness k in N/m: force per metre of stretch (shear and bend springs keep their multiples of it)",
    ) {
        edit(Edit::Stiffness(k));
    }
    let mut b = r.damping;
    if slider(
        ui,
        &mut b,
        0.0..=100.0,
        "damping b (N·s/m)",
        true,
        "Spring damping b in N·s/m: force per m/s of stretching speed along the spring",
    ) {
        edit(Edit::Damping(b));
    }
}

/// The particles across, down, deep or along, as the layout has them.
fn size_sliders(ui: &mut Ui, r: &Resolved, edit: &mut impl FnMut(Edit)) {
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
            if int_slider(
                ui,
                &mut w,
                side.clone(),
                "width (particles)",
                "Particles across; rebuilds the scene keeping the other settings",
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

/// Particle mass, gravity and the force on every particle.
fn mass_and_forces(ui: &mut Ui, r: &Resolved, edit: &mut impl FnMut(Edit)) {
    let p = r.params;
    let mut m = r.particle_mass;
    if slider(
        ui,
        &mut m,
        0.000_001..=10.0,
        "particle mass (kg)",
        true,
        "Mass of each particle in kg",
    ) {
        edit(Edit::ParticleMass(m));
    }
    let mut g = p.gravity;
    if slider(
        ui,
        &mut g.y,
        -30.0..=10.0,
        "gravity y (m/s²)",
        false,
        "Gravitational acceleration along y in m/s² (negative is down; Earth: -9.81)",
    ) {
        edit(Edit::Gravity(g));
    }
    // Seed 001's force vector: a force on every particle, in every scene.
    // The sliders reach a few times the particle's weight (or the force set).
    let mut f = p.force;
    let reach = (20.0 * m * 9.81)
        .max(2.0 * p.force.abs().max_element())
        .min(1e6);
    ui.label("Force on every particle (N)").on_hover_text(
        "Seed 001's force vector: a force in N on every particle besides gravity, \
         e.g. a push or a steady wind on the cloth of bars",
    );
    let mut changed = false;
    for (value, axis) in [(&mut f.x, "x"), (&mut f.y, "y"), (&mut f.z, "z")] {
        let tip = format!("Force along {axis} in N on every particle");
        changed |= slider(
            ui,
            value,
            -reach..=reach,
            &format!("force {axis} (N)"),
            false,
            &tip,
        );
    }
    if changed {
        edit(Edit::Force(f));
    }
}

/// The wind switch, velocity and gusts; returns the switch if it was flipped.
fn wind(ui: &mut Ui, session: &Session, edit: &mut impl FnMut(Edit)) -> Option<bool> {
    let p = session.settings().params;
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
    switch
}

/// Provot's stretch limit: its switch and tau.
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
    if let Some(mut tau) = p.stretch_limit
        && slider(
            ui,
            &mut tau,
            0.0..=1.0,
            "max stretch (tau)",
            false,
            "Maximum stretch tau (Provot): springs are kept no longer than (1 + tau) times their rest length; 0.1 = 10% (0 to 100)",
        )
    {
        edit(Edit::StretchLimit(Some(tau)));
    }
}

/// Friction and thickness where there is something to touch, and self-collision
/// where there is a surface.
fn contact(ui: &mut Ui, p: &Params, surface: bool, edit: &mut impl FnMut(Edit)) {
    if p.ground.is_some() || p.sphere.is_some() || surface {
        let mut mu = p.friction;
        if slider(
            ui,
            &mut mu,
            0.0..=2.0,
            "friction μ",
            false,
            "Coulomb friction coefficient μ of the ground and the sphere (no unit); 0 is frictionless",
        ) {
            edit(Edit::Friction(mu));
        }
        let mut t = p.thickness;
        if slider(
            ui,
            &mut t,
            0.0..=0.1,
            "thickness (m)",
            false,
            "Contact thickness in m: how far above the ground and outside the sphere the cloth rests",
        ) {
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
}

/// Tearing: its switch and the tear strain.
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
    if let Some(mut tau) = p.tear_strain
        && slider(
            ui,
            &mut tau,
            0.01..=2.0,
            "tear strain",
            true,
            "A spring breaks when longer than (1 + strain) times its rest length: 0.5 = 50% stretched (0.01 to 100)",
        )
    {
        edit(Edit::TearStrain(Some(tau)));
    }
}

/// The speed limit: its switch and the speed.
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
    if let Some(mut v) = p.max_speed
        && slider(
            ui,
            &mut v,
            0.1..=100.0,
            "max speed (m/s)",
            true,
            "Speed limit in m/s: no particle leaves a step faster than this (above 0, up to 1e6)",
        )
    {
        edit(Edit::MaxSpeed(Some(v)));
    }
}
