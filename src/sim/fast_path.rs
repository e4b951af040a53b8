//! The fast engine's hook into [`System::run`]: a regular grid cloth goes to the
//! stencil kernel of [`super::grid_kernel`] when the caller allows it
//! ([`System::set_fast_path`]) and the kernel models the system exactly: a grid
//! topology whose springs really are the 12-neighbour stencil (checked spring by
//! spring, not trusted from the scene), uniform mass, one stiffness, damping and
//! rest length per spring kind (rest `h`, `h√2`, `2h`), symplectic Euler, explicit
//! Euler, Verlet or XPBD, and no bars. Every parameter is named in `grid_spec`,
//! so a new one fails to compile until the kernel models it or refuses it. Results
//! agree with the f64 general engine to round-off (`tests/engines/fast_engine.rs`).
//!
//! A lattice block whose springs really are the 26-neighbour stencil (the jelly
//! cube) goes to the lattice kernel of [`super::grid_kernel::lattice`] on the same
//! terms (without bars, drag, self-collision, tearing or a speed limit), within a
//! stated bound of the f64 engine (`tests/engines/lattice_kernel.rs`).
//!
//! Any other system (chains, ropes, meshes, the lattices the lattice kernel
//! leaves) runs on the general f64 engine, the reference, on the system's own
//! state: a CSR gather of each particle's springs, threaded on a big model.
//!
//! The f64 state stays the system's state: it is copied into the engine when
//! something outside changed it, and back after every chunk of steps (or when a
//! cheap scan of the engine's state finds trouble), where the divergence check
//! runs. A live edit of a coefficient (stiffness, damping, mass, wind...) updates
//! the engine in place ([`GridCloth::respec`](grid_kernel::GridCloth::respec));
//! only a new shape, integrator or precision builds a new one.

use glam::DVec3;

use super::grid_kernel::{self, Precision, SimdLevel, SpringCoefficients, SpringNoise};
use super::{Divergence, Ground, Sphere, SpringKind, System};

mod chunks;
#[cfg(feature = "gpu")]
pub(crate) use chunks::Stepped;
mod grid;
mod lattice;

use grid::FastPath;
pub(super) use grid::StencilSprings;
use lattice::LatticePath;

/// Steps the kernel runs between copies back to the f64 state and divergence checks.
const CHUNK: u64 = 32;

/// Which code steps a system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// The general f64 path: any topology, force term, integrator or constraint.
    General,
    /// The grid stencil kernel, in the precision the system needs.
    Grid(Precision),
    /// The lattice stencil kernel ([`grid_kernel::lattice`]), in the precision the
    /// lattice needs.
    Lattice(Precision),
}

/// What the precision rule ([`Precision::cheapest`]) weighed for the grid or
/// lattice kernel: the acceleration noise (m/s²) that float32 arithmetic puts on a
/// particle on float32 positions and on fixed-point ones (whose unit it names), and
/// the level it took, the first under [`Precision::NOISE_LIMIT`], float64 past both.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrecisionRule {
    /// The level taken.
    pub precision: Precision,
    /// The noise (m/s²) on float32 positions.
    pub float32_positions: f64,
    /// The noise (m/s²) on fixed-point positions at `unit`.
    pub fixed_point: f64,
    /// The fixed-point unit (m): roomy, or tight where the roomy one's noise is
    /// over the limit ([`GridSpec::fixed_unit`](grid_kernel::GridSpec::fixed_unit));
    /// or, once the body spread past what that holds, the coarser unit a kernel
    /// had to take then.
    pub unit: f64,
}

