//! Linearised backward Euler (Baraff & Witkin 1998) for stiff springs.
//!
//! One Newton step of `v_{n+1} = v_n + h M^-1 f(x_n + h v_{n+1}, v_{n+1})`:
//! `(M - h df/dv - h² df/dx) dv = h (f + h df/dx v)`, then `v += dv`, `x += h v`.
//! The matrix is applied without being assembled: per spring, the blocks
//! `df_a/dx_a = -k [u uᵀ + max(0, 1 - L/l)(I - u uᵀ)]` (the compressive part is
//! dropped so the matrix stays positive definite, as Baraff & Witkin and Choi & Ko
//! do) and `df_a/dv_a = -b u uᵀ`; air damping and ground contact add to the
//! diagonal. It is solved by conjugate gradients with a 3x3 block-Jacobi
//! preconditioner (each particle's own block of the matrix, inverted);
//! pinned particles are filtered out (their `dv` is zero); each solve starts from the
//! previous step's `dv`. Aerodynamic drag is
//! treated explicitly. Unconditionally stable; first order.

use glam::{DMat3, DVec3};

use super::{Model, State};

/// Relative residual at which conjugate gradients stop.
pub const CG_TOLERANCE: f64 = 1e-6;
/// Iteration cap of conjugate gradients.
pub const CG_MAX_ITERATIONS: usize = 1000;

/// Scratch space for the implicit step.
#[derive(Clone, Debug, Default)]
pub struct ImplicitWorkspace {
    forces: Vec<DVec3>,
    spring_forces: Vec<DVec3>,
    /// Per spring, `S = h b u uᵀ + h² k [u uᵀ + max(0, 1 - L/l)(I - u uᵀ)]` (positive semidefinite).
    blocks: Vec<DMat3>,
    /// Per spring, the stiffness part alone (`h² k [...]`), for the `h² df/dx v` term.
    stiffness_blocks: Vec<DMat3>,
    diagonal: Vec<DMat3>,
    /// Per particle, the inverse of its 3x3 diagonal block (zero when held).
    preconditioner: Vec<DMat3>,
    rhs: Vec<DVec3>,
    dv: Vec<DVec3>,
    residual: Vec<DVec3>,
    direction: Vec<DVec3>,
    product: Vec<DVec3>,
    preconditioned: Vec<DVec3>,
    /// Iterations the last solve took.
    pub last_iterations: usize,
}

impl ImplicitWorkspace {
    /// Sizes the buffers for `n` particles and `m` springs.
    pub fn resize(&mut self, n: usize, m: usize) {
        for v in [
            &mut self.forces,
            &mut self.rhs,
            &mut self.dv,
            &mut self.residual,
            &mut self.direction,
            &mut self.product,
            &mut self.preconditioned,
        ] {
            v.resize(n, DVec3::ZERO);
        }
        self.diagonal.resize(n, DMat3::ZERO);
        self.preconditioner.resize(n, DMat3::ZERO);
        self.spring_forces.resize(m, DVec3::ZERO);
        self.blocks.resize(m, DMat3::ZERO);
        self.stiffness_blocks.resize(m, DMat3::ZERO);
    }
}

