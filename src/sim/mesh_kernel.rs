//! The mesh engine: any topology (chains, lattices, ropes, meshes) stepped in f64
//! on structure-of-arrays state, each particle gathering its own forces.
//!
//! State is `x, y, z, vx, vy, vz` (m, m/s) and, for position Verlet, the velocity of
//! the last position update `u = (x - x_prev) / h`. A step is two passes, three
//! with aerodynamic drag (below); under XPBD the first is skipped: its springs are
//! constraints, after the step:
//! 1. each spring's force on its `a` end, `f_a = -(k (l - L) + b (v_a - v_b)·u) u`
//!    with `u = (x_a - x_b)/l` ([`spring_force`]), into a per-spring array: the
//!    springs are evaluated in batches of up to `BATCH`, their ends read as
//!    slices where they come in runs with consecutive ends (a lattice's do, in
//!    `SpringArrays`' order), else gathered to the stack, in a loop the compiler
//!    vectorizes (built for AVX2 when the CPU has it);
//! 2. per particle, the sum over its springs from a compressed adjacency (CSR) in
//!    the model's canonical spring order, `+f` at an `a` end and `-f` at a `b` end,
//!    then air damping `-c v`, ground penalty `k_c d - c_g v_y` (at depth `d > 0`),
//!    `a = F / m + g` (0 when pinned) and one step of symplectic Euler, explicit
//!    Euler or position Verlet (`u += h a; x += h u; v = u + h/2 a`), written into
//!    a second set of arrays (ping-pong).
//!
//! That is the f64 engine's arithmetic in its order, so symplectic and explicit
//! Euler give bit for bit its results (Verlet rounds differently: it keeps `u`, not
//! `x_prev`). Threads split the springs, then the particles, into ranges: no two
//! write the same memory, and results are the same for any number of threads.
//! (Evaluating each spring from both ends in the particle pass, which needs no
//! per-spring array, measured 0.7x as fast: twice the square roots and divisions.)
//!
//! Constraints follow, on one thread, Gauss-Seidel in the f64 engine's order (bars
//! `bar_iterations` times, stretch limit, self-collision, the colliders' contact);
//! a particle moved by `δ` gains `δ/h` in `v` (and in `u` for Verlet).
//! Self-collision is the shared pass ([`super::self_collision`]) on a copy of the
//! positions, on the pool's threads from its own size on.
//!
//! Per-triangle aerodynamic drag is a third pass before the particles' one, as
//! the f64 engine computes it: each triangle's [`triangle_drag`] (the wind
//! at the step's start time, gusts included) into a per-triangle array, which each
//! particle adds after its springs, in the order of the triangles.
//!
//! With a tear strain, a step that leaves springs past it breaks them as the f64
//! engine does ([`super::tearing`]): the engine removes them (and the triangles
//! along them) from its own copies, rebuilds its adjacency without sorting the
//! springs again, and hands the breaks to the model with its state.
//!
//! A step allocates nothing.

use glam::DVec3;

use super::constraints::{xpbd_pass, xpbd_sweeps_back};
use super::forces::{ground_force, spring_force, triangle_drag};
use super::grid_kernel::SimdLevel;
use super::integrators::euler_update;
use super::laws::overstretched;
use super::laws::{self, Method, V3, step_particle};
use super::laws::{Contact, length_correction, speed_limit};
use super::springs;
use super::springs::{Adjacency, BarPairs};
use super::tearing::remove_broken;
use super::{
    Bar, GridShape, Ground, Integrator, LatticeShape, Model, SelfCollision, Sphere, Spring, Wind,
};

/// Models with fewer particles than this run on the calling thread even when
/// several threads are allowed. Measured on the jelly lattice (about 12 springs a
/// particle), 2 threads against 1 on two busy cores: no gain at 512 particles,
/// 1.1-1.65x at 1,000, 1.75-1.9x from 1,728 on.
pub const PARALLEL_MIN_PARTICLES: usize = 1500;

/// Smallest range of springs or particles one task takes on when a pass is split.
const MIN_LEAF: usize = 512;

/// Springs gathered to the stack and evaluated together.
const BATCH: usize = 32;

/// The shortest run of springs with consecutive ends read as slices.
const RUN_MIN: usize = 4;

/// Marks a link at a spring's `b` end (the force there is minus the spring's).
const B_END: u32 = 1 << 31;