impl Engine {
    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::General => "general-f64",
            Self::Grid(Precision::Single) => "grid-f32",
            Self::Grid(Precision::Mixed) => "grid-mixed",
            Self::Grid(Precision::Double) => "grid-f64",
            Self::Lattice(Precision::Single) => "lattice-f32",
            Self::Lattice(Precision::Mixed) => "lattice-mixed",
            Self::Lattice(Precision::Double) => "lattice-f64",
        }
    }

    /// The engine on `threads` threads, as the command line and the panel show
    /// it: `grid-f32 (2 threads, avx512)`.
    pub fn label(self, threads: usize) -> String {
        let simd = self.simd_level().name();
        match threads {
            1 => format!("{} (1 thread, {simd})", self.name()),
            n => format!("{} ({n} threads, {simd})", self.name()),
        }
    }

    /// The compiled version of the loops this engine steps with on this CPU: the
    /// grid and lattice kernels pick the best the CPU has
    /// ([`SimdLevel::detect`]); the general engine is compiled for the baseline
    /// target only.
    pub fn simd_level(self) -> SimdLevel {
        match self {
            Self::Grid(_) | Self::Lattice(_) => SimdLevel::detect(),
            Self::General => SimdLevel::Baseline,
        }
    }

    /// Whether this is one of the fast engines (grid or lattice).
    pub fn is_fast(self) -> bool {
        matches!(self, Self::Grid(_) | Self::Lattice(_))
    }

    /// Whether this is the fast grid kernel (in either precision).
    pub fn is_grid(self) -> bool {
        matches!(self, Self::Grid(_))
    }
}

/// A grid's shape, recorded by the scene builder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridShape {
    /// Particles per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

/// A system's fast engines: whether they may run, each one once built, and the
/// grid summary the grid kernel is specified from. A clone of a system starts
/// without built engines and builds its own on first use (their buffers and
/// threads are not shared).
#[derive(Debug, Default)]
pub(super) struct Engines {
    /// Whether [`System::run`] may hand runs to them ([`System::set_fast_path`]).
    allowed: bool,
    /// Whether lattices are kept off the lattice kernel, for the general engine
    /// ([`System::refuse_lattice_kernel`]).
    lattice_refused: bool,
    grid: Option<FastPath>,
    lattice: Option<LatticePath>,
    /// The springs and masses as the grid kernel sees them, summarised on each edit.
    pub(super) stencil_springs: Option<StencilSprings>,
    /// How many times a grid or lattice kernel was built for this system.
    builds: u64,
    /// Bumped each time springs break ([`super::tearing`]): a grid kernel that saw
    /// an older count takes the springs left from the model.
    springs_version: u64,
    /// The engine that has run steps the f64 state has not had yet
    /// ([`System::run_ahead`]), and the time and step count the f64 state is at.
    ahead: Option<(Ahead, f64, u64)>,
    /// Steps run since the last full check, counted across runs.
    pub(super) unchecked: u64,
    /// The fixed-point unit (m) a grid or lattice kernel had to take when the body
    /// spread past what its spec's unit holds, where the noise was over the limit
    /// (at which the run went on in float64): the precision rule weighs this unit
    /// until the body fits its spec's unit again ([`grid_kernel::frame::holds_again`]).
    outgrown_unit: Option<f64>,
}

/// Which fast engine holds the latest state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ahead {
    Grid,
    Lattice,
}

impl Clone for Engines {
    fn clone(&self) -> Self {
        Self {
            allowed: self.allowed,
            lattice_refused: self.lattice_refused,
            grid: None,
            lattice: None,
            stencil_springs: self.stencil_springs,
            builds: self.builds,
            springs_version: self.springs_version,
            // A clone has no engine: its f64 state must already be the latest
            // (see [`System::settle`]).
            ahead: None,
            unchecked: self.unchecked,
            outgrown_unit: self.outgrown_unit,
        }
    }
}

impl Engines {
    /// Springs broke in the model: the engines must take the springs left.
    pub(super) fn springs_changed(&mut self) {
        self.springs_version += 1;
    }

    /// The f64 state changed outside the engines: copy it in before they next run.
    pub(super) fn mark_stale(&mut self) {
        if let Some(grid) = &mut self.grid {
            grid.in_sync = false;
        }
        if let Some(lattice) = &mut self.lattice {
            lattice.in_sync = false;
        }
    }

