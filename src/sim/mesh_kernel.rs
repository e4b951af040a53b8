//! The mesh engine: any topology (chains, lattices, ropes, meshes) stepped in f64
//! on structure-of-arrays state, each particle gathering its own forces.
//!
//! State is `x, y, z, vx, vy, vz` (m, m/s) and, for position Verlet, the velocity of
//! the last position update `u = (x - x_prev) / h`. A step is two passes, three
//! with aerodynamic drag (below); under XPBD the first is skipped: its springs are
//! constraints, after the step:
//! 1. each spring's force on its `a` end, `f_a = -(k (l - L) + b (v_a - v_b)·u) u`
//!    with `u = (x_a - x_b)/l` ([`spring_force`](super::forces::spring_force)),
//!    into a per-spring array: the springs are evaluated in batches of up to
//!    `BATCH`, their ends read as slices where they come in runs with consecutive
//!    ends (a lattice's do, in `SpringArrays`' order), else gathered to the stack,
//!    in a loop the compiler vectorizes (built for AVX2 when the CPU has it);
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
//! the f64 engine computes it: each triangle's
//! [`triangle_drag`](super::forces::triangle_drag) (the wind at the step's start
//! time, gusts included) into a per-triangle array, which each particle adds
//! after its springs, in the order of the triangles.
//!
//! With a tear strain, a step that leaves springs past it breaks them as the f64
//! engine does ([`super::tearing`]): the engine removes them (and the triangles
//! along them) from its own copies, rebuilds its adjacency without sorting the
//! springs again, and hands the breaks to the model with its state.
//!
//! A step allocates nothing.

use glam::DVec3;

use super::springs::{Adjacency, BarPairs};
use super::{
    Bar, GridShape, Ground, Integrator, LatticeShape, Model, SelfCollision, Sphere, Spring,
    SpringMaterials, Wind,
};

mod build;
mod passes;
mod step;

use build::SpringArrays;
pub(crate) use passes::simd_level;

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

/// Per-triangle aerodynamic drag ([`triangle_drag`](super::forces::triangle_drag)).
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
    /// The model's colliders ([`crate::sim::colliders`]).
    colliders: Vec<crate::sim::Collider>,
    /// Their poses at the end of the step (scratch).
    collider_poses: Vec<crate::sim::Pose>,
    /// The grid's or the lattice's shape, if the particles form one (the order of
    /// the constraint passes follows it).
    grid: Option<GridShape>,
    lattice: Option<LatticeShape>,
    /// Springs torn since the model last took them ([`Self::take_torn`]).
    torn: Vec<(u32, u32)>,
    /// The model's springs, canonical (for the stretch limit and to notice edits).
    model_springs: Vec<Spring>,
    /// Their kinds' stiffness and damping (the model's).
    materials: SpringMaterials,
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