/// What the mesh engine needs of the parameters, already reduced to the terms that
/// run (gravity zero when off, air damping 0 when off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshParams {
    /// Gravitational acceleration in m/s² (zero when the term is off).
    pub gravity: DVec3,
    /// The applied force on every particle in N (zero when the term is off).
    pub force: DVec3,
    /// Viscous air damping `c` in N·s/m (0: off).
    pub air_damping: f64,
    /// Ground plane, if any.
    pub ground: Option<Ground>,
    /// Sphere collider, if any.
    pub sphere: Option<Sphere>,
    /// Symplectic Euler, explicit Euler, position Verlet or XPBD (symplectic Euler
    /// without the springs' forces, then their constraint pass).
    pub integrator: Integrator,
    /// Time step in s.
    pub dt: f64,
    /// Bar relaxation passes per step.
    pub bar_iterations: u32,
    /// Maximum stretch `tau` of springs, if any.
    pub stretch_limit: Option<f64>,
    /// Coulomb friction coefficient of the ground and the sphere (and of the
    /// cloth on itself).
    pub friction: f64,
    /// Self-collision's thickness `h_c` in m, if the particles keep it apart
    /// ([`super::self_collision`]).
    pub self_collision: Option<f64>,
    /// Speed limit in m/s, if any (`super::laws::speed_limit`).
    pub max_speed: Option<f64>,
    /// Whether the springs are forces; under XPBD they are constraints instead,
    /// one Gauss-Seidel pass of `xpbd_pass` after the prediction.
    pub spring_forces: bool,
    /// Per-triangle aerodynamic drag, if on.
    pub drag: Option<Drag>,
    /// Tear strain `tau`, if springs tear ([`super::tearing`]).
    pub tear_strain: Option<f64>,
}

/// Per-triangle aerodynamic drag ([`triangle_drag`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drag {
    /// `ρ C_d / 2` in kg/m³.
    pub half_rho_cd: f64,
    /// The air's velocity over time.
    pub wind: Wind,
}

impl MeshParams {
    /// The parameters of `model`, if the mesh engine models it exactly: an
    /// integrator it [`MeshKernel::supports`].
    ///
    /// Every parameter and force term is named here (no `..`): a new one fails to
    /// compile until it is either passed to the engine or made a reason to refuse it.
    pub fn of(model: &Model) -> Option<Self> {
        let super::Params {
            gravity,
            force,
            wind: _, // in `model.wind`, with the gusts
            gust: _,
            air_density: _,      // in `Params::half_rho_cd`
            drag_coefficient: _, // likewise
            air_damping,
            ground,
            sphere,
            integrator,
            dt,
            bar_iterations,
            stretch_limit,
            tear_strain,
            max_speed,
            friction,
            thickness,
            self_collision: _, // with `thickness`, in `Params::self_collides`
            seed: _,           // only the gusts use it, in `model.wind`
        } = model.params;
        let super::ForceTerms {
            gravity: gravity_on,
            springs: spring_forces,
            aero,
            air_damping: air_damping_on,
            ground: _, // `ground` itself says
            applied,
        } = model.terms;
        if !MeshKernel::supports(integrator) {
            return None;
        }
        Some(Self {
            gravity: if gravity_on { gravity } else { DVec3::ZERO },
            force: if applied { force } else { DVec3::ZERO },
            air_damping: if air_damping_on { air_damping } else { 0.0 },
            ground,
            sphere,
            integrator,
            dt,
            bar_iterations,
            stretch_limit,
            friction,
            self_collision: model.params.self_collides().then_some(thickness),
            max_speed,
            spring_forces,
            drag: aero.then_some(Drag {
                half_rho_cd: model.params.half_rho_cd(),
                wind: model.wind,
            }),
            tear_strain,
        })
    }
}

/// The mesh engine's state and topology.
pub struct MeshKernel {
    params: MeshParams,
    /// Positions `[x, y, z]` in m.
    x: [Vec<f64>; 3],
    /// Velocities in m/s.
    v: [Vec<f64>; 3],
    /// Verlet's velocity of the last position update (empty for the other methods).
    u: [Vec<f64>; 3],
    /// The other half of the ping-pong pair for `x` and `v`.
    x_next: [Vec<f64>; 3],
    v_next: [Vec<f64>; 3],
    /// Positions before the constraints (empty without constraints).
    before: [Vec<f64>; 3],
    inv_mass: Vec<f64>,
    /// Each spring's force on its `a` end in N, this step.
    spring_f: [Vec<f64>; 3],
    /// `offsets[i]..offsets[i + 1]` indexes `links`.
    offsets: Vec<u32>,
    /// Per particle, the springs touching it, with [`B_END`] set at a `b` end.
    links: Vec<u32>,
    /// The springs as the first pass reads them.
    springs: SpringArrays,
    /// The surface triangles the drag acts on.
    triangles: Vec<[u32; 3]>,
    /// Each triangle's drag on each of its vertices in N, this step.
    triangle_f: [Vec<f64>; 3],
    /// `triangle_offsets[i]..triangle_offsets[i + 1]` indexes `triangle_links`.
    triangle_offsets: Vec<u32>,
    /// Per particle, the triangles it is a vertex of, in the model's order (as
    /// often as it is a vertex of each).
    triangle_links: Vec<u32>,
    /// Simulated time in s at the start of the next step (the gusts' clock).
    time: f64,
    /// The grid's or the lattice's shape, if the particles form one (the order of
    /// the constraint passes follows it).
    grid: Option<GridShape>,
    lattice: Option<LatticeShape>,
    /// Springs torn since the model last took them ([`Self::take_torn`]).
    torn: Vec<(u32, u32)>,
    /// The model's springs, canonical (for the stretch limit and to notice edits).
    model_springs: Vec<Spring>,
    /// The order the stretch limit visits `model_springs` in (the model's).
    constraint_order: Vec<u32>,
    bars: Vec<Bar>,
    threads: usize,
    pool: Option<rayon::ThreadPool>,
    /// Whether the passes run their AVX2 builds.
    avx2: bool,
    /// The model's adjacency and bars, for self-collision to tell the pairs a
    /// spring or a bar joins.
    adjacency: Adjacency,
    bar_pairs: BarPairs,
    /// Self-collision's pass and what it keeps between steps.
    self_collision: SelfCollision,
    /// Copies of the positions, now and at the start of the step, for the passes
    /// the f64 engine shares (XPBD's springs, self-collision), which work on
    /// arrays of vectors.
    copy_x: Vec<DVec3>,
    copy_start: Vec<DVec3>,
    /// XPBD's multiplier of each spring in its pass.
    multipliers: Vec<f64>,
}