    /// Applies `edit` to the coefficients of one whole spring kind in the grid
    /// summary (the grid stays a grid, no rescan); rescans `model` if there was none.
    pub(super) fn edit_stencil_springs(
        &mut self,
        model: &super::Model,
        kind: SpringKind,
        edit: impl Fn(&mut SpringCoefficients),
    ) {
        self.stencil_springs = match self.stencil_springs {
            Some(grid) => Some(grid.with_kind(kind, edit)),
            None => StencilSprings::of(model),
        };
    }
}

impl System {
    /// Allows (or forbids) the fast engines (the grid and lattice kernels) for
    /// [`System::run`]. Off by default: the library is exact (the general f64
    /// engine) unless asked otherwise.
    pub fn set_fast_path(&mut self, allowed: bool) {
        self.engines.allowed = allowed;
        if !allowed {
            self.engines.grid = None;
            self.engines.lattice = None;
        }
    }

    /// Keeps a lattice off the lattice kernel (when `refused`), so that the general
    /// engine steps it: to compare the two, in tests and benchmarks.
    pub fn refuse_lattice_kernel(&mut self, refused: bool) {
        self.catch_up();
        self.engines.lattice_refused = refused;
        self.engines.lattice = None;
    }

    /// How many times a grid or lattice kernel was built for this system: once, unless its
    /// shape, integrator or precision changed (live edits of coefficients update the
    /// kernel in place).
    pub fn kernel_builds(&self) -> u64 {
        self.engines.builds
    }

    /// Pairs of particles the last self-collision pass pushed apart, on whichever
    /// engine ran the last step.
    pub fn self_collision_contacts(&self) -> usize {
        match (&self.engines.grid, self.engine()) {
            (Some(fast), Engine::Grid(_)) => fast.kernel.self_collision_contacts(),
            _ => self.work.self_collision.contacts(),
        }
    }

    /// Threads the engine [`Self::engine`] names steps on: its pool's
    /// (`pool_threads`) when the system is large enough to split (a fast engine's
    /// own threshold, or the general engine's spring count:
    /// `super::forces::uses_threads`), else one.
    pub fn engine_threads(&self) -> usize {
        let Engines { grid, lattice, .. } = &self.engines;
        let parallel = match self.engine() {
            Engine::Grid(_) => grid.as_ref().is_some_and(|f| f.kernel.is_parallel()),
            Engine::Lattice(_) => lattice.as_ref().is_some_and(|l| l.kernel.is_parallel()),
            Engine::General => super::forces::uses_threads(&self.model),
        };
        if parallel { pool_threads() } else { 1 }
    }

    /// The engine [`System::run`] would use now.
    pub fn engine(&self) -> Engine {
        if !self.engines.allowed {
            return Engine::General;
        }
        if let Some(spec) = self.grid_spec() {
            Engine::Grid(spec.precision)
        } else if let Some(spec) = self.lattice_spec() {
            Engine::Lattice(spec.precision)
        } else {
            Engine::General
        }
    }

    /// What the precision rule weighed for the kernel [`Self::engine`] names, if it
    /// is the grid or the lattice kernel (`cloth info` shows it).
    pub fn precision_rule(&self) -> Option<PrecisionRule> {
        if !self.engines.allowed {
            return None;
        }
        let reach = self.float32_reach();
        let rule = |precision, (unit, noise): (f64, &dyn Fn(Option<f64>) -> f64)| PrecisionRule {
            precision,
            float32_positions: noise(Some(reach)),
            fixed_point: noise(None),
            unit,
        };
        if let Some(spec) = self.grid_spec() {
            let (unit, noise) = self.noise_rule(&spec);
            return Some(rule(spec.precision, (unit, &noise)));
        }
        let spec = self.lattice_spec()?;
        let (unit, noise) = self.noise_rule(&spec);
        Some(rule(spec.precision, (unit, &noise)))
    }

