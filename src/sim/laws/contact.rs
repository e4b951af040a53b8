//! Contact with the colliders, one particle per lane: a particle inside the
//! sphere is projected onto its surface (its move over the step `h` added to its
//! velocity), then Coulomb friction takes from the velocity along each surface
//! up to `μ` times the velocity the contact gave along its normal.
//!
//! The grid and lattice kernels run it on blocks of particles in their own
//! registers, the f64 engine on one particle: each lane computes
//! exactly what the `f64` version computes for its particle.

use glam::DVec3;

use super::collide::contact_velocity;
use super::forces::{DEGENERATE_LENGTH2, ground_support};
use super::{Lanes, V3};
use crate::sim::{Ground, Params, Sphere};

/// The colliders and their friction, as every engine resolves them after a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Contact {
    pub sphere: Option<Sphere>,
    pub ground: Option<Ground>,
    /// Coulomb coefficient μ of the sphere (the ground has its own).
    pub friction: f64,
    /// The step in s.
    pub dt: f64,
}

impl Contact {
    /// The colliders of `p`.
    pub fn of(p: &Params) -> Self {
        Self {
            sphere: p.sphere,
            ground: p.ground,
            friction: p.friction,
            dt: p.dt,
        }
    }

    /// Whether a step has contact to resolve after it: a sphere, or a ground with
    /// friction (the ground's push is its penalty force).
    pub fn is_active(&self) -> bool {
        self.sphere.is_some() || self.ground.is_some_and(|g| g.friction > 0.0)
    }

    /// Whether either collider has friction (the sphere's `friction`, the ground's
    /// own).
    pub fn has_friction(&self) -> bool {
        self.friction > 0.0 || self.ground.is_some_and(|g| g.friction > 0.0)
    }

    /// The contact of a free particle at `x` with velocity `v` (every other
    /// constraint's move already added to it) and inverse mass `w`, after a step
    /// `h`: the particle is projected out of the sphere, its move over the step
    /// added to its velocity; then Coulomb friction takes from the velocity along
    /// each surface up to μ times the velocity the contact gave along its normal in
    /// the step (the sphere's push over `h`; the ground's penalty impulse `h N w`),
    /// stopping the particle there when that is more. Returns the new position and
    /// velocity.
    ///
    /// Inlined: as a call it took `x` from the stack, where a caller that had just
    /// assembled it there in three stores stalled on the load.
    #[inline(always)]
    pub fn resolve(&self, x: DVec3, v: DVec3, w: f64) -> (DVec3, DVec3) {
        let near = Near {
            from_centre: V3::from(x - self.sphere.map_or(DVec3::ZERO, |s| s.center)),
            above_ground: x.y - self.ground.map_or(0.0, |g| g.height),
        };
        let (push, v) = self.resolve_lanes(near, V3::from(v), w);
        (x + DVec3::from(push), v.into())
    }

    /// [`Contact::resolve`] for one particle per lane (`f64`: one particle), given
    /// where each is as the colliders see it: returns each lane's move (0 where it
    /// does not move) and new velocity. A lane of a free particle gets exactly what
    /// `resolve` gives its particle; the caller leaves pinned particles (`w = 0`)
    /// alone.
    #[inline(always)]
    pub(crate) fn resolve_lanes<T: Lanes>(&self, at: Near<T>, v: V3<T>, w: T) -> (V3<T>, V3<T>) {
        let (push, v) = self.sphere_lanes(at.from_centre, v);
        (
            push,
            self.ground_friction_lanes(at.above_ground + push.y, v, w),
        )
    }

