//! Moving a collider with the mouse (Shift + left drag): the collider under the
//! cursor is taken at the point the cursor meets it, which then follows the
//! cursor in the view plane. Each frame it is given the velocity that reaches the
//! cursor in one frame, at most its speed limit, so that it moves through the
//! frame's steps rather than jumping, and friction feels its motion.

use cloth_sandbox::scene::Vector;
use glam::{DVec3, Vec2};

use super::App;

/// A collider being moved: which, the offset of its centre from the point held,
/// where the centre is going, and the velocity it had before.
#[derive(Clone, Copy, Debug)]
pub(super) struct Moving {
    index: usize,
    offset: DVec3,
    target: DVec3,
    velocity: DVec3,
}

impl App {
    /// Takes the collider under `cursor` (px) for Shift + drag; whether there was one.
    pub(super) fn grab_collider(&mut self, cursor: Vec2) -> bool {
        self.session.hold();
        let ray = self.camera.ray(self.to_scene(cursor), self.viewport());
        let (origin, dir) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let system = self.session.system();
        let t = system.time();
        let nearest = (system.colliders().iter().enumerate())
            .filter_map(|(i, c)| c.ray_hit(origin, dir, t, 1e3).map(|s| (i, s)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        let Some((index, s)) = nearest else {
            return false;
        };
        let collider = &system.colliders()[index];
        let (centre, _) = collider.pose_at(t);
        self.moving = Some(Moving {
            index,
            offset: centre - (origin + dir * s),
            target: centre,
            velocity: collider.velocity,
        });
        self.mouse.press_collider(index);
        log::info!("moving collider {index} ({})", collider.shape.name());
        true
    }

    /// The held point follows `cursor` in the view plane through it.
    pub(super) fn move_collider(&mut self, index: usize, cursor: Vec2) {
        let Some(moving) = self.moving.filter(|m| m.index == index) else {
            return;
        };
        let held = (moving.target - moving.offset).as_vec3();
        let (scene, viewport) = (self.to_scene(cursor), self.viewport());
        if let Some(point) = self.camera.drag_point(scene, viewport, held)
            && point.is_finite()
            && let Some(m) = self.moving.as_mut()
        {
            m.target = point.as_dvec3() + moving.offset;
        }
    }

    /// Lets go: the collider moves on as it did before it was taken, from where
    /// it was left, which the scene keeps (for a reset, a save, the panel).
    pub(super) fn release_collider(&mut self, index: usize) {
        let Some(moving) = self.moving.take().filter(|m| m.index == index) else {
            return;
        };
        let system = self.session.system();
        let Some(c) = system.colliders().get(index) else {
            return;
        };
        let (t, (centre, _)) = (system.time(), c.pose_at(system.time()));
        // The scene's pose is at time 0: from there its own motion brings it here.
        let start = centre - moving.velocity * t;
        let mut specs = self.session.scene().spec.colliders.clone();
        if let Some(spec) = specs.get_mut(index) {
            if let (Some(a), Some(b)) = (spec.a, spec.b) {
                let shift = start - 0.5 * (a.0 + b.0);
                (spec.a, spec.b) = (Some(Vector(a.0 + shift)), Some(Vector(b.0 + shift)));
            } else {
                spec.center = Some(Vector(start));
            }
        }
        log::info!("released collider {index}");
        if let Err(e) = self.session.set_colliders(specs) {
            self.panel.error = Some(e.to_string());
        }
    }

    /// Each frame: the velocity that takes the collider to its target in one
    /// frame's simulated time.
    pub(super) fn steer_collider(&mut self) {
        let Some(moving) = self.moving else {
            return;
        };
        let frame = f64::from(self.session.substeps()) * self.session.system().params().dt;
        let system = self.session.system_mut();
        let Some(c) = system.colliders().get(moving.index) else {
            self.moving = None;
            return;
        };
        let (centre, _) = c.pose_at(system.time());
        let velocity = (moving.target - centre) / frame.max(1e-6);
        system.move_collider(moving.index, centre, velocity);
    }
}
