//! Position constraints enforced after integration, each optional per scene:
//! - rigid bars (seed 001), relaxed `bar_iterations` times per step: each pass moves
//!   the two ends along the bar so that its length is restored, split by inverse mass;
//! - maximum stretch (Provot 1995, seed 004): no spring longer than `(1 + tau) L`;
//! - the sphere collider (seed 003): particles inside are projected onto its surface.
//!
//! Moving a position by `dx` in a velocity-based integrator also changes the velocity
//! by `dx / h` (as position-based dynamics does), so a corrected particle does not
//! keep the motion the constraint removed. Position Verlet needs no more: its next
//! step reads the correction from the positions; its velocity estimate is corrected
//! the same way for the force terms that use it.

use glam::DVec3;

use super::{Model, State, Workspace, forces::EPSILON_LENGTH};

/// Applies every constraint the model has, then updates velocities.
pub fn apply(model: &Model, state: &mut State, work: &mut Workspace) {
    let p = &model.params;
    let x = &mut state.positions;
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
        for s in &model.springs {
            let longest = (1.0 + tau) * s.rest;
            restore_length(x, &model.inv_mass, s.a as usize, s.b as usize, |l| {
                (l > longest).then_some(longest)
            });
        }
    }
    if let Some(sphere) = p.sphere {
        for (xi, &w) in x.iter_mut().zip(&model.inv_mass) {
            let d = *xi - sphere.center;
            let dist = d.length();
            if w > 0.0 && dist < sphere.radius {
                let normal = if dist > EPSILON_LENGTH {
                    d / dist
                } else {
                    DVec3::Y
                };
                *xi = sphere.center + normal * sphere.radius;
            }
        }
    }
    let h = p.dt;
    for ((v, x), before) in state
        .velocities
        .iter_mut()
        .zip(x.iter())
        .zip(&work.before_constraints)
    {
        *v += (*x - *before) / h;
    }
}

/// Moves particles `a` and `b` along their joining line so that their distance becomes
/// `target(l)` when it returns a length, sharing the move by inverse mass (a pinned end
/// stays put). Coincident particles have no direction and are left alone.
fn restore_length(
    x: &mut [DVec3],
    inv_mass: &[f64],
    a: usize,
    b: usize,
    target: impl Fn(f64) -> Option<f64>,
) {
    let (wa, wb) = (inv_mass[a], inv_mass[b]);
    let w = wa + wb;
    if w == 0.0 {
        return;
    }
    let d = x[a] - x[b];
    let l = d.length();
    if l <= EPSILON_LENGTH {
        return;
    }
    let Some(goal) = target(l) else { return };
    let correction = (l - goal) / (l * w) * d;
    x[a] -= wa * correction;
    x[b] += wb * correction;
}