    /// The sphere's part of [`Contact::resolve_lanes`] for particles `d` from its
    /// centre: those inside are projected out, with friction. Returns their moves
    /// (0 elsewhere) and velocities; leaves `v` as it is, to the bit, where no lane
    /// is within the sphere's radius.
    #[inline(always)]
    fn sphere_lanes<T: Lanes>(&self, d: V3<T>, v: V3<T>) -> (V3<T>, V3<T>) {
        let h = d.x.splat(self.dt);
        let (mut moves, mut v) = (V3::splat(h, DVec3::ZERO), v);
        if let Some(sphere) = self.sphere {
            let radius = h.splat(sphere.radius);
            let dist2 = d.dot(d);
            // The cheap test first: particles all farther than the radius by much
            // more than a square root's rounding are outside, without the root.
            let reach2 = sphere.radius * sphere.radius * (1.0 + 1e-9);
            if T::any(dist2.lt(h.splat(reach2))) {
                let dist = dist2.sqrt();
                let inside = dist.lt(radius);
                if T::any(inside) {
                    let outside = surface_offset(d, dist2, radius);
                    let push = outside - d;
                    let friction = (self.friction > 0.0).then(|| {
                        // (Unlimited outside, as for the ground.)
                        let most = T::select(
                            inside,
                            h.splat(self.friction) * push.length() / h,
                            h.splat(f64::INFINITY),
                        );
                        (outside.over(radius), most)
                    });
                    let pushed = contact_velocity(v, push, h.splat(1.0 / self.dt), friction);
                    moves = V3::select(inside, push, moves);
                    v = V3::select(inside, pushed, v);
                }
            }
        }
        (moves, v)
    }

    /// The ground's part of [`Contact::resolve_lanes`], after the sphere's: its
    /// friction on particles `above` m above it with velocity `v` and inverse mass
    /// `w`, which changes only their velocity (the ground's push is its penalty
    /// force).
    #[inline(always)]
    pub(crate) fn ground_friction_lanes<T: Lanes>(&self, above: T, v: V3<T>, w: T) -> V3<T> {
        let Some(ground) = self.ground.filter(|g| g.friction > 0.0) else {
            return v;
        };
        let (k_c, c_g) = (above.splat(ground.stiffness), above.splat(ground.damping));
        let support = ground_support(above.splat(0.0) - above, v.y, k_c, c_g);
        let on = support.gt(above.splat(0.0));
        if !T::any(on) {
            return v;
        }
        // (Unlimited where off the ground, so that those lanes pass `coulomb`'s
        // cheap test: their result is not taken.)
        let most = T::select(
            on,
            above.splat(ground.friction) * above.splat(self.dt) * support * w,
            above.splat(f64::INFINITY),
        );
        V3::select(on, coulomb_up(v, most), v)
    }
}

/// Where particles are as [`Contact`] sees them, one per lane: their offsets (m)
/// from the sphere's centre and their heights (m) above the ground (each from 0
/// for a collider that is absent). Offsets, not positions: a fast engine takes
/// them exactly from its fixed-point integers, so that a body and its colliders
/// moved by a whole number of units step exactly as they did.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Near<T> {
    pub(crate) from_centre: V3<T>,
    pub(crate) above_ground: T,
}

/// `v` with its part along the surface of unit normal `normal` shortened by
/// `most` (m/s), or removed when it is slower than that.
#[inline(always)]
pub(super) fn coulomb<T: Lanes>(v: V3<T>, normal: V3<T>, most: T) -> V3<T> {
    coulomb_along(v, v - normal.scale(v.dot(normal)), most)
}

/// [`coulomb`] given `along`, the part of `v` along the surface.
#[inline(always)]
fn coulomb_along<T: Lanes>(v: V3<T>, along: V3<T>, most: T) -> V3<T> {
    let speed2 = along.dot(along);
    // The cheap test first: where every lane is slower than `most` by much more
    // than the root's rounding, all stop, without the root and the division
    // (particles at rest on a surface; a NaN fails the test). The margin, 5e-7 of
    // the speed, is far over the rounding of float32 lanes too (6e-8 a
    // rounding), so that the test never stops a lane the root would not.
    if T::all(speed2.le(most * most * most.splat(1.0 - 1e-6))) {
        return v - along;
    }
    let speed = speed2.sqrt();
    let slower = speed.le(most);
    V3::select(slower, v - along, v - along.scale(most / speed))
}