/// Springs as structure of arrays, in the order the spring pass evaluates them:
/// by the offset `b - a` between their ends, then by `a`. A lattice's springs of one
/// direction then come in runs with consecutive ends (`a, a + 1, ...` and `b, b +
/// 1, ...`), whose positions are read as contiguous slices instead of one by one.
/// (The order of evaluation changes no result: each force is stored apart and the
/// particles sum them in the model's order.)
#[derive(Clone, Debug, Default)]
struct SpringArrays {
    /// The model's index of each spring, in evaluation order.
    order: Vec<u32>,
    /// Ends `[a, b]`.
    ends: Vec<[u32; 2]>,
    /// How many springs from this one on continue its run (at least 1, at most
    /// [`BATCH`]).
    run: Vec<u8>,
    /// `[rest length (m), stiffness (N/m), damping (N·s/m)]`.
    coefficients: [Vec<f64>; 3],
}

impl SpringArrays {
    fn new(springs: &[Spring]) -> Self {
        let mut order: Vec<u32> = (0..springs.len() as u32).collect();
        // The keys differ from spring to spring.
        order.sort_unstable_by_key(|&i| {
            let s = &springs[i as usize];
            (i64::from(s.b) - i64::from(s.a), s.a)
        });
        Self::in_order(springs, order)
    }

    /// The arrays for `springs` when they are `old`'s springs with some removed
    /// (torn), in `old`'s order less the removed ones, without sorting again;
    /// `None` when they are not.
    fn kept(&self, old: &[Spring], springs: &[Spring]) -> Option<Self> {
        // Each old spring's index among those kept (springs keep their order).
        let mut index = vec![u32::MAX; old.len()];
        let mut next = springs.iter().enumerate().peekable();
        for (i, s) in old.iter().enumerate() {
            if let Some((j, _)) = next.next_if(|(_, t)| (t.a, t.b) == (s.a, s.b)) {
                index[i] = j as u32;
            }
        }
        if next.peek().is_some() {
            return None;
        }
        let order = self.order.iter().map(|&i| index[i as usize]);
        Some(Self::in_order(
            springs,
            order.filter(|&j| j != u32::MAX).collect(),
        ))
    }

    /// The arrays for `springs` evaluated in `order` (model indices).
    fn in_order(springs: &[Spring], order: Vec<u32>) -> Self {
        let m = springs.len();
        let ends: Vec<[u32; 2]> = order
            .iter()
            .map(|&i| [springs[i as usize].a, springs[i as usize].b])
            .collect();
        let mut run = vec![1u8; m];
        for e in (0..m.saturating_sub(1)).rev() {
            let ([a, b], [na, nb]) = (ends[e], ends[e + 1]);
            if na == a + 1 && nb == b + 1 && usize::from(run[e + 1]) < BATCH {
                run[e] = run[e + 1] + 1;
            }
        }
        let mut arrays = Self {
            order,
            ends,
            run,
            coefficients: [vec![0.0; m], vec![0.0; m], vec![0.0; m]],
        };
        arrays.set_coefficients(springs);
        arrays
    }

    fn set_coefficients(&mut self, springs: &[Spring]) {
        let [rest, k, b] = &mut self.coefficients;
        for (e, &i) in self.order.iter().enumerate() {
            let s = &springs[i as usize];
            (rest[e], k[e], b[e]) = (s.rest, s.stiffness, s.damping);
        }
    }
}

impl std::fmt::Debug for MeshKernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshKernel")
            .field("particles", &self.len())
            .field("springs", &self.model_springs.len())
            .field("bars", &self.bars.len())
            .field("params", &self.params)
            .field("threads", &self.threads)
            .finish_non_exhaustive()
    }
}

/// The springs and surface triangles the engine runs on (the model's, or those
/// left after a tear), with their constraint order and adjacency, which the
/// model or the tear computes: see [`MeshKernel::set_springs`].
struct SpringSet {
    /// Canonical springs.
    springs: Vec<Spring>,
    /// The same springs as the spring pass reads them.
    arrays: SpringArrays,
    /// The order the stretch limit and XPBD visit `springs` in.
    constraint_order: Vec<u32>,
    adjacency: Adjacency,
    triangles: Vec<[u32; 3]>,
}

type Halves<'b> = ([&'b mut [f64]; 3], [&'b mut [f64]; 3]);

/// Three slices each split at `mid` (or at their end when shorter: empty ones).
fn halves(a: [&mut [f64]; 3], mid: usize) -> Halves<'_> {
    let [a0, a1, a2] = a.map(|s| {
        let mid = mid.min(s.len());
        s.split_at_mut(mid)
    });
    ([a0.0, a1.0, a2.0], [a0.1, a1.1, a2.1])
}

