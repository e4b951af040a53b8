//! The Colliders section: each collider's shape, size, friction and motion, a
//! button to remove it, and buttons to add a sphere, a box or a capsule under the
//! cloth. Shift + drag in the view moves one.

use cloth_sandbox::scene::{ColliderSpec, Vector};
use cloth_sandbox::session::Session;
use egui::Ui;
use glam::DVec3;

use super::Action;

/// The section; a change sends the whole list as [`Action::Colliders`].
pub(super) fn colliders(ui: &mut Ui, session: &Session, actions: &mut Vec<Action>) {
    let specs = &session.scene().spec.colliders;
    egui::CollapsingHeader::new(format!("Colliders ({})", specs.len()))
        .default_open(!specs.is_empty())
        .show(ui, |ui| {
            let mut list = specs.clone();
            let mut changed = false;
            let mut remove = None;
            for (i, spec) in list.iter_mut().enumerate() {
                ui.push_id(i, |ui| {
                    ui.horizontal(|ui| {
                        ui.strong(format!("{} {}", i + 1, spec.shape));
                        if ui.small_button("remove").clicked() {
                            remove = Some(i);
                        }
                    });
                    changed |= size(ui, spec);
                    changed |= friction(ui, spec, session);
                    changed |= motion(ui, spec);
                });
                ui.add_space(4.0);
            }
            if let Some(i) = remove {
                list.remove(i);
                changed = true;
            }
            ui.horizontal(|ui| {
                for shape in ["sphere", "box", "capsule"] {
                    if ui
                        .button(format!("+ {shape}"))
                        .on_hover_text(format!("Add a {shape} under the cloth"))
                        .clicked()
                    {
                        list.push(new_collider(shape, session));
                        changed = true;
                    }
                }
            });
            ui.label(egui::RichText::new("Shift + drag a collider to move it").small());
            if changed {
                actions.push(Action::Colliders(list));
            }
        });
}

/// A new collider of `shape` half a metre under the middle of the cloth.
fn new_collider(shape: &str, session: &Session) -> ColliderSpec {
    let points: Vec<glam::Vec3> = (session.system().positions().iter())
        .map(|p| p.as_vec3())
        .collect();
    let (lo, hi) = cloth_sandbox::view::bounds(&points).unwrap_or_default();
    let middle = (0.5 * (lo + hi)).as_dvec3();
    let centre = DVec3::new(middle.x, f64::from(lo.y) - 0.5, middle.z);
    let mut spec = ColliderSpec {
        shape: shape.to_string(),
        ..ColliderSpec::default()
    };
    match shape {
        "capsule" => {
            spec.a = Some(Vector(centre - DVec3::new(0.4, 0.0, 0.0)));
            spec.b = Some(Vector(centre + DVec3::new(0.4, 0.0, 0.0)));
            spec.radius = Some(0.1);
        }
        "box" => {
            spec.center = Some(Vector(centre));
            spec.half_extents = Some(Vector(DVec3::new(0.3, 0.1, 0.3)));
        }
        _ => {
            spec.center = Some(Vector(centre));
            spec.radius = Some(0.3);
        }
    }
    spec
}

/// A length slider on a log scale from 1 cm to 5 m.
fn length(ui: &mut Ui, value: &mut f64, label: &str) -> bool {
    ui.add(
        egui::Slider::new(value, 0.01..=5.0)
            .logarithmic(true)
            .text(label)
            .suffix(" m"),
    )
    .changed()
}

/// The radius, or the box's half extents.
fn size(ui: &mut Ui, spec: &mut ColliderSpec) -> bool {
    match spec.shape.as_str() {
        "sphere" | "capsule" => {
            let mut r = spec
                .radius
                .unwrap_or(if spec.shape == "sphere" { 0.5 } else { 0.1 });
            let changed = length(ui, &mut r, "radius");
            spec.radius = Some(r);
            changed
        }
        "box" => {
            let mut half = spec.half_extents.map_or(DVec3::splat(0.5), |v| v.0);
            let mut changed = false;
            for (axis, name) in ["half x", "half y", "half z"].iter().enumerate() {
                changed |= length(ui, &mut half[axis], name);
            }
            spec.half_extents = Some(Vector(half));
            changed
        }
        _ => false,
    }
}

/// Friction μ, the scene's unless set.
fn friction(ui: &mut Ui, spec: &mut ColliderSpec, session: &Session) -> bool {
    let mut mu = spec.friction.unwrap_or(session.system().params().friction);
    let changed = ui
        .add(egui::Slider::new(&mut mu, 0.0..=2.0).text("friction μ"))
        .on_hover_text("Coulomb friction between this collider and the cloth")
        .changed();
    if changed {
        spec.friction = Some(mu);
    }
    changed
}

/// The velocity along x and z and the turn about y.
fn motion(ui: &mut Ui, spec: &mut ColliderSpec) -> bool {
    let mut v = spec.velocity.map_or(DVec3::ZERO, |v| v.0);
    let mut w = spec.angular_velocity.map_or(DVec3::ZERO, |v| v.0);
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.label("moves");
        changed |= ui
            .add(
                egui::DragValue::new(&mut v.x)
                    .range(-5.0..=5.0)
                    .speed(0.01)
                    .suffix(" m/s x"),
            )
            .changed();
        changed |= ui
            .add(
                egui::DragValue::new(&mut v.z)
                    .range(-5.0..=5.0)
                    .speed(0.01)
                    .suffix(" m/s z"),
            )
            .changed();
    });
    changed |= ui
        .add(
            egui::Slider::new(&mut w.y, -10.0..=10.0)
                .text("turns about y")
                .suffix(" rad/s"),
        )
        .changed();
    if changed {
        spec.velocity = Some(Vector(v));
        spec.angular_velocity = Some(Vector(w));
    }
    changed
}