/// [`coulomb`] on a surface whose normal is up (the ground's), written for it:
/// the part along the surface is `(v_x, 0, v_z)`. For finite velocities the same
/// numbers as `coulomb(v, Y, most)`, whose `v·Y` and `Y (v·Y)` add and subtract
/// only zeros (which may give a zero the other sign), with a third of its
/// arithmetic.
#[inline(always)]
fn coulomb_up<T: Lanes>(v: V3<T>, most: T) -> V3<T> {
    let zero = most.splat(0.0);
    let along = V3 {
        x: v.x,
        y: zero,
        z: v.z,
    };
    coulomb_along(v, along, most)
}

/// Where a particle at `x` inside `sphere` is projected to (the nearest point of the
/// surface; straight up from the centre), or `None` if it is not inside.
pub(crate) fn out_of_sphere(x: DVec3, sphere: &Sphere) -> Option<DVec3> {
    let d = V3::from(x - sphere.center);
    let dist = d.length();
    let offset = |r| DVec3::from(surface_offset(d, d.dot(d), r));
    (dist < sphere.radius).then(|| sphere.center + offset(sphere.radius))
}

/// The point of the surface of a sphere of `radius` nearest to a particle `d` from
/// its centre, `dist2 = |d|²` (straight up from the centre for a particle at the
/// centre), as an offset from the centre, one particle per lane: `r d / l`, with
/// `1 / l` from the lanes' reciprocal root. Every engine's projection onto the
/// sphere (here and the grid and lattice kernels' row pass).
#[inline(always)]
pub(crate) fn surface_offset<T: Lanes>(d: V3<T>, dist2: T, radius: T) -> V3<T> {
    let offset = d.scale(radius * dist2.rsqrt_or_zero(DEGENERATE_LENGTH2));
    // A particle at the centre has no direction: up (its x and z are 0 already).
    let off_center = dist2.gt(dist2.splat(DEGENERATE_LENGTH2));
    V3 {
        y: T::select(off_center, offset.y, radius),
        ..offset
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::lanes::{F64s, Floats};
    use rand::{Rng, SeedableRng, rngs::StdRng};

    /// Contact on a block of lanes gives each lane bit for bit what it gives its
    /// particle alone: particles in, on and around a sphere with friction and on
    /// a frictional ground, sliding and resting, with lanes of both kinds mixed in
    /// one block, one at the sphere's centre and one NaN; and no particle inside
    /// the sphere is left there, also within 2e-9 of its surface.
    #[test]
    fn lanes_resolve_each_particle_as_alone() {
        let contact = Contact {
            sphere: Some(Sphere {
                center: DVec3::new(0.1, 0.0, -0.2),
                radius: 0.5,
            }),
            ground: Some(Ground {
                height: -0.45,
                stiffness: 200.0,
                damping: 0.05,
                friction: 0.5,
            }),
            friction: 0.4,
            dt: 1.0 / 960.0,
        };
        let mut rng = StdRng::seed_from_u64(11);
        let mut differ = 0;
        for block in 0..2000 {
            let mut x = [DVec3::ZERO; 8];
            let mut v = [DVec3::ZERO; 8];
            let mut w = [0.0; 8];
            // Every third block lies all within 2e-9 of the sphere's surface, where
            // the cheap test on squared distances must decide as the root would.
            let shell = block % 3 == 0;
            for l in 0..8 {
                let r: f64 = if shell {
                    0.5 * (1.0 + rng.random_range(-2e-9..2e-9))
                } else {
                    rng.random_range(0.0..0.7)
                };
                let dir = DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
                .normalize_or(DVec3::Y);
                x[l] = contact.sphere.unwrap().center + r * dir;
                // Some resting (slower than friction stops), some sliding.
                let scale = if rng.random_bool(0.5) { 1e-3 } else { 2.0 };
                v[l] = scale * DVec3::new(rng.random(), rng.random(), rng.random());
                w[l] = rng.random_range(100.0..3000.0);
            }
            if block == 0 {
                x[3] = contact.sphere.unwrap().center;
                x[5] = DVec3::NAN;
            }
            let lanes = |p: &[DVec3; 8], a: usize| Floats(std::array::from_fn(|l| p[l][a]));
            let v3 = |p: &[DVec3; 8]| V3 {
                x: lanes(p, 0),
                y: lanes(p, 1),
                z: lanes(p, 2),
            };
            let (centre, height) = (
                contact.sphere.unwrap().center,
                contact.ground.unwrap().height,
            );
            let near = Near {
                from_centre: v3(&x.map(|x| x - centre)),
                above_ground: Floats(x.map(|x| x.y - height)),
            };
            let (push, v_new) = contact.resolve_lanes(near, v3(&v), Floats(w));
            let to = V3 {
                x: Floats(std::array::from_fn(|l| x[l].x + push.x.0[l])),
                y: Floats(std::array::from_fn(|l| x[l].y + push.y.0[l])),
                z: Floats(std::array::from_fn(|l| x[l].z + push.z.0[l])),
            };
            for l in 0..8 {
                let (x1, v1) = contact.resolve(x[l], v[l], w[l]);
                let lane = |p: &V3<F64s<8>>| DVec3::new(p.x.0[l], p.y.0[l], p.z.0[l]);
                let same = |a: DVec3, b: DVec3| {
                    (0..3).all(|i| {
                        a[i].to_bits() == b[i].to_bits() || (a[i].is_nan() && b[i].is_nan())
                    })
                };
                assert!(
                    same(lane(&to), x1) && same(lane(&v_new), v1),
                    "block {block} lane {l}: {x1} {v1} alone, {} {} in lanes",
                    lane(&to),
                    lane(&v_new)
                );
                differ += usize::from(x1 != x[l] || v1 != v[l]);
                // A particle left where it was is not inside the sphere.
                let sphere = contact.sphere.unwrap();
                let left = x1 == x[l] && x[l].is_finite();
                assert!(
                    !left || x[l].distance(sphere.center) >= sphere.radius,
                    "{}",
                    x[l]
                );
            }
        }
        // The contact did act on most particles.
        assert!(differ > 6000, "{differ} of 16000 changed");
    }

    /// The ground's Coulomb (normal up) gives what the general one gives, for
    /// finite velocities of every sign and size, zeros of both signs among them,
    /// sliding and sticking: the same numbers (`==`: a zero may come out with the
    /// other sign, the general one's `v - 0 (v·Y)` adding a zero of `v_y`'s).
    #[test]
    fn the_grounds_coulomb_is_the_general_one() {
        let mut rng = StdRng::seed_from_u64(5);
        let values = [0.0, -0.0, 1e-300, -2.5, 3.0, 1e10, -7e-8];
        for _ in 0..20_000 {
            let mut pick = || {
                if rng.random_bool(0.2) {
                    values[rng.random_range(0..values.len())]
                } else {
                    rng.random_range(-10.0..10.0)
                }
            };
            let v = DVec3::new(pick(), pick(), pick());
            let most = pick().abs();
            let general = DVec3::from(coulomb(V3::from(v), V3::from(DVec3::Y), most));
            let up = DVec3::from(coulomb_up(V3::from(v), most));
            assert_eq!(general, up, "v {v}, most {most}");
        }
    }

    /// In float32 lanes (the ground's friction in a float32 kernel) the cheap
    /// test decides as the root would: around `most`, ulp by ulp of the speed
    /// (the squared speed's rounding included), each lane stops exactly when its
    /// float32 speed is at most `most`, as `coulomb` without the test gives it.
    #[test]
    fn in_float32_the_cheap_test_stops_what_the_root_would() {
        type F = Floats<f32, 8>;
        for most in [0.7f32, 1.3e-3, 42.0] {
            for step in -2000i32..=200 {
                // Speeds one float32 step apart around `most`, along x.
                let speed = f32::from_bits((most.to_bits() as i32 + step) as u32);
                let v = V3 {
                    x: F::of(f64::from(speed)),
                    y: F::of(-0.25),
                    z: F::of(0.0),
                };
                let out = coulomb_up(v, F::of(f64::from(most)));
                // Without the cheap test: the root and its comparison.
                let root = (speed * speed + 0.0 * 0.0).sqrt();
                let expected = if root <= most {
                    0.0
                } else {
                    speed - speed * (most / root)
                };
                for l in 0..8 {
                    assert_eq!(out.x.0[l], expected, "most {most}, speed {speed}");
                }
            }
        }
    }

    /// Friction at the edge of sticking, in blocks whose lanes all take
    /// `coulomb`'s cheap test or not: a particle sliding no faster than `most`
    /// stops along the surface (exactly), a faster one keeps its direction and
    /// `speed - most` of its speed, to round-off. Speeds from 1e-5 below `most` to
    /// 1e-6 above, in relative steps down to 1e-13 around it (the cheap test's
    /// margin is 5e-7 of the speed), and the same in lanes.
    #[test]
    fn friction_stops_what_is_slower_than_most_and_slows_the_rest_by_most() {
        let most = 0.7;
        let normal = V3::from(DVec3::Y);
        let offsets = [
            -1e-5, -1e-6, -5e-7, -4e-7, -1e-7, -1e-9, -1e-13, 0.0, 1e-13, 1e-10, 1e-9, 1e-6,
        ];
        let speeds = offsets.map(|e| most * (1.0 + e));
        for (i, &speed) in speeds.iter().enumerate() {
            // Sliding along (3, 0, 4) / 5, pressed down at 0.25 m/s.
            let v = DVec3::new(0.6 * speed, -0.25, 0.8 * speed);
            let got = DVec3::from(coulomb(V3::from(v), normal, most));
            let up = DVec3::from(coulomb_up(V3::from(v), most));
            assert_eq!(got, up, "{speed}: the ground's Coulomb is the general one");
            assert_eq!(got.y, v.y, "{speed}: the normal part is left");
            let kept = DVec3::new(got.x, 0.0, got.z);
            if speed <= most {
                assert_eq!(kept, DVec3::ZERO, "{speed} <= {most} stops");
            } else {
                let expected = speed - most;
                assert!(
                    (kept.length() - expected).abs() <= 1e-15 * most
                        && kept.normalize().dot(DVec3::new(0.6, 0.0, 0.8)) > 1.0 - 1e-9,
                    "{speed} > {most}: keeps {kept}, expected {expected} along (0.6, 0, 0.8)"
                );
            }
            // The same in a block of lanes, all alike and mixed with resting ones.
            for mixed in [false, true] {
                let lane = |l: usize| if mixed && l % 2 == 1 { v * 1e-3 } else { v };
                let block = V3 {
                    x: Floats::<f64, 8>(std::array::from_fn(|l| lane(l).x)),
                    y: Floats::<f64, 8>(std::array::from_fn(|l| lane(l).y)),
                    z: Floats::<f64, 8>(std::array::from_fn(|l| lane(l).z)),
                };
                let out = coulomb(block, V3::splat(F64s::of(0.0), DVec3::Y), F64s::of(most));
                for l in 0..8 {
                    let alone = DVec3::from(coulomb(V3::from(lane(l)), normal, most));
                    let got = DVec3::new(out.x.0[l], out.y.0[l], out.z.0[l]);
                    assert_eq!(got, alone, "speed {i}, lane {l}, mixed {mixed}");
                }
            }
        }
    }
}