/// One linearised backward-Euler step of `h`.
pub fn step(model: &Model, state: &mut State, w: &mut ImplicitWorkspace, h: f64, t: f64) {
    let n = state.positions.len();
    w.resize(n, model.springs.len());
    let (x, v) = (&state.positions, &state.velocities);
    model.forces(x, v, t, &mut w.spring_forces, &mut w.forces);
    let gravity = if model.terms.gravity {
        model.params.gravity
    } else {
        DVec3::ZERO
    };

    // Diagonal: M + h c I, plus ground contact for particles in it.
    let c_air = if model.terms.air_damping {
        model.params.air_damping
    } else {
        0.0
    };
    for i in 0..n {
        w.diagonal[i] = DMat3::from_diagonal(DVec3::splat(model.mass[i] + h * c_air));
    }
    // rhs = h (f + m g) + h² (df/dx) v.
    for i in 0..n {
        w.rhs[i] = h * (w.forces[i] + model.mass[i] * gravity);
    }
    if let (true, Some(ground)) = (model.terms.ground, model.params.ground) {
        for i in 0..n {
            if ground.height - x[i].y > 0.0 {
                w.diagonal[i].y_axis.y += h * ground.damping + h * h * ground.stiffness;
                w.rhs[i].y -= h * h * ground.stiffness * v[i].y;
            }
        }
    }
    for (si, s) in model.springs.iter().enumerate() {
        let (a, b) = (s.a as usize, s.b as usize);
        let d = x[a] - x[b];
        let l = d.length();
        if l <= super::forces::EPSILON_LENGTH {
            w.blocks[si] = DMat3::ZERO;
            w.stiffness_blocks[si] = DMat3::ZERO;
            continue;
        }
        let u = d / l;
        let uu = outer(u, u);
        let transverse = (1.0 - s.rest / l).max(0.0);
        let m = model.material(s.kind);
        let stiffness = h * h * m.stiffness * (uu + transverse * (DMat3::IDENTITY - uu));
        w.stiffness_blocks[si] = stiffness;
        w.blocks[si] = stiffness + h * m.damping * uu;
        // h² (df/dx v)_a = -h² K_s (v_a - v_b); the block already holds the h².
        let kv = stiffness * (v[a] - v[b]);
        w.rhs[a] -= kv;
        w.rhs[b] += kv;
    }
    for i in 0..n {
        // The particle's block of the matrix: its diagonal plus each spring's block
        // (positive definite: the mass term alone is).
        let mut block = w.diagonal[i];
        for (si, _) in model.adjacency().springs_of(i) {
            block += w.blocks[si];
        }
        w.preconditioner[i] = if model.inv_mass[i] > 0.0 && block.determinant() > 0.0 {
            block.inverse()
        } else {
            DMat3::ZERO
        };
        if model.inv_mass[i] == 0.0 {
            w.rhs[i] = DVec3::ZERO;
        }
    }
    solve(model, w);
    for i in 0..n {
        if model.inv_mass[i] > 0.0 {
            state.velocities[i] += w.dv[i];
            state.positions[i] += h * state.velocities[i];
        }
    }
}

/// `product = A p` with pinned rows and columns filtered out.
fn apply(model: &Model, blocks: &[DMat3], diagonal: &[DMat3], p: &[DVec3], out: &mut [DVec3]) {
    for i in 0..p.len() {
        out[i] = diagonal[i] * p[i];
    }
    for (s, blk) in model.springs.iter().zip(blocks) {
        let (a, b) = (s.a as usize, s.b as usize);
        let y = *blk * (p[a] - p[b]);
        out[a] += y;
        out[b] -= y;
    }
    for (o, &w) in out.iter_mut().zip(&model.inv_mass) {
        if w == 0.0 {
            *o = DVec3::ZERO;
        }
    }
}

fn dot(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a.dot(*b)).sum()
}

/// Preconditioned conjugate gradients for `A dv = rhs`, warm-started from the
/// previous step's `dv` (consecutive steps change velocity alike).
fn solve(model: &Model, w: &mut ImplicitWorkspace) {
    for (dv, &inv_mass) in w.dv.iter_mut().zip(&model.inv_mass) {
        if inv_mass == 0.0 || !dv.is_finite() {
            *dv = DVec3::ZERO;
        }
    }
    apply(model, &w.blocks, &w.diagonal, &w.dv, &mut w.product);
    for i in 0..w.dv.len() {
        w.residual[i] = w.rhs[i] - w.product[i];
    }
    for i in 0..w.dv.len() {
        w.preconditioned[i] = w.preconditioner[i] * w.residual[i];
    }
    w.direction.copy_from_slice(&w.preconditioned);
    let rhs_norm2 = dot(&w.rhs, &w.rhs);
    let mut rz = dot(&w.residual, &w.preconditioned);
    w.last_iterations = 0;
    if rhs_norm2 == 0.0 {
        w.dv.fill(DVec3::ZERO);
        return;
    }
    if dot(&w.residual, &w.residual) <= CG_TOLERANCE * CG_TOLERANCE * rhs_norm2 {
        return;
    }
    for iteration in 1..=CG_MAX_ITERATIONS {
        apply(model, &w.blocks, &w.diagonal, &w.direction, &mut w.product);
        let pap = dot(&w.direction, &w.product);
        if pap.is_nan() || pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        for i in 0..w.dv.len() {
            w.dv[i] += alpha * w.direction[i];
            w.residual[i] -= alpha * w.product[i];
        }
        w.last_iterations = iteration;
        if dot(&w.residual, &w.residual) <= CG_TOLERANCE * CG_TOLERANCE * rhs_norm2 {
            break;
        }
        for i in 0..w.dv.len() {
            w.preconditioned[i] = w.preconditioner[i] * w.residual[i];
        }
        let rz_next = dot(&w.residual, &w.preconditioned);
        let beta = rz_next / rz;
        rz = rz_next;
        for i in 0..w.dv.len() {
            w.direction[i] = w.preconditioned[i] + beta * w.direction[i];
        }
    }
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}
