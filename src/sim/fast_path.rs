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
//! Any other system stepped by symplectic
//! Euler, explicit Euler, position Verlet or XPBD (chains, ropes, meshes, and the
//! lattices the lattice kernel leaves) goes to the f64 mesh engine of
//! [`super::mesh_kernel`], which does the
//! general path's arithmetic in its order: bit for bit its results for the Euler
//! methods and XPBD, f64 round-off for Verlet (`tests/engines/mesh_engine.rs`).
//!
//! The f64 state stays the system's state: it is copied into the engine when
//! something outside changed it, and back after every chunk of steps (or when a
//! cheap scan of the engine's state finds trouble), where the divergence check
//! runs. A live edit of a coefficient (stiffness, damping, mass, wind...) updates
//! the engine in place ([`GridCloth::respec`]); only a new shape, integrator or
//! precision builds a new one.

use glam::DVec3;

use super::energy_budget::ENERGY_CHECK_STEPS;
use super::grid_kernel::lattice::{LatticeKernel, LatticeSpec};
use super::grid_kernel::{
    self, GridCloth, GridSpec, Precision, SimdLevel, SpringCoefficients, SpringNoise,
};
use super::mesh_kernel::{MeshKernel, MeshParams};
use super::springs::STENCIL_DIRECTIONS;
use super::{Divergence, Ground, Integrator, Sphere, SpringKind, System};

/// Steps the kernel runs between copies back to the f64 state and divergence checks.
const CHUNK: u64 = 32;

/// Which code steps a system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// The general f64 path: any topology, force term, integrator or constraint.
    General,
    /// The grid stencil kernel, in the precision the system needs.
    Grid(Precision),
    /// The f64 mesh engine ([`super::mesh_kernel`]): any topology, results equal to
    /// the general path's to f64 round-off.
    Mesh,
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
    /// over the limit ([`GridSpec::fixed_unit`]); or, once the body spread past
    /// what that holds, the coarser unit a kernel had to take then.
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
            Self::Mesh => "mesh-f64",
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
    /// ([`SimdLevel::detect`]), the mesh engine its AVX2 build where the CPU has
    /// AVX2, and the general engine is compiled for the baseline target only.
    pub fn simd_level(self) -> SimdLevel {
        match self {
            Self::Grid(_) | Self::Lattice(_) => SimdLevel::detect(),
            Self::Mesh => super::mesh_kernel::simd_level(),
            Self::General => SimdLevel::Baseline,
        }
    }

    /// Whether this is one of the fast engines (grid, lattice or mesh).
    pub fn is_fast(self) -> bool {
        matches!(self, Self::Grid(_) | Self::Lattice(_) | Self::Mesh)
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
    /// Whether lattices are kept off the lattice kernel, for the mesh engine
    /// ([`System::refuse_lattice_kernel`]).
    lattice_refused: bool,
    grid: Option<FastPath>,
    lattice: Option<LatticePath>,
    mesh: Option<MeshPath>,
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
    Mesh,
}

