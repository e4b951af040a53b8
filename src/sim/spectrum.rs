//! The highest angular frequency of the linearised spring network, `omega_max =
//! sqrt(lambda_max(M^-1/2 K M^-1/2))` (rad/s), by Lanczos iteration.
//!
//! `K` is the Hessian of the elastic energy at the given positions: each spring
//! couples its ends with `K_s = k [u uᵀ + max(0, 1 - L/l) (I - u uᵀ)]` (its
//! compressive transverse part dropped, as the implicit integrator does, so that
//! `K` is positive semidefinite), and the ground adds its `k_c` on the vertical of
//! every free particle (any of them may come to touch it). Pinned particles are no
//! degrees of freedom: their rows and columns are zero.
//!
//! Every Ritz value of Lanczos is a Rayleigh quotient, so the estimate never
//! exceeds the true `lambda_max`, and it rises towards it fast: the error of the
//! top Ritz value after `j` iterations falls like `1/j²` even where the spectrum
//! is dense up to its top (a large cloth), where power iteration's falls like
//! `1/j`. Without reorthogonalisation the basis loses orthogonality once a value
//! has converged, which makes copies of converged values but never a larger one.
//! Gershgorin's bound ([`super::stability::omega_max_bound`]) needs no positions
//! but counts every spring at its full `k` in every direction: on a grid cloth
//! with shear and bend springs it is 1.6 times this.

use std::sync::Mutex;

use glam::DVec3;

use super::{Model, SpringKind, forces::EPSILON_LENGTH, springs::Spring};

/// Most Lanczos iterations (each one pass over the springs).
pub const MAX_ITERATIONS: usize = 80;
/// The estimate has converged when its top Ritz value rose by less than this,
/// relative, over the last [`SETTLED_OVER`] iterations. On the 256 x 256 bench
/// cloth it then stops after about 20 iterations, 0.2% below the limit its
/// value reaches (0.08% after 30, 0.04% after 40): the rise over 8 iterations is
/// about the distance left.
pub const TOLERANCE: f64 = 1e-3;
/// Iterations over which the rise is measured.
pub const SETTLED_OVER: usize = 8;

/// The estimate and how it was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spectrum {
    /// Highest angular frequency found, rad/s (0 if nothing oscillates); at most
    /// the true one.
    pub omega_max: f64,
    /// Lanczos iterations taken.
    pub iterations: usize,
}

/// One spring's block `K_s = k [(1 - t) u uᵀ + t I]` at positions `at`, as
/// `(t, u)` with `t = max(0, 1 - L/l)` the transverse part (`None` for coincident
/// ends of a spring with a rest length: no direction, no stiffness). Found again
/// in every product rather than stored: a stored block per spring was the largest
/// allocation of a big cloth.
fn block(s: &Spring, at: &[DVec3]) -> Option<(f64, DVec3)> {
    let d = at[s.a as usize] - at[s.b as usize];
    let l = d.length();
    if l > EPSILON_LENGTH {
        Some(((1.0 - s.rest / l).max(0.0), d / l))
    } else {
        // A zero-rest spring still pulls isotropically with k.
        (s.rest <= EPSILON_LENGTH).then_some((1.0, DVec3::ZERO))
    }
}

/// `y = S K S x` for `model`'s springs linearised at `at` (none where the springs
/// are constraints, not forces), scattered onto both ends, plus the ground's `k_c`
/// on the vertical of every free particle; `S` is the diagonal `scale`.
fn apply(model: &Model, at: &[DVec3], scale: &[f64], x: &[DVec3], y: &mut [DVec3], ground: f64) {
    for (yi, (xi, s)) in y.iter_mut().zip(x.iter().zip(scale)) {
        *yi = DVec3::new(0.0, ground * s * xi.y, 0.0);
    }
    if model.terms.springs {
        for s in &model.springs {
            let Some((t, u)) = block(s, at) else { continue };
            let (a, b) = (s.a as usize, s.b as usize);
            let dx = x[a] * scale[a] - x[b] * scale[b];
            let f = model.material(s.kind).stiffness * (t * dx + ((1.0 - t) * u.dot(dx)) * u);
            y[a] += f;
            y[b] -= f;
        }
    }
    for (yi, s) in y.iter_mut().zip(scale) {
        *yi *= *s;
    }
}

