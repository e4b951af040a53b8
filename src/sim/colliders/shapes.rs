//! The analytic shapes' signed distances and outward normals, in their own
//! frames, for one point or a block of them ([`Lanes`]): negative inside, the
//! normal that of the nearest surface point. Branches are per-lane selects, so a
//! lane gets exactly what the point alone gets.

use glam::DVec3;

use crate::sim::lanes::{Lanes, V3};
use crate::sim::laws::EPSILON_LENGTH;

/// A ball of `radius` about the origin; straight up from the centre.
#[inline(always)]
pub(super) fn sphere<T: Lanes>(p: V3<T>, radius: f64) -> (T, V3<T>) {
    let like = p.x;
    let dist = p.length();
    let away = dist.gt(like.splat(EPSILON_LENGTH));
    let normal = V3::select(
        away,
        p.scale(like.splat(1.0) / dist),
        V3::splat(like, DVec3::Y),
    );
    (dist - like.splat(radius), normal)
}

/// A box of half extents `half` about the origin. Outside, the nearest point is
/// the clamped one; inside, the nearest face's, whose axis is the one with the
/// least room (x before y before z on ties).
#[inline(always)]
pub(super) fn cuboid<T: Lanes>(p: V3<T>, half: DVec3) -> (T, V3<T>) {
    let like = p.x;
    let (zero, one) = (like.splat(0.0), like.splat(1.0));
    let q = p.zip(V3::splat(like, half), |p, h| p.abs() - h);
    let outside = q.zip(V3::splat(like, DVec3::ZERO), T::max);
    let out = outside.length();
    let sign = p.zip(p, |p, _| p.sign());
    let out_normal = outside.zip(sign, |o, s| o * s).scale(one / out);
    // Inside: the face with the least room.
    let x_face = T::both(q.y.le(q.x), q.z.le(q.x));
    let y_face = q.z.le(q.y);
    let in_distance = T::select(x_face, q.x, T::select(y_face, q.y, q.z));
    let nx = T::select(x_face, one, zero);
    let ny = T::select(x_face, zero, T::select(y_face, one, zero));
    let face = V3 {
        x: nx,
        y: ny,
        z: one - nx - ny,
    };
    let in_normal = face.zip(sign, |n, s| n * s);
    let is_out = out.gt(zero);
    (
        T::select(is_out, out, in_distance),
        V3::select(is_out, out_normal, in_normal),
    )
}

/// The points within `radius` of the segment `a`–`b`: a ball about the segment's
/// point nearest to `p`.
#[inline(always)]
pub(super) fn capsule<T: Lanes>(p: V3<T>, (a, b): (DVec3, DVec3), radius: f64) -> (T, V3<T>) {
    sphere(p - nearest_on_segment(p, a, b), radius)
}

/// The point of the segment `a`–`b` nearest to `p` (`a` for a segment of no length).
#[inline(always)]
pub(super) fn nearest_on_segment<T: Lanes>(p: V3<T>, a: DVec3, b: DVec3) -> V3<T> {
    let like = p.x;
    let ab = b - a;
    let len2 = ab.length_squared();
    let a = V3::splat(like, a);
    if len2 <= EPSILON_LENGTH * EPSILON_LENGTH {
        return a;
    }
    let ab = V3::splat(like, ab);
    let s = (p - a).dot(ab) / like.splat(len2);
    let s = s.max(like.splat(0.0)).min(like.splat(1.0));
    a + ab.scale(s)
}