    /// The float32 noise (m/s²) the precision rule weighs for a kernel on `spec`
    /// ([`Precision::cheapest`]: on float32 positions within a reach, on
    /// fixed-point ones with `None`), and the fixed-point unit it weighs
    /// ([`Self::weighed_unit`]).
    fn noise_rule<'a>(
        &self,
        spec: &'a impl SpringNoise,
    ) -> (f64, impl Fn(Option<f64>) -> f64 + 'a) {
        let (unit, dt) = (self.weighed_unit(spec.fixed_unit()), self.model.params.dt);
        (unit, move |reach: Option<f64>| {
            spec.spring_noise(reach.ok_or(unit), dt)
        })
    }

    /// The fixed-point unit (m) the precision rule weighs for a kernel whose spec
    /// asks for `spec_unit`: that, or the coarser one a kernel of this system had
    /// to take when the body outgrew it ([`Engines::outgrown_unit`]).
    fn weighed_unit(&self, spec_unit: f64) -> f64 {
        (self.engines.outgrown_unit).map_or(spec_unit, |unit| unit.max(spec_unit))
    }

    /// Forgets the unit the body outgrew its spec's for
    /// ([`Engines::outgrown_unit`]) once the spec's unit `spec_unit` holds the
    /// particles again, beside the colliders: whether it did.
    fn forget_outgrown_unit(
        &mut self,
        spec_unit: f64,
        (ground, sphere): (Option<Ground>, Option<Sphere>),
    ) -> bool {
        let positions = &self.state.positions;
        let back = self.engines.outgrown_unit.is_some()
            && grid_kernel::frame::holds_again(
                spec_unit,
                positions,
                ground.as_ref(),
                sphere.as_ref(),
            );
        if back {
            self.engines.outgrown_unit = None;
        }
        back
    }

    /// How far from the origin (m) the particles may go for the precision rule
    /// ([`Precision::cheapest`]) of the float32 engines: twice the start's farthest
    /// point.
    fn float32_reach(&self) -> f64 {
        2.0 * (self.runaway.center.length() + self.runaway.extent)
    }

    /// Runs `n` steps on a kernel for the spec that `spec_of` gives (`None` when
    /// it gives none), by `run` (which returns the steps it ran). When the body
    /// outgrows its fixed-point unit, `run` stops early and the rest of the steps
    /// go to the kernel for the spec chosen again; once the spec's unit holds the
    /// body again, the rule forgets the coarser unit
    /// ([`Self::forget_outgrown_unit`]).
    fn run_choosing<S: SpringNoise>(
        &mut self,
        n: u64,
        settle: bool,
        spec_of: impl Fn(&Self) -> Option<S>,
        mut run: impl FnMut(&mut Self, S, u64) -> Result<u64, Divergence>,
    ) -> Option<Result<(), Divergence>> {
        let mut spec = spec_of(self)?;
        if self.forget_outgrown_unit(spec.fixed_unit(), spec.colliders()) {
            spec = spec_of(self)?;
        }
        let mut left = n;
        loop {
            match run(self, spec, left) {
                Ok(done) if done < left => {
                    left -= done;
                    // The precision the rule weighs has changed, or tearing broke
                    // what the kernel models (a grid that lost springs): the rest
                    // of the steps go to the engine that models the system now
                    // (returning `None` would have the caller run all `n` again).
                    match spec_of(self) {
                        Some(next) => spec = next,
                        None => return Some(self.run_on_an_engine(left, settle)),
                    }
                }
                result => return Some(result.map(|_| ())),
            }
        }
    }
}

/// The acceleration (m/s²) of every free particle of a system of one `mass` (kg)
/// under `gravity` and an applied `force` (N) on each particle, when on.
fn uniform_acceleration(gravity: Option<DVec3>, force: Option<DVec3>, mass: f64) -> [f64; 3] {
    (gravity.unwrap_or(DVec3::ZERO) + force.map_or(DVec3::ZERO, |f| f / mass)).to_array()
}

/// Threads a fast engine's pool has: rayon's global setting, one per core unless
/// `RAYON_NUM_THREADS` says otherwise (the general engine's threads follow it too).
fn pool_threads() -> usize {
    rayon::current_num_threads()
}
