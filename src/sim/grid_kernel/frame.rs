//! Fixed-point positions ([`super::Precision::Mixed`]): a coordinate `q` (m) is kept
//! as the 32-bit integer `n = round((q - centre) / unit)` in the bits of a float32,
//! in a frame that follows the body (a cloth or a lattice).
//!
//! * A spring's `d` is an integer subtraction, exact, then one conversion to float
//!   (good to `2^-24` of the spring's own length, as float32 arithmetic on `d`
//!   is anyway); `x += h v` adds the move rounded to a whole unit. The unit is
//!   folded into the constants (a spring's `k`, the drag's `ρ C_d`, the step's `h /
//!   unit`), so the kernels' arithmetic is the same code in units as in metres.
//! * The rounding of each move, at most half a unit, is the only noise fixed point
//!   adds; [`fixed_unit`] picks the unit from the body's size (roomy, or as fine
//!   as the body allows where the roomy unit's noise is too much) and
//!   [`super::Precision::spring_noise`] counts it. A constraint's or a collider's
//!   move is rounded likewise, but the velocity gets the move as computed, so that
//!   the part under half a unit reaches the position at the next step (rounded
//!   away, it would be a dead zone: XPBD's small corrections were lost whole).
//! * Particles are kept within `RANGE` units of the centre (just under half the
//!   integers' range) and colliders' coordinates within `COLLIDER_RANGE` (half),
//!   so that the difference of any two coordinates, or of a coordinate and a
//!   collider's, is exact. Every `CHECK_STEPS` steps the kernels check that the
//!   particles, moved as far as their speed takes them in those steps, stay inside;
//!   if not, `Frame::fitting` recentres the frame on them (a shift by whole
//!   units, exact) or, when they spread wider than the range, doubles the unit
//!   until they fit. An unrepresentable collider (a ground or sphere so far off
//!   that no particle can reach it) is left out of the frame's constants.
//!
//! Float32 and float64 positions use the identity frame (`Frame::FLOAT`): the
//! same code, in metres.

use glam::DVec3;

use super::Real;
use crate::sim::{Ground, Sphere};

/// Steps between the kernels' checks that the particles stay in range: each
/// check makes room for this many steps' moves at the particles' top speed.
pub(super) const CHECK_STEPS: usize = 32;

/// Particles stay within this many units of the centre: just under half the
/// integers' range, so that the difference of two of them (under `2 RANGE`) or of
/// one and a collider's coordinate (under `RANGE + COLLIDER_RANGE`) is exact in 32
/// bits (`the_ranges_keep_every_difference_exact`).
pub(super) const RANGE: f64 = ((1u64 << 30) - (1u64 << 25)) as f64;

/// Half the range of the integers: colliders' coordinates are kept within this
/// many units of the centre (a ground below it is stored at it, still below every
/// particle), so that a particle's coordinate less a collider's never overflows.
pub(super) const COLLIDER_RANGE: f64 = (1u64 << 30) as f64;

// A ground stored at `-COLLIDER_RANGE` is below every particle; a particle and a
// collider differ by under `RANGE + COLLIDER_RANGE`, under 2^31, and so two
// particles do (under `2 RANGE`).
const _: () = {
    assert!(COLLIDER_RANGE > RANGE);
    assert!(RANGE + COLLIDER_RANGE < (1u64 << 31) as f64);
};

/// A quarter of the integers' range: the roomy unit holds the body within this
/// many units of the centre and leaves it as far again to spread.
const ROOMY_RANGE: f64 = (1u64 << 29) as f64;

/// How far a body on a tight unit may spread, as a multiple of its radius, before
/// the frame doubles its unit.
const TIGHT_ROOM: f64 = 1.125;