impl Clone for Engines {
    fn clone(&self) -> Self {
        Self {
            allowed: self.allowed,
            lattice_refused: self.lattice_refused,
            grid: None,
            lattice: None,
            mesh: None,
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
        if let Some(mesh) = &mut self.mesh {
            mesh.in_sync = false;
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

/// The lattice kernel, and whether it holds the f64 state.
#[derive(Debug)]
struct LatticePath {
    kernel: LatticeKernel,
    /// Whether the kernel holds the same state as the f64 arrays.
    in_sync: bool,
    /// Positions of the particles held in place, exactly as the f64 state had them.
    held: Vec<(usize, DVec3)>,
}

/// The mesh engine and whether it holds the f64 state.
#[derive(Debug)]
struct MeshPath {
    kernel: MeshKernel,
    /// Whether the engine holds the same state as the f64 arrays.
    in_sync: bool,
}

/// The kernel and what it was built from.
#[derive(Debug)]
struct FastPath {
    kernel: GridCloth,
    spec: GridSpec,
    /// Whether the kernel holds the same state as the f64 arrays.
    in_sync: bool,
    /// Positions of the particles held in place (pinned or grabbed), exactly as
    /// the f64 state had them: the kernel holds them in f32.
    held: Vec<(usize, DVec3)>,
    /// The [`Engines::springs_version`] whose springs the kernel holds.
    springs_seen: Option<u64>,
}

/// A grid cloth's or a lattice's springs and masses as its stencil kernel needs
/// them: one mass, and per kind one stiffness and damping. A grid's kinds are
/// structural, shear and bend, with rest lengths `h`, `h√2`, `2h`; every spring is
/// a stencil spring of its kind, though not every stencil spring need be there
/// (springs tear: the kernel takes which are left from the model,
/// [`springs_left`]). A lattice's kinds are its axis springs (structural), face
/// diagonals (shear) and body diagonals (other), with rest lengths `h`, `h√2`,
/// `h√3`, and every spring of the kinds present must be there. A kind with none,
/// e.g. `shear_scale = 0`, gets `k = b = 0`. Computed when springs or masses
/// change, not on every run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct StencilSprings {
    coefficients: [SpringCoefficients; 3],
    /// Which kinds exist.
    present: [bool; 3],
    spacing: f64,
    mass: f64,
    /// Whether this is a lattice's (else a grid's).
    lattice: bool,
}

impl StencilSprings {
    /// The summary's slot of springs of `kind`, if the stencil has such springs.
    fn slot(kind: SpringKind, lattice: bool) -> Option<usize> {
        match (kind, lattice) {
            (SpringKind::Structural, _) => Some(0),
            (SpringKind::Shear, _) => Some(1),
            (SpringKind::Bend, false) | (SpringKind::Other, true) => Some(2),
            (SpringKind::Bend, true) | (SpringKind::Other, false) => None,
        }
    }

    /// The summary after every spring of `kind` had its coefficients changed by
    /// `edit` (a kind with no springs keeps `k = b = 0`).
    pub(super) fn with_kind(
        mut self,
        kind: SpringKind,
        edit: impl Fn(&mut SpringCoefficients),
    ) -> Self {
        if let Some(slot) = Self::slot(kind, self.lattice)
            && self.present[slot]
        {
            edit(&mut self.coefficients[slot]);
        }
        self
    }

    /// The summary of `model`, or `None` when no stencil kernel can model it.
    pub(super) fn of(model: &super::Model) -> Option<Self> {
        let mass = *model.mass.first()?;
        if model.mass.iter().any(|&m| m != mass) {
            return None;
        }
        let (lattice, rest_ratio) = match (model.grid, model.lattice) {
            (Some(_), _) => (false, [1.0, std::f64::consts::SQRT_2, 2.0]),
            (None, Some(_)) => (true, [1.0, std::f64::consts::SQRT_2, 3f64.sqrt()]),
            (None, None) => return None,
        };
        let mut kinds: [Option<(f64, f64, f64)>; 3] = [None; 3];
        let mut counts = [0; 3];
        for s in &model.springs {
            let slot = Self::slot(s.kind, lattice)?;
            // The scene says this is a grid or a lattice: check that the spring is
            // a stencil spring of its kind (canonical springs being unique, the
            // springs are then a subset of the stencil, and the grid kernel masks
            // the others).
            let (a, b) = (s.a as usize, s.b as usize);
            let in_stencil = match (model.grid, model.lattice) {
                (Some(shape), _) => {
                    let (ra, ca) = (a / shape.width, a % shape.width);
                    let (rb, cb) = (b / shape.width, b % shape.width);
                    let offset = (rb as isize - ra as isize, cb as isize - ca as isize);
                    let in_stencil = match slot {
                        0 => offset == (0, 1) || offset == (1, 0),
                        1 => offset == (1, 1) || offset == (1, -1),
                        _ => offset == (0, 2) || offset == (2, 0),
                    };
                    in_stencil && b < shape.width * shape.height
                }
                (None, Some(shape)) => shape.kind_of(a, b) == Some(slot),
                (None, None) => false,
            };
            if !in_stencil {
                return None;
            }
            counts[slot] += 1;
            let coefficients = (s.stiffness, s.damping, s.rest);
            match kinds[slot] {
                None => kinds[slot] = Some(coefficients),
                Some(c) if c == coefficients => {}
                Some(_) => return None,
            }
        }
        if let Some(shape) = model.lattice.filter(|_| lattice) {
            // The lattice kernel evaluates every spring of a kind present.
            let full = shape.spring_counts();
            if (0..3).any(|k| kinds[k].is_some() && counts[k] != full[k]) {
                return None;
            }
        }
        let h = kinds[0]?.2;
        let mut coefficients = [SpringCoefficients::default(); 3];
        for slot in 0..3 {
            if let Some((k, b, rest)) = kinds[slot] {
                let stencil_rest = (rest - rest_ratio[slot] * h).abs() <= 1e-12 * h.max(1e-300);
                if !stencil_rest {
                    return None;
                }
                coefficients[slot] = SpringCoefficients { k, b };
            }
        }
        Some(Self {
            coefficients,
            present: kinds.map(|k| k.is_some()),
            spacing: h,
            mass,
            lattice,
        })
    }
}

/// Which stencil springs and triangles `model` (a grid that [`StencilSprings::of`]
/// accepted) has left, as [`GridCloth::set_springs_left`] takes them; `None` when
/// it has every stencil spring of the kinds `present` and every triangle.
fn springs_left(model: &super::Model, present: [bool; 3]) -> Option<Vec<u8>> {
    let shape = model.grid?;
    let (w, h) = (shape.width, shape.height);
    let stencil = grid_kernel::stencil_counts(w, h);
    let whole_springs: usize = (0..3).filter(|&k| present[k]).map(|k| stencil[k]).sum();
    let whole_triangles = 2 * w.saturating_sub(1) * h.saturating_sub(1);
    if model.springs.len() == whole_springs && model.triangles.len() == whole_triangles {
        return None;
    }
    let mut bits = vec![0u8; w * h];
    for s in &model.springs {
        let (a, b) = (s.a as usize, s.b as usize);
        let offset = (b / w - a / w, (b % w) as isize - (a % w) as isize);
        if let Some(d) = STENCIL_DIRECTIONS.iter().position(|&o| o == offset) {
            bits[a] |= 1 << d;
        }
    }
    for &[a, b, c] in &model.triangles {
        let [a, b, c] = [a, b, c].map(|i| i as usize);
        // (a, b, d) with b = a + 1, d = a + w; (b, e, d) with e = b + w, d = e - 1.
        if b == a + 1 && c == a + w {
            bits[a] |= 1 << 6;
        } else if b == a + w && c + 1 == b && a >= 1 {
            bits[a - 1] |= 1 << 7;
        }
    }
    Some(bits)
}

impl System {
    /// Allows (or forbids) the fast engines (the grid kernel, the mesh engine) for
    /// [`System::run`]. Off by default: the library is exact (the general f64
    /// engine) unless asked otherwise.
    pub fn set_fast_path(&mut self, allowed: bool) {
        self.engines.allowed = allowed;
        if !allowed {
            self.engines.grid = None;
            self.engines.lattice = None;
            self.engines.mesh = None;
        }
    }

    /// Keeps a lattice off the lattice kernel (when `refused`), so that the mesh
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
        match (&self.engines.grid, &self.engines.mesh, self.engine()) {
            (Some(fast), _, Engine::Grid(_)) => fast.kernel.self_collision_contacts(),
            (_, Some(mesh), Engine::Mesh) => mesh.kernel.self_collision_contacts(),
            _ => self.work.self_collision.contacts(),
        }
    }

    /// Threads the engine [`Self::engine`] names steps on: its pool's
    /// (`pool_threads`) when the system is large enough to split (a fast engine's
    /// own threshold, or the general engine's spring count:
    /// [`super::forces::uses_threads`]), else one.
    pub fn engine_threads(&self) -> usize {
        let Engines {
            grid,
            lattice,
            mesh,
            ..
        } = &self.engines;
        let parallel = match self.engine() {
            Engine::Grid(_) => grid.as_ref().is_some_and(|f| f.kernel.is_parallel()),
            Engine::Lattice(_) => lattice.as_ref().is_some_and(|l| l.kernel.is_parallel()),
            Engine::Mesh => mesh.as_ref().is_some_and(|m| m.kernel.is_parallel()),
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
        } else if MeshParams::of(&self.model).is_some() {
            Engine::Mesh
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

    /// Runs `n` steps on the lattice kernel if allowed and it models the system;
    /// `None` when another engine must run them. Call after [`Self::run_on_grid`]
    /// declined.
    pub(super) fn run_on_lattice(
        &mut self,
        n: u64,
        settle: bool,
    ) -> Option<Result<(), Divergence>> {
        if !self.engines.allowed {
            return None;
        }
        self.run_choosing(n, settle, Self::lattice_spec, |system, spec, n| {
            system.run_lattice_once(spec, n, settle)
        })
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

    /// [`Self::run_on_lattice`]'s run of up to `n` steps on a lattice kernel for
    /// `spec`, the one built before when it can take the spec: the steps run
    /// ([`Self::run_in_chunks`]).
    fn run_lattice_once(
        &mut self,
        spec: LatticeSpec,
        n: u64,
        settle: bool,
    ) -> Result<u64, Divergence> {
        let reused = self.engines.lattice.take().and_then(|mut lattice| {
            if *lattice.kernel.spec() != spec {
                // A live edit of a coefficient: updated in place (pins are set
                // again below); a new shape, integrator or precision needs a new
                // kernel.
                if !lattice.kernel.respec(spec.clone()) {
                    return None;
                }
                lattice.in_sync = false;
            }
            Some(lattice)
        });
        let mut lattice = match reused {
            Some(lattice) => lattice,
            None => {
                self.engines.builds += 1;
                let mut kernel = LatticeKernel::new(spec);
                kernel.set_threads(pool_threads());
                LatticePath {
                    kernel,
                    in_sync: false,
                    held: Vec::new(),
                }
            }
        };
        if !lattice.in_sync {
            lattice.load(self);
            lattice.held = self.held(|i, pinned| lattice.kernel.set_pinned(i, pinned));
            lattice.in_sync = true;
        }
        let result = self.run_in_chunks(n, &mut lattice, settle);
        self.engines.lattice = Some(lattice);
        result
    }

    /// The lattice kernel's description of this system, if it models it: a
    /// lattice whose springs are checked to be its stencil's, one mass, gravity and
    /// the applied force, air damping, a penalty ground and a sphere with or
    /// without friction, symplectic Euler, explicit Euler or Verlet, in the
    /// precision the precision rule asks for.
    ///
    /// Every parameter is named here (no `..`): a new one fails to compile until
    /// it is either passed to the kernel or made a reason to refuse it.
    pub(super) fn lattice_spec(&self) -> Option<LatticeSpec> {
        let model = &self.model;
        if self.engines.lattice_refused {
            return None;
        }
        let (shape, springs) = (model.lattice?, self.engines.stencil_springs?);
        let super::Params {
            gravity,
            force,
            wind: _,             // only the aerodynamic drag uses it (refused below)
            gust: _,             // likewise
            air_density: _,      // likewise
            drag_coefficient: _, // likewise
            air_damping,
            ground,
            sphere,
            integrator,
            dt: _,             // given to each run
            bar_iterations: _, // bars are refused below
            stretch_limit,
            tear_strain,
            max_speed,
            friction,
            thickness: _, // already in `ground` and `sphere`
            self_collision,
            seed: _, // only the gusts use it
        } = model.params;
        let super::ForceTerms {
            gravity: gravity_on,
            springs: _, // the kernel always evaluates the stencil
            aero,
            air_damping: air_damping_on,
            ground: _, // `ground` itself says
            applied,
        } = model.terms;
        let bars = !model.bars.is_empty() && model.params.bar_iterations > 0;
        let others = aero || self_collision || tear_strain.is_some() || max_speed.is_some();
        if !springs.lattice || bars || others || !LatticeSpec::supports(integrator) {
            return None;
        }
        let mut spec = LatticeSpec {
            shape,
            spacing: springs.spacing,
            particle_mass: springs.mass,
            kinds: springs.coefficients,
            gravity: uniform_acceleration(
                gravity_on.then_some(gravity),
                applied.then_some(force),
                springs.mass,
            ),
            air_damping: if air_damping_on { air_damping } else { 0.0 },
            ground,
            sphere,
            friction,
            stretch_limit: stretch_limit.filter(|_| !model.springs.is_empty()),
            integrator,
            precision: Precision::Single,
        };
        let precision = Precision::cheapest(self.noise_rule(&spec).1, self.float32_reach());
        spec.precision = precision;
        Some(spec)
    }

    /// Runs `n` steps on the mesh engine if allowed and it models the system
    /// exactly; `None` when the general path must run them. Call after
    /// [`Self::run_on_grid`] and [`Self::run_on_lattice`] declined.
    pub(super) fn run_on_mesh(&mut self, n: u64, settle: bool) -> Option<Result<(), Divergence>> {
        if !self.engines.allowed {
            return None;
        }
        let params = MeshParams::of(&self.model)?;
        if (self.engines.mesh.as_ref()).is_some_and(|mesh| mesh.kernel.has_torn()) {
            // The engine ran ahead and tore springs: the model breaks them too
            // before the two are compared.
            self.catch_up();
        }
        let reused = self.engines.mesh.take().map(|mut mesh| {
            // Coefficients, masses and pins are taken in place; a new topology or
            // integrator needs a new engine (on the same threads).
            if !mesh.kernel.refresh(&self.model, params) {
                mesh.kernel.rebuild(&self.model, params);
                mesh.in_sync = false;
            }
            mesh
        });
        let mut mesh = match reused {
            Some(mesh) => mesh,
            None => {
                let mut kernel = MeshKernel::new(&self.model, params);
                kernel.set_threads(pool_threads());
                MeshPath {
                    kernel,
                    in_sync: false,
                }
            }
        };
        if !mesh.in_sync {
            load_state(&mut mesh.kernel, self);
            mesh.in_sync = true;
        }
        // Float64 positions: the mesh engine runs every step.
        let result = self.run_in_chunks(n, &mut mesh, settle).map(|_| ());
        self.engines.mesh = Some(mesh);
        Some(result)
    }

    /// The kernel's description of this system, if the kernel models it exactly.
    ///
    /// Every parameter is named here (no `..`): a new one fails to compile until
    /// it is either passed to the kernel or made a reason to refuse it.
    fn grid_spec(&self) -> Option<GridSpec> {
        let model = &self.model;
        let (shape, springs) = (model.grid?, self.engines.stencil_springs?);
        let super::Params {
            gravity,
            force,
            wind,
            gust: _, // the wind's gusts are set step by step (`run_on_grid`)
            air_density,
            drag_coefficient,
            air_damping,
            ground,
            sphere,
            integrator,
            dt: _,             // given to each run
            bar_iterations: _, // bars are refused below
            stretch_limit,
            tear_strain,
            max_speed,
            friction,
            thickness,
            self_collision,
            seed: _, // only the gusts use it
        } = model.params;
        let super::ForceTerms {
            gravity: gravity_on,
            springs: _, // the kernel always evaluates the stencil
            aero,
            air_damping: air_damping_on,
            ground: _, // `ground` itself says
            applied,
        } = model.terms;
        if !GridCloth::supports(integrator)
            || (!model.bars.is_empty() && model.params.bar_iterations > 0)
        {
            return None;
        }
        let (air_density, drag_coefficient) = if aero {
            (air_density, drag_coefficient)
        } else {
            (0.0, 0.0)
        };
        let [structural, shear, bend] = springs.coefficients;
        let mut spec = GridSpec {
            width: shape.width,
            height: shape.height,
            spacing: springs.spacing,
            particle_mass: springs.mass,
            origin: [0.0; 3],
            structural,
            shear,
            bend,
            gravity: uniform_acceleration(
                gravity_on.then_some(gravity),
                applied.then_some(force),
                springs.mass,
            ),
            wind: wind.to_array(),
            air_density,
            drag_coefficient,
            pinned: Vec::new(),
            air_damping: if air_damping_on { air_damping } else { 0.0 },
            ground,
            sphere,
            friction,
            self_collision: self_collision.then_some(thickness).filter(|&t| t > 0.0),
            stretch_limit: stretch_limit.filter(|_| !model.springs.is_empty()),
            tear_strain,
            max_speed,
            integrator,
            present: springs.present,
            precision: Precision::Single,
        };
        let precision = Precision::cheapest(self.noise_rule(&spec).1, self.float32_reach());
        spec.precision = precision;
        Some(spec)
    }

    /// Runs `n` steps on the kernel if allowed and possible; `None` when the general
    /// path must run them.
    pub(super) fn run_on_grid(&mut self, n: u64, settle: bool) -> Option<Result<(), Divergence>> {
        if !self.engines.allowed {
            return None;
        }
        self.run_choosing(n, settle, Self::grid_spec, |system, spec, n| {
            system.run_grid_once(spec, n, settle)
        })
    }

    /// [`Self::run_on_grid`]'s run of up to `n` steps on a grid kernel for `spec`,
    /// the one built before when it can take the spec: the steps run
    /// ([`Self::run_in_chunks`]).
    fn run_grid_once(&mut self, spec: GridSpec, n: u64, settle: bool) -> Result<u64, Divergence> {
        // The kernel is taken out of `self` while it runs, so that the divergence
        // check can borrow the system.
        let reused = self.engines.grid.take().and_then(|mut fast| {
            if fast.spec != spec {
                // A live edit of a coefficient: updated in place, no new arrays or
                // threads; a new shape or integrator needs a new kernel.
                if !fast.kernel.respec(spec.clone()) {
                    return None;
                }
                fast.spec = spec.clone();
                fast.in_sync = false;
            }
            Some(fast)
        });
        let mut fast = match reused {
            Some(fast) => fast,
            None => {
                self.engines.builds += 1;
                let mut kernel = GridCloth::new(spec.clone());
                kernel.set_threads(pool_threads());
                FastPath {
                    kernel,
                    spec,
                    in_sync: false,
                    held: Vec::new(),
                    springs_seen: None,
                }
            }
        };
        if fast.springs_seen != Some(self.engines.springs_version) {
            (fast.kernel).set_springs_left(springs_left(&self.model, fast.spec.present));
            fast.springs_seen = Some(self.engines.springs_version);
        }
        if !fast.in_sync {
            load_state(&mut fast.kernel, self);
            fast.held = self.held(|i, pinned| fast.kernel.set_pinned(i, pinned));
            fast.in_sync = true;
        }
        let result = self.run_in_chunks(n, &mut fast, settle);
        self.engines.grid = Some(fast);
        result
    }

    /// The particles held in place (pinned or grabbed: inverse mass 0) with their
    /// positions exactly as the f64 state has them, after telling an engine which
    /// particles are held (`set_pinned(i, held)` for every particle): a float32
    /// engine holds them only to its precision, and puts them back on copying out.
    fn held(&self, mut set_pinned: impl FnMut(usize, bool)) -> Vec<(usize, DVec3)> {
        let mut held = Vec::new();
        for (i, &w) in self.model.inv_mass.iter().enumerate() {
            set_pinned(i, w == 0.0);
            if w == 0.0 {
                held.push((i, self.state.positions[i]));
            }
        }
        held
    }

    /// Runs `n` steps on a fast engine in chunks of [`CHUNK`]. Simulated time
    /// advances by whole steps, as in the general path. After each chunk a cheap scan
    /// of the engine's own arrays; the f64 state and the full check (with the
    /// energy budget, and the message) every [`ENERGY_CHECK_STEPS`] steps (counted
    /// across runs), when the scan finds trouble, and at the end when `settle`.
    /// Without `settle` the engine may end the run ahead of the f64 state: see
    /// [`System::run_ahead`].
    ///
    /// When the scan finds a non-finite or runaway state, the steps since the f64
    /// state was last brought up to date (a full check, or [`System::settle`]) are
    /// run again one at a time from it, so that the divergence is reported at the
    /// step where it happened rather than at the end of its chunk.
    ///
    /// Returns the steps run: fewer than `n` when the engine's body outgrew its
    /// fixed-point unit ([`FastEngine::outgrown_unit`]), with the f64 state up to
    /// date; the caller runs the rest on the engine chosen again.
    fn run_in_chunks<E: FastEngine>(
        &mut self,
        n: u64,
        engine: &mut E,
        settle: bool,
    ) -> Result<u64, Divergence> {
        let dt = self.model.params.dt;
        let mut done = 0;
        let mut from = match self.engines.ahead.take() {
            Some((_, time, steps)) => (time, steps),
            None => (self.state.time, self.state.steps),
        };
        if from.1 == self.state.steps
            && let Some(unit) = engine.outgrown_unit(dt)
        {
            // Loaded with a body spread past its unit (the f64 state is the
            // engine's): none of the run on it.
            self.engines.outgrown_unit = Some(unit);
            return Ok(0);
        }
        while done < n {
            let chunk = CHUNK.min(n - done);
            engine.advance(self, chunk as usize);
            done += chunk;
            self.engines.unchecked += chunk;
            for _ in 0..chunk {
                self.state.time += dt;
            }
            self.state.steps += chunk;
            let (speed2, dist2) = engine.extremes(self.runaway.center);
            let plausible = self.runaway.plausible(speed2, dist2);
            if !plausible && self.state.steps - from.1 > 1 {
                self.replay_one_by_one(engine, from);
            }
            let outgrown = engine.outgrown_unit(dt);
            let check = (settle && done == n) || self.engines.unchecked >= ENERGY_CHECK_STEPS;
            if check || !plausible || outgrown.is_some() {
                self.engines.unchecked = 0;
                engine.copy_back(self);
                self.check()?;
                from = (self.state.time, self.state.steps);
            }
            if outgrown.is_some() {
                // The body spread past what its fixed-point unit holds, and the
                // coarser unit is too noisy: the rest of the run goes to the kernel
                // the precision rule now chooses, from the state just copied back.
                self.engines.outgrown_unit = outgrown;
                break;
            }
        }
        if from.1 != self.state.steps {
            self.engines.ahead = Some((E::KIND, from.0, from.1));
        }
        Ok(done)
    }

    /// Brings the f64 state up to the fast engine's, if the engine ran ahead.
    pub(super) fn catch_up(&mut self) {
        let Some((ahead, _, _)) = self.engines.ahead.take() else {
            return;
        };
        match ahead {
            Ahead::Grid => {
                if let Some(mut fast) = self.engines.grid.take() {
                    fast.copy_back(self);
                    self.engines.grid = Some(fast);
                }
            }
            Ahead::Lattice => {
                if let Some(mut lattice) = self.engines.lattice.take() {
                    lattice.copy_back(self);
                    self.engines.lattice = Some(lattice);
                }
            }
            Ahead::Mesh => {
                if let Some(mut mesh) = self.engines.mesh.take() {
                    mesh.copy_back(self);
                    self.engines.mesh = Some(mesh);
                }
            }
        }
    }

    /// After [`System::run_ahead`]: brings the f64 state up to the fast engine's
    /// and checks it in full, as [`System::run`] leaves it. Does nothing when the
    /// state was checked at this step already.
    pub fn settle(&mut self) -> Result<(), Divergence> {
        if self.engines.ahead.is_none() && self.engines.unchecked == 0 {
            return Ok(());
        }
        self.catch_up();
        self.engines.unchecked = 0;
        self.check()
    }

    /// The f64 state is about to change or be read outside the fast engines:
    /// brings it up to date first, and has the engines copy it in again before
    /// they next run.
    pub(super) fn mark_changed(&mut self) {
        self.catch_up();
        self.engines.mark_stale();
        self.checked_energy = None;
    }

    /// The held particle `i` was put at `position`, at rest, in the f64 state (a
    /// grab moved by the mouse): the grid kernel, when it holds the f64 state,
    /// takes that one particle, so that dragging a particle does not reload the
    /// whole cloth at every move; the other engines, and Verlet (whose update
    /// velocities the hold resets), copy the whole state in again.
    pub(super) fn held_particle_moved(&mut self, i: usize, position: DVec3) {
        let verlet = self.model.params.integrator == Integrator::Verlet;
        let moved_in_place = match &mut self.engines.grid {
            Some(grid) if grid.in_sync && !verlet => {
                match grid.held.iter_mut().find(|(j, _)| *j == i) {
                    Some(held) => {
                        held.1 = position;
                        grid.kernel.set_particle(i, position, DVec3::ZERO);
                        true
                    }
                    None => false,
                }
            }
            _ => false,
        };
        self.engines.mark_stale();
        if let Some(grid) = self.engines.grid.as_mut().filter(|_| moved_in_place) {
            grid.in_sync = true;
        }
        self.checked_energy = None;
    }

    /// Runs the steps from the last full check (`checked`: its time and step count,
    /// with its positions and velocities still in the f64 state) up to the current
    /// step again, one at a time, stopping at the first whose scan fails: the
    /// engine and the step count are left at that step.
    fn replay_one_by_one(&mut self, engine: &mut impl FastEngine, from: (f64, u64)) {
        let dt = self.model.params.dt;
        let last = self.state.steps;
        (self.state.time, self.state.steps) = from;
        engine.load(self);
        while self.state.steps < last {
            engine.advance(self, 1);
            self.state.time += dt;
            self.state.steps += 1;
            let (speed2, dist2) = engine.extremes(self.runaway.center);
            if !self.runaway.plausible(speed2, dist2) {
                break;
            }
        }
    }

    /// Position Verlet's update velocities `(x - x_prev) / h` for a fast engine
    /// (`None` for the other integrators).
    fn verlet_update_velocities(&self) -> Option<Vec<DVec3>> {
        if self.model.params.integrator != Integrator::Verlet {
            return None;
        }
        let state = &self.state;
        (state.verlet).update_velocities(&state.positions, self.model.params.dt)
    }

    /// The f64 Verlet history from a fast engine's update velocities (which `fill`
    /// writes).
    fn set_verlet_history(&mut self, fill: impl FnOnce(&mut [DVec3])) {
        if self.model.params.integrator != Integrator::Verlet {
            return;
        }
        let state = &mut self.state;
        let h = self.model.params.dt;
        (state.verlet).set_from_update_velocities(&state.positions, &state.velocities, h, fill);
    }
}

/// What [`System::run_in_chunks`] needs of a fast engine.
trait FastEngine {
    /// Which engine this is.
    const KIND: Ahead;
    /// `steps` steps of the system's `dt`, from the system's time.
    fn advance(&mut self, system: &System, steps: usize);
    /// The largest squared speed and squared distance from `center` (infinite on
    /// NaN).
    fn extremes(&self, center: DVec3) -> (f64, f64);
    /// The engine's state into the system's f64 state (and springs it broke into
    /// the model).
    fn copy_back(&mut self, system: &mut System);
    /// The system's f64 state into the engine (the reverse of `copy_back`).
    fn load(&mut self, system: &System);
    /// The unit (m) of the engine's fixed-point positions when the body has spread
    /// past what its spec's unit holds and the float32 noise at the unit it took
    /// instead is over [`Precision::NOISE_LIMIT`] (steps of `dt` s): the precision
    /// rule must then choose again.
    fn outgrown_unit(&self, dt: f64) -> Option<f64>;
}

/// [`FastEngine::outgrown_unit`] of a kernel keeping positions in `unit` (if fixed
/// point) for `spec`, at steps of `dt` s.
fn outgrown(unit: Option<f64>, spec: &impl SpringNoise, dt: f64) -> Option<f64> {
    let noisy = |unit| spec.spring_noise(Err(unit), dt) > Precision::NOISE_LIMIT;
    unit.filter(|&unit| unit > spec.fixed_unit() && noisy(unit))
}

impl FastEngine for FastPath {
    const KIND: Ahead = Ahead::Grid;
    fn advance(&mut self, system: &System, steps: usize) {
        let (model, dt) = (&system.model, system.model.params.dt);
        if model.wind.gust != 0.0 && model.terms.aero {
            (self.kernel).steps_in_wind(dt, steps, system.state.time, &model.wind);
        } else {
            self.kernel.steps(dt, steps);
        }
    }
    fn extremes(&self, center: DVec3) -> (f64, f64) {
        self.kernel.extremes(center)
    }
    fn copy_back(&mut self, system: &mut System) {
        let torn = self.kernel.take_torn();
        if !torn.is_empty() {
            let width = self.spec.width;
            let mut pairs: Vec<(usize, usize)> = torn
                .into_iter()
                .map(|(p, d)| {
                    let (dr, dc) = STENCIL_DIRECTIONS[d];
                    (p, (p + dr * width).wrapping_add_signed(dc))
                })
                .collect();
            pairs.sort_unstable();
            let pair = |s: &super::Spring| (s.a as usize, s.b as usize);
            system.break_springs(|s| pairs.binary_search(&pair(s)).is_ok());
            // The kernel broke them itself: its masks are the model's.
            self.springs_seen = Some(system.engines.springs_version);
        }
        copy_state_back(&self.kernel, &self.held, system);
    }
    fn load(&mut self, system: &System) {
        load_state(&mut self.kernel, system);
    }
    fn outgrown_unit(&self, dt: f64) -> Option<f64> {
        outgrown(self.kernel.position_unit(), self.kernel.spec(), dt)
    }
}

impl FastEngine for LatticePath {
    const KIND: Ahead = Ahead::Lattice;
    fn advance(&mut self, system: &System, steps: usize) {
        self.kernel.steps(system.model.params.dt, steps);
    }
    fn extremes(&self, center: DVec3) -> (f64, f64) {
        self.kernel.extremes(center)
    }
    fn copy_back(&mut self, system: &mut System) {
        copy_state_back(&self.kernel, &self.held, system);
    }
    fn load(&mut self, system: &System) {
        load_state(&mut self.kernel, system);
    }
    fn outgrown_unit(&self, dt: f64) -> Option<f64> {
        outgrown(self.kernel.position_unit(), self.kernel.spec(), dt)
    }
}

impl FastEngine for MeshPath {
    const KIND: Ahead = Ahead::Mesh;
    fn advance(&mut self, system: &System, steps: usize) {
        self.kernel.set_time(system.state.time);
        self.kernel.steps(steps);
    }
    fn extremes(&self, center: DVec3) -> (f64, f64) {
        self.kernel.extremes(center)
    }
    fn copy_back(&mut self, system: &mut System) {
        let torn = self.kernel.take_torn();
        if !torn.is_empty() {
            // The kernel broke them itself, by the same rule at the same steps:
            // the model breaks them too, and then has the kernel's springs.
            system.break_springs(|s| torn.binary_search(&(s.a, s.b)).is_ok());
        }
        copy_state_back(&self.kernel, &[], system);
    }
    fn load(&mut self, system: &System) {
        load_state(&mut self.kernel, system);
    }
    fn outgrown_unit(&self, _dt: f64) -> Option<f64> {
        None // float64 positions
    }
}

/// The acceleration (m/s²) of every free particle of a system of one `mass` (kg)
/// under `gravity` and an applied `force` (N) on each particle, when on.
fn uniform_acceleration(gravity: Option<DVec3>, force: Option<DVec3>, mass: f64) -> [f64; 3] {
    (gravity.unwrap_or(DVec3::ZERO) + force.map_or(DVec3::ZERO, |f| f / mass)).to_array()
}

/// How a fast engine's state goes in and out: the same calls on each kernel.
trait KernelState {
    fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]);
    fn set_update_velocities(&mut self, u: &[DVec3]);
    fn positions_into(&self, out: &mut [DVec3]);
    fn velocities_into(&self, out: &mut [DVec3]);
    fn update_velocities_into(&self, out: &mut [DVec3]);
}

macro_rules! kernel_state {
    ($($kernel:ty),*) => {$(
        impl KernelState for $kernel {
            fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) {
                <$kernel>::set_state(self, positions, velocities);
            }
            fn set_update_velocities(&mut self, u: &[DVec3]) {
                <$kernel>::set_update_velocities(self, u);
            }
            fn positions_into(&self, out: &mut [DVec3]) {
                <$kernel>::positions_into(self, out);
            }
            fn velocities_into(&self, out: &mut [DVec3]) {
                <$kernel>::velocities_into(self, out);
            }
            fn update_velocities_into(&self, out: &mut [DVec3]) {
                <$kernel>::update_velocities_into(self, out);
            }
        }
    )*};
}

kernel_state!(GridCloth, LatticeKernel, MeshKernel);

/// The system's f64 state (and Verlet's update velocities) into `kernel`.
fn load_state(kernel: &mut impl KernelState, system: &System) {
    let state = &system.state;
    kernel.set_state(&state.positions, &state.velocities);
    if let Some(u) = system.verlet_update_velocities() {
        kernel.set_update_velocities(&u);
    }
}

/// `kernel`'s state into the system's f64 state, the `held` particles put back
/// exactly where the f64 state had them.
fn copy_state_back(kernel: &impl KernelState, held: &[(usize, DVec3)], system: &mut System) {
    kernel.positions_into(&mut system.state.positions);
    kernel.velocities_into(&mut system.state.velocities);
    for &(i, position) in held {
        system.state.positions[i] = position;
    }
    system.set_verlet_history(|u| kernel.update_velocities_into(u));
}

/// Threads a fast engine's pool has: rayon's global setting, one per core unless
/// `RAYON_NUM_THREADS` says otherwise (the general engine's threads follow it too).
fn pool_threads() -> usize {
    rayon::current_num_threads()
}
