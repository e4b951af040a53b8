//! Solids the cloth cannot enter, besides the ground and the scene's one sphere:
//! spheres, oriented boxes, capsules and static triangle meshes, each at a pose
//! that may move kinematically (a velocity and an angular velocity about its
//! centre) or be moved by the user.
//!
//! A collider answers one question, [`Collider::touch`]: how deep a point is
//! within its contact surface (the solid grown by the cloth's thickness) and along
//! which normal it leaves, and how fast the solid's surface moves there. The
//! response (the push out and Coulomb friction on the velocity relative to the
//! surface) is one law for every shape and engine, `laws::collide`.

mod mesh;
mod shapes;

use std::sync::Arc;

use glam::{DMat3, DQuat, DVec3};

use crate::sim::lanes::{Lanes, V3};

pub use mesh::ColliderMesh;

/// A collider's geometry, in its own frame (centred on its pose's origin).
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A ball of this radius (m).
    Sphere {
        /// Radius in m.
        radius: f64,
    },
    /// A box of these half extents (m) along its own axes.
    Box {
        /// Half the box's size along x, y and z, in m.
        half_extents: DVec3,
    },
    /// The points within `radius` of the segment from `a` to `b` (m, in the
    /// collider's frame).
    Capsule {
        /// One end of the axis.
        a: DVec3,
        /// The other end.
        b: DVec3,
        /// Radius in m.
        radius: f64,
    },
    /// A closed triangle mesh, outward normals by its winding.
    Mesh(Arc<ColliderMesh>),
}

impl Shape {
    /// The shape's name in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Sphere { .. } => "sphere",
            Self::Box { .. } => "box",
            Self::Capsule { .. } => "capsule",
            Self::Mesh(_) => "mesh",
        }
    }

    /// The radius (m) of a ball about the frame's origin that holds the shape.
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Self::Sphere { radius } => *radius,
            Self::Box { half_extents } => half_extents.length(),
            Self::Capsule { a, b, radius } => a.length().max(b.length()) + radius,
            Self::Mesh(mesh) => mesh.bounding_radius(),
        }
    }

    /// A box on the world's axes that holds the shape turned by `rotation`: its
    /// least and greatest corners (m) as offsets from the frame's origin.
    pub fn bounds(&self, rotation: DQuat) -> (DVec3, DVec3) {
        // The half extents on the world's axes of a box of half extents `h`.
        let turned = |h: DVec3| {
            let m = DMat3::from_quat(rotation);
            m.x_axis.abs() * h.x + m.y_axis.abs() * h.y + m.z_axis.abs() * h.z
        };
        let about = |centre: DVec3, half: DVec3| (centre - half, centre + half);
        match self {
            Self::Sphere { radius } => about(DVec3::ZERO, DVec3::splat(*radius)),
            Self::Box { half_extents } => about(DVec3::ZERO, turned(*half_extents)),
            Self::Capsule { a, b, radius } => {
                let (a, b) = (rotation * *a, rotation * *b);
                (a.min(b) - *radius, a.max(b) + *radius)
            }
            Self::Mesh(mesh) => {
                let (lo, hi) = mesh.bounds();
                about(rotation * (0.5 * (lo + hi)), turned(0.5 * (hi - lo)))
            }
        }
    }

    /// The shape's smallest half size (m): how far it may move in a step without a
    /// particle on one side ending up past its middle.
    pub fn smallest_half_size(&self) -> f64 {
        match self {
            Self::Sphere { radius } | Self::Capsule { radius, .. } => *radius,
            Self::Box { half_extents } => half_extents.min_element(),
            Self::Mesh(mesh) => mesh.smallest_half_size(),
        }
    }

    /// The signed distance (m) of `p` (in the shape's frame) from its surface,
    /// negative inside, and the outward unit normal there, when `p` is closer to
    /// the surface than `reach` outside it (anywhere inside for the analytic
    /// shapes; within `reach` of the surface for a mesh).
    pub fn surface(&self, p: DVec3, reach: f64) -> Option<(f64, DVec3)> {
        let (distance, normal) = self.surface_lanes(V3::from(p), true, reach);
        (distance < reach).then(|| (distance, normal.into()))
    }

    /// [`Self::surface`] of a block of points, for the lanes `near` says (the
    /// others' answers are not read): the distance, or infinity for a mesh's
    /// lane that it does not reach, and the normal.
    #[inline(always)]
    pub(crate) fn surface_lanes<T: Lanes>(
        &self,
        p: V3<T>,
        near: T::Mask,
        reach: f64,
    ) -> (T, V3<T>) {
        match self {
            Self::Sphere { radius } => shapes::sphere(p, *radius),
            Self::Box { half_extents } => shapes::cuboid(p, *half_extents),
            Self::Capsule { a, b, radius } => shapes::capsule(p, (*a, *b), *radius),
            Self::Mesh(mesh) => mesh_lanes(mesh, p, near, reach),
        }
    }
}

