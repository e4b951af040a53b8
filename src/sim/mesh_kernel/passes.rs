//! The mesh engine's passes over its arrays: the springs' forces in batches, the
//! triangles' drag, and each particle's sum of them and its step, split into
//! ranges over the pool's threads.

use glam::DVec3;

use super::build::SpringArrays;
use super::{B_END, BATCH, MeshParams, RUN_MIN};
use crate::sim::Integrator;
use crate::sim::forces::{ground_force, spring_force, triangle_drag};
use crate::sim::grid_kernel::SimdLevel;
use crate::sim::integrators::euler_update;
use crate::sim::laws::length_correction;
use crate::sim::laws::{self, Method, V3, step_particle};

pub(super) type Halves<'b> = ([&'b mut [f64]; 3], [&'b mut [f64]; 3]);

/// Three slices each split at `mid` (or at their end when shorter: empty ones).
pub(super) fn halves(a: [&mut [f64]; 3], mid: usize) -> Halves<'_> {
    let [a0, a1, a2] = a.map(|s| {
        let mid = mid.min(s.len());
        s.split_at_mut(mid)
    });
    ([a0.0, a1.0, a2.0], [a0.1, a1.1, a2.1])
}

/// What the spring pass reads.
pub(super) struct SpringCtx<'a> {
    pub(super) springs: &'a SpringArrays,
    pub(super) x: [&'a [f64]; 3],
    pub(super) v: [&'a [f64]; 3],
    pub(super) avx2: bool,
}

/// Each spring's force on its `a` end, for springs `start..start + out[0].len()`.
pub(super) fn spring_pass(ctx: &SpringCtx, start: usize, out: [&mut [f64]; 3]) {
    #[cfg(target_arch = "x86_64")]
    if ctx.avx2 {
        // SAFETY: `avx2` is set only when the CPU has AVX2.
        unsafe { spring_pass_avx2(ctx, start, out) };
        return;
    }
    spring_pass_body(ctx, start, out);
}

/// The compiled version of the spring pass this CPU runs: its AVX2 build where
/// the grid kernels may run AVX2 or better ([`SimdLevel::detect`]), else the
/// baseline one.
pub(crate) fn simd_level() -> SimdLevel {
    SimdLevel::detect().min(SimdLevel::Avx2)
}

/// [`spring_pass`] compiled for AVX2: four springs per instruction (IEEE square
/// roots and divisions and no fused multiply-add, so the same results as the
/// baseline build). (An AVX-512 build measured no faster on the 32^3 jelly: the
/// pass streams 56 bytes a spring.)
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn spring_pass_avx2(ctx: &SpringCtx, start: usize, out: [&mut [f64]; 3]) {
    spring_pass_body(ctx, start, out);
}

#[inline(always)]
pub(super) fn spring_pass_body(ctx: &SpringCtx, start: usize, out: [&mut [f64]; 3]) {
    let (x, v) = (ctx.x, ctx.v);
    let springs = ctx.springs;
    let [rest, k, b] = springs.coefficients.each_ref().map(Vec::as_slice);
    let mut d = [[0.0; BATCH]; 3];
    let mut dv = [[0.0; BATCH]; 3];
    let [fx, fy, fz] = out;
    let len = fx.len();
    let mut lo = 0;
    while lo < len {
        let first = start + lo;
        let run = usize::from(springs.run[first]).min(len - lo);
        // A run of at least a vector's width: its ends are contiguous slices.
        let n = if run >= RUN_MIN {
            let [a, b] = springs.ends[first].map(|e| e as usize);
            for k in 0..3 {
                let (xa, xb) = (&x[k][a..a + run], &x[k][b..b + run]);
                let (va, vb) = (&v[k][a..a + run], &v[k][b..b + run]);
                let (d, dv) = (&mut d[k][..run], &mut dv[k][..run]);
                for e in 0..run {
                    d[e] = xa[e] - xb[e];
                    dv[e] = va[e] - vb[e];
                }
            }
            run
        } else {
            // Gathered one by one, up to the next run.
            let mut n = 0;
            while n < BATCH && lo + n < len && (n == 0 || springs.run[first + n] < RUN_MIN as u8) {
                let [a, b] = springs.ends[first + n].map(|e| e as usize);
                for k in 0..3 {
                    d[k][n] = x[k][a] - x[k][b];
                    dv[k][n] = v[k][a] - v[k][b];
                }
                n += 1;
            }
            n
        };
        let (rest, k, b) = (
            &rest[first..first + n],
            &k[first..first + n],
            &b[first..first + n],
        );
        let (fx, fy, fz) = (
            &mut fx[lo..lo + n],
            &mut fy[lo..lo + n],
            &mut fz[lo..lo + n],
        );
        for e in 0..n {
            let f = spring_force(
                DVec3::new(d[0][e], d[1][e], d[2][e]),
                DVec3::new(dv[0][e], dv[1][e], dv[2][e]),
                rest[e],
                k[e],
                b[e],
            );
            (fx[e], fy[e], fz[e]) = (f.x, f.y, f.z);
        }
        lo += n;
    }
}

/// Runs `pass(start, out)` over `out` split in halves down to `leaf` entries,
/// with `rayon::join` (a pass over springs or triangles, each writing its own).
pub(super) fn split_pass(
    start: usize,
    out: [&mut [f64]; 3],
    leaf: usize,
    pass: &(impl Fn(usize, [&mut [f64]; 3]) + Sync),
) {
    let len = out[0].len();
    if len <= leaf {
        pass(start, out);
        return;
    }
    let mid = len / 2;
    let (a, b) = halves(out, mid);
    rayon::join(
        || split_pass(start, a, leaf, pass),
        || split_pass(start + mid, b, leaf, pass),
    );
}

/// What the drag pass reads: the triangles, the state and the air.
pub(super) struct TriangleCtx<'a> {
    pub(super) triangles: &'a [[u32; 3]],
    pub(super) x: [&'a [f64]; 3],
    pub(super) v: [&'a [f64]; 3],
    /// The wind at the step's start time.
    pub(super) wind: DVec3,
    pub(super) half_rho_cd: f64,
}

/// Each triangle's drag on each of its vertices ([`triangle_drag`], the f64
/// engine's), for triangles `start..start + out[0].len()`. (Gathered in batches for an AVX2
/// build that vectorizes the forces, it measured no faster on the tablecloth:
/// 10.2 M particle-steps/s on one core either way.)
pub(super) fn triangle_pass(ctx: &TriangleCtx, start: usize, out: [&mut [f64]; 3]) {
    let [fx, fy, fz] = out;
    for (e, &[a, b, c]) in ctx.triangles[start..start + fx.len()].iter().enumerate() {
        let (a, b, c) = (a as usize, b as usize, c as usize);
        let x = [load(ctx.x, a), load(ctx.x, b), load(ctx.x, c)];
        let v = [load(ctx.v, a), load(ctx.v, b), load(ctx.v, c)];
        let f = triangle_drag(x, v, ctx.wind, ctx.half_rho_cd);
        (fx[e], fy[e], fz[e]) = (f.x, f.y, f.z);
    }
}

/// How many springs, triangles and particles one task of a pass takes on at least.
#[derive(Clone, Copy)]
pub(super) struct Leaves {
    pub(super) springs: usize,
    pub(super) triangles: usize,
    pub(super) particles: usize,
}

/// What the particle pass reads.
pub(super) struct Ctx<'a> {
    pub(super) p: MeshParams,
    pub(super) x: [&'a [f64]; 3],
    pub(super) v: [&'a [f64]; 3],
    pub(super) inv_mass: &'a [f64],
    pub(super) offsets: &'a [u32],
    pub(super) links: &'a [u32],
    pub(super) spring_f: [&'a [f64]; 3],
    pub(super) triangle_offsets: &'a [u32],
    pub(super) triangle_links: &'a [u32],
    pub(super) triangle_f: [&'a [f64]; 3],
}

/// What the particle pass writes, for particles `start..start + len`.
pub(super) struct Out<'a> {
    pub(super) start: usize,
    pub(super) x: [&'a mut [f64]; 3],
    pub(super) v: [&'a mut [f64]; 3],
    /// Verlet's `u`, updated in place (only its own particle reads it); empty otherwise.
    pub(super) u: [&'a mut [f64]; 3],
}

impl Out<'_> {
    pub(super) fn len(&self) -> usize {
        self.x[0].len()
    }

    pub(super) fn split(self, mid: usize) -> (Self, Self) {
        let (x0, x1) = halves(self.x, mid);
        let (v0, v1) = halves(self.v, mid);
        let (u0, u1) = halves(self.u, mid);
        let first = Self {
            start: self.start,
            x: x0,
            v: v0,
            u: u0,
        };
        let second = Self {
            start: self.start + mid,
            x: x1,
            v: v1,
            u: u1,
        };
        (first, second)
    }
}

pub(super) fn load(a: [&[f64]; 3], i: usize) -> DVec3 {
    DVec3::new(a[0][i], a[1][i], a[2][i])
}

pub(super) fn store(a: &mut [&mut [f64]; 3], i: usize, value: DVec3) {
    a[0][i] = value.x;
    a[1][i] = value.y;
    a[2][i] = value.z;
}

/// `out` made a copy of the positions `x` (structure of arrays), one vector each.
pub(super) fn copy_positions(out: &mut Vec<DVec3>, x: &[Vec<f64>; 3]) {
    out.clear();
    out.extend((x[0].iter().zip(&x[1]).zip(&x[2])).map(|((&x, &y), &z)| DVec3::new(x, y, z)));
}

/// Forces, accelerations and the integrator's update for the particles of `out`.
pub(super) fn advance(ctx: &Ctx, mut out: Out) {
    let p = &ctx.p;
    let h = p.dt;
    let verlet = !out.u[0].is_empty();
    let sf = ctx.spring_f;
    for local in 0..out.len() {
        let i = out.start + local;
        let xi = load(ctx.x, i);
        let vi = load(ctx.v, i);
        // The f64 engine's gather: `f += sign * f_spring` in spring order.
        let mut f = DVec3::ZERO;
        let links = if p.spring_forces {
            &ctx.links[ctx.offsets[i] as usize..ctx.offsets[i + 1] as usize]
        } else {
            &[]
        };
        for &e in links {
            let s = (e & !B_END) as usize;
            let sign = if e & B_END == 0 { 1.0 } else { -1.0 };
            f += sign * DVec3::new(sf[0][s], sf[1][s], sf[2][s]);
        }
        if p.drag.is_some() {
            let tf = ctx.triangle_f;
            let range = ctx.triangle_offsets[i] as usize..ctx.triangle_offsets[i + 1] as usize;
            for &t in &ctx.triangle_links[range] {
                let t = t as usize;
                f += DVec3::new(tf[0][t], tf[1][t], tf[2][t]);
            }
        }
        if p.air_damping > 0.0 {
            let neg_c = -p.air_damping;
            f = V3::from(f)
                .zip(V3::from(vi), |f, v| laws::air_damped(f, neg_c, v))
                .into();
        }
        if let Some(ground) = &p.ground {
            f.y += ground_force(ground, xi, vi);
        }
        f += p.force;
        let w = ctx.inv_mass[i];
        let a: DVec3 = V3::from(f)
            .zip(V3::from(p.gravity), |f, g| laws::acceleration(f, w, g))
            .into();
        let (x_new, v_new) = match p.integrator {
            Integrator::ExplicitEuler => euler_update(false, xi, vi, a, w, h),
            Integrator::Verlet if verlet => {
                let u = load(out.u.each_ref().map(|s| &**s), local);
                let [x, u, v] = step_particle(Method::Verlet, xi, u, a, w, h);
                store(&mut out.u, local, u);
                (x, v)
            }
            _ => euler_update(true, xi, vi, a, w, h),
        };
        store(&mut out.x, local, x_new);
        store(&mut out.v, local, v_new);
    }
}

/// Splits `out` in halves down to `leaf` particles, run with `rayon::join`.
pub(super) fn advance_parallel(ctx: &Ctx, out: Out, leaf: usize) {
    if out.len() <= leaf {
        advance(ctx, out);
        return;
    }
    let mid = out.len() / 2;
    let (a, b) = out.split(mid);
    rayon::join(
        || advance_parallel(ctx, a, leaf),
        || advance_parallel(ctx, b, leaf),
    );
}

/// Moves particles `a` and `b` along their joining line to distance `target(l)`
/// ([`length_correction`]), on structure-of-arrays positions.
pub(super) fn restore_length(
    x: &mut [Vec<f64>; 3],
    inv_mass: &[f64],
    a: usize,
    b: usize,
    target: impl Fn(f64) -> Option<f64>,
) {
    let (wa, wb) = (inv_mass[a], inv_mass[b]);
    let xa = DVec3::new(x[0][a], x[1][a], x[2][a]);
    let xb = DVec3::new(x[0][b], x[1][b], x[2][b]);
    if let Some(c) = length_correction(xa, xb, wa, wb, target) {
        let (na, nb) = (xa - wa * c, xb + wb * c);
        for (k, axis) in x.iter_mut().enumerate() {
            axis[a] = na[k];
            axis[b] = nb[k];
        }
    }
}
