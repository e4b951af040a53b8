//! Position constraints enforced after integration, each optional per scene:
//! - with XPBD, every spring: a distance constraint of compliance `1/k`, one
//!   Gauss-Seidel sweep in the model's constraint order, and on a lattice one back
//!   (`xpbd_pass`);
//! - rigid bars (seed 001), relaxed `bar_iterations` times per step: each pass moves
//!   the two ends along the bar so that its length is restored, split by inverse mass;
//! - maximum stretch (Provot 1995, seed 004): no spring longer than `(1 + tau) L`,
//!   one Gauss-Seidel pass in the model's constraint order (by colour on a grid:
//!   in particle order a single pass can diverge, see `springs::constraint_order`);
//! - the sphere collider (seed 003): particles inside are projected onto its surface;
//! - self-collision ([`super::self_collision`]), particles kept `thickness` apart;
//! - Coulomb friction on the sphere and the ground (`Contact::resolve`).
//!
//! Moving a position by `dx` in a velocity-based integrator also changes the velocity
//! by `dx / h` (as position-based dynamics does), so a corrected particle does not
//! keep the motion the constraint removed. Position Verlet needs no more: its next
//! step reads the correction from the positions; its velocity estimate is corrected
//! the same way for the force terms that use it.

use glam::DVec3;

use super::forces::{EPSILON_LENGTH, ground_support};
use super::lanes::{Lanes, V3};
use super::{Ground, Integrator, LatticeShape, Model, Params, Sphere, State, Workspace};

/// Applies every constraint the model has, then updates velocities.
pub fn apply(model: &Model, state: &mut State, work: &mut Workspace) {
    let p = &model.params;
    let x = &mut state.positions;
    if p.integrator == Integrator::Xpbd {
        let order = (&model.constraint_order[..], xpbd_sweeps_back(model.lattice));
        xpbd_pass(
            x,
            &work.step_start,
            &model.springs,
            order,
            &model.inv_mass,
            p.dt,
            &mut work.multipliers,
        );
    }
    if p.bar_iterations > 0 {
        for _ in 0..p.bar_iterations {
            for bar in &model.bars {
                restore_length(x, &model.inv_mass, bar.a as usize, bar.b as usize, |l| {
                    (l != bar.length).then_some(bar.length)
                });
            }
        }
    }
    if let Some(tau) = p.stretch_limit {
        for s in model
            .constraint_order
            .iter()
            .map(|&i| &model.springs[i as usize])
        {
            let longest = (1.0 + tau) * s.rest;
            restore_length(x, &model.inv_mass, s.a as usize, s.b as usize, |l| {
                (l > longest).then_some(longest)
            });
        }
    }
    if p.self_collision {
        let joined = |i, j| model.joins(i, j);
        let (start, w) = (&work.step_start, &model.inv_mass);
        let particle = |i: usize| (start[i], w[i]);
        // On the threads of the spring forces (`System::run`'s scope), with the
        // same result as on one.
        let parallel = super::forces::uses_threads(model);
        (work.self_collision).apply(x, particle, p.thickness, p.friction, joined, parallel);
    }
    let h = p.dt;
    let contact = Contact::of(p);
    let active = contact.is_active();
    let verlet = &mut state.verlet.positions;
    for (i, (v, x)) in state.velocities.iter_mut().zip(x.iter_mut()).enumerate() {
        *v += (*x - work.before_constraints[i]) / h;
        let w = model.inv_mass[i];
        if active && w > 0.0 {
            let (x_in, v_in) = (*x, *v);
            (*x, *v) = contact.resolve(x_in, v_in, w);
            // Verlet reads the push from the positions; the friction's change of
            // velocity goes into its previous position.
            if let Some(prev) = verlet.get_mut(i) {
                *prev -= h * (*v - v_in) - (*x - x_in);
            }
        }
    }
}

/// Whether XPBD's pass sweeps back after it sweeps forward ([`xpbd_pass`]) over
/// the springs of a model with this `lattice` shape: on a lattice (a solid), not
/// on a cloth or a chain.
///
/// Why: on a stiff solid the forward sweep alone pumps energy into a spin. In a
/// NumPy reproduction of the pass, a free 4³ jelly (k = 1e7 N/m, 0.1 kg, 1.4 ms
/// steps, the engines' colour order) spinning at 1 rad/s went from 9 J to 3.2e5 J
/// of kinetic energy in 250 steps; swept back as well, it kept its 9 J (9.00 after
/// 1,000 steps). Round-off starts such a spin in any falling jelly: at the
/// panel's k = 1e8 to 1e9 N/m and the scene's 2e-4 s steps the forward sweep ran
/// it away, on every engine (`tests/xpbd.rs`). Both ways, the jelly also came
/// 1.1 to 1.4 times closer to symplectic Euler at a fifth of its critical step
/// after 1.5 s (k = 2e3 and 2e4 N/m, steps of 0.2 to 2.5 ms). A cloth showed
/// neither: a spinning flat cloth lost the same energy either way in the
/// reproduction, no scene's cloth ran away on the forward sweep (k of 1e7 and
/// 1e9 N/m, 1/960 and 1/250 s steps), and at 5 and 10 substeps a frame the
/// stiff-cloth study's cloth came out up to twice as far from its reference swept
/// both ways (the forward sweep last corrects the springs that carry its weight),
/// at twice the cost.
pub(crate) fn xpbd_sweeps_back(lattice: Option<LatticeShape>) -> bool {
    lattice.is_some_and(|l| !l.is_empty())
}

