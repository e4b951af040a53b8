//! Contact with the colliders of [`crate::sim::colliders`] (boxes, capsules,
//! meshes, moving spheres), one law for every shape and engine: a particle within
//! a collider's contact surface is pushed out along the normal by its depth, the
//! push over the step added to its velocity relative to the surface, and Coulomb
//! friction takes from that relative velocity along the surface up to μ times the
//! normal velocity the push gave (so a turning sphere twists the cloth and a
//! sliding box drags it, and μ = 0 does neither).

use glam::DVec3;

use super::contact::coulomb;
use super::{Contact, Lanes, V3};
use crate::sim::colliders::{Collider, Pose, Touches};

/// The colliders' contact of free particles at `x` with velocities `v` (one, or
/// a block of them in lanes), after a step `h`, the colliders at `poses` (where
/// they are at its end): each collider in turn, in the order given. Returns the
/// new positions and velocities.
#[inline(always)]
pub(crate) fn collide<T: Lanes>(
    colliders: &[Collider],
    poses: &[Pose],
    x: V3<T>,
    v: V3<T>,
    h: f64,
) -> (V3<T>, V3<T>) {
    let (mut x, mut v) = (x, v);
    for (collider, pose) in colliders.iter().zip(poses) {
        if let Some(touch) = collider.touches(pose, x) {
            let (x_new, v_new) = pushed_out(x, v, &touch, collider.friction, h);
            x = V3::select(touch.touched, x_new, x);
            v = V3::select(touch.touched, v_new, v);
        }
    }
    (x, v)
}

/// A particle's contacts at the end of a step `h`, at `x` with velocity `v` (the
/// constraints' moves already in it): for a free particle (inverse mass `w >
/// 0`), the ground's and the scene sphere's `contact`, then the `colliders` at
/// `poses`. The f64 engine's pass after its constraints; the grid
/// kernel's passes call the same laws on blocks. Returns the new position and
/// velocity.
#[inline(always)]
pub(crate) fn end_of_step_contacts(
    contact: &Contact,
    (colliders, poses): (&[Collider], &[Pose]),
    (x, v): (DVec3, DVec3),
    w: f64,
    h: f64,
) -> (DVec3, DVec3) {
    if w <= 0.0 {
        return (x, v);
    }
    let (x, v) = if contact.is_active() {
        contact.resolve(x, v, w)
    } else {
        (x, v)
    };
    if colliders.is_empty() {
        return (x, v);
    }
    let (x, v) = collide(colliders, poses, V3::from(x), V3::from(v), h);
    (x.into(), v.into())
}

/// Particles at `x` with velocities `v` pushed out of a collider they `touch`,
/// with friction μ, after a step `h` (the lanes it does not touch come back at
/// rest, to be left out by the caller).
#[inline(always)]
pub(crate) fn pushed_out<T: Lanes>(
    x: V3<T>,
    v: V3<T>,
    touch: &Touches<T>,
    friction: f64,
    h: f64,
) -> (V3<T>, V3<T>) {
    let like = x.x;
    let push = touch.normal.scale(touch.depth);
    // Untouched lanes at rest (their depth is 0): friction's shortcut for a
    // block at rest on the surface is not lost to them.
    let still = V3::splat(like, DVec3::ZERO);
    let relative = V3::select(touch.touched, v - touch.surface_velocity, still);
    // Reciprocals of the step's constants: no division per particle.
    let per_h = like.splat(1.0 / h);
    let friction = (friction > 0.0).then(|| (touch.normal, like.splat(friction / h) * touch.depth));
    let relative = contact_velocity(relative, push, per_h, friction);
    (x + push, relative + touch.surface_velocity)
}

/// The velocity, relative to the surface, of a particle moving at `v` (relative
/// to it) that a contact pushed by `push` over a step of `1 / per_h`: the push's
/// velocity added, then, given the surface's unit normal and `most` (m/s),
/// Coulomb friction removing up to `most` of the part along the surface. The
/// response of every contact with a solid: the scene's sphere and the colliders.
#[inline(always)]
pub(crate) fn contact_velocity<T: Lanes>(
    v: V3<T>,
    push: V3<T>,
    per_h: T,
    friction: Option<(V3<T>, T)>,
) -> V3<T> {
    let pushed = v + push.scale(per_h);
    match friction {
        Some((normal, most)) => coulomb(pushed, normal, most),
        None => pushed,
    }
}