/// The unit (m, a power of two) of fixed-point positions for a body of radius
/// `extent` (m) whose acceleration noise at a unit is `noise(unit)` (m/s²,
/// [`super::Precision::spring_noise`]): the roomy unit, the finest with
/// `ROOMY_RANGE` units at least twice the extent (the body, and as far again to
/// spread before the frame widens), where its noise is under the limit; else the
/// tight one, the finest with `RANGE` units at least `TIGHT_ROOM` times the extent,
/// 2 to 4 times finer. (The 32³ jelly at k = 2,000 N/m: 0.1188 m/s² at its roomy
/// 2^-23 m, 0.0956 at its tight 2^-25 m, under the limit of 0.0981.) A power of
/// two, so that the same body moved by a multiple of it (any whole number of metres
/// where the unit is finer than 1 m) is stored as the same integers and steps the
/// same.
pub fn fixed_unit(extent: f64, noise: impl Fn(f64) -> f64) -> f64 {
    let roomy = finest_unit(2.0 * extent, ROOMY_RANGE);
    if noise(roomy) <= super::Precision::NOISE_LIMIT {
        roomy
    } else {
        finest_unit(TIGHT_ROOM * extent, RANGE)
    }
}

/// The finest power of two `u` with `units u >= length` (m; at least 1 mm).
fn finest_unit(length: f64, units: f64) -> f64 {
    let wanted = length.abs().max(1e-3) / units;
    2f64.powi(wanted.log2().ceil() as i32)
}

/// The fixed-point coordinate of `n` units (a whole number), clamped to the
/// integers' range.
#[inline]
pub(super) fn whole_units<E: Real>(n: f64) -> E {
    E::fixed_from(n.clamp(-2.0 * COLLIDER_RANGE + 1.0, 2.0 * COLLIDER_RANGE - 1.0) as i64)
}

/// What a kernel's spec asks of its positions' frame: fixed point or floats, the
/// unit ([`fixed_unit`] of the body's radius and noise), and the colliders it must
/// hold.
#[derive(Clone, Copy, Debug)]
pub(super) struct FrameRule<'a> {
    pub(super) fixed: bool,
    pub(super) unit: f64,
    pub(super) ground: Option<&'a Ground>,
    pub(super) sphere: Option<&'a Sphere>,
}

impl FrameRule<'_> {
    /// The frame for positions in the box `bounds` (m) grown by `margin` (m):
    /// [`Frame::FLOAT`] for floats, else [`Frame::fitting`] (`None` if none fits).
    pub(super) fn frame(&self, bounds: ([f64; 3], [f64; 3]), margin: f64) -> Option<Frame> {
        if !self.fixed {
            return Some(Frame::FLOAT);
        }
        Frame::fitting(self.unit, bounds, margin, self.ground, self.sphere)
    }

    /// The frame to move fixed-point positions `x` (with velocities `v`, real
    /// particles at the indices `rows`) to, so that they stay in range for `time`
    /// s more at their top speed: `None` while `frame` holds them at the rule's
    /// unit (or they fit in no frame).
    pub(super) fn refit<E: Real>(
        &self,
        frame: &Frame,
        (x, v): ([&[E]; 3], [&[E]; 3]),
        rows: impl Iterator<Item = std::ops::Range<usize>>,
        time: f64,
    ) -> Option<Frame> {
        if !frame.fixed {
            return None;
        }
        let (bounds, speed) = span(frame, x, v, rows);
        let margin = speed * time;
        if frame.unit == self.unit && frame.holds(bounds, margin) {
            return None;
        }
        self.frame(bounds, margin).filter(|new| new != frame)
    }
}

/// How a kernel's position arrays map to metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Frame {
    /// Fixed-point positions (else floats in metres, with `centre` 0 and `unit` 1).
    pub(super) fixed: bool,
    /// The point (m) stored as 0.
    pub(super) centre: [f64; 3],
    /// Metres per unit.
    pub(super) unit: f64,
}

impl Frame {
    /// Float positions in metres.
    pub(super) const FLOAT: Frame = Frame {
        fixed: false,
        centre: [0.0; 3],
        unit: 1.0,
    };