/// [`Shape::surface_lanes`] of a mesh: triangles are not lanes, so each lane's
/// query on its own (out of line, to leave the analytic shapes' code its
/// registers).
#[inline(never)]
fn mesh_lanes<T: Lanes>(mesh: &ColliderMesh, p: V3<T>, near: T::Mask, reach: f64) -> (T, V3<T>) {
    let mut distance = p.x.splat(f64::INFINITY);
    let mut normal = V3::splat(p.x, DVec3::Y);
    for i in (0..T::WIDTH).filter(|&i| T::lane_says(near, i)) {
        let at = DVec3::new(p.x.lane(i), p.y.lane(i), p.z.lane(i));
        if let Some((d, n)) = mesh.surface(at, reach) {
            distance = distance.with_lane(i, d);
            normal = V3 {
                x: normal.x.with_lane(i, n.x),
                y: normal.y.with_lane(i, n.y),
                z: normal.z.with_lane(i, n.z),
            };
        }
    }
    (distance, normal)
}

/// A solid at a pose, moving at constant velocity and angular velocity from the
/// time the pose was set.
#[derive(Clone, Debug, PartialEq)]
pub struct Collider {
    /// Its geometry.
    pub shape: Shape,
    /// Where its frame's origin is (m) at time [`Self::since`].
    pub center: DVec3,
    /// Its orientation at time [`Self::since`].
    pub rotation: DQuat,
    /// Velocity of its centre in m/s.
    pub velocity: DVec3,
    /// Angular velocity in rad/s about its centre, on the world's axes.
    pub angular_velocity: DVec3,
    /// The simulated time (s) at which it is at `center` and `rotation`.
    pub since: f64,
    /// Coulomb friction coefficient μ between it and the cloth.
    pub friction: f64,
    /// How far outside its surface the cloth rests, m.
    pub thickness: f64,
}

/// Where a collider is at one time: its centre, its orientation and the
/// orientation's inverse, worked out once a step for all the particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Centre in m.
    pub center: DVec3,
    /// Orientation.
    pub rotation: DQuat,
    /// Its inverse, from the world's axes to the collider's.
    pub inverse: DQuat,
}

/// The poses of `colliders` at time `t` into `out` (which allocates only when
/// the number of colliders grows).
pub fn poses_at(colliders: &[Collider], t: f64, out: &mut Vec<Pose>) {
    out.clear();
    out.extend(colliders.iter().map(|c| c.pose(t)));
}

/// A point's contact with a collider: how deep it is within the contact surface,
/// the outward normal, and the velocity of the solid there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touch {
    /// Depth (m) within the contact surface, positive.
    pub depth: f64,
    /// Outward unit normal.
    pub normal: DVec3,
    /// Velocity (m/s) of the solid's material at the point.
    pub surface_velocity: DVec3,
}

/// [`Touch`] for a block of points: its fields in the lanes `touched` says (a
/// depth of 0 in the others).
#[derive(Clone, Copy)]
pub(crate) struct Touches<T: Lanes> {
    pub touched: T::Mask,
    pub depth: T,
    pub normal: V3<T>,
    pub surface_velocity: V3<T>,
}

impl Collider {
    /// A collider of `shape` at rest at `center`, unrotated, with friction μ and
    /// contact `thickness` (m).
    pub fn at_rest(shape: Shape, center: DVec3, friction: f64, thickness: f64) -> Self {
        Self {
            shape,
            center,
            rotation: DQuat::IDENTITY,
            velocity: DVec3::ZERO,
            angular_velocity: DVec3::ZERO,
            since: 0.0,
            friction,
            thickness,
        }
    }

    /// Its centre and orientation at time `t` (s).
    pub fn pose_at(&self, t: f64) -> (DVec3, DQuat) {
        let elapsed = t - self.since;
        let turn = DQuat::from_scaled_axis(self.angular_velocity * elapsed);
        (self.center + self.velocity * elapsed, turn * self.rotation)
    }

    /// Its [`Pose`] at time `t` (s).
    pub fn pose(&self, t: f64) -> Pose {
        let (center, rotation) = self.pose_at(t);
        Pose {
            center,
            rotation,
            inverse: rotation.inverse(),
        }
    }

    /// Whether it moves.
    pub fn moves(&self) -> bool {
        self.velocity != DVec3::ZERO || self.angular_velocity != DVec3::ZERO
    }

    /// The fastest a point of its surface moves (m/s).
    pub fn surface_speed(&self) -> f64 {
        self.velocity.length() + self.angular_velocity.length() * self.shape.bounding_radius()
    }

