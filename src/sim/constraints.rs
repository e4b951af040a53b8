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

use super::colliders::poses_at;
use super::laws::{Contact, XpbdSpring, end_of_step_contacts, length_correction, xpbd_correction};
use super::{Integrator, LatticeShape, Model, State, Workspace};

/// Applies every constraint the model has, then updates velocities.
pub fn apply(model: &Model, state: &mut State, work: &mut Workspace) {
    let p = &model.params;
    let x = &mut state.positions;
    if p.integrator == Integrator::Xpbd {
        xpbd_pass(model, x, &work.step_start, &mut work.multipliers);
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
            .constraint_order()
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
    // The colliders where they are at the end of the step.
    poses_at(&model.colliders, state.time + h, &mut work.collider_poses);
    let solids = (&model.colliders[..], &work.collider_poses[..]);
    let verlet = &mut state.verlet.positions;
    for (i, (v, x)) in state.velocities.iter_mut().zip(x.iter_mut()).enumerate() {
        *v += (*x - work.before_constraints[i]) / h;
        let (x_in, v_in) = (*x, *v);
        (*x, *v) = end_of_step_contacts(&contact, solids, (x_in, v_in), model.inv_mass[i], h);
        // Verlet reads the push from the positions; the friction's change of
        // velocity goes into its previous position.
        if let Some(prev) = verlet.get_mut(i) {
            *prev -= h * (*v - v_in) - (*x - x_in);
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
/// it away, on every engine (`tests/physics/xpbd.rs`). Both ways, the jelly also came
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

/// XPBD's pass over `model`'s springs ([`xpbd_correction`] of each) on positions
/// `x` that were `prev` at the start of the step: one Gauss-Seidel sweep in the
/// model's constraint order and, where [`xpbd_sweeps_back`], one in the reverse
/// order after it, each spring's multiplier `λ` (in `multipliers`, one per
/// spring, only then) kept from its first correction to its second. Forward and
/// back, the two are a symmetric Gauss-Seidel iteration on the step's linearised
/// system, whose iteration matrix has real eigenvalues in [0, 1) (the system is
/// symmetric positive definite), where a forward sweep's may be complex (though
/// linearised at rest, both steps' error recurrences had a spectral radius of 1
/// on 3³ and 4³ lattices in the reproduction: the spin that tells them apart is
/// nonlinear). From `λ = 0` the second correction would count the compliance
/// twice (a mass hanging on a spring would stop at half its stretch,
/// `tests/physics/xpbd.rs`). In exact arithmetic a spring's second correction
/// straight after its first changes nothing, so the lattice kernel does not sweep
/// its last class back; this pass does, to round-off.
fn xpbd_pass(model: &Model, x: &mut [DVec3], prev: &[DVec3], multipliers: &mut Vec<f64>) {
    let (inv_mass, dt) = (&model.inv_mass, model.params.dt);
    // Corrects spring `i` whose multiplier so far is `lambda`; returns its change.
    let correct = |x: &mut [DVec3], i: u32, lambda: f64| -> Option<f64> {
        let s = &model.springs[i as usize];
        let (a, b) = (s.a as usize, s.b as usize);
        let (wa, wb) = (inv_mass[a], inv_mass[b]);
        let m = model.material(s.kind);
        let spring = XpbdSpring::new(s.rest, m.stiffness, m.damping, dt)?;
        let ends = ([x[a], x[b]], [prev[a], prev[b]]);
        let (c, delta) = xpbd_correction(ends.0, ends.1, wa, wb, &spring, lambda)?;
        x[a] -= wa * c;
        x[b] += wb * c;
        Some(delta)
    };
    let order = model.constraint_order();
    multipliers.clear();
    if !xpbd_sweeps_back(model.lattice) {
        // One sweep visits each spring once, from `λ = 0`: nothing to keep.
        for &i in order {
            correct(x, i, 0.0);
        }
        return;
    }
    multipliers.resize(model.springs.len(), 0.0);
    for &i in order.iter().chain(order.iter().rev()) {
        let lambda = &mut multipliers[i as usize];
        if let Some(delta) = correct(x, i, *lambda) {
            *lambda += delta;
        }
    }
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