/// XPBD's pass over `springs` ([`xpbd_correction`] of each) on positions `x`
/// that were `prev` at the start of the step `dt`, with inverse masses
/// `inv_mass`: one Gauss-Seidel sweep in `order` and, with `back`
/// ([`xpbd_sweeps_back`]), one in the reverse order after it, each spring's
/// multiplier `λ` (in `multipliers`, one per spring, only then) kept from its first
/// correction to its second. Forward and back, the two are a symmetric
/// Gauss-Seidel iteration on the step's linearised system, whose iteration
/// matrix has real eigenvalues in [0, 1) (the system is symmetric positive
/// definite), where a forward sweep's may be complex (though linearised at rest,
/// both steps' error recurrences had a spectral radius of 1 on 3³ and 4³
/// lattices in the reproduction: the spin that tells them apart is nonlinear).
/// From `λ = 0` the second correction would count the compliance twice (a mass
/// hanging on a spring would stop at half its stretch, `tests/xpbd.rs`). In exact
/// arithmetic a spring's second correction straight after its first changes
/// nothing, so the lattice kernel does not sweep its last class back; this pass
/// does, to round-off. The f64 and mesh engines' pass.
pub(crate) fn xpbd_pass(
    x: &mut [DVec3],
    prev: &[DVec3],
    springs: &[super::Spring],
    (order, back): (&[u32], bool),
    inv_mass: &[f64],
    dt: f64,
    multipliers: &mut Vec<f64>,
) {
    // Corrects spring `i` whose multiplier so far is `lambda`; returns its change.
    #[inline(always)]
    fn correct(
        x: &mut [DVec3],
        (prev, springs, inv_mass, dt): (&[DVec3], &[super::Spring], &[f64], f64),
        i: u32,
        lambda: f64,
    ) -> Option<f64> {
        let s = &springs[i as usize];
        let (a, b) = (s.a as usize, s.b as usize);
        let (wa, wb) = (inv_mass[a], inv_mass[b]);
        let spring = XpbdSpring::new(s.rest, s.stiffness, s.damping, dt)?;
        let ends = ([x[a], x[b]], [prev[a], prev[b]]);
        let (c, delta) = xpbd_correction(ends.0, ends.1, wa, wb, &spring, lambda)?;
        x[a] -= wa * c;
        x[b] += wb * c;
        Some(delta)
    }
    let given = (prev, springs, inv_mass, dt);
    multipliers.clear();
    if !back {
        // One sweep visits each spring once, from `λ = 0`: nothing to keep.
        for &i in order {
            correct(x, given, i, 0.0);
        }
        return;
    }
    multipliers.resize(springs.len(), 0.0);
    for &i in order.iter().chain(order.iter().rev()) {
        let lambda = &mut multipliers[i as usize];
        if let Some(delta) = correct(x, given, i, *lambda) {
            *lambda += delta;
        }
    }
}

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
    /// assembled it there in three stores stalled on the load (the mesh engine's
    /// tablecloth ran 1.4x faster on one core once inlined).
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
                    let outside = surface_offset(d, dist, &sphere);
                    let push = outside - d;
                    let mut pushed = v + push.over(h);
                    if self.friction > 0.0 {
                        let normal = outside.over(radius);
                        // (Unlimited outside, as for the ground.)
                        let most = T::select(
                            inside,
                            h.splat(self.friction) * push.length() / h,
                            h.splat(f64::INFINITY),
                        );
                        pushed = coulomb(pushed, normal, most);
                    }
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
        let support = ground_support(&ground, above.splat(0.0) - above, v.y);
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

/// The factor a particle's velocity `v` is scaled by under the speed limit
/// `max_speed` (m/s): `max_speed / |v|` when it is faster, else 1 (also for a
/// non-finite `v`, which is a divergence, not a speed to limit). Under Verlet the
/// update velocity `(x - x_prev) / h` is scaled by the same factor.
pub fn speed_limit(v: DVec3, max_speed: f64) -> f64 {
    let speed = v.length();
    if speed > max_speed && speed.is_finite() {
        max_speed / speed
    } else {
        1.0
    }
}

/// `v` with its part along the surface of unit normal `normal` shortened by
/// `most` (m/s), or removed when it is slower than that.
#[inline(always)]
fn coulomb<T: Lanes>(v: V3<T>, normal: V3<T>, most: T) -> V3<T> {
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
    (dist < sphere.radius).then(|| sphere.center + DVec3::from(surface_offset(d, dist, sphere)))
}