/// What the spring pass reads.
struct SpringCtx<'a> {
    springs: &'a SpringArrays,
    x: [&'a [f64]; 3],
    v: [&'a [f64]; 3],
    avx2: bool,
}

/// Each spring's force on its `a` end, for springs `start..start + out[0].len()`.
fn spring_pass(ctx: &SpringCtx, start: usize, out: [&mut [f64]; 3]) {
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
unsafe fn spring_pass_avx2(ctx: &SpringCtx, start: usize, out: [&mut [f64]; 3]) {
    spring_pass_body(ctx, start, out);
}

#[inline(always)]
fn spring_pass_body(ctx: &SpringCtx, start: usize, out: [&mut [f64]; 3]) {
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
fn split_pass(
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
struct TriangleCtx<'a> {
    triangles: &'a [[u32; 3]],
    x: [&'a [f64]; 3],
    v: [&'a [f64]; 3],
    /// The wind at the step's start time.
    wind: DVec3,
    half_rho_cd: f64,
}

/// Each triangle's drag on each of its vertices ([`triangle_drag`], the f64
/// engine's), for triangles `start..start + out[0].len()`. (Gathered in batches for an AVX2
/// build that vectorizes the forces, it measured no faster on the tablecloth:
/// 10.2 M particle-steps/s on one core either way.)
fn triangle_pass(ctx: &TriangleCtx, start: usize, out: [&mut [f64]; 3]) {
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
struct Leaves {
    springs: usize,
    triangles: usize,
    particles: usize,
}

/// What the particle pass reads.
struct Ctx<'a> {
    p: MeshParams,
    x: [&'a [f64]; 3],
    v: [&'a [f64]; 3],
    inv_mass: &'a [f64],
    offsets: &'a [u32],
    links: &'a [u32],
    spring_f: [&'a [f64]; 3],
    triangle_offsets: &'a [u32],
    triangle_links: &'a [u32],
    triangle_f: [&'a [f64]; 3],
}

/// What the particle pass writes, for particles `start..start + len`.
struct Out<'a> {
    start: usize,
    x: [&'a mut [f64]; 3],
    v: [&'a mut [f64]; 3],
    /// Verlet's `u`, updated in place (only its own particle reads it); empty otherwise.
    u: [&'a mut [f64]; 3],
}

impl Out<'_> {
    fn len(&self) -> usize {
        self.x[0].len()
    }

    fn split(self, mid: usize) -> (Self, Self) {
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

fn load(a: [&[f64]; 3], i: usize) -> DVec3 {
    DVec3::new(a[0][i], a[1][i], a[2][i])
}

fn store(a: &mut [&mut [f64]; 3], i: usize, value: DVec3) {
    a[0][i] = value.x;
    a[1][i] = value.y;
    a[2][i] = value.z;
}

/// `out` made a copy of the positions `x` (structure of arrays), one vector each.
fn copy_positions(out: &mut Vec<DVec3>, x: &[Vec<f64>; 3]) {
    out.clear();
    out.extend((x[0].iter().zip(&x[1]).zip(&x[2])).map(|((&x, &y), &z)| DVec3::new(x, y, z)));
}

/// Forces, accelerations and the integrator's update for the particles of `out`.
fn advance(ctx: &Ctx, mut out: Out) {
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
fn advance_parallel(ctx: &Ctx, out: Out, leaf: usize) {
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
fn restore_length(
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

impl MeshKernel {
    /// Builds the engine for `model`'s particles, springs, bars and masses, with
    /// `params` ([`MeshParams::of`]). The state starts at rest at the origin: set it
    /// with [`Self::set_state`]. Runs on the calling thread until
    /// [`Self::set_threads`] is called.
    pub fn new(model: &Model, params: MeshParams) -> Self {
        Self::with_springs(model, params, SpringArrays::new(&model.springs))
    }

    /// [`Self::new`] with the springs' arrays given.
    fn with_springs(model: &Model, params: MeshParams, springs: SpringArrays) -> Self {
        let n = model.mass.len();
        let zeros = |len| [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
        let verlet = params.integrator == Integrator::Verlet;
        let mut kernel = Self {
            params,
            x: zeros(n),
            v: zeros(n),
            u: zeros(if verlet { n } else { 0 }),
            x_next: zeros(n),
            v_next: zeros(n),
            before: Default::default(),
            inv_mass: model.inv_mass.clone(),
            spring_f: Default::default(),
            offsets: Vec::new(),
            links: Vec::new(),
            springs: SpringArrays::default(),
            triangles: Vec::new(),
            triangle_f: Default::default(),
            triangle_offsets: Vec::new(),
            triangle_links: Vec::new(),
            time: 0.0,
            grid: model.grid,
            lattice: model.lattice,
            torn: Vec::new(),
            model_springs: Vec::new(),
            constraint_order: Vec::new(),
            bars: model.bars.clone(),
            threads: 1,
            pool: None,
            avx2: simd_level() == SimdLevel::Avx2,
            adjacency: Adjacency::default(),
            bar_pairs: model.bar_pairs.clone(),
            self_collision: SelfCollision::default(),
            copy_x: Vec::new(),
            copy_start: Vec::new(),
            multipliers: Vec::new(),
        };
        kernel.set_springs(SpringSet {
            springs: model.springs.clone(),
            arrays: springs,
            constraint_order: model.constraint_order.clone(),
            adjacency: model.adjacency.clone(),
            triangles: model.triangles.clone(),
        });
        kernel.size_before();
        kernel
    }

    /// Takes a spring set and surface (the model's, or those left after a tear)
    /// with what follows from them: the particles' links to their springs and
    /// triangles, and the per-spring and per-triangle force arrays.
    fn set_springs(&mut self, set: SpringSet) {
        let SpringSet {
            springs,
            arrays,
            constraint_order,
            adjacency,
            triangles,
        } = set;
        let n = self.len();
        let m = springs.len();
        let mut offsets = vec![0u32; n + 1];
        for s in &springs {
            offsets[s.a as usize + 1] += 1;
            offsets[s.b as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        // Where each of the model's springs is evaluated.
        let mut slot_of = vec![0u32; m];
        for (e, &i) in arrays.order.iter().enumerate() {
            slot_of[i as usize] = e as u32;
        }
        // Filled in the model's spring order per particle: the f64 engine's gather
        // order.
        let mut cursor = offsets.clone();
        let mut links = vec![0u32; 2 * m];
        for (index, s) in springs.iter().enumerate() {
            for (end, flag) in [(s.a, 0), (s.b, B_END)] {
                let slot = &mut cursor[end as usize];
                links[*slot as usize] = slot_of[index] | flag;
                *slot += 1;
            }
        }
        // Each particle's triangles, in the model's order: the f64 engine adds
        // their drag in that order.
        let mut triangle_offsets = vec![0u32; n + 1];
        for &vertex in triangles.iter().flatten() {
            triangle_offsets[vertex as usize + 1] += 1;
        }
        for i in 0..n {
            triangle_offsets[i + 1] += triangle_offsets[i];
        }
        let mut cursor = triangle_offsets.clone();
        let mut triangle_links = vec![0u32; 3 * triangles.len()];
        for (index, triangle) in triangles.iter().enumerate() {
            for &vertex in triangle {
                let slot = &mut cursor[vertex as usize];
                triangle_links[*slot as usize] = index as u32;
                *slot += 1;
            }
        }
        // Written whole by each step's passes before they are read.
        let sized =
            |arrays: &mut [Vec<f64>; 3], len| arrays.iter_mut().for_each(|a| a.resize(len, 0.0));
        sized(&mut self.spring_f, m);
        sized(&mut self.triangle_f, triangles.len());
        (self.offsets, self.links, self.springs) = (offsets, links, arrays);
        (self.triangle_offsets, self.triangle_links) = (triangle_offsets, triangle_links);
        (self.model_springs, self.triangles) = (springs, triangles);
        (self.constraint_order, self.adjacency) = (constraint_order, adjacency);
    }

    /// Whether the engine steps a system with this integrator.
    pub fn supports(integrator: Integrator) -> bool {
        match integrator {
            Integrator::SymplecticEuler
            | Integrator::ExplicitEuler
            | Integrator::Verlet
            | Integrator::Xpbd => true,
            Integrator::Rk2 | Integrator::Rk4 | Integrator::ImplicitEuler => false,
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.inv_mass.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The parameters in effect.
    pub fn params(&self) -> &MeshParams {
        &self.params
    }

    /// Takes in `model`'s current springs, bars and inverse masses and `params`
    /// without new arrays when only coefficients changed (a live edit). Returns
    /// `false`, changing nothing, when the topology or the integrator differs (a
    /// new engine is needed).
    pub fn refresh(&mut self, model: &Model, params: MeshParams) -> bool {
        let same_ends = |a: &Spring, b: &Spring| (a.a, a.b) == (b.a, b.b);
        let same_bars = |a: &Bar, b: &Bar| (a.a, a.b) == (b.a, b.b);
        if params.integrator != self.params.integrator
            || model.inv_mass.len() != self.len()
            || model.springs.len() != self.model_springs.len()
            || model.bars.len() != self.bars.len()
            || model.triangles != self.triangles
            || !model
                .springs
                .iter()
                .zip(&self.model_springs)
                .all(|(a, b)| same_ends(a, b))
            || !model
                .bars
                .iter()
                .zip(&self.bars)
                .all(|(a, b)| same_bars(a, b))
        {
            return false;
        }
        self.params = params;
        self.size_before();
        self.inv_mass.copy_from_slice(&model.inv_mass);
        self.bars.copy_from_slice(&model.bars);
        if model.springs != self.model_springs {
            self.model_springs.copy_from_slice(&model.springs);
            self.springs.set_coefficients(&model.springs);
        }
        true
    }

    /// Builds the engine anew for `model` and `params` ([`Self::new`]) when
    /// [`Self::refresh`] cannot take them (springs cut, a new integrator), keeping
    /// its threads when the particle count is the same. The state must be set again.
    pub fn rebuild(&mut self, model: &Model, params: MeshParams) {
        let (threads, pool) = (self.threads, self.pool.take());
        let same_size = model.mass.len() == self.len();
        let springs = (self.springs.kept(&self.model_springs, &model.springs))
            .unwrap_or_else(|| SpringArrays::new(&model.springs));
        *self = Self::with_springs(model, params, springs);
        if same_size {
            (self.threads, self.pool) = (threads, pool);
        } else {
            self.set_threads(threads);
        }
    }

    /// Whether anything is enforced after integration.
    fn has_constraints(&self) -> bool {
        let p = &self.params;
        (p.bar_iterations > 0 && !self.bars.is_empty())
            || (p.stretch_limit.is_some() && !self.model_springs.is_empty())
            || p.self_collision.is_some()
            || (p.integrator == Integrator::Xpbd && !self.model_springs.is_empty())
            || self.contact().is_active()
    }

    /// The colliders and their friction.
    fn contact(&self) -> Contact {
        let p = &self.params;
        Contact {
            sphere: p.sphere,
            ground: p.ground,
            friction: p.friction,
            dt: p.dt,
        }
    }

    fn size_before(&mut self) {
        let len = if self.has_constraints() {
            self.len()
        } else {
            0
        };
        for axis in &mut self.before {
            axis.resize(len, 0.0);
        }
    }

    /// Use `n` threads (at least 1) for models of [`PARALLEL_MIN_PARTICLES`]
    /// particles or more; smaller ones run on the calling thread. Builds a rayon pool
    /// (this allocates; the steps do not).
    pub fn set_threads(&mut self, n: usize) {
        self.set_threads_from(n, PARALLEL_MIN_PARTICLES);
    }

    /// As [`Self::set_threads`], with the size from which threads are used given
    /// (for tests: results must not depend on the thread count at any size).
    pub fn set_threads_from(&mut self, n: usize, min_particles: usize) {
        let n = n.max(1);
        self.threads = n;
        self.pool = if n > 1 && self.len() >= min_particles.max(2) {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .thread_name(|i| format!("cloth-mesh-{i}"))
                .build()
                .ok()
        } else {
            None
        };
    }

    /// True if steps run on several threads.
    pub fn is_parallel(&self) -> bool {
        self.pool.is_some()
    }

    /// Sets positions (m) and velocities (m/s). Verlet's update velocities start
    /// equal to the velocities (call [`Self::set_update_velocities`] after this to
    /// give them their own values).
    pub fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) {
        for (i, (p, v)) in positions
            .iter()
            .zip(velocities)
            .enumerate()
            .take(self.len())
        {
            for k in 0..3 {
                self.x[k][i] = p[k];
                self.v[k][i] = v[k];
            }
        }
        if self.params.integrator == Integrator::Verlet {
            self.set_update_velocities(velocities);
        }
    }

    /// Sets position Verlet's velocities of the last position update,
    /// `(x - x_prev) / h` (m/s); ignored for the other integrators.
    pub fn set_update_velocities(&mut self, u: &[DVec3]) {
        if self.u[0].is_empty() {
            return;
        }
        for (i, q) in u.iter().enumerate().take(self.len()) {
            for k in 0..3 {
                self.u[k][i] = q[k];
            }
        }
    }

    fn read_into(arrays: &[Vec<f64>; 3], out: &mut [DVec3]) {
        for (i, o) in out.iter_mut().enumerate().take(arrays[0].len()) {
            *o = DVec3::new(arrays[0][i], arrays[1][i], arrays[2][i]);
        }
    }

    /// Copies the positions (m) into `out`.
    pub fn positions_into(&self, out: &mut [DVec3]) {
        Self::read_into(&self.x, out);
    }

    /// Copies the velocities (m/s) into `out`.
    pub fn velocities_into(&self, out: &mut [DVec3]) {
        Self::read_into(&self.v, out);
    }

    /// Copies Verlet's update velocities (m/s) into `out`; nothing for the other
    /// integrators.
    pub fn update_velocities_into(&self, out: &mut [DVec3]) {
        Self::read_into(&self.u, out);
    }

    /// The largest squared speed and squared distance from `center`, or infinities
    /// when a value is not finite (for a cheap divergence scan).
    pub fn extremes(&self, center: DVec3) -> (f64, f64) {
        let n = self.len();
        let x = self.x.each_ref().map(|a| &a[..n]);
        let v = self.v.each_ref().map(|a| &a[..n]);
        super::grid_kernel::runaway_scan_f64(x, v, center)
    }

    /// Sets the simulated time (s) at the start of the next step, which the gusts
    /// of the drag's wind follow (0 when built); each step advances it by `dt`.
    pub fn set_time(&mut self, time: f64) {
        self.time = time;
    }

    /// Advances by `n` steps of the parameters' `dt`. On several threads the pool is
    /// entered once for all `n` steps.
    pub fn steps(&mut self, n: usize) {
        match self.pool.take() {
            Some(pool) => {
                let per_task = |len: usize| (len / (4 * self.threads)).max(MIN_LEAF);
                let leaves = Leaves {
                    springs: per_task(self.model_springs.len()),
                    triangles: per_task(self.triangles.len()),
                    particles: per_task(self.len()),
                };
                pool.install(|| {
                    for _ in 0..n {
                        self.one_step(Some(leaves));
                    }
                });
                self.pool = Some(pool);
            }
            None => {
                for _ in 0..n {
                    self.one_step(None);
                }
            }
        }
    }

    /// The step's last phase with a tear strain `tau`, as the f64 engine's
    /// ([`super::tearing`]): breaks the springs past it, in this engine's copies
    /// (kept for the model in [`Self::take_torn`]). Allocates, but only when
    /// something breaks.
    fn tear(&mut self, tau: f64, leaf: Option<usize>) {
        if !self.overstretched(tau, leaf) {
            return;
        }
        let (mut springs, mut triangles) = (
            self.model_springs.clone(),
            std::mem::take(&mut self.triangles),
        );
        let x = self.x.each_ref().map(Vec::as_slice);
        let pairs = remove_broken(&mut springs, &mut triangles, |s| {
            overstretched(load(x, s.a as usize), load(x, s.b as usize), s.rest, tau)
        });
        let arrays = (self.springs.kept(&self.model_springs, &springs))
            .unwrap_or_else(|| SpringArrays::new(&springs));
        let set = SpringSet {
            constraint_order: springs::constraint_order(&springs, self.grid, self.lattice),
            adjacency: Adjacency::new(self.len(), &springs),
            springs,
            arrays,
            triangles,
        };
        self.set_springs(set);
        self.torn.extend(pairs);
    }

    /// Whether a spring is past the tear strain `tau` ([`overstretched`], the f64
    /// engine's rule); over the springs in ranges of `leaf` on the pool's threads
    /// when given one.
    fn overstretched(&self, tau: f64, leaf: Option<usize>) -> bool {
        let x = self.x.each_ref().map(Vec::as_slice);
        let over =
            |s: &Spring| overstretched(load(x, s.a as usize), load(x, s.b as usize), s.rest, tau);
        match leaf {
            Some(leaf) => {
                use rayon::prelude::*;
                self.model_springs.par_iter().with_min_len(leaf).any(over)
            }
            None => self.model_springs.iter().any(over),
        }
    }

    /// Whether springs tore since the model last took them.
    pub fn has_torn(&self) -> bool {
        !self.torn.is_empty()
    }

    /// The ends of the springs torn since the last call, sorted: the model breaks
    /// them too ([`super::System`]'s `break_springs`) as it takes the state.
    pub fn take_torn(&mut self) -> Vec<(u32, u32)> {
        let mut torn = std::mem::take(&mut self.torn);
        torn.sort_unstable();
        torn
    }

    /// One step; `leaves` when on the pool.
    fn one_step(&mut self, leaves: Option<Leaves>) {
        let x = self.x.each_ref().map(Vec::as_slice);
        let v = self.v.each_ref().map(Vec::as_slice);
        let springs = SpringCtx {
            springs: &self.springs,
            x,
            v,
            avx2: self.avx2,
        };
        let out = self.spring_f.each_mut().map(Vec::as_mut_slice);
        let pass = |start: usize, out: [&mut [f64]; 3]| spring_pass(&springs, start, out);
        match leaves {
            _ if !self.params.spring_forces => {}
            Some(leaves) => split_pass(0, out, leaves.springs, &pass),
            None => pass(0, out),
        }
        if let Some(drag) = self.params.drag {
            let triangles = TriangleCtx {
                triangles: &self.triangles,
                x,
                v,
                wind: drag.wind.at(self.time),
                half_rho_cd: drag.half_rho_cd,
            };
            let out = self.triangle_f.each_mut().map(Vec::as_mut_slice);
            let pass = |start: usize, out: [&mut [f64]; 3]| triangle_pass(&triangles, start, out);
            match leaves {
                Some(leaves) => split_pass(0, out, leaves.triangles, &pass),
                None => pass(0, out),
            }
        }
        let ctx = Ctx {
            p: self.params,
            x,
            v,
            inv_mass: &self.inv_mass,
            offsets: &self.offsets,
            links: &self.links,
            spring_f: self.spring_f.each_ref().map(Vec::as_slice),
            triangle_offsets: &self.triangle_offsets,
            triangle_links: &self.triangle_links,
            triangle_f: self.triangle_f.each_ref().map(Vec::as_slice),
        };
        let out = Out {
            start: 0,
            x: self.x_next.each_mut().map(Vec::as_mut_slice),
            v: self.v_next.each_mut().map(Vec::as_mut_slice),
            u: self.u.each_mut().map(Vec::as_mut_slice),
        };
        match leaves {
            Some(leaves) => advance_parallel(&ctx, out, leaves.particles),
            None => advance(&ctx, out),
        }
        std::mem::swap(&mut self.x, &mut self.x_next);
        std::mem::swap(&mut self.v, &mut self.v_next);
        if self.has_constraints() {
            self.constrain();
        }
        if let Some(max_speed) = self.params.max_speed {
            self.limit_speed(max_speed);
        }
        if let Some(tau) = self.params.tear_strain {
            self.tear(tau, leaves.map(|l| l.springs));
        }
        // As the f64 engine's clock: one `dt` added per step.
        self.time += self.params.dt;
    }

    /// The speed limit, as the f64 engine applies it after the constraints
    /// ([`speed_limit`]): a faster particle's velocity (and Verlet's update
    /// velocity) scaled down to it.
    fn limit_speed(&mut self, max_speed: f64) {
        let verlet = !self.u[0].is_empty();
        for i in 0..self.len() {
            let factor = speed_limit(load(self.v.each_ref().map(Vec::as_slice), i), max_speed);
            if factor < 1.0 {
                for a in 0..3 {
                    self.v[a][i] *= factor;
                    if verlet {
                        self.u[a][i] *= factor;
                    }
                }
            }
        }
    }

    /// Bars, stretch limit, then `v += δ/h` (and `u` for Verlet) and the colliders'
    /// contact with friction, in the f64 engine's order.
    fn constrain(&mut self) {
        let p = self.params;
        for k in 0..3 {
            self.before[k].copy_from_slice(&self.x[k]);
        }
        if p.integrator == Integrator::Xpbd {
            self.xpbd_pass();
        }
        let x = &mut self.x;
        let inv_mass = &self.inv_mass;
        for _ in 0..p.bar_iterations {
            for bar in &self.bars {
                restore_length(x, inv_mass, bar.a as usize, bar.b as usize, |l| {
                    (l != bar.length).then_some(bar.length)
                });
            }
        }
        if let Some(tau) = p.stretch_limit {
            for s in self
                .constraint_order
                .iter()
                .map(|&i| &self.model_springs[i as usize])
            {
                let longest = (1.0 + tau) * s.rest;
                restore_length(x, inv_mass, s.a as usize, s.b as usize, |l| {
                    (l > longest).then_some(longest)
                });
            }
        }
        if let Some(h_c) = p.self_collision {
            self.self_collision_pass(h_c);
        }
        let h = p.dt;
        let contact = self.contact();
        let active = contact.is_active();
        let verlet = !self.u[0].is_empty();
        for i in 0..self.inv_mass.len() {
            let before = load(self.before.each_ref().map(Vec::as_slice), i);
            let x = load(self.x.each_ref().map(Vec::as_slice), i);
            let v_old = load(self.v.each_ref().map(Vec::as_slice), i);
            let mut v = v_old + (x - before) / h;
            if active && self.inv_mass[i] > 0.0 {
                let x_new;
                (x_new, v) = contact.resolve(x, v, self.inv_mass[i]);
                store(&mut self.x.each_mut().map(Vec::as_mut_slice), i, x_new);
            }
            store(&mut self.v.each_mut().map(Vec::as_mut_slice), i, v);
            if verlet {
                let u = load(self.u.each_ref().map(Vec::as_slice), i) + (v - v_old);
                store(&mut self.u.each_mut().map(Vec::as_mut_slice), i, u);
            }
        }
    }

    /// Self-collision ([`super::self_collision`]) at thickness `h_c`, as the f64
    /// engine runs it after the stretch limit: on a copy of the positions, reading
    /// those at the start of the step (the other half of the ping-pong pair) and
    /// the inverse masses for the pairs in contact; the particles it moved are
    /// written back. On the pool's threads when the engine has them (the same
    /// result as on one).
    fn self_collision_pass(&mut self, h_c: f64) {
        let mut x = std::mem::take(&mut self.copy_x);
        copy_positions(&mut x, &self.x);
        let (start, inv_mass) = (self.x_next.each_ref().map(Vec::as_slice), &self.inv_mass);
        let particle = |i: usize| (load(start, i), inv_mass[i]);
        let (adjacency, springs, bars) = (&self.adjacency, &self.model_springs, &self.bar_pairs);
        let joined = |i: usize, j: usize| adjacency.joins(springs, i, j) || bars.join(i, j);
        let (friction, parallel) = (self.params.friction, self.pool.is_some());
        let pass = &mut self.self_collision;
        pass.apply(&mut x, particle, h_c, friction, joined, parallel);
        let mut positions = self.x.each_mut().map(Vec::as_mut_slice);
        for &i in self.self_collision.moved() {
            store(&mut positions, i as usize, x[i as usize]);
        }
        self.copy_x = x;
    }

    /// XPBD's springs ([`xpbd_pass`], the f64 engine's pass) on copies of the
    /// positions now and at the start of the step (the other half of the ping-pong
    /// pair), written back whole.
    fn xpbd_pass(&mut self) {
        let (mut x, mut start) = (
            std::mem::take(&mut self.copy_x),
            std::mem::take(&mut self.copy_start),
        );
        copy_positions(&mut x, &self.x);
        copy_positions(&mut start, &self.x_next);
        let springs = &self.model_springs;
        let order = (&self.constraint_order[..], xpbd_sweeps_back(self.lattice));
        xpbd_pass(
            &mut x,
            &start,
            springs,
            order,
            &self.inv_mass,
            self.params.dt,
            &mut self.multipliers,
        );
        let mut positions = self.x.each_mut().map(Vec::as_mut_slice);
        for (i, &p) in x.iter().enumerate() {
            store(&mut positions, i, p);
        }
        (self.copy_x, self.copy_start) = (x, start);
    }

    /// Pairs pushed apart by the last self-collision pass.
    pub fn self_collision_contacts(&self) -> usize {
        self.self_collision.contacts()
    }
}