    /// Coordinate `axis` of `q` (m) as stored, clamped to the integers' range.
    #[inline]
    pub(super) fn encode<E: Real>(&self, q: f64, axis: usize) -> E {
        if self.fixed {
            whole_units(((q - self.centre[axis]) / self.unit).round())
        } else {
            E::of(q)
        }
    }

    /// Coordinate `axis` (m) of a stored value.
    #[inline]
    pub(super) fn decode<E: Real>(&self, p: E, axis: usize) -> f64 {
        if self.fixed {
            p.fixed_value() * self.unit + self.centre[axis]
        } else {
            p.f64()
        }
    }

    /// A length (m) in the frame's units.
    pub(super) fn units(&self, length: f64) -> f64 {
        length / self.unit
    }

    /// The fixed-point frame with the finest unit from `unit` up (doubling) in
    /// which the box `lo ..= hi` (m), grown by `margin` (m) on every side, lies
    /// within [`RANGE`] units of its centre, and the colliders that particles in
    /// it can reach are representable (a ground or a sphere's centre within the
    /// range). `None` when nothing fits (a non-finite box).
    pub(super) fn fitting(
        unit: f64,
        (lo, hi): ([f64; 3], [f64; 3]),
        margin: f64,
        ground: Option<&Ground>,
        sphere: Option<&Sphere>,
    ) -> Option<Frame> {
        let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
        let half = (0..3).map(|a| 0.5 * (hi[a] - lo[a])).fold(0.0, f64::max) + margin.max(0.0);
        if !(half.is_finite() && centre.iter().all(|c| c.is_finite())) {
            return None;
        }
        let mut unit = unit;
        // Whole units of the old unit: a recentring keeps every position exact.
        loop {
            let frame = Frame {
                fixed: true,
                centre: centre.map(|c| (c / unit).round() * unit),
                unit,
            };
            let (reach, colliders) = (RANGE * unit, COLLIDER_RANGE * unit);
            let ground_ok = ground.is_none_or(|g| g.height - frame.centre[1] <= colliders);
            let sphere_ok = sphere.is_none_or(|s| {
                let far = (0..3).any(|a| (s.center[a] - frame.centre[a]).abs() - s.radius > reach);
                far || (0..3).all(|a| (s.center[a] - frame.centre[a]).abs() <= colliders)
            });
            if half + unit <= reach && ground_ok && sphere_ok {
                return Some(frame);
            }
            unit *= 2.0;
            if unit > 1e30 {
                return None;
            }
        }
    }

    /// Whether the box `lo ..= hi` (m) grown by `margin` stays in range.
    pub(super) fn holds(&self, (lo, hi): ([f64; 3], [f64; 3]), margin: f64) -> bool {
        let reach = RANGE * self.unit - margin.max(0.0) - self.unit;
        (0..3).all(|a| lo[a] - self.centre[a] >= -reach && hi[a] - self.centre[a] <= reach)
    }

    /// The ground's height as stored: below every particle the frame holds when
    /// it lies further below ([`COLLIDER_RANGE`]).
    pub(super) fn ground_height<E: Real>(&self, height: f64) -> E {
        if self.fixed {
            let lowest = self.centre[1] - COLLIDER_RANGE * self.unit;
            self.encode(height.max(lowest), 1)
        } else {
            E::of(height)
        }
    }

    /// A sphere's centre as stored, its radius and squared radius in units, or
    /// `None` where no particle in range can reach it.
    pub(super) fn sphere<E: Real>(&self, sphere: &Sphere) -> Option<([E; 3], E, E)> {
        let reach = RANGE * self.unit;
        let c = sphere.center;
        if self.fixed && (0..3).any(|a| (c[a] - self.centre[a]).abs() - sphere.radius > reach) {
            return None;
        }
        let r = self.units(sphere.radius);
        Some((
            std::array::from_fn(|a| self.encode(c[a], a)),
            E::of(r),
            E::of(r * r),
        ))
    }

    /// Positions (m) of `at` as a vector.
    pub(super) fn decode3<E: Real>(&self, x: &[&[E]; 3], at: usize) -> DVec3 {
        DVec3::new(
            self.decode(x[0][at], 0),
            self.decode(x[1][at], 1),
            self.decode(x[2][at], 2),
        )
    }
}