    /// The fastest its surface may move at step `dt` without passing through a
    /// particle in one step: half its smallest half size (with the thickness) per
    /// step.
    pub fn speed_limit(&self, dt: f64) -> f64 {
        0.5 * (self.shape.smallest_half_size() + self.thickness) / dt
    }

    /// Moves it to `center` at time `t`, keeping its orientation then, and gives
    /// it `velocity` (m/s) from then on.
    pub fn move_to(&mut self, center: DVec3, velocity: DVec3, t: f64) {
        let (_, rotation) = self.pose_at(t);
        (self.center, self.rotation, self.velocity, self.since) = (center, rotation, velocity, t);
    }

    /// The contact of a point at `x` (m) at time `t`, if it is within the contact
    /// surface.
    pub fn touch(&self, x: DVec3, t: f64) -> Option<Touch> {
        self.touch_at(&self.pose(t), x)
    }

    /// A box on the world's axes (its least and greatest corners, m) outside
    /// which no point touches it at `pose` ([`Self::touch_at`] is `None`): the
    /// shape's bounds grown by the thickness, and by a billionth of their size
    /// for the rounding of the turn.
    pub fn bounds_at(&self, pose: &Pose) -> (DVec3, DVec3) {
        let (lo, hi) = self.shape.bounds(pose.rotation);
        let size = (hi - lo).max_element() + pose.center.abs().max_element();
        let grow = DVec3::splat(self.thickness + 1e-9 * (1.0 + size));
        (pose.center + lo - grow, pose.center + hi + grow)
    }

    /// [`Self::touch`] with the collider at `pose`.
    #[inline]
    pub fn touch_at(&self, pose: &Pose, x: DVec3) -> Option<Touch> {
        self.touches(pose, V3::from(x)).map(|t| Touch {
            depth: t.depth,
            normal: t.normal.into(),
            surface_velocity: t.surface_velocity.into(),
        })
    }

    /// [`Self::touch_at`] of a block of points `x` (m): `None` when none touches.
    #[inline(always)]
    pub(crate) fn touches<T: Lanes>(&self, pose: &Pose, x: V3<T>) -> Option<Touches<T>> {
        let like = x.x;
        let offset = x - V3::splat(like, pose.center);
        let reach = self.shape.bounding_radius() + self.thickness;
        let near = offset.dot(offset).lt(like.splat(reach * reach));
        if !T::any(near) {
            return None;
        }
        let local = offset.rotated(pose.inverse);
        let (distance, normal) = self.shape.surface_lanes(local, near, self.thickness);
        let depth = like.splat(self.thickness) - distance;
        let touched = T::both(near, depth.gt(like.splat(0.0)));
        if !T::any(touched) {
            return None;
        }
        let spin = V3::splat(like, self.angular_velocity).cross(offset);
        Some(Touches {
            touched,
            depth: T::select(touched, depth, like.splat(0.0)),
            normal: normal.rotated(pose.rotation),
            surface_velocity: V3::splat(like, self.velocity) + spin,
        })
    }

    /// How far (m) along the ray from `origin` in unit direction `dir` it first
    /// meets the solid at time `t`, within `max` m: marched in steps of a quarter
    /// of its smallest half size (for picking with the mouse, not for contact).
    pub fn ray_hit(&self, origin: DVec3, dir: DVec3, t: f64, max: f64) -> Option<f64> {
        let (center, rotation) = self.pose_at(t);
        let radius = self.shape.bounding_radius();
        // Only the part of the ray within its bounding ball.
        let along = (center - origin).dot(dir);
        let miss2 = (center - origin).length_squared() - along * along;
        if miss2 > radius * radius || !along.is_finite() {
            return None;
        }
        let half = (radius * radius - miss2).sqrt();
        let (from, to) = ((along - half).max(0.0), (along + half).min(max));
        let step = (0.25 * self.shape.smallest_half_size()).max(1e-4);
        let inverse = rotation.inverse();
        let mut s = from;
        while s <= to {
            let local = inverse * (origin + dir * s - center);
            if self
                .shape
                .surface(local, 0.0)
                .is_some_and(|(d, _)| d <= 0.0)
            {
                return Some(s);
            }
            s += step;
        }
        None
    }

    /// A ball (centre, radius in m) that holds its contact surface over the time
    /// from `t0` to `t1`.
    pub fn reach(&self, t0: f64, t1: f64) -> (DVec3, f64) {
        let (a, _) = self.pose_at(t0);
        let (b, _) = self.pose_at(t1);
        let radius = self.shape.bounding_radius() + self.thickness;
        (0.5 * (a + b), radius + 0.5 * (b - a).length())
    }
}

#[cfg(test)]
mod tests;