/// A fixed pseudo-random start in [-1, 1]³ per particle (splitmix64 of the index).
fn start(i: usize, component: u64) -> f64 {
    let mut z = (i as u64).wrapping_mul(3).wrapping_add(component);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Largest eigenvalue of the symmetric tridiagonal matrix with diagonal `alpha`
/// and off-diagonal `beta` (`beta.len() + 1 == alpha.len()`), by bisection on the
/// Sturm count.
fn top_eigenvalue(alpha: &[f64], beta: &[f64]) -> f64 {
    let n = alpha.len();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..n {
        let r = if i > 0 { beta[i - 1].abs() } else { 0.0 } + beta.get(i).map_or(0.0, |b| b.abs());
        lo = lo.min(alpha[i] - r);
        hi = hi.max(alpha[i] + r);
    }
    // Eigenvalues above `x`: the sign changes of the LDLᵀ pivots of T - x I.
    let above = |x: f64| {
        let mut count = 0;
        let mut d = 1.0;
        for i in 0..n {
            let off = if i > 0 {
                beta[i - 1] * beta[i - 1]
            } else {
                0.0
            };
            d = alpha[i] - x - if i > 0 { off / d } else { 0.0 };
            if d == 0.0 {
                d = -f64::EPSILON * (x.abs() + 1.0);
            }
            if d > 0.0 {
                count += 1;
            }
        }
        count
    };
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if above(mid) > 0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The highest angular frequency of `model`'s springs and ground contact
/// linearised at `positions`, over its free particles (see the module doc).
pub fn omega_max(model: &Model, positions: &[DVec3]) -> Spectrum {
    let n = model.mass.len();
    let none = Spectrum {
        omega_max: 0.0,
        iterations: 0,
    };
    if positions.len() != n {
        return none;
    }
    let ground = model.params.ground.map_or(0.0, |g| g.stiffness.max(0.0));
    let scale: Vec<f64> = (model.inv_mass.iter()).map(|w| w.max(0.0).sqrt()).collect();
    // `A = S K S` with `S = M^-1/2` (0 on pinned particles).
    let dot = |a: &[DVec3], b: &[DVec3]| a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum::<f64>();
    let mut v: Vec<DVec3> = (0..n)
        .map(|i| {
            let free = if scale[i] > 0.0 { 1.0 } else { 0.0 };
            DVec3::new(start(i, 0), start(i, 1), start(i, 2)) * free
        })
        .collect();
    let norm = dot(&v, &v).sqrt();
    if norm == 0.0 {
        return none;
    }
    v.iter_mut().for_each(|x| *x /= norm);
    let mut previous = vec![DVec3::ZERO; n];
    let mut w = vec![DVec3::ZERO; n];
    let (mut alpha, mut beta) = (Vec::new(), Vec::<f64>::new());
    let mut ritz = Vec::new();
    let mut top = 0.0;
    for j in 0..MAX_ITERATIONS {
        apply(model, positions, &scale, &v, &mut w, ground);
        let a = dot(&v, &w);
        let b_prev = beta.last().copied().unwrap_or(0.0);
        for ((wi, vi), pi) in w.iter_mut().zip(&v).zip(&previous) {
            *wi -= a * *vi + b_prev * *pi;
        }
        alpha.push(a);
        top = top_eigenvalue(&alpha, &beta).max(0.0);
        ritz.push(top);
        let b = dot(&w, &w).sqrt();
        let settled = j >= SETTLED_OVER && top - ritz[j - SETTLED_OVER] <= TOLERANCE * top;
        // An invariant subspace (the spring's one direction, a chain's few):
        // the Ritz values are its eigenvalues.
        if settled || !b.is_finite() || b <= 1e-12 * top.max(f64::MIN_POSITIVE) {
            return Spectrum {
                omega_max: top.sqrt(),
                iterations: j + 1,
            };
        }
        beta.push(b);
        std::mem::swap(&mut previous, &mut v);
        for (vi, wi) in v.iter_mut().zip(&w) {
            *vi = *wi / b;
        }
    }
    Spectrum {
        omega_max: top.sqrt(),
        iterations: MAX_ITERATIONS,
    }
}

/// The last [`omega_max`] a system found, kept so that an edit that scales every
/// spring's stiffness (and the ground's) by one factor and every inverse mass by
/// another scales it instead of iterating again: `lambda_max(c K, w M^-1) = c w
/// lambda_max(K, M^-1)`. The stiffness and mass sliders make such edits (each of
/// a grid's three kinds set from one stiffness); any other change of the springs,
/// the pins or the integrator's use of the springs finds the spectrum again, at
/// the positions then. It keeps each spring kind's stiffness and each particle's
/// inverse mass: 8 bytes a particle.
#[derive(Debug, Default)]
pub struct Cache(Mutex<Option<Cached>>);

#[derive(Clone, Debug)]
struct Cached {
    /// `omega_max²`, rad²/s².
    lambda: f64,
    springs_on: bool,
    springs: usize,
    ground: f64,
    stiffness: [f64; SpringKind::ALL.len()],
    inv_mass: Vec<f64>,
}

impl Clone for Cache {
    fn clone(&self) -> Self {
        let inner = self.0.lock().map_or(None, |c| c.clone());
        Self(Mutex::new(inner))
    }
}

/// The one factor `new = f old` for every pair (`None` where the factors differ
/// or the zeros do not match), with relative tolerance `1e-9`.
fn common_factor(
    mut new: impl Iterator<Item = f64>,
    mut old: impl Iterator<Item = f64>,
) -> Option<f64> {
    let mut factor = None;
    loop {
        let (n, o) = match (new.next(), old.next()) {
            (Some(n), Some(o)) => (n, o),
            (None, None) => return Some(factor.unwrap_or(1.0)),
            _ => return None,
        };
        if o == 0.0 || n == 0.0 {
            if o != n {
                return None;
            }
            continue;
        }
        let f = *factor.get_or_insert(n / o);
        if (n - f * o).abs() > 1e-9 * n.abs() {
            return None;
        }
    }
}

impl Cached {
    /// `lambda_max` for `model` if it is this one with its stiffness and inverse
    /// masses scaled.
    fn scaled_to(&self, model: &Model) -> Option<f64> {
        let ground = model.params.ground.map_or(0.0, |g| g.stiffness.max(0.0));
        if model.terms.springs != self.springs_on
            || model.springs.len() != self.springs
            || model.inv_mass.len() != self.inv_mass.len()
        {
            return None;
        }
        let stiffness = (model.materials.iter().map(|m| m.stiffness)).chain([ground]);
        let old = self.stiffness.iter().copied().chain([self.ground]);
        let k = common_factor(stiffness, old)?;
        let inv_mass = model.inv_mass.iter().map(|w| w.max(0.0));
        let w = common_factor(inv_mass, self.inv_mass.iter().copied())?;
        Some(self.lambda * k * w)
    }
}

impl Cache {
    /// [`omega_max`] for `model` at `positions`, scaled from the last one where
    /// only the stiffness and masses were scaled since.
    pub fn omega_max(&self, model: &Model, positions: &[DVec3]) -> f64 {
        let Ok(mut cached) = self.0.lock() else {
            return omega_max(model, positions).omega_max;
        };
        if let Some(lambda) = cached.as_ref().and_then(|c| c.scaled_to(model)) {
            return lambda.sqrt();
        }
        let omega = omega_max(model, positions).omega_max;
        *cached = Some(Cached {
            lambda: omega * omega,
            springs_on: model.terms.springs,
            ground: model.params.ground.map_or(0.0, |g| g.stiffness.max(0.0)),
            springs: model.springs.len(),
            stiffness: model.materials.map(|m| m.stiffness),
            inv_mass: model.inv_mass.iter().map(|w| w.max(0.0)).collect(),
        });
        omega
    }
}

#[cfg(test)]
mod tests {
    use super::top_eigenvalue;

    /// The tridiagonal solver on the path Laplacian, whose top eigenvalue is
    /// `2 - 2 cos(n π / (n + 1))`.
    #[test]
    fn the_top_eigenvalue_of_a_path_laplacian_is_its_closed_form() {
        for n in [1usize, 2, 5, 40] {
            let alpha = vec![2.0; n];
            let beta = vec![-1.0; n - 1];
            let exact = 2.0 - 2.0 * (n as f64 * std::f64::consts::PI / (n as f64 + 1.0)).cos();
            let top = top_eigenvalue(&alpha, &beta);
            assert!((top - exact).abs() < 1e-9, "n = {n}: {top} vs {exact}");
        }
    }
}