/// Whether fixed-point positions of `unit` (m) hold `points` again with a tenth of
/// their range to spare, and the colliders beside them: a kernel built for them
/// now would keep that unit rather than doubling it. (The spare keeps a body that
/// has just drawn back in from outgrowing the unit again at once.)
pub(crate) fn holds_again(
    unit: f64,
    points: &[DVec3],
    ground: Option<&Ground>,
    sphere: Option<&Sphere>,
) -> bool {
    let spare = 0.1 * RANGE * unit;
    Frame::fitting(unit, bounds(points), spare, ground, sphere).is_some_and(|f| f.unit == unit)
}

/// The bounding box (m) of `points`.
pub(super) fn bounds(points: &[DVec3]) -> ([f64; 3], [f64; 3]) {
    let (lo, hi) = (points.iter()).fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &q| {
        (lo.min(q), hi.max(q))
    });
    (lo.into(), hi.into())
}

/// The bounding box (m) of the particles at the indices `rows` of the position
/// arrays `x` in `frame`, and their largest speed (m/s) in `v`: non-finite when
/// any velocity is.
pub(super) fn span<E: Real>(
    frame: &Frame,
    x: [&[E]; 3],
    v: [&[E]; 3],
    rows: impl Iterator<Item = std::ops::Range<usize>>,
) -> (([f64; 3], [f64; 3]), f64) {
    #[cfg(target_arch = "x86_64")]
    if super::SimdLevel::detect() >= super::SimdLevel::Avx2 {
        // SAFETY: the CPU has AVX2 (the level needs it).
        return unsafe { span_avx2(frame, x, v, rows) };
    }
    span_in(frame, x, v, rows)
}

/// [`span`] compiled for AVX2: the scans in 256-bit vectors (compiled for the
/// baseline, they were 1.6-2% of a one-core drape at 128, `perf record`).
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn span_avx2<E: Real>(
    frame: &Frame,
    x: [&[E]; 3],
    v: [&[E]; 3],
    rows: impl Iterator<Item = std::ops::Range<usize>>,
) -> (([f64; 3], [f64; 3]), f64) {
    span_in(frame, x, v, rows)
}

/// [`span`], for the caller's target features.
#[inline(always)]
fn span_in<E: Real>(
    frame: &Frame,
    x: [&[E]; 3],
    v: [&[E]; 3],
    rows: impl Iterator<Item = std::ops::Range<usize>>,
) -> (([f64; 3], [f64; 3]), f64) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let (mut speed2, mut nan) = (E::ZERO, false);
    for row in rows {
        for a in 0..3 {
            let xs = &x[a][row.clone()];
            let (l, h) = if frame.fixed {
                let (l, h) = E::fixed_range(xs);
                (l as f64, h as f64)
            } else {
                let bounds = (f64::INFINITY, f64::NEG_INFINITY);
                xs.iter()
                    .fold(bounds, |(l, h), p| (l.min(p.f64()), h.max(p.f64())))
            };
            lo[a] = lo[a].min(l);
            hi[a] = hi[a].max(h);
        }
        let (vx, vy, vz) = (&v[0][row.clone()], &v[1][row.clone()], &v[2][row]);
        let (vy, vz) = (&vy[..vx.len()], &vz[..vx.len()]);
        // Squared speeds in the kernel's float, a vector compare and select each
        // (`max` of floats, with its rule for NaN, is not one).
        for i in 0..vx.len() {
            let s = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
            nan |= s.is_nan();
            speed2 = if s > speed2 { s } else { speed2 };
        }
    }
    let to_m = |n: f64, a: usize| {
        if frame.fixed {
            n * frame.unit + frame.centre[a]
        } else {
            n
        }
    };
    let lo = std::array::from_fn(|a| to_m(lo[a], a));
    let hi = std::array::from_fn(|a| to_m(hi[a], a));
    let speed = if nan {
        f64::INFINITY
    } else {
        speed2.f64().sqrt()
    };
    ((lo, hi), speed)
}

