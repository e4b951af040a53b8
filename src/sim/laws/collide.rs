//! Contact with the colliders of [`crate::sim::colliders`] (boxes, capsules,
//! meshes, moving spheres), one law for every shape and engine: a particle within
//! a collider's contact surface is pushed out along the normal by its depth, the
//! push over the step added to its velocity relative to the surface, and Coulomb
//! friction takes from that relative velocity along the surface up to μ times the
//! normal velocity the push gave (so a turning sphere twists the cloth and a
//! sliding box drags it, and μ = 0 does neither).

use glam::DVec3;

use super::contact::coulomb;
use super::{Lanes, V3};
use crate::sim::colliders::{Collider, Pose, Touch};

/// The colliders' contact of a free particle at `x` with velocity `v`, after a
/// step `h`, the colliders at `poses` (where they are at its end): each collider
/// in turn, in the order given. Returns the new position and velocity.
#[inline]
pub(crate) fn collide(
    colliders: &[Collider],
    poses: &[Pose],
    x: DVec3,
    v: DVec3,
    h: f64,
) -> (DVec3, DVec3) {
    let (mut x, mut v) = (x, v);
    for (collider, pose) in colliders.iter().zip(poses) {
        if let Some(touch) = collider.touch_at(pose, x) {
            (x, v) = pushed_out(x, v, &touch, collider.friction, h);
        }
    }
    (x, v)
}

/// A particle at `x` with velocity `v` pushed out of a collider it `touch`es,
/// with friction μ, after a step `h`.
pub(crate) fn pushed_out(
    x: DVec3,
    v: DVec3,
    touch: &Touch,
    friction: f64,
    h: f64,
) -> (DVec3, DVec3) {
    let push = touch.normal * touch.depth;
    let surface = V3::from(touch.surface_velocity);
    let relative = V3::from(v) - surface;
    let most = friction * touch.depth / h;
    let relative = contact_velocity(relative, V3::from(push), V3::from(touch.normal), h, most);
    (x + push, DVec3::from(relative + surface))
}

/// The velocity, relative to the surface, of a particle moving at `v` (relative
/// to it) that a contact pushed by `push` along unit `normal` over a step `h`:
/// the push's velocity added, then Coulomb friction removing up to `most` (m/s)
/// of the part along the surface (none when `most` is 0).
#[inline(always)]
pub(crate) fn contact_velocity<T: Lanes>(
    v: V3<T>,
    push: V3<T>,
    normal: V3<T>,
    h: T,
    most: T,
) -> V3<T> {
    let pushed = v + push.over(h);
    if T::all(most.le(most.splat(0.0))) {
        return pushed;
    }
    coulomb(pushed, normal, most)
}