/// The point of the surface of `sphere` nearest to a particle `d` from its centre,
/// `dist` away (straight up from the centre for a particle at the centre), as an
/// offset from the centre, one particle per lane.
#[inline(always)]
fn surface_offset<T: Lanes>(d: V3<T>, dist: T, sphere: &Sphere) -> V3<T> {
    let off_center = dist.gt(dist.splat(EPSILON_LENGTH));
    let normal = V3::select(off_center, d.over(dist), V3::splat(dist, DVec3::Y));
    normal.scale(dist.splat(sphere.radius))
}

/// The correction `c` that brings particles at `xa` and `xb` (inverse masses `wa`,
/// `wb`) to distance `target(l)` when it returns a length: `xa -= wa c`, `xb += wb c`
/// (a pinned end stays put). `None` when nothing moves: both ends pinned, coincident
/// particles (no direction), or no target.
pub(crate) fn length_correction(
    xa: DVec3,
    xb: DVec3,
    wa: f64,
    wb: f64,
    target: impl Fn(f64) -> Option<f64>,
) -> Option<DVec3> {
    let w = wa + wb;
    if w == 0.0 {
        return None;
    }
    let d = xa - xb;
    let l = d.length();
    if l <= EPSILON_LENGTH {
        return None;
    }
    let goal = target(l)?;
    Some((l - goal) / (l * w) * d)
}

/// A spring as XPBD's pass sees it at step `h`: its rest length and its
/// coefficients ([`xpbd_coefficients`]), worked out once for every spring that
/// shares them (the grid engine's springs of one kind).
#[derive(Clone, Copy, Debug)]
pub(crate) struct XpbdSpring {
    pub(crate) rest: f64,
    /// `α̃ = 1 / (k h²)`.
    pub(crate) alpha: f64,
    /// `γ = b / (k h)`.
    pub(crate) gamma: f64,
}

impl XpbdSpring {
    /// The spring `(rest, k, b)` at step `h`; `None` for `k <= 0`, which
    /// constrains nothing.
    #[inline]
    pub(crate) fn new(rest: f64, k: f64, b: f64, h: f64) -> Option<Self> {
        let (alpha, gamma) = xpbd_coefficients(k, b, h);
        (k > 0.0).then_some(Self { rest, alpha, gamma })
    }
}

/// XPBD's correction of a `spring` between particles now at `x = [xa, xb]` that
/// were at `prev` at the start of the step, with inverse masses `wa`, `wb`, and its
/// multiplier so far `λ`: `xa -= wa c`, `xb += wb c`, as [`length_correction`].
/// Returns `c` and the multiplier's change `Δλ`.
///
/// The spring `(rest, k, b)` is the constraint `C = l - L` with compliance `α = 1/k`
/// (the same k, the same material), `α̃ = α / h²`, and the XPBD paper's damping
/// `γ = α̃ β̃ / h` with `β̃ = h² b`, i.e. `γ = b / (k h)`. One iteration:
/// `Δλ = -(C + α̃ λ + γ ∇C·(x - x_prev)) / ((1 + γ)(wa + wb) + α̃)`, `c = -Δλ n`
/// with `n = (xa - xb) / l`.
///
/// The grid and lattice engines do the same arithmetic in float32 lanes, a
/// colour class at a time (`grid_kernel/spring_passes.rs`, as they do
/// [`length_correction`]), the lattice's keeping `α̃ λ` rather than `λ`;
/// `tests/fast_engine.rs`, `tests/grid_kernel.rs` and `tests/lattice_kernel.rs`
/// hold them together.
#[inline(always)]
pub(crate) fn xpbd_correction(
    x: [DVec3; 2],
    prev: [DVec3; 2],
    wa: f64,
    wb: f64,
    spring: &XpbdSpring,
    lambda: f64,
) -> Option<(DVec3, f64)> {
    let w = wa + wb;
    if w == 0.0 {
        return None;
    }
    let d = x[0] - x[1];
    let l = d.length();
    if l <= EPSILON_LENGTH {
        return None;
    }
    let n = d * (1.0 / l);
    let moved = n.dot((x[0] - prev[0]) - (x[1] - prev[1]));
    let (alpha, gamma) = (spring.alpha, spring.gamma);
    // `C + α̃ λ`, with `α̃ λ` taken from the rest length, off the chain of
    // positions that a Gauss-Seidel pass waits on.
    let stretch = l - (spring.rest - alpha * lambda);
    let delta = -(stretch + gamma * moved) / ((1.0 + gamma) * w + alpha);
    Some((-delta * n, delta))
}

/// XPBD's `(α̃, γ) = (1 / (k h²), b / (k h))` for a spring `(k, b)` at step `h`.
#[inline]
pub(crate) fn xpbd_coefficients(k: f64, b: f64, h: f64) -> (f64, f64) {
    (1.0 / (k * h * h), b / (k * h))
}

/// Moves particles `a` and `b` along their joining line so that their distance becomes
/// `target(l)` (see [`length_correction`]).
fn restore_length(
    x: &mut [DVec3],
    inv_mass: &[f64],
    a: usize,
    b: usize,
    target: impl Fn(f64) -> Option<f64>,
) {
    let (wa, wb) = (inv_mass[a], inv_mass[b]);
    if let Some(c) = length_correction(x[a], x[b], wa, wb, target) {
        x[a] -= wa * c;
        x[b] += wb * c;
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
