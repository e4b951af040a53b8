//! Highest angular frequency `omega_max = sqrt(lambda_max(M^-1 K))` of the linearised
//! spring network, by power iteration on the symmetric `M^-1/2 K M^-1/2`.
//!
//! `K` is the Hessian of the elastic energy at the given positions: per spring
//! `K_s = k [u uᵀ + max(0, 1 - L/l) (I - u uᵀ)]` coupling its two ends (the
//! compressive transverse part is dropped, as the implicit integrator does, so `K`
//! is positive semidefinite), plus `k_c` on the vertical of particles in ground
//! contact. Pinned particles are removed (zero rows and columns). Unlike the
//! Gershgorin bound of [`crate::sim::stability::omega_max_bound`], this is the
//! eigenvalue itself: for a PSD matrix the Rayleigh quotient of power iteration
//! increases monotonically towards it from below.

use glam::{DMat3, DVec3};
use rand::{Rng, SeedableRng, rngs::StdRng};

use crate::sim::{Model, forces::EPSILON_LENGTH};

/// Result of power iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerIteration {
    /// Highest angular frequency in rad/s (`sqrt` of the Rayleigh quotient).
    pub omega_max: f64,
    /// Iterations taken.
    pub iterations: usize,
    /// Relative change of the Rayleigh quotient over the last 100 iterations.
    pub last_change: f64,
}

/// Power iteration on `M^-1/2 K M^-1/2` at positions `x`, at most `max_iterations`,
/// stopping when the Rayleigh quotient changes by less than `tolerance` (relative)
/// over 100 iterations.
pub fn omega_max(
    model: &Model,
    x: &[DVec3],
    max_iterations: usize,
    tolerance: f64,
) -> PowerIteration {
    let n = x.len();
    let scale: Vec<f64> = model.inv_mass.iter().map(|w| w.max(0.0).sqrt()).collect();
    let blocks = spring_blocks(model, x);
    let ground = ground_stiffness(model, x);
    let apply = |v: &[DVec3], out: &mut [DVec3]| {
        for i in 0..n {
            out[i] = DVec3::new(0.0, ground[i], 0.0) * v[i] * scale[i];
        }
        for (s, blk) in model.springs.iter().zip(&blocks) {
            let (a, b) = (s.a as usize, s.b as usize);
            let y = *blk * (v[a] * scale[a] - v[b] * scale[b]);
            out[a] += y;
            out[b] -= y;
        }
        for i in 0..n {
            out[i] *= scale[i];
        }
    };
    let mut rng = StdRng::seed_from_u64(12345);
    let mut v: Vec<DVec3> = (0..n)
        .map(|i| {
            let r = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            r * scale[i].signum()
        })
        .collect();
    let norm = |v: &[DVec3]| v.iter().map(|p| p.length_squared()).sum::<f64>().sqrt();
    let mut w = vec![DVec3::ZERO; n];
    let v_norm = norm(&v);
    if v_norm == 0.0 || model.springs.is_empty() && model.params.ground.is_none() {
        return PowerIteration {
            omega_max: 0.0,
            iterations: 0,
            last_change: 0.0,
        };
    }
    v.iter_mut().for_each(|p| *p /= v_norm);
    let mut lambda = 0.0;
    let mut checkpoint = 0.0;
    let mut last_change = f64::INFINITY;
    let mut iterations = 0;
    for it in 1..=max_iterations {
        apply(&v, &mut w);
        lambda = v.iter().zip(&w).map(|(a, b)| a.dot(*b)).sum::<f64>();
        let w_norm = norm(&w);
        iterations = it;
        if w_norm == 0.0 {
            lambda = 0.0;
            break;
        }
        for (p, q) in v.iter_mut().zip(&w) {
            *p = *q / w_norm;
        }
        if it % 100 == 0 {
            last_change = ((lambda - checkpoint) / lambda).abs();
            checkpoint = lambda;
            if last_change < tolerance {
                break;
            }
        }
    }
    PowerIteration {
        omega_max: lambda.max(0.0).sqrt(),
        iterations,
        last_change,
    }
}

/// Each spring's 3x3 block of `K` at positions `x`: `k [u uᵀ + max(0, 1 - L/l)
/// (I - u uᵀ)]`.
fn spring_blocks(model: &Model, x: &[DVec3]) -> Vec<DMat3> {
    (model.springs.iter())
        .map(|s| {
            let k = model.material(s.kind).stiffness;
            let d = x[s.a as usize] - x[s.b as usize];
            let l = d.length();
            if l <= EPSILON_LENGTH {
                // Coincident ends: the force is zero and has no direction, but a
                // zero-rest spring still pulls isotropically with k.
                return if s.rest <= EPSILON_LENGTH {
                    DMat3::from_diagonal(DVec3::splat(k))
                } else {
                    DMat3::ZERO
                };
            }
            let u = d / l;
            let uu = DMat3::from_cols(u * u.x, u * u.y, u * u.z);
            let transverse = (1.0 - s.rest / l).max(0.0);
            k * (uu + transverse * (DMat3::IDENTITY - uu))
        })
        .collect()
}

/// The ground's contact stiffness on the vertical of each particle below it at
/// positions `x`, 0 elsewhere.
fn ground_stiffness(model: &Model, x: &[DVec3]) -> Vec<f64> {
    match model.params.ground {
        Some(g) => x
            .iter()
            .map(|p| {
                if g.height - p.y > 0.0 {
                    g.stiffness
                } else {
                    0.0
                }
            })
            .collect(),
        None => vec![0.0; x.len()],
    }
}