/// Re-encodes the coordinates of `x` at the indices `rows` from `old` to `new`
/// and sets every other entry (ghosts) to `new`'s 0.
pub(super) fn reencode<E: Real>(
    old: &Frame,
    new: &Frame,
    x: [&mut [E]; 3],
    rows: impl Iterator<Item = std::ops::Range<usize>> + Clone,
) {
    for (a, x) in x.into_iter().enumerate() {
        let mut next = 0;
        for row in rows.clone() {
            x[next..row.start].fill(E::fixed_from(0));
            for p in &mut x[row.clone()] {
                *p = new.encode(old.decode(*p, a), a);
            }
            next = row.end;
        }
        let len = x.len();
        x[next..len].fill(E::fixed_from(0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The roomy unit leaves twice the extent in a quarter of the range, and no
    /// more than four times; the tight one, taken where the roomy one's noise is
    /// over the limit, leaves `TIGHT_ROOM` times the extent in `RANGE`, and no more
    /// than twice that.
    #[test]
    fn the_unit_leaves_room_for_the_body_and_as_much_again() {
        for extent in [0.01, 0.7, 1.0, 3.3, 26.85, 250.0] {
            let room = ROOMY_RANGE * fixed_unit(extent, |_| 0.0);
            assert!(
                room >= 2.0 * extent && room < 4.0 * extent,
                "{extent}: {room}"
            );
            let tight = fixed_unit(extent, |_| 1.0);
            let room = RANGE * tight;
            assert!(
                room >= TIGHT_ROOM * extent && room < 2.0 * TIGHT_ROOM * extent,
                "{extent}: {room}"
            );
            assert!(tight < fixed_unit(extent, |_| 0.0));
        }
        // The noise is asked at the roomy unit: the tight one only where it is over.
        let roomy = fixed_unit(1.0, |_| 0.0);
        let over_at_roomy = |u: f64| if u < roomy { 0.0 } else { 1.0 };
        assert_eq!(fixed_unit(1.0, over_at_roomy), fixed_unit(1.0, |_| 1.0));
        assert_eq!(
            fixed_unit(1.0, |u| if u > roomy { 1.0 } else { 0.0 }),
            roomy
        );
    }

    /// The 32-bit wrapping difference of the extreme coordinates, two particles'
    /// (within `RANGE` of the centre) or a particle's and a collider's (within
    /// `COLLIDER_RANGE`), is exact.
    #[test]
    fn the_ranges_keep_every_difference_exact() {
        let (p, c) = (RANGE as i64, COLLIDER_RANGE as i64);
        for (a, b) in [(p, -p), (-p, p), (p, -c), (-p, c)] {
            let wrapped = (a as i32).wrapping_sub(b as i32);
            assert_eq!(i64::from(wrapped), a - b, "{a} - {b}");
        }
    }

    /// Encoding rounds to the nearest unit, and a recentred frame keeps every
    /// coordinate exactly.
    #[test]
    fn a_recentred_frame_keeps_positions_exact() {
        let unit = fixed_unit(2.0, |_| 0.0);
        let frame = Frame::fitting(unit, ([-1.0; 3], [1.0; 3]), 0.0, None, None).unwrap();
        let q = 0.123_456_789;
        let p: f32 = frame.encode(q, 0);
        assert!((frame.decode(p, 0) - q).abs() <= 0.5 * unit);
        let moved = Frame::fitting(unit, ([-0.5; 3], [2.5; 3]), 0.0, None, None).unwrap();
        assert_ne!(moved.centre, frame.centre);
        let mut x = [vec![p; 4], vec![p; 4], vec![p; 4]];
        let [a, b, c] = &mut x;
        reencode(&frame, &moved, [a, b, c], std::iter::once(1..3));
        assert_eq!(moved.decode(x[0][1], 0), frame.decode(p, 0));
        assert_eq!(x[0][0].fixed_value(), 0.0);
    }
}
