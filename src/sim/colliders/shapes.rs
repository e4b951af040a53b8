//! The analytic shapes' signed distances and outward normals, in their own
//! frames: negative inside, the normal that of the nearest surface point.

use glam::DVec3;

use crate::sim::laws::EPSILON_LENGTH;

/// A ball of `radius` about the origin; straight up from the centre.
pub(super) fn sphere(p: DVec3, radius: f64, reach: f64) -> Option<(f64, DVec3)> {
    let dist = p.length();
    let distance = dist - radius;
    (distance < reach).then(|| {
        let normal = if dist > EPSILON_LENGTH {
            p / dist
        } else {
            DVec3::Y
        };
        (distance, normal)
    })
}

/// A box of half extents `half` about the origin. Outside, the nearest point is
/// the clamped one; inside, the nearest face's, whose axis is the one with the
/// least room.
pub(super) fn cuboid(p: DVec3, half: DVec3, reach: f64) -> Option<(f64, DVec3)> {
    let q = p.abs() - half;
    if q.max_element() >= reach {
        return None;
    }
    let outside = q.max(DVec3::ZERO);
    let out = outside.length();
    if out > 0.0 {
        if out >= reach {
            return None;
        }
        let normal = (outside * p.signum()) / out;
        return Some((out, normal));
    }
    // Inside: the face with the least room (x before y before z on ties).
    let axis = if q.x >= q.y && q.x >= q.z {
        0
    } else if q.y >= q.z {
        1
    } else {
        2
    };
    let mut normal = DVec3::ZERO;
    normal[axis] = if p[axis] < 0.0 { -1.0 } else { 1.0 };
    Some((q[axis], normal))
}

/// The points within `radius` of the segment `a`–`b`: a ball about the segment's
/// point nearest to `p`.
pub(super) fn capsule(
    p: DVec3,
    (a, b): (DVec3, DVec3),
    radius: f64,
    reach: f64,
) -> Option<(f64, DVec3)> {
    sphere(p - nearest_on_segment(p, a, b), radius, reach)
}

/// The point of the segment `a`–`b` nearest to `p` (`a` for a segment of no length).
pub(super) fn nearest_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= EPSILON_LENGTH * EPSILON_LENGTH {
        return a;
    }
    let s = ((p - a).dot(ab) / len2).clamp(0.0, 1.0);
    a + s * ab
}
