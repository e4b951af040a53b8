//! The fast engine for regular grid cloths: a stencil kernel for damped springs,
//! gravity, per-triangle aero drag, air damping and a ground, stepped with
//! symplectic Euler, explicit Euler or position Verlet, then constrained by a sphere
//! collider and Provot's stretch limit. With XPBD the fused pass predicts with every
//! force but the springs, and the springs become distance constraints corrected
//! after it (`spring_passes`, in the f64 engine's colour classes).
//!
//! Units are SI (m, s, kg, N). The cloth is a `width x height` grid of particles,
//! `p = r * width + c` (row `r` from the top). Every particle is joined to its
//! 12-neighbour stencil: structural springs to `(r, c±1)`, `(r±1, c)` (rest `h`),
//! shear springs to `(r±1, c±1)` (rest `h√2`) and bend springs to `(r, c±2)`,
//! `(r±2, c)` (rest `2h`), with one stiffness `k` and damping `b` per kind. A spring
//! with `d = x_i - x_j`, `l = |d|`, `u = d / l` pushes particle `i` with
//! `f_i = -(k (l - L) + b u·(v_i - v_j)) u` and `j` with `-f_i`. Each cell
//! `(r, c)` gives the drag triangles `(a, b, d)` and `(b, e, d)` with `a = (r, c)`,
//! `b = (r, c+1)`, `d = (r+1, c)`, `e = (r+1, c+1)`; with `v_rel` the mean vertex
//! velocity minus the wind and `n` the unit normal of the current triangle of area
//! `A`, each vertex gets a third of `F = -½ ρ C_d A |v_rel| (v_rel·n) n`. Each
//! particle adds `-c v` (air damping) and, below the ground at depth `d`,
//! `k_c d - c_g v_y` upwards. These are the f64 engine's force terms
//! (`super::forces`), and the three integrators are its ones (`super::integrators`):
//! with `a = F / m + g`, symplectic Euler `v += h a; x += h v`, explicit Euler
//! `x += h v; v += h a`, and position Verlet written with the velocity of the last
//! position update `u = (x - x_prev) / h`: `u += h a; x += h u`, and the velocity
//! the forces see `v = u + h/2 a`. A particle with inverse mass 0 is pinned or held
//! (its velocity is 0). After the step, particles inside the sphere are projected
//! onto it (fused into the step when there is no stretch limit) and the stretch limit
//! runs a Gauss-Seidel pass in the f64 engine's colour order; a move `δ` adds `δ/h`
//! to the velocity, as in `super::constraints` (when it is the only spring pass,
//! the step runs it on each band's few rows as soon as it has stepped them, with
//! the same result). With friction, the colliders'
//! contact is the f64 engine's rule (`super::laws::Contact`) after the
//! step (`contact`); when nothing else comes after the step before it, it goes
//! into the step: the ground's friction to each row as soon as the row is stepped,
//! the sphere's to each band's few rows after them.
//!
//! # Precision
//! * Float32 positions lose the low bits of each move `x += h v`, and the lost bits
//!   times `k` are force noise that heats stiff cloth (0.15 J in 200 steps of a k =
//!   1e7 N/m cloth that the f64 engine keeps at 2e-6 J). Where that noise, summed
//!   over a particle's springs ([`Precision::needed`]), would pass 1% of gravity,
//!   positions are fixed point ([`Precision::Mixed`], [`frame`]): 32-bit integers
//!   in a unit chosen from the cloth's size, in a frame that follows the cloth. A
//!   spring's `d` is then exact before its conversion to float, and a move loses
//!   at most half a unit.
//! * The arithmetic is float32 when the noise of float32 spring lengths, about
//!   `2^-23 L` per spring, and of the positions, times `k / m` summed over a
//!   particle's springs, stays under 1% of gravity; otherwise the same code runs in
//!   float64 ([`Precision::Double`]), at half the lanes. `tests/engines/fast_engine.rs`
//!   shows both: float32 heats the stiff cloth, and the engine's choice follows
//!   the f64 engine's kinetic energy to 1% from k = 1e3 to 1e9 N/m.
//!
//! # How it is fast
//! * Structure of arrays (`x`, `y`, `z`, `vx`, `vy`, `vz`,
//!   inverse mass, and Verlet's `u`),
//!   rows padded to a multiple of 16 floats plus 16 ghost columns, and two ghost rows
//!   below the cloth: every loop runs over whole SIMD blocks with no scalar tail.
//!   Ghost particles are pinned at the origin; forces of springs or triangles that
//!   reach a ghost are zeroed before use.
//! * Each spring and each triangle is evaluated **once** (a plain per-particle
//!   gather evaluates every spring twice), in one fused pass per row `s` over SIMD
//!   blocks of columns: it computes the six springs that start on the row, `(s, c)`
//!   to `(s, c+1)`, `(s, c+2)`, `(s+1, c)`, `(s+1, c+1)`, `(s+2, c)` and `(s, c+1)`
//!   to `(s+1, c)`, and the two drag triangles of cell `(s, c)`; adds their forces
//!   on rows `s+1` and `s+2` to a ring of three accumulator rows; moves the forces
//!   between neighbours of the same row by one or two lanes (a lane shift carried
//!   from block to block); and, the force on `(s, c)` now being complete,
//!   integrates the particle at once. Positions and velocities are read from memory
//!   once per step (neighbour reads hit L1) and written once.
//! * The step reads the old state and writes the new one into a second set of
//!   arrays (ping-pong), so row bands can run on different threads: a band first
//!   recomputes the two spring rows above it, no thread writes memory another one
//!   reads, and the result is bit-identical for any number of threads.
//! * The loops are written once over a small SIMD trait with three versions:
//!   AVX-512 (16 lanes, `vrsqrt14ps` + one Newton step for `1/l`), AVX2 + FMA
//!   (8 lanes, `vrsqrtps` + one Newton step) and a portable one (`1/sqrt`, which
//!   the compiler vectorises for SSE2 or NEON); in float64, AVX-512 (8 lanes,
//!   `vrsqrt14pd` + one fourth-order step, within an ulp of `1/sqrt`: on an
//!   Intel core the divider had bound the float64 kernels), AVX2 (4 lanes, a
//!   correctly rounded `1/sqrt`) and the portable one. The
//!   best one this CPU has is picked at run time; the binary runs on any x86-64 or
//!   aarch64 machine.
//! * Nothing is allocated inside a step.
//!
//! # Where things are
//! * This file: the spec and precision rule, the state's arrays, the kernel's
//!   step (the row pass, then `Kernel::constrain`) and its public face, [`GridCloth`].
//! * `row`: the fused row pass, the step itself: springs, drag triangles,
//!   integration and the sphere, per SIMD block.
//! * `simd`: the vector operations the loops are written over, and `x86` their
//!   AVX2 and AVX-512 versions with the entry points compiled for them.
//! * `spring_passes` (XPBD's springs, the stretch limit), `contact` (the
//!   colliders with friction, also in the step): the passes after the step;
//!   [`lattice`]: the same
//!   physics on a 3-D lattice (the jelly cube).

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU8, Ordering};

use bytemuck::Pod;
use glam::DVec3;

use super::duo::{Duo, run_in_pool};
use super::lanes::LaneFloat;
use super::laws;
use super::springs::{STENCIL_DIRECTIONS, STENCIL_KINDS};
use super::{Ground, Integrator, SelfCollision, Sphere, Wind};
use frame::{Frame, FrameRule};

/// Grids with fewer particles than this run on the calling thread even when
/// several threads are allowed (threading costs more than it saves there).
pub const PARALLEL_MIN_PARTICLES: usize = 48 * 48;

/// Grids with at least this many particles hand their second band (and the spring
/// passes and the tear scan their second half) over by spinning ([`Duo`]) rather
/// than with `rayon::join`, when no pass after the step uses rayon's parallel
/// iterators. Measured on two AVX-512 cores (best of 3 runs of 960 steps, old and
/// new binaries interleaved): 1.12x to 1.24x at 256 x 256, 0.9x to 1.1x at 128 x 128
/// and 0.85x at 96 x 96; in runs of 10,000 steps 1.5x at 128 x 128. At the start of
/// a run the system may put both threads on one core for a few milliseconds, and
/// a short step loses most there.
const SPIN_MIN_PARTICLES: usize = 128 * 128;

/// Stiffness and damping of one kind of spring.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SpringCoefficients {
    /// Stiffness `k` in N/m.
    pub k: f64,
    /// Damping `b` along the spring in N·s/m.
    pub b: f64,
}

/// Everything that defines a grid cloth for [`GridCloth::new`].
///
/// The cloth starts flat in the x-y plane: particle `(r, c)` at
/// `origin + (c h, -r h, 0)` with `h = spacing`, at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct GridSpec {
    /// Particles per row (columns), at least 1.
    pub width: usize,
    /// Particles per column (rows), at least 1.
    pub height: usize,
    /// Distance between neighbouring particles `h` in m (rest length of structural
    /// springs; shear springs rest at `h√2`, bend springs at `2h`).
    pub spacing: f64,
    /// Mass of every particle in kg.
    pub particle_mass: f64,
    /// Position of particle `(0, 0)` in m.
    pub origin: [f64; 3],
    /// Structural springs `(r, c)-(r, c+1)` and `(r, c)-(r+1, c)`.
    pub structural: SpringCoefficients,
    /// Shear springs `(r, c)-(r+1, c±1)`.
    pub shear: SpringCoefficients,
    /// Bend springs `(r, c)-(r, c+2)` and `(r, c)-(r+2, c)`.
    pub bend: SpringCoefficients,
    /// Gravity in m/s² (default `(0, -9.81, 0)`).
    pub gravity: [f64; 3],
    /// Air velocity in m/s for the drag.
    pub wind: [f64; 3],
    /// Air density ρ in kg/m³; 0 turns the drag off.
    pub air_density: f64,
    /// Drag coefficient `C_d`; 0 turns the drag off.
    pub drag_coefficient: f64,
    /// Indices `r * width + c` of the pinned particles.
    pub pinned: Vec<usize>,
    /// Viscous air damping `c` in `-c v`, N·s/m (0: none).
    pub air_damping: f64,
    /// Ground plane with penalty contact, if any.
    pub ground: Option<Ground>,
    /// Sphere collider, if any: particles inside are projected onto its surface.
    pub sphere: Option<Sphere>,
    /// Coulomb friction coefficient μ of the sphere (the ground's is its own, see
    /// `laws::Contact::resolve`); with friction on either the sphere is
    /// resolved after the step rather than inside it.
    pub friction: f64,
    /// Self-collision's thickness `h_c` in m, if the particles keep it apart
    /// ([`super::self_collision`]).
    pub self_collision: Option<f64>,
    /// Provot's stretch limit `tau`, if any: no spring longer than `(1 + tau) L`.
    pub stretch_limit: Option<f64>,
    /// Tear strain `tau`, if springs tear ([`super::tearing`]): a spring longer
    /// than `(1 + tau) L` at the end of a step breaks.
    pub tear_strain: Option<f64>,
    /// Speed limit in m/s, if any (`laws::speed_limit`).
    pub max_speed: Option<f64>,
    /// Symplectic Euler, explicit Euler or position Verlet (see [`GridCloth::supports`]).
    pub integrator: Integrator,
    /// Which kinds of spring exist (structural, shear, bend); an absent kind has
    /// `k = b = 0` and no stretch limit.
    pub present: [bool; 3],
    /// The float type of the arithmetic (see [`Precision::needed`]).
    pub precision: Precision,
}

/// The float types a [`GridCloth`] keeps and computes in.
///
/// Float32 positions lose the low bits of each move `x += h v`, and float32 spring
/// lengths resolve the stretch only to about `2^-23 L`; times `k / m`, either is an
/// acceleration noise that heats a stiff cloth (0.15 J in 200 steps of a k = 1e7 N/m
/// cloth that the f64 engine keeps at 2e-6 J). [`Precision::needed`] takes the
/// cheapest level whose noise stays under [`Precision::NOISE_LIMIT`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Precision {
    /// Float32 positions and arithmetic: noise `~ k 2^-23 |x| / m`, with `|x|` the
    /// largest coordinate.
    #[default]
    Single,
    /// Float32 arithmetic on fixed-point positions ([`frame`]: 32-bit integers in a
    /// frame that follows the cloth, a spring's `d` exact before its conversion,
    /// `x += h v` rounded to the unit): noise `~ k (2^-23 L + unit / 2) / m`.
    Mixed,
    /// Float64 positions and arithmetic (the same code at half the lanes).
    Double,
}

impl Precision {
    /// Largest acceleration noise (m/s²) float32 may add to a particle: 1% of
    /// standard gravity.
    pub const NOISE_LIMIT: f64 = 0.0981;

    /// The precision a grid cloth needs whose coordinates stay within `reach` (m)
    /// of the origin, stepped at `dt` s: `Single` when float32 positions keep the
    /// noise under the limit, else `Mixed` when float32 spring lengths do, else
    /// `Double`.
    pub fn needed(spec: &GridSpec, reach: f64, dt: f64) -> Self {
        Self::cheapest(|r| Self::float32_noise(spec, r, dt), reach)
    }

    /// The cheapest level whose float32 noise (`noise(Some(reach))` with float32
    /// positions, `noise(None)` with fixed-point ones) stays under the limit.
    pub fn cheapest(noise: impl Fn(Option<f64>) -> f64, reach: f64) -> Self {
        if noise(Some(reach)) <= Self::NOISE_LIMIT {
            Self::Single
        } else if noise(None) <= Self::NOISE_LIMIT {
            Self::Mixed
        } else {
            Self::Double
        }
    }

    /// The acceleration noise (m/s²) of float32 on `spec`'s cloth stepped at `dt`
    /// s, `sum_kinds 4 k r / m` (a particle has up to 4 springs of each kind),
    /// with `r` the float32 rounding of the position's size `reach`, `2^-23 reach`,
    /// for float32 positions, or for fixed-point positions (`None`) that of each
    /// kind's rest length plus the rounding of a move to half its unit; for XPBD
    /// see [`Precision::spring_noise`].
    pub fn float32_noise(spec: &GridSpec, reach: Option<f64>, dt: f64) -> f64 {
        spec.spring_noise(reach.ok_or_else(|| spec.fixed_unit()), dt)
    }

    /// `sum count k r / m` over a particle's springs, given as `(k, count, rest
    /// length)` of each kind, with `r` the rounding of a length: `2^-23 reach` for
    /// float32 positions (`Ok(reach)`), `2^-23 rest + unit / 2` for fixed-point
    /// ones (`Err(unit)`, see [`frame`]).
    ///
    /// With XPBD at steps of `h` s (`xpbd`), a spring's round-off moves its ends
    /// as a spring of stiffness `k / (1 + 2 k h² / m)` would (XPBD's compliance,
    /// two ends of mass `m`): `k` while `k h² / m` is small, `m / 2h²` for a stiff
    /// one, whose correction takes out the whole round-off in one step. So XPBD's
    /// precision follows its step as well as `k`. (The jelly 8 m up, at h = 1.4 ms
    /// and k = 1e5 N/m: kinetic energy 2.7% from the f64 engine's after 1.4 s on
    /// float32 positions, 2.3% on double-float ones (before fixed point) with
    /// float32 arithmetic, the same to 5 digits in float64, which this picks.)
    pub fn spring_noise(
        springs: impl Iterator<Item = (f64, f64, f64)>,
        mass: f64,
        positions: Result<f64, f64>,
        xpbd: Option<f64>,
    ) -> f64 {
        if mass <= 0.0 {
            return f64::INFINITY;
        }
        let ulp = f32::EPSILON as f64;
        let stiffness = |k: f64| match xpbd {
            Some(h) => k / (1.0 + 2.0 * k * h * h / mass),
            None => k,
        };
        let rounding = |rest: f64| match positions {
            Ok(reach) => ulp * reach.abs(),
            Err(unit) => ulp * rest.abs() + 0.5 * unit,
        };
        let noise: f64 = springs
            .map(|(k, count, rest)| count * stiffness(k.abs()) * rounding(rest))
            .sum();
        noise / mass
    }
}

/// What the precision rule reads of a kernel's spec, a grid's or a lattice's: one
/// rule for both (`System`'s choice of precision, and of when a body has outgrown
/// its fixed-point unit, in [`crate::sim::fast_path`]).
pub(crate) trait SpringNoise {
    /// The float32 noise (m/s²) of its springs at steps of `dt` s, on positions
    /// rounded as [`Precision::spring_noise`] says (`Ok(reach)`: float32 ones
    /// within `reach` m; `Err(unit)`: fixed-point ones of `unit` m), XPBD's
    /// weighed at its step.
    fn spring_noise(&self, positions: Result<f64, f64>, dt: f64) -> f64;
    /// The unit (m) of its positions in fixed point.
    fn fixed_unit(&self) -> f64;
    /// The colliders its positions' frame holds beside the body.
    fn colliders(&self) -> (Option<Ground>, Option<Sphere>);
}

/// The step that XPBD's noise follows under `integrator` (`None` for the other
/// integrators: [`Precision::spring_noise`]).
fn xpbd_step(integrator: Integrator, dt: f64) -> Option<f64> {
    (integrator == Integrator::Xpbd).then_some(dt)
}

impl SpringNoise for GridSpec {
    fn spring_noise(&self, positions: Result<f64, f64>, dt: f64) -> f64 {
        self.noise(positions, xpbd_step(self.integrator, dt))
    }
    fn fixed_unit(&self) -> f64 {
        GridSpec::fixed_unit(self)
    }
    fn colliders(&self) -> (Option<Ground>, Option<Sphere>) {
        (self.ground, self.sphere)
    }
}

impl GridSpec {
    /// The peers' benchmark scene (`shared/peers/scene.py`, "stable" variant): an
    /// `n x n` cloth 1 m square hanging from its two top corners, particle mass
    /// `m = 1/n²` kg, `k = 5000 m` N/m and `b = 0.5 m` N·s/m for every spring, and,
    /// with `wind`, drag with ρ = 1.2 kg/m³, `C_d` = 1 and a wind of (0, 0, 5) m/s.
    pub fn peer_bench(n: usize, wind: bool) -> Self {
        let n = n.max(2);
        let m = 1.0 / (n * n) as f64;
        let kind = SpringCoefficients {
            k: 5000.0 * m,
            b: 0.5 * m,
        };
        GridSpec {
            width: n,
            height: n,
            spacing: 1.0 / (n - 1) as f64,
            particle_mass: m,
            origin: [0.0, 1.0, 0.0],
            structural: kind,
            shear: kind,
            bend: kind,
            gravity: [0.0, -9.81, 0.0],
            wind: if wind { [0.0, 0.0, 5.0] } else { [0.0; 3] },
            air_density: if wind { 1.2 } else { 0.0 },
            drag_coefficient: 1.0,
            pinned: vec![0, n - 1],
            air_damping: 0.0,
            ground: None,
            sphere: None,
            friction: 0.0,
            self_collision: None,
            stretch_limit: None,
            tear_strain: None,
            max_speed: None,
            integrator: Integrator::SymplecticEuler,
            present: [true; 3],
            precision: Precision::Single,
        }
    }

    /// Radius (m) of the cloth laid flat: half its diagonal.
    pub fn extent(&self) -> f64 {
        let (w, h) = (self.width.max(1) - 1, self.height.max(1) - 1);
        0.5 * self.spacing.abs() * ((w * w + h * h) as f64).sqrt()
    }

    /// [`Precision::spring_noise`] of its springs (a particle has up to 4 of each
    /// kind) with `positions` rounded as there, and XPBD's steps.
    fn noise(&self, positions: Result<f64, f64>, xpbd: Option<f64>) -> f64 {
        let h = self.spacing.abs();
        let rests = [h, std::f64::consts::SQRT_2 * h, 2.0 * h];
        let kinds = [self.structural, self.shear, self.bend];
        let springs = (kinds.iter().zip(rests)).map(|(kind, rest)| (kind.k, 4.0, rest));
        Precision::spring_noise(springs, self.particle_mass, positions, xpbd)
    }

    /// The unit (m) of its positions in fixed point: [`frame::fixed_unit`] of its
    /// radius and its springs' noise. The noise is weighed without XPBD's step,
    /// which the unit does not follow: at any step XPBD's noise is at most that
    /// (its compliance only softens a spring, [`Precision::spring_noise`]), so the
    /// unit holds it at every step the sliders reach.
    pub fn fixed_unit(&self) -> f64 {
        frame::fixed_unit(self.extent(), |unit| self.noise(Err(unit), None))
    }

    /// How its positions are stored: fixed point with [`Precision::Mixed`].
    fn frame_rule(&self) -> FrameRule<'_> {
        FrameRule {
            fixed: self.precision == Precision::Mixed,
            unit: self.fixed_unit(),
            ground: self.ground.as_ref(),
            sphere: self.sphere.as_ref(),
        }
    }

    /// Number of springs of the 12-neighbour stencil on this grid.
    pub fn spring_count(&self) -> usize {
        let (w, h) = (self.width, self.height);
        stencil_counts(w, h).iter().sum()
    }

    /// Number of drag triangles (two per cell).
    pub fn triangle_count(&self) -> usize {
        2 * self.width.saturating_sub(1) * self.height.saturating_sub(1)
    }
}

/// Springs of each kind (structural, shear, bend) of the 12-neighbour stencil on a
/// `w x h` grid.
pub fn stencil_counts(w: usize, h: usize) -> [usize; 3] {
    [
        w.saturating_sub(1) * h + w * h.saturating_sub(1),
        2 * w.saturating_sub(1) * h.saturating_sub(1),
        w.saturating_sub(2) * h + w * h.saturating_sub(2),
    ]
}

/// Which compiled version of the loops runs (in order: each level's CPU has the
/// ones before it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum SimdLevel {
    /// Portable code (vectorised by the compiler for the baseline target: SSE2 on
    /// x86-64, NEON on aarch64).
    Baseline,
    /// x86-64 with AVX2 and FMA, 8 lanes.
    Avx2,
    /// x86-64 with AVX-512F/VL and FMA, 16 lanes.
    Avx512,
}

/// The highest level the engines may run at, as set by [`SimdLevel::cap`]
/// (`u8::MAX`: no cap).
static SIMD_CAP: AtomicU8 = AtomicU8::new(u8::MAX);

impl SimdLevel {
    /// Every level, lowest first.
    pub const ALL: [Self; 3] = [Self::Baseline, Self::Avx2, Self::Avx512];

    /// Name for reports: `avx512`, `avx2` or `baseline` (as `cloth run --simd`
    /// and `grid_timing --simd` take them).
    pub fn name(self) -> &'static str {
        match self {
            Self::Baseline => "baseline",
            Self::Avx2 => "avx2",
            Self::Avx512 => "avx512",
        }
    }

    /// The level named `name` ([`Self::name`]), if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|level| level.name() == name)
    }

    /// The level the engines built from now on run at: the best this CPU has
    /// ([`Self::best`]), or the lower one [`Self::cap`] asked for.
    pub fn detect() -> Self {
        let cap = Self::ALL.get(usize::from(SIMD_CAP.load(Ordering::Relaxed)));
        cap.map_or(Self::best(), |&cap| Self::best().min(cap))
    }

    /// The best level this CPU supports (detected once).
    pub fn best() -> Self {
        static LEVEL: OnceLock<SimdLevel> = OnceLock::new();
        *LEVEL.get_or_init(|| {
            #[cfg(target_arch = "x86_64")]
            {
                let avx2 = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
                if avx2
                    && is_x86_feature_detected!("avx512f")
                    && is_x86_feature_detected!("avx512vl")
                {
                    return SimdLevel::Avx512;
                }
                if avx2 {
                    return SimdLevel::Avx2;
                }
            }
            SimdLevel::Baseline
        })
    }

    /// Whether this CPU can run the level's loops.
    pub fn is_supported(self) -> bool {
        self <= Self::best()
    }

    /// Runs every engine built from now on in this process at `level` at most
    /// (for measuring one level against another on one machine: `cloth run
    /// --simd avx2`). Engines already built keep their level. A level this CPU
    /// lacks is refused, with the reason.
    pub fn cap(level: Self) -> Result<(), String> {
        if !level.is_supported() {
            return Err(format!(
                "this CPU cannot run the {} loops (the best it has is {})",
                level.name(),
                Self::best().name()
            ));
        }
        // (`ALL` lists the levels in their declared order: `level as u8` indexes it.)
        SIMD_CAP.store(level as u8, Ordering::Relaxed);
        Ok(())
    }
}

/// Rows are padded to a multiple of this many floats (the widest SIMD block).
const BLOCK: usize = 16;

/// The float type a kernel computes in: `f32`, or `f64` where float32 cannot
/// resolve the springs (see [`Precision`]).
trait Real:
    LaneFloat
    + Copy
    + Default
    + PartialOrd
    + Pod
    + Send
    + Sync
    + std::fmt::Debug
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
    + std::ops::Neg<Output = Self>
    + std::ops::AddAssign
    + 'static
{
    const ZERO: Self;
    const ONE: Self;
    /// Below any height: the ground height when there is no ground.
    const LOWEST: Self;
    /// The float's bits as an unsigned integer.
    type Bits: Copy + Ord;
    fn of(x: f64) -> Self;
    fn f64(self) -> f64;
    fn sqrt(self) -> Self;
    fn bits(self) -> Self::Bits;
    fn from_bits(bits: Self::Bits) -> Self;
    /// `self * a + b`, fused where the build target has FMA (aarch64 always does).
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// The integer `n` as a fixed-point coordinate in the float's bits
    /// ([`frame`]).
    fn fixed_from(n: i64) -> Self;
    /// The fixed-point coordinate in the float's bits, as f64.
    fn fixed_value(self) -> f64;
    /// The least and the greatest of the fixed-point coordinates `xs` (a plain
    /// integer reduction, for the compiler to vectorise).
    fn fixed_range(xs: &[Self]) -> (i64, i64);
    /// Fixed-point `a - b` (exact, wrapping) as a float.
    fn fixed_sub(a: Self, b: Self) -> Self;
    /// Fixed-point `x` moved by `t` units, rounded to the nearest.
    fn fixed_add(x: Self, t: Self) -> Self;
    /// Runs one band of a step, with the best code this CPU has for this type.
    fn band_dispatch(
        ctx: &Ctx<Self>,
        band: &mut Band<Self>,
        out: Out<Self>,
        rows: std::ops::Range<usize>,
    );
    /// Runs one band of a lattice's step, likewise.
    fn lattice_band(ctx: &lattice::Ctx<Self>, band: &mut lattice::Band<Self>, out: Out<Self>);
    /// Runs [`spring_sweep`], likewise.
    fn spring_sweep(simd: SimdLevel, out: &mut Out<Self>, base: usize, lines: &SweepLines<Self>);
}

/// `Real` for a float type: its constants and the row functions of each SIMD level.
macro_rules! real {
    ($t:ident, bits: $bits:ty, int: $int:ty, avx512: $avx512:ident, avx2: $avx2:ident,
     lattice: $lattice512:ident, $lattice2:ident, springs: $springs512:ident, $springs2:ident) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const LOWEST: Self = $t::MIN;
            type Bits = $bits;
            fn of(x: f64) -> Self {
                x as $t
            }
            fn f64(self) -> f64 {
                self as f64
            }
            fn sqrt(self) -> Self {
                $t::sqrt(self)
            }
            #[inline(always)]
            fn bits(self) -> $bits {
                self.to_bits()
            }
            fn from_bits(bits: $bits) -> Self {
                $t::from_bits(bits)
            }
            #[inline(always)]
            fn mul_add(self, a: Self, b: Self) -> Self {
                if cfg!(any(target_arch = "aarch64", target_feature = "fma")) {
                    $t::mul_add(self, a, b)
                } else {
                    self * a + b
                }
            }
            fn fixed_from(n: i64) -> Self {
                $t::from_bits(n as $int as $bits)
            }
            #[inline(always)]
            fn fixed_range(xs: &[Self]) -> (i64, i64) {
                let (lo, hi) = xs.iter().fold((<$int>::MAX, <$int>::MIN), |(lo, hi), x| {
                    let n = x.to_bits() as $int;
                    (lo.min(n), hi.max(n))
                });
                (lo as i64, hi as i64)
            }
            fn fixed_value(self) -> f64 {
                self.to_bits() as $int as f64
            }
            #[inline(always)]
            fn fixed_sub(a: Self, b: Self) -> Self {
                (a.to_bits() as $int).wrapping_sub(b.to_bits() as $int) as $t
            }
            #[inline(always)]
            fn fixed_add(x: Self, t: Self) -> Self {
                $t::from_bits(
                    (x.to_bits() as $int).wrapping_add(t.round_ties_even() as $int) as $bits,
                )
            }
            fn band_dispatch(
                ctx: &Ctx<Self>,
                band: &mut Band<Self>,
                out: Out<Self>,
                rows: std::ops::Range<usize>,
            ) {
                // The rows with one row function of `x86`.
                macro_rules! rows_with {
                    ($row:path) => {
                        band_rows(
                            ctx,
                            band,
                            out,
                            rows,
                            |ctx, band, row, out, lo, own| unsafe {
                                $row(ctx, band, row, out, lo, own)
                            },
                        )
                    };
                }
                match ctx.simd {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: the level is Avx512 only when the CPU has AVX-512F/VL, AVX2
                    // and FMA.
                    SimdLevel::Avx512 => rows_with!(x86::$avx512),
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: the level is Avx2 only when the CPU has AVX2 and FMA.
                    SimdLevel::Avx2 => rows_with!(x86::$avx2),
                    _ => band_rows(ctx, band, out, rows, row_portable::<$t>),
                }
            }
            fn lattice_band(
                ctx: &lattice::Ctx<Self>,
                band: &mut lattice::Band<Self>,
                out: Out<Self>,
            ) {
                match ctx.simd {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: as above.
                    SimdLevel::Avx512 => unsafe { x86::$lattice512(ctx, band, out) },
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: as above.
                    SimdLevel::Avx2 => unsafe { x86::$lattice2(ctx, band, out) },
                    _ => lattice::band_modes(Portable::<$t>::default(), ctx, band, out),
                }
            }
            fn spring_sweep(
                simd: SimdLevel,
                out: &mut Out<Self>,
                base: usize,
                lines: &SweepLines<Self>,
            ) {
                fn at<const LO: bool>(
                    simd: SimdLevel,
                    out: &mut Out<$t>,
                    base: usize,
                    lines: &SweepLines<$t>,
                ) {
                    match simd {
                        #[cfg(target_arch = "x86_64")]
                        // SAFETY: as above.
                        SimdLevel::Avx512 => unsafe { x86::$springs512::<LO>(out, base, lines) },
                        #[cfg(target_arch = "x86_64")]
                        // SAFETY: as above.
                        SimdLevel::Avx2 => unsafe { x86::$springs2::<LO>(out, base, lines) },
                        _ => spring_sweep::<_, LO>(Portable::<$t>::default(), out, base, lines),
                    }
                }
                // Positions in fixed point or floats.
                if lines.sweep.fixed() {
                    at::<true>(simd, out, base, lines)
                } else {
                    at::<false>(simd, out, base, lines)
                }
            }
        }
    };
}

// Both types: the intrinsics of `x86` at AVX2 and AVX-512, the portable lanes
// below those.
real!(f32, bits: u32, int: i32, avx512: row_avx512, avx2: row_avx2,
      lattice: lattice_band_avx512, lattice_band_avx2,
      springs: spring_sweep_avx512, spring_sweep_avx2);
real!(f64, bits: u64, int: i64, avx512: row_avx512_f64, avx2: row_avx2_f64,
      lattice: lattice_band_avx512_f64, lattice_band_avx2_f64,
      springs: spring_sweep_avx512_f64, spring_sweep_avx2_f64);

/// 16 floats, so that buffers and padded rows start on a cache line.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Line<E>([E; BLOCK]);

/// A zero-initialised, 64-byte aligned float buffer.
#[derive(Clone, Debug, Default)]
struct Buf<E>(Vec<Line<E>>);

impl<E: Real> Buf<E> {
    fn zeros(n: usize) -> Self {
        Buf(vec![Line([E::ZERO; BLOCK]); n.div_ceil(BLOCK)])
    }
    fn as_slice(&self) -> &[E] {
        // SAFETY: `Line<E>` is `repr(C)` around `[E; BLOCK]`, 64 or 128 bytes: a
        // multiple of its alignment, so there is no padding between lines.
        unsafe { std::slice::from_raw_parts(self.0.as_ptr().cast(), self.0.len() * BLOCK) }
    }
    fn as_mut_slice(&mut self) -> &mut [E] {
        // SAFETY: as in `as_slice`.
        unsafe { std::slice::from_raw_parts_mut(self.0.as_mut_ptr().cast(), self.0.len() * BLOCK) }
    }
}

/// Sizes of the padded arrays.
#[derive(Clone, Copy, Debug)]
struct Grid {
    /// Columns and rows of real particles.
    w: usize,
    h: usize,
    /// Columns covered by the SIMD blocks: `w` rounded up to [`BLOCK`].
    nv: usize,
    /// Floats per row: `nv + BLOCK` (at least two ghost columns).
    stride: usize,
}

impl Grid {
    fn new(w: usize, h: usize) -> Self {
        let nv = w.next_multiple_of(BLOCK);
        Grid {
            w,
            h,
            nv,
            stride: nv + BLOCK,
        }
    }
    /// Floats per array: `h` rows and two ghost rows.
    fn len(&self) -> usize {
        (self.h + 2) * self.stride
    }
    /// Array index of particle `p = r * w + c`.
    fn index(&self, p: usize) -> usize {
        (p / self.w) * self.stride + p % self.w
    }
}

/// Per-step constants shared by all bands (f32, as the kernel uses them).
#[derive(Clone, Copy, Debug)]
struct Params<E> {
    /// Per spring kind (0 structural, 1 bend, 2 shear): `k`, `k L`, `b`.
    ks: [E; 3],
    kls: [E; 3],
    bs: [E; 3],
    gravity: [E; 3],
    wind: [E; 3],
    /// `ρ C_d / 12`: a third of the drag force with `A = |m| / 2`, over
    /// `air_scale²`.
    drag: E,
    /// What the drag multiplies the relative air velocity by: 2^-32 with
    /// fixed-point positions, else 1. A triangle's `|v_rel|² |m|²` is in units⁴ m²/s²
    /// there, which overflowed float32 for a small cloth on a fine unit (a 2 x 2
    /// cloth on its tight unit, 2^-34 m, went non-finite in its first step in a 30
    /// m/s wind); the power of two changes no other result by a bit (the drag is
    /// `σ² v_rel (v_rel·m) m / (σ |v_rel| |m|)` times `drag / σ²`).
    air_scale: E,
    dt: E,
    /// `-c` of the air damping `-c v`.
    neg_air: E,
    /// Ground height (as positions are stored), penalty stiffness per unit of
    /// depth and damping.
    ground: [E; 3],
    /// Explicit Euler (positions move with the old velocity).
    explicit: bool,
    /// `h/2` for position Verlet's velocity estimate `u + h/2 a`, else 0.
    verlet_half_dt: E,
    /// Whether the velocity of the last position update `u` is its own array (Verlet).
    verlet: bool,
    /// Whether positions are fixed point ([`Precision::Mixed`], [`frame`]).
    fixed: bool,
    /// Metres per unit of the positions (1 unless fixed point), and units per metre.
    unit: E,
    inv_unit: E,
    /// Whether there is a ground.
    ground_on: bool,
    /// Sphere centre (as positions are stored), radius and squared radius (in
    /// units), projected onto inside the fused step.
    sphere: Option<([E; 3], E, E)>,
}

impl<E: Real> Params<E> {
    /// These constants with the step (`dt`, and Verlet's `h/2`) of `old`.
    fn with_step_of(self, old: &Self) -> Self {
        Params {
            dt: old.dt,
            verlet_half_dt: old.verlet_half_dt,
            ..self
        }
    }

    /// Symplectic Euler with no air damping, ground or sphere in the step.
    fn is_plain(&self) -> bool {
        !self.verlet
            && !self.explicit
            && self.neg_air == E::ZERO
            && !self.ground_on
            && self.sphere.is_none()
    }

    /// The constants of `spec` with positions in `frame` (the step `dt` is set by
    /// each run). Lengths are in the frame's units: a spring's `k` per unit, the
    /// drag's `ρ C_d` per unit².
    fn of(spec: &GridSpec, frame: &Frame) -> Self {
        let hs = spec.spacing;
        // XPBD's springs are constraints (`constrain`), not forces: the fused pass
        // predicts with every other force.
        let xpbd = spec.integrator == Integrator::Xpbd;
        let frictional = laws::Contact {
            sphere: spec.sphere,
            ground: spec.ground,
            friction: spec.friction,
            dt: 0.0,
        }
        .has_friction();
        let force = |kind: SpringCoefficients| {
            if xpbd {
                SpringCoefficients::default()
            } else {
                kind
            }
        };
        // Index 0: structural (rest h), 1: bend (2h), 2: shear (h√2).
        let kinds = [
            (force(spec.structural), hs),
            (force(spec.bend), 2.0 * hs),
            (force(spec.shear), hs * std::f64::consts::SQRT_2),
        ];
        let unit = frame.unit;
        let air_scale = if frame.fixed { 2f64.powi(-32) } else { 1.0 };
        Params {
            ks: kinds.map(|(kind, _)| E::of(kind.k * unit)),
            kls: kinds.map(|(kind, rest)| E::of(kind.k * rest)),
            bs: kinds.map(|(kind, _)| E::of(kind.b)),
            gravity: spec.gravity.map(E::of),
            wind: spec.wind.map(E::of),
            drag: E::of(
                spec.air_density * spec.drag_coefficient / 12.0 * unit * unit
                    / (air_scale * air_scale),
            ),
            air_scale: E::of(air_scale),
            dt: E::ZERO,
            neg_air: E::of(-spec.air_damping),
            ground: ground_constants(spec.ground.as_ref(), frame),
            ground_on: spec.ground.is_some(),
            explicit: spec.integrator == Integrator::ExplicitEuler,
            verlet_half_dt: E::ZERO,
            verlet: spec.integrator == Integrator::Verlet,
            fixed: frame.fixed,
            unit: E::of(unit),
            inv_unit: E::of(1.0 / unit),
            // With a stretch limit or XPBD the sphere comes after them, in the
            // constraint pass, and so with friction (the sphere's or the ground's:
            // the pass resolves both, in the f64 engine's order).
            sphere: spec
                .sphere
                .filter(|_| spec.stretch_limit.is_none() && !xpbd && !frictional)
                .and_then(|s| frame.sphere(&s)),
        }
    }
}

/// A ground's height (as positions are stored), penalty stiffness per unit of
/// depth and damping in `frame`; with no ground, the lowest height.
fn ground_constants<E: Real>(ground: Option<&Ground>, frame: &Frame) -> [E; 3] {
    match ground {
        Some(g) => [
            frame.ground_height(g.height),
            E::of(g.stiffness * frame.unit),
            E::of(g.damping),
        ],
        None => [E::LOWEST, E::ZERO, E::ZERO],
    }
}

/// Ring of accumulator rows: row `r` collects forces from rows `r-2` and `r-1`.
const SLOTS: usize = 3;

/// Scratch of one row band: a ring of three rows of force accumulators (x, y, z).
#[derive(Clone, Debug)]
struct Band<E> {
    /// First row of the band.
    r0: usize,
    /// One past the last row.
    r1: usize,
    /// `SLOTS` x 3 components x `nv` floats.
    acc: Buf<E>,
    /// Per row, whether a free particle is near the sphere after the step, when
    /// the step gives the ground's friction ([`ContactRows::ground_friction_row`]):
    /// the rows the sphere's contact then resolves.
    near_sphere: Vec<bool>,
}

impl<E: Real> Band<E> {
    fn new(r0: usize, r1: usize, grid: &Grid) -> Self {
        Band {
            r0,
            r1,
            acc: Buf::zeros(SLOTS * 3 * grid.nv),
            near_sphere: vec![true; r1 - r0],
        }
    }
}

/// Split the rows into `n` bands of nearly equal size.
fn make_bands<E: Real>(grid: &Grid, n: usize) -> Vec<Band<E>> {
    let n = n.clamp(1, grid.h);
    (0..n)
        .map(|i| Band::new(i * grid.h / n, (i + 1) * grid.h / n, grid))
        .collect()
}

/// Cloth state in padded structure-of-arrays form: positions as the kernel's
/// [`Frame`] stores them (floats in metres, or fixed point), velocities in m/s.
#[derive(Clone, Debug)]
struct State<E> {
    x: [Buf<E>; 3],
    v: [Buf<E>; 3],
    /// Position Verlet's velocity of the last position update, `(x - x_prev) / h`
    /// (empty for the Euler methods, whose positions move with `v`).
    u: [Buf<E>; 3],
}

impl<E: Real> State<E> {
    /// [`FrameRule::refit`] of these positions (real particles at the indices
    /// `rows`), stored in `frame`.
    fn refit(
        &self,
        frame: &Frame,
        rule: FrameRule,
        rows: impl Iterator<Item = std::ops::Range<usize>>,
        time: f64,
    ) -> Option<Frame> {
        let state = (
            self.x.each_ref().map(Buf::as_slice),
            self.v.each_ref().map(Buf::as_slice),
        );
        rule.refit(frame, state, rows, time)
    }

    /// Re-encodes the positions (real particles at `rows`) from `frame` to `new`,
    /// which becomes the frame.
    fn reframe(
        &mut self,
        frame: &mut Frame,
        new: Frame,
        rows: impl Iterator<Item = std::ops::Range<usize>> + Clone,
    ) {
        frame::reencode(frame, &new, self.x.each_mut().map(Buf::as_mut_slice), rows);
        *frame = new;
    }

    /// Every array, whole (ghost rows included), as [`Out`] rows from row 0.
    fn rows(&mut self) -> Out<'_, E> {
        let State { x, v, u } = self;
        let [[x0, x1, x2], [v0, v1, v2], [u0, u1, u2]] =
            [x, v, u].map(|a| a.each_mut().map(Buf::as_mut_slice));
        Out([x0, x1, x2, v0, v1, v2, u0, u1, u2])
    }
}

/// Output rows of a band (or of several consecutive bands): `x`, `y`, `z`, `vx`,
/// `vy`, `vz`, and (Verlet only, else empty) `ux`, `uy`, `uz`, each starting at the
/// band's first row.
struct Out<'a, E>([&'a mut [E]; 9]);

impl<'a, E> Out<'a, E> {
    /// The same arrays, borrowed for a shorter while.
    fn reborrow(&mut self) -> Out<'_, E> {
        Out(self.0.each_mut().map(|a| &mut **a))
    }

    fn split_at(self, at: usize) -> (Out<'a, E>, Out<'a, E>) {
        let mut lo: [&'a mut [E]; 9] = Default::default();
        let mut hi: [&'a mut [E]; 9] = Default::default();
        for (i, a) in self.0.into_iter().enumerate() {
            let at = at.min(a.len());
            (lo[i], hi[i]) = a.split_at_mut(at);
        }
        (Out(lo), Out(hi))
    }
}

/// The stencil kernel in one precision (see [`GridCloth`], which holds one).
struct Kernel<E: Real> {
    spec: GridSpec,
    grid: Grid,
    /// How the position arrays map to metres.
    frame: Frame,
    params: Params<E>,
    cur: State<E>,
    next: State<E>,
    inv_mass: Buf<E>,
    /// Two rows: 1 for columns `c < w - 1` (springs to `c + 1` exist), then 1 for
    /// `c < w - 2`; 0 elsewhere.
    col_mask: Buf<E>,
    drag_on: bool,
    threads: usize,
    pool: Option<rayon::ThreadPool>,
    /// One band: the sequential path.
    seq_band: Vec<Band<E>>,
    /// One band per thread.
    par_bands: Vec<Band<E>>,
    simd: SimdLevel,
    /// Self-collision's f64 copy of the positions, kept between steps (empty
    /// without it).
    self_collision_scratch: Vec<DVec3>,
    /// Self-collision's candidate pairs.
    self_collision: SelfCollision,
    /// The springs left when some tore or were cut (`None`: the whole stencil).
    torn: Option<Torn<E>>,
    /// Springs torn by the steps since [`GridCloth::take_torn`]: (particle in cloth
    /// order, stencil direction).
    torn_log: Vec<(usize, usize)>,
    /// The tear scan's verdict per stencil direction and row (scratch).
    tear_rows: Vec<bool>,
}

/// In [`Torn::bits`], the bits of the cell's triangles `(a, b, d)` and `(b, e, d)`
/// (after the six springs' bits).
const TRIANGLE_BITS: [u8; 2] = [1 << 6, 1 << 7];

/// A grid cloth with springs missing: which springs and triangles are left, and
/// the masks the row pass multiplies their forces and drag by.
#[derive(Clone, Debug)]
struct Torn<E> {
    /// Per particle in cloth order: bit `d < 6` set when its spring in stencil
    /// direction `d` ([`STENCIL_DIRECTIONS`]) exists, then [`TRIANGLE_BITS`] for
    /// the triangles of the cell it is the top left corner of.
    bits: Vec<u8>,
    /// Per direction, at each particle's array index: 1 where that spring exists.
    springs: [Buf<E>; 6],
    /// Per cell, at the array index of its top left particle: 1 where the triangle
    /// `(a, b, d)` (first array) or `(b, e, d)` (second) exists.
    triangles: [Buf<E>; 2],
}

impl<E: Real> Torn<E> {
    /// The springs and triangles `bits` (see [`Torn::bits`]) on `grid`, with masks.
    fn new(bits: Vec<u8>, grid: &Grid) -> Self {
        let mut torn = Self {
            bits,
            springs: std::array::from_fn(|_| Buf::zeros(grid.len())),
            triangles: std::array::from_fn(|_| Buf::zeros(grid.len())),
        };
        torn.refresh(grid);
        torn
    }

    /// Every stencil spring of the kinds `present` that fits on `grid`, and every
    /// triangle.
    fn whole(grid: &Grid, present: [bool; 3]) -> Vec<u8> {
        let (w, h) = (grid.w, grid.h);
        (0..w * h)
            .map(|p| {
                let (r, c) = (p / w, p % w);
                let mut bits = 0;
                for (d, &(dr, dc)) in STENCIL_DIRECTIONS.iter().enumerate() {
                    let cc = c as isize + dc;
                    if present[STENCIL_KINDS[d].index()]
                        && r + dr < h
                        && (0..w as isize).contains(&cc)
                    {
                        bits |= 1 << d;
                    }
                }
                if r + 1 < h && c + 1 < w {
                    bits |= TRIANGLE_BITS[0] | TRIANGLE_BITS[1];
                }
                bits
            })
            .collect()
    }

    /// Whether the spring from particle `p` in stencil direction `d` is left.
    fn has(&self, p: usize, d: usize) -> bool {
        self.bits[p] >> d & 1 == 1
    }

    /// Breaks the spring from particle `p` in direction `d` on a grid `w` wide,
    /// and the triangles along it.
    fn break_spring(&mut self, p: usize, d: usize, w: usize) {
        self.bits[p] &= !(1 << d);
        let c = p % w;
        let [first, second] = TRIANGLE_BITS;
        let mut clear = |cell: Option<usize>, bit: u8| {
            if let Some(cell) = cell {
                self.bits[cell] &= !bit;
            }
        };
        match STENCIL_DIRECTIONS[d] {
            // Edge a-b of its cell, e-d of the cell above.
            (0, 1) => {
                clear(Some(p), first);
                clear(p.checked_sub(w), second);
            }
            // Edge a-d of its cell, b-e of the cell to the left.
            (1, 0) => {
                clear(Some(p), first);
                clear((c > 0).then(|| p - 1), second);
            }
            // Edge b-d of both triangles of the cell to the left.
            (1, -1) => clear(Some(p - 1), first | second),
            // Bend springs and the other diagonal are no triangle's edge.
            _ => {}
        }
    }

    /// Recomputes the masks from `bits`.
    fn refresh(&mut self, grid: &Grid) {
        let one = |on: bool| if on { E::ONE } else { E::ZERO };
        for p in 0..grid.w * grid.h {
            let (i, bits) = (grid.index(p), self.bits[p]);
            for d in 0..6 {
                self.springs[d].as_mut_slice()[i] = one(bits >> d & 1 == 1);
            }
            for (mask, bit) in self.triangles.iter_mut().zip(TRIANGLE_BITS) {
                mask.as_mut_slice()[i] = one(bits & bit != 0);
            }
        }
    }
}

impl<E: Real> std::fmt::Debug for Kernel<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GridCloth")
            .field("width", &self.grid.w)
            .field("height", &self.grid.h)
            .field("threads", &self.threads)
            .field("simd", &self.simd)
            .finish_non_exhaustive()
    }
}

impl<E: Real> Kernel<E> {
    /// Build the cloth at rest, flat in the x-y plane (see [`GridSpec`]). Runs on one
    /// thread until [`GridCloth::set_threads`] is called. A width or height of 0 is
    /// taken as 1; pinned indices out of range are ignored.
    ///
    /// # Panics
    /// If the spec's integrator is not one the kernel has ([`GridCloth::supports`]).
    pub fn new(mut spec: GridSpec) -> Self {
        assert!(
            GridCloth::supports(spec.integrator),
            "the grid kernel has no {} step",
            spec.integrator
        );
        spec.width = spec.width.max(1);
        spec.height = spec.height.max(1);
        let grid = Grid::new(spec.width, spec.height);
        let verlet = spec.integrator == Integrator::Verlet;
        let mut cur = State {
            x: std::array::from_fn(|_| Buf::zeros(grid.len())),
            v: std::array::from_fn(|_| Buf::zeros(grid.len())),
            u: std::array::from_fn(|_| Buf::zeros(if verlet { grid.len() } else { 0 })),
        };
        let start = |p: usize| {
            let (r, c) = (p / grid.w, p % grid.w);
            DVec3::new(
                spec.origin[0] + c as f64 * spec.spacing,
                spec.origin[1] - r as f64 * spec.spacing,
                spec.origin[2],
            )
        };
        let corners = [start(0), start(grid.w * grid.h - 1)];
        let frame = (spec.frame_rule().frame(frame::bounds(&corners), 0.0)).unwrap_or(Frame::FLOAT);
        for p in 0..grid.w * grid.h {
            let i = grid.index(p);
            for (a, q) in start(p).to_array().into_iter().enumerate() {
                cur.x[a].as_mut_slice()[i] = frame.encode(q, a);
            }
        }
        let mut inv_mass = Buf::zeros(grid.len());
        let inv_m = if spec.particle_mass > 0.0 {
            E::of(1.0 / spec.particle_mass)
        } else {
            E::ZERO
        };
        for p in 0..grid.w * grid.h {
            inv_mass.as_mut_slice()[grid.index(p)] = inv_m;
        }
        for &p in &spec.pinned {
            if p < grid.w * grid.h {
                inv_mass.as_mut_slice()[grid.index(p)] = E::ZERO;
            }
        }
        let mut col_mask = Buf::zeros(2 * grid.stride);
        for c in 0..grid.w {
            col_mask.as_mut_slice()[c] = if c + 1 < grid.w { E::ONE } else { E::ZERO };
            col_mask.as_mut_slice()[grid.stride + c] =
                if c + 2 < grid.w { E::ONE } else { E::ZERO };
        }
        let params = Params::of(&spec, &frame);
        let drag_on = params.drag != E::ZERO;
        Kernel {
            frame,
            params,
            next: cur.clone(),
            cur,
            inv_mass,
            col_mask,
            drag_on,
            threads: 1,
            pool: None,
            seq_band: make_bands(&grid, 1),
            par_bands: Vec::new(),
            simd: SimdLevel::detect(),
            self_collision_scratch: Vec::new(),
            self_collision: SelfCollision::default(),
            torn: None,
            torn_log: Vec::new(),
            tear_rows: Vec::new(),
            grid,
            spec,
        }
    }

    /// Changes coefficients in place (stiffness, damping, mass, rest length, wind,
    /// gravity, drag, air damping, colliders, stretch limit) without rebuilding the
    /// arrays or the thread pool. Returns `false`, changing nothing, when `spec` has
    /// another shape or another integrator: then build a new cloth. The particles'
    /// inverse masses are reset to the new mass (pins included: pin them again).
    pub fn respec(&mut self, spec: GridSpec) -> bool {
        let same_shape = spec.width.max(1) == self.grid.w && spec.height.max(1) == self.grid.h;
        if !same_shape || spec.integrator != self.spec.integrator {
            return false;
        }
        self.params = Params::of(&spec, &self.frame).with_step_of(&self.params);
        self.drag_on = self.params.drag != E::ZERO;
        let inv_m = if spec.particle_mass > 0.0 {
            E::of(1.0 / spec.particle_mass)
        } else {
            E::ZERO
        };
        for p in 0..self.len() {
            self.inv_mass.as_mut_slice()[self.grid.index(p)] = inv_m;
        }
        self.spec = spec;
        true
    }

    /// The spec the cloth was built from (with the current wind and gravity).
    pub fn spec(&self) -> &GridSpec {
        &self.spec
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.grid.w * self.grid.h
    }

    /// True if the cloth has no particles (never: a grid has at least one).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Use `n` threads (at least 1) for grids of [`PARALLEL_MIN_PARTICLES`] particles
    /// or more; smaller grids always run on the calling thread. Builds a rayon pool
    /// of `n` threads (this allocates; the steps do not).
    pub fn set_threads(&mut self, n: usize) {
        let n = n.max(1);
        self.threads = n;
        if n == 1 || self.len() < PARALLEL_MIN_PARTICLES || self.grid.h < 2 * n {
            self.pool = None;
            self.par_bands.clear();
            return;
        }
        self.pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .thread_name(|i| format!("cloth-grid-{i}"))
            .build()
            .ok();
        self.par_bands = make_bands(&self.grid, n);
    }

    /// Threads asked for with [`GridCloth::set_threads`].
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// True if steps run on several threads (enough threads and a large grid).
    pub fn is_parallel(&self) -> bool {
        self.pool.is_some()
    }

    /// The SIMD level the loops run with.
    pub fn simd_level(&self) -> SimdLevel {
        self.simd
    }

    /// The unit (m) of the fixed-point positions now: the spec's
    /// ([`GridSpec::fixed_unit`]) or, once the cloth has spread past what that
    /// holds, a coarser one; `None` on float positions.
    pub fn position_unit(&self) -> Option<f64> {
        self.frame.fixed.then_some(self.frame.unit)
    }

    /// Force a SIMD level (for tests and benches). A level this CPU lacks is
    /// ignored.
    pub fn set_simd_level(&mut self, level: SimdLevel) {
        if level.is_supported() {
            self.simd = level;
        }
    }

    /// Change the wind (m/s), e.g. every step for gusts.
    pub fn set_wind(&mut self, wind: DVec3) {
        self.spec.wind = wind.to_array();
        self.params.wind = self.spec.wind.map(E::of);
    }

    /// Change gravity (m/s²).
    pub fn set_gravity(&mut self, gravity: DVec3) {
        self.spec.gravity = gravity.to_array();
        self.params.gravity = self.spec.gravity.map(E::of);
    }

    /// Advance by one semi-implicit Euler step of `dt` seconds.
    pub fn step(&mut self, dt: f64) {
        self.steps(dt, 1);
    }

    /// Advance by `n` steps of `dt` seconds. On several threads the pool is entered
    /// once for all `n` steps, so prefer this to calling [`GridCloth::step`] in a loop.
    pub fn steps(&mut self, dt: f64, n: usize) {
        self.steps_in_wind(dt, n, None);
    }

    /// `n` steps of `dt`; with `wind = Some((t0, wind))` step `i` blows
    /// `wind.at(t0 + i dt)` (gusts), all inside one entry into the thread pool.
    fn steps_in_wind(&mut self, dt: f64, n: usize, wind: Option<(f64, &Wind)>) {
        self.params.dt = E::of(dt);
        if self.params.verlet {
            self.params.verlet_half_dt = E::of(0.5 * dt);
        }
        let pool = self.pool.take();
        let parallel = pool.is_some();
        // Two bands and no pass after the step that splits its work with rayon: the
        // second band (and the spring passes' second half) is handed over by
        // spinning (`Duo`).
        let spin = parallel
            && self.par_bands.len() == 2
            && self.len() >= SPIN_MIN_PARTICLES
            && !self.has_pooled_constraints();
        let run = |duo: Option<&Duo>| {
            for i in 0..n {
                if i % frame::CHECK_STEPS == 0 {
                    self.keep_in_frame(frame::CHECK_STEPS.min(n - i) as f64 * dt);
                }
                if let Some((t0, wind)) = wind {
                    self.set_wind(wind.at(t0 + i as f64 * dt));
                }
                self.one_step(dt, parallel, duo);
                self.constrain(dt, parallel, duo);
            }
        };
        run_in_pool(pool.as_ref(), spin, run);
        self.pool = pool;
    }

    /// Whether a pass after the step splits its work with rayon's parallel
    /// iterators (self-collision), which need the pool's other thread free.
    fn has_pooled_constraints(&self) -> bool {
        self.spec.self_collision.is_some()
    }

    /// One step of `dt` (the one [`Self::params`] holds, in f64), and what comes
    /// first after it when the step can run it on its rows as it writes them: the
    /// colliders' contact ([`Self::contact_in_step`]) or the one spring pass
    /// ([`Self::spring_pass_in_step`]).
    fn one_step(&mut self, dt: f64, parallel: bool, duo: Option<&Duo>) {
        let colliders = self.contact(dt);
        let contact = self.contact_in_step().then(|| {
            let cloth = (self.grid, self.inv_mass.as_slice());
            ContactRows::new(
                &colliders,
                cloth,
                self.frame,
                self.simd,
                (self.params.verlet, true),
            )
        });
        // The spring pass after the step, run by the step on each band's rows.
        let planned = self
            .spring_pass_in_step(parallel)
            .map(|rule| (rule, self.sweep_plan(rule, dt)));
        let springs = planned.map(|(rule, plan)| SpringPass {
            plan,
            inv_mass: self.inv_mass.as_slice(),
            simd: self.simd,
            torn: self.torn.as_ref(),
            start: step_start(rule, &self.cur),
        });
        let ctx = Ctx {
            grid: self.grid,
            p: self.params,
            x: self.cur.x.each_ref().map(Buf::as_slice),
            v: self.cur.v.each_ref().map(Buf::as_slice),
            u: self.cur.u.each_ref().map(Buf::as_slice),
            inv_mass: self.inv_mass.as_slice(),
            col_mask: self.col_mask.as_slice(),
            // In the order `block` evaluates them: right, two right, down,
            // down-right, the other diagonal (down-left from the next column), two
            // down, then the two triangles.
            torn: self.torn.as_ref().map(|t| {
                let [right, two_right, down_left, down, down_right, two_down] =
                    t.springs.each_ref().map(Buf::as_slice);
                let [first, second] = t.triangles.each_ref().map(Buf::as_slice);
                [
                    right, two_right, down, down_right, down_left, two_down, first, second,
                ]
            }),
            drag: self.drag_on,
            simd: self.simd,
            contact: contact.as_ref(),
            springs: springs.as_ref(),
            rows_in_cache: self.rows_in_cache(),
        };
        let real = self.grid.h * self.grid.stride;
        fn rows<E: Real>(arrays: &mut [Buf<E>; 3], real: usize) -> [&mut [E]; 3] {
            arrays.each_mut().map(|b| {
                let a = b.as_mut_slice();
                let len = real.min(a.len());
                &mut a[..len]
            })
        }
        let State { x, v, u } = &mut self.next;
        let ([x0, x1, x2], [v0, v1, v2], [u0, u1, u2]) =
            (rows(x, real), rows(v, real), rows(u, real));
        let mut out = Out([x0, x1, x2, v0, v1, v2, u0, u1, u2]);
        let bands = if parallel && self.par_bands.len() > 1 {
            &mut self.par_bands
        } else {
            &mut self.seq_band
        };
        if let Some(duo) = duo {
            run_two_bands(&ctx, bands, out.reborrow(), duo);
        } else {
            run_bands(&ctx, bands, out.reborrow(), parallel);
        }
        // The spring pass's lines between the two bands, once both have run.
        if let (Some(springs), [_, second]) = (&springs, &bands[..]) {
            springs.between_bands(&mut out, second.r0);
        }
        std::mem::swap(&mut self.cur, &mut self.next);
    }

    /// The constraints the fused row pass leaves to after the step: XPBD's springs,
    /// Provot's stretch limit, then the colliders' contact with friction, as in the
    /// f64 engine. A move `δ` of a particle also adds `δ / h` to its velocity.
    /// With `duo`, the pool's other thread is serving it: the spring passes hand
    /// it their second half, and the passes that would split their work with rayon
    /// run on this thread ([`Kernel::has_pooled_constraints`] keeps them out of
    /// that mode).
    fn constrain(&mut self, dt: f64, parallel: bool, duo: Option<&Duo>) {
        let parallel_pooled = parallel && duo.is_none();
        // Unless the step ran it ([`Self::spring_pass_in_step`]).
        if self.spring_pass_in_step(parallel).is_none() {
            if self.spec.integrator == Integrator::Xpbd {
                self.spring_pass(SpringRule::Xpbd, dt, parallel, duo);
            }
            if let Some(tau) = self.spec.stretch_limit {
                self.spring_pass(SpringRule::StretchLimit(tau), dt, parallel, duo);
            }
        }
        let parallel = parallel_pooled;
        if let Some(thickness) = self.spec.self_collision {
            self.self_collision_pass(thickness, dt, parallel);
        }
        let contact = self.contact(dt);
        // Without friction, stretch limit or XPBD the step itself projected the
        // particles out of the sphere; with nothing before the contact, the step
        // resolved it.
        if contact.is_active() && self.params.sphere.is_none() && !self.contact_in_step() {
            self.resolve_contact(&contact, parallel, duo);
        }
        if let Some(max_speed) = self.spec.max_speed {
            self.limit_speed(max_speed);
        }
        if let Some(tau) = self.spec.tear_strain {
            self.tear_pass(tau, parallel, duo);
        }
    }

    /// The spring pass that the step runs on each band's rows as soon as they are
    /// stepped, in the same hand-over ([`SpringPass`]), while the rows are in the
    /// core's cache: the only spring pass after the step (XPBD's or the stretch
    /// limit's, not both), when the step runs in one band or two (the pass's
    /// own halves, [`Self::spring_pass`]). The pass's lines then see the same
    /// positions as after the whole step: a band's lines touch only rows it has
    /// stepped, and the step reads only the positions before it.
    fn spring_pass_in_step(&self, parallel: bool) -> Option<SpringRule> {
        let rule = match (self.spec.integrator, self.spec.stretch_limit) {
            (Integrator::Xpbd, None) => SpringRule::Xpbd,
            (Integrator::Xpbd, Some(_)) => return None,
            (_, Some(tau)) => SpringRule::StretchLimit(tau),
            (_, None) => return None,
        };
        let bands = if parallel { self.par_bands.len() } else { 1 };
        (bands <= 2).then_some(rule)
    }

    /// The colliders' contact after a step of `dt`.
    fn contact(&self, dt: f64) -> laws::Contact {
        laws::Contact {
            sphere: self.spec.sphere,
            ground: self.spec.ground,
            friction: self.spec.friction,
            dt,
        }
    }

    /// Whether the step resolves the colliders' contact on each band's rows as
    /// soon as they are stepped, in the same hand-over (one fork and join a step,
    /// not two): when the contact is the first constraint after the step (no
    /// XPBD, stretch limit or self-collision) and the step does not project onto
    /// the sphere itself; the ground's friction then goes to each row as soon as
    /// it is stepped ([`ContactRows::ground_friction_row`]). Each particle's
    /// contact is its own, so the result is the same.
    fn contact_in_step(&self) -> bool {
        self.spec.integrator != Integrator::Xpbd
            && self.spec.stretch_limit.is_none()
            && self.spec.self_collision.is_none()
            && self.params.sphere.is_none()
            && self.contact(0.0).is_active()
    }

    /// The speed limit, as the f64 engine applies it ([`laws::speed_limit`]):
    /// a cheap check in the kernel's precision, then the particle's velocity (and
    /// Verlet's update velocity) scaled in f64.
    fn limit_speed(&mut self, max_speed: f64) {
        let limit2 = E::of(max_speed * max_speed);
        let verlet = self.params.verlet;
        let (w, st) = (self.grid.w, self.grid.stride);
        for r in 0..self.grid.h {
            let row = r * st..r * st + w;
            let [vx, vy, vz] = self.cur.v.each_ref().map(|a| &a.as_slice()[row.clone()]);
            // A vectorised scan of the row, then the particles over the limit one
            // by one: the same test either way.
            let any = match self.simd {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the level is AVX2 or AVX-512 only when the CPU has AVX2.
                SimdLevel::Avx2 | SimdLevel::Avx512 => unsafe {
                    x86::any_faster_avx2([vx, vy, vz], limit2)
                },
                _ => any_faster([vx, vy, vz], limit2),
            };
            if !any {
                continue;
            }
            for i in row {
                let v = self.cur.v.each_ref().map(|a| a.as_slice()[i]);
                if !faster(v, limit2) {
                    continue;
                }
                let factor = laws::speed_limit(DVec3::from(v.map(E::f64)), max_speed);
                for a in 0..3 {
                    let v = &mut self.cur.v[a].as_mut_slice()[i];
                    *v = E::of(v.f64() * factor);
                    if verlet {
                        let u = &mut self.cur.u[a].as_mut_slice()[i];
                        *u = E::of(u.f64() * factor);
                    }
                }
            }
        }
    }

    /// The springs the model has left (`bits` as in [`Torn::bits`]; `None`: the
    /// whole stencil, every triangle).
    pub fn set_springs_left(&mut self, bits: Option<Vec<u8>>) {
        self.torn = bits.map(|bits| Torn::new(bits, &self.grid));
    }

    /// The springs torn since the last call: (particle in cloth order, stencil
    /// direction).
    pub fn take_torn(&mut self) -> Vec<(usize, usize)> {
        std::mem::take(&mut self.torn_log)
    }

    /// Tearing, the step's last phase ([`super::tearing`]): breaks every spring
    /// past the tear strain `tau`. A scan of each row of each stencil direction in
    /// the kernel's precision (vectorised, its rows split over the pool's threads
    /// when `parallel`, or handed half to the spinning server with `duo`) finds
    /// the rows that may hold one, with a margin; there
    /// [`super::tearing::overstretched`] decides in f64, as in the f64 engine, in
    /// a fixed order, so the breaks do not depend on the threads.
    fn tear_pass(&mut self, tau: f64, parallel: bool, duo: Option<&Duo>) {
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let fixed = self.frame.fixed;
        // Per direction: first column, columns, rows, rest length, scan bound (in
        // the positions' units).
        let lines = self.stencil().map(|stencil| {
            let Stencil {
                offset: (dr, dc),
                rest,
                present,
                ..
            } = stencil;
            let c0 = (-dc).max(0) as usize;
            let len = w.saturating_sub(dc.max(0) as usize).saturating_sub(c0);
            let longest = self.frame.units((1.0 + tau) * rest);
            // f32 lengths are good to about 1e-6 of themselves: the scan's margin.
            let scan2 = E::of(longest * longest * (1.0 - 1e-4));
            let rows = if present && len > 0 {
                h.saturating_sub(dr)
            } else {
                0
            };
            (c0, len, rows, rest, scan2)
        });
        let mut flags = std::mem::take(&mut self.tear_rows);
        flags.clear();
        flags.resize(6 * h, false);
        {
            let (cur, torn, simd) = (&self.cur, self.torn.as_ref(), self.simd);
            // Row by row, all six directions of a row together: the rows they
            // read stay in cache.
            let scan = |k: usize, flag: &mut bool| {
                let (d, r) = (k % 6, k / 6);
                let (c0, len, rows, _, scan2) = lines[d];
                if r >= rows {
                    return;
                }
                let (dr, dc) = STENCIL_DIRECTIONS[d];
                let (a, b) = (r * st + c0, ((r + dr) * st + c0).wrapping_add_signed(dc));
                let alive = torn.map(|t| &t.springs[d].as_slice()[a..a + len]);
                let ends = (a, b, len);
                *flag = row_may_tear_dispatch(simd, cur, fixed, ends, alive, scan2);
            };
            let large = w * h >= PARALLEL_MIN_PARTICLES;
            let scan_all = |from: usize, flags: &mut [bool]| {
                (flags.iter_mut().enumerate()).for_each(|(k, f)| scan(from + k, f));
            };
            match duo {
                // The rows in two halves, the second handed over by spinning.
                Some(duo) if large => {
                    let half = 6 * (h / 2);
                    let (first, second) = flags.split_at_mut(half);
                    duo.fork_once(|| scan_all(half, second), || scan_all(0, first));
                }
                _ if parallel && large => {
                    use rayon::prelude::*;
                    // Whole rows of 16 at a time: a task per row cost more than its scan.
                    flags
                        .par_iter_mut()
                        .enumerate()
                        .with_min_len(6 * 16)
                        .for_each(|(k, f)| scan(k, f));
                }
                _ => scan_all(0, &mut flags),
            }
        }
        let mut broke = false;
        for k in (0..6 * h).filter(|&k| flags[k]) {
            let (d, r) = (k % 6, k / 6);
            let (c0, len, _, rest, _) = lines[d];
            let (dr, dc) = STENCIL_DIRECTIONS[d];
            for c in c0..c0 + len {
                let p = r * w + c;
                let q = (p + dr * w).wrapping_add_signed(dc);
                let there = self.torn.as_ref().is_none_or(|t| t.has(p, d));
                let (i, j) = (self.grid.index(p), self.grid.index(q));
                let (xi, xj) = (self.position_at(i), self.position_at(j));
                if there && super::tearing::overstretched(xi, xj, rest, tau) {
                    let (present, grid) = (self.spec.present, self.grid);
                    let torn = self
                        .torn
                        .get_or_insert_with(|| Torn::new(Torn::<E>::whole(&grid, present), &grid));
                    torn.break_spring(p, d, w);
                    self.torn_log.push((p, d));
                    broke = true;
                }
            }
        }
        self.tear_rows = flags;
        if broke && let Some(torn) = &mut self.torn {
            torn.refresh(&self.grid);
        }
    }

    /// The stencil's directions in the order the springs sort (the f64 engine's
    /// order, [`STENCIL_DIRECTIONS`]).
    fn stencil(&self) -> [Stencil; 6] {
        let h = self.spec.spacing;
        // Indexed by kind: structural, shear, bend.
        let rests = [h, std::f64::consts::SQRT_2 * h, 2.0 * h];
        let coefficients = [self.spec.structural, self.spec.shear, self.spec.bend];
        std::array::from_fn(|d| {
            let i = STENCIL_KINDS[d].index();
            Stencil {
                offset: STENCIL_DIRECTIONS[d],
                rest: rests[i],
                present: self.spec.present[i],
                coefficients: coefficients[i],
            }
        })
    }

    /// Self-collision ([`super::self_collision`]) at thickness `h_c`, on an f64
    /// copy of the positions (made on the pool's threads with `parallel`); springs
    /// are the stencil's kinds that exist. The pass reads the positions at the
    /// start of the step and the inverse masses from the kernel's arrays, for the
    /// pairs in contact only, and only the particles it moved are written back,
    /// each with its move over `dt` added to its velocity.
    fn self_collision_pass(&mut self, h_c: f64, dt: f64, parallel: bool) {
        let (width, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let n = width * h;
        let parallel = parallel && n >= super::self_collision::PARALLEL_MIN_PARTICLES;
        let mut x = std::mem::take(&mut self.self_collision_scratch);
        x.resize(n, DVec3::ZERO);
        let (positions, frame) = (&self.cur.x, &self.frame);
        // Blocks of 8 rows, each row's arrays read as slices.
        let copy = |(k, out): (usize, &mut [DVec3])| {
            for (r, out) in out.chunks_exact_mut(width).enumerate() {
                row_to_f64(out, frame, positions, (8 * k + r) * st);
            }
        };
        if parallel {
            use rayon::prelude::*;
            x.par_chunks_mut(8 * width).enumerate().for_each(copy);
        } else {
            x.chunks_mut(8 * width).enumerate().for_each(copy);
        }

        // The stencil direction of each step `(dr, dc)` from a particle to one after
        // it (`dr` 0 to 2, `dc` -2 to 2) whose kind of spring exists, and the
        // springs left when some tore. (The search asks this of every pair within
        // its reach: by table and in 32 bits, the fold scene ran 1% fewer
        // instructions than with a search of the stencil; valgrind, 1,500 steps.)
        let mut direction = [[None; 5]; 3];
        for (d, stencil) in self.stencil().into_iter().enumerate() {
            if stencil.present {
                let (dr, dc) = stencil.offset;
                direction[dr][(dc + 2) as usize] = Some(d);
            }
        }
        let torn = self.torn.as_ref();
        let w = width as u32;
        let joined = |i: usize, j: usize| {
            let (a, b) = (i.min(j) as u32, i.max(j) as u32);
            let (dr, dc) = (b / w - a / w, (b % w) as i32 - (a % w) as i32);
            let d = (dr <= 2 && dc.abs() <= 2)
                .then(|| direction[dr as usize][(dc + 2) as usize])
                .flatten();
            d.is_some_and(|d| torn.is_none_or(|t| t.has(a as usize, d)))
        };
        // Each particle's position at the start of the step (the other state
        // buffer, after the swap) and inverse mass.
        let (start, inv_mass) = (self.next.x.each_ref().map(Buf::as_slice), &self.inv_mass);
        let particle = |i: usize| {
            let g = (i / width) * st + i % width;
            (frame.decode3(&start, g), inv_mass.as_slice()[g].f64())
        };
        let (friction, pass) = (self.spec.friction, &mut self.self_collision);
        pass.apply(&mut x, particle, h_c, friction, joined, parallel);
        for k in 0..self.self_collision.moved().len() {
            let i = self.self_collision.moved()[k] as usize;
            let g = (i / width) * st + i % width;
            if x[i] != self.position_at(g) {
                self.move_particle(g, x[i], dt);
            }
        }
        self.self_collision_scratch = x;
    }

    /// Pairs pushed apart by the last self-collision pass.
    fn self_collision_contacts(&self) -> usize {
        self.self_collision.contacts()
    }

    /// Moves the particle at array index `i` to `to` (m) after a step of `dt`,
    /// adding the move over `dt` to its velocities.
    fn move_particle(&mut self, i: usize, to: DVec3, dt: f64) {
        let dv = (to - self.position_at(i)) / dt;
        self.set_position_at(i, to);
        for a in 0..3 {
            self.cur.v[a].as_mut_slice()[i] += E::of(dv[a]);
            if self.params.verlet {
                self.cur.u[a].as_mut_slice()[i] += E::of(dv[a]);
            }
        }
    }

    fn extremes(&self, center: DVec3) -> (f64, f64) {
        let x = self.cur.x.each_ref().map(Buf::as_slice);
        runaway_scan(
            &self.frame,
            x,
            self.cur.v.each_ref().map(Buf::as_slice),
            center,
        )
    }

    /// The real particles' array indices, row by row.
    fn real_rows(&self) -> impl Iterator<Item = std::ops::Range<usize>> + Clone + use<E> {
        let Grid { w, h, stride, .. } = self.grid;
        (0..h).map(move |r| r * stride..r * stride + w)
    }

    /// Keeps fixed-point positions in range for `time` s more ([`frame`]): when
    /// the particles, moved at their top speed for that long, would leave the
    /// frame's range (or the spec asks for another unit), re-encodes them in a
    /// frame that fits them.
    fn keep_in_frame(&mut self, time: f64) {
        let rule = self.spec.frame_rule();
        if let Some(frame) = self.cur.refit(&self.frame, rule, self.real_rows(), time) {
            self.adopt(frame);
        }
    }

    /// Re-encodes the positions in `frame`, and the constants with them.
    fn adopt(&mut self, frame: Frame) {
        let rows = self.real_rows();
        self.cur.reframe(&mut self.frame, frame, rows);
        self.params = Params::of(&self.spec, &frame).with_step_of(&self.params);
    }

    fn read_into(&self, arrays: &[Buf<E>; 3], out: &mut [DVec3]) {
        let [x, y, z] = arrays.each_ref().map(Buf::as_slice);
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            let i = self.grid.index(p);
            *o = DVec3::new(x[i].f64(), y[i].f64(), z[i].f64());
        }
    }

    /// Position (m) of array index `i`.
    fn position_at(&self, i: usize) -> DVec3 {
        self.frame
            .decode3(&self.cur.x.each_ref().map(Buf::as_slice), i)
    }

    /// Sets the position (m) of array index `i`, refitting the frame first if it
    /// does not hold it.
    fn set_position_at(&mut self, i: usize, q: DVec3) {
        if self.frame.fixed && !self.frame.holds((q.into(), q.into()), 0.0) {
            let x = self.cur.x.each_ref().map(Buf::as_slice);
            let v = self.cur.v.each_ref().map(Buf::as_slice);
            let ((lo, hi), _) = frame::span(&self.frame, x, v, self.real_rows());
            let bounds = (q.min(lo.into()).into(), q.max(hi.into()).into());
            if let Some(frame) = self.spec.frame_rule().frame(bounds, 0.0) {
                self.adopt(frame);
            }
        }
        for a in 0..3 {
            self.cur.x[a].as_mut_slice()[i] = self.frame.encode(q[a], a);
        }
    }

    /// Copy the positions (m) of particles `0..out.len()` into `out`.
    pub fn positions_into(&self, out: &mut [DVec3]) {
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            *o = self.position_at(self.grid.index(p));
        }
    }

    /// Position Verlet's velocities of the last position update, `(x - x_prev) / h`
    /// (m/s), of particles `0..out.len()`; nothing for the other integrators.
    pub fn update_velocities_into(&self, out: &mut [DVec3]) {
        if self.params.verlet {
            self.read_into(&self.cur.u, out);
        }
    }

    /// Sets position Verlet's velocities of the last position update (m/s); ignored
    /// for the other integrators.
    pub fn set_update_velocities(&mut self, u: &[DVec3]) {
        if !self.params.verlet {
            return;
        }
        for (p, q) in u.iter().enumerate().take(self.len()) {
            let j = self.grid.index(p);
            for a in 0..3 {
                self.cur.u[a].as_mut_slice()[j] = E::of(q[a]);
            }
        }
    }

    /// Copy the velocities (m/s) of particles `0..out.len()` into `out`.
    pub fn velocities_into(&self, out: &mut [DVec3]) {
        self.read_into(&self.cur.v, out);
    }

    /// Floats per row in the arrays of [`GridCloth::raw_positions`] (width rounded up,
    /// plus ghost columns): particle `(r, c)` is at `r * row_stride() + c`.
    pub fn row_stride(&self) -> usize {
        self.grid.stride
    }

    /// The padded position arrays `[x, y, z]` in m (see [`GridCloth::row_stride`]).
    pub fn raw_positions(&self) -> [Vec<f64>; 3] {
        let frame = &self.frame;
        let mut axis = 0..3;
        self.cur.x.each_ref().map(|b| {
            let a = axis.next().unwrap_or_default();
            b.as_slice().iter().map(|&x| frame.decode(x, a)).collect()
        })
    }

    /// The padded velocity arrays `[vx, vy, vz]` in m/s.
    pub fn raw_velocities(&self) -> [Vec<f64>; 3] {
        self.cur
            .v
            .each_ref()
            .map(|b| b.as_slice().iter().map(|x| x.f64()).collect())
    }

    /// Overwrite the state of particle `i` (ignored if out of range), e.g. for
    /// dragging it with the mouse.
    pub fn set_particle(&mut self, i: usize, position: DVec3, velocity: DVec3) {
        if i < self.len() {
            let j = self.grid.index(i);
            self.set_position_at(j, position);
            for a in 0..3 {
                self.cur.v[a].as_mut_slice()[j] = E::of(velocity[a]);
                if self.params.verlet {
                    self.cur.u[a].as_mut_slice()[j] = E::of(velocity[a]);
                }
            }
        }
    }

    /// Overwrite positions and velocities of particles `0..len` from f64 vectors
    /// (extra entries are ignored, missing ones left unchanged).
    pub fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) {
        if self.frame.fixed && positions.len() >= self.len() {
            // A frame around the new positions.
            let bounds = frame::bounds(&positions[..self.len()]);
            let frame = self.spec.frame_rule().frame(bounds, 0.0);
            if let Some(frame) = frame.filter(|f| *f != self.frame) {
                self.adopt(frame);
            }
        }
        for (p, &q) in positions.iter().enumerate().take(self.len()) {
            self.set_position_at(self.grid.index(p), q);
        }
        for (p, q) in velocities.iter().enumerate().take(self.len()) {
            let j = self.grid.index(p);
            for a in 0..3 {
                self.cur.v[a].as_mut_slice()[j] = E::of(q[a]);
            }
        }
        // Verlet's update velocities start equal to the velocities (call
        // `set_update_velocities` after this to give them their own values).
        if self.params.verlet {
            self.set_update_velocities(velocities);
        }
    }

    /// Pin (`true`: inverse mass 0, velocity 0) or free particle `i`.
    pub fn set_pinned(&mut self, i: usize, pinned: bool) {
        if i < self.len() {
            let j = self.grid.index(i);
            if pinned {
                self.inv_mass.as_mut_slice()[j] = E::ZERO;
                for a in 0..3 {
                    self.cur.v[a].as_mut_slice()[j] = E::ZERO;
                    if self.params.verlet {
                        self.cur.u[a].as_mut_slice()[j] = E::ZERO;
                    }
                }
            } else if self.spec.particle_mass > 0.0 {
                self.inv_mass.as_mut_slice()[j] = E::of(1.0 / self.spec.particle_mass);
            }
        }
    }
}

/// A regular grid cloth stepped by the fast stencil kernel, in float32 or float64
/// arithmetic as its spec asks ([`Precision`]).
///
/// ```
/// use cloth_sandbox::sim::grid_kernel::{GridCloth, GridSpec};
/// let mut cloth = GridCloth::new(GridSpec::peer_bench(32, false));
/// cloth.steps(1.0 / 960.0, 960);
/// let mut p = vec![glam::DVec3::ZERO; cloth.len()];
/// cloth.positions_into(&mut p);
/// assert!(p[1008].y < -0.6);
/// ```
#[derive(Debug)]
pub struct GridCloth(Kernels);

/// The kernel of each precision.
#[derive(Debug)]
enum Kernels {
    Single(Kernel<f32>),
    Double(Kernel<f64>),
}

/// Calls the same method on the kernel, whichever precision it has.
macro_rules! forward {
    ($(#[$doc:meta])* fn $name:ident(&self $(, $arg:ident: $ty:ty)*) $(-> $ret:ty)?) => {
        $(#[$doc])*
        pub fn $name(&self $(, $arg: $ty)*) $(-> $ret)? {
            match &self.0 {
                Kernels::Single(k) => k.$name($($arg),*),
                Kernels::Double(k) => k.$name($($arg),*),
            }
        }
    };
    ($(#[$doc:meta])* fn $name:ident(&mut self $(, $arg:ident: $ty:ty)*) $(-> $ret:ty)?) => {
        $(#[$doc])*
        pub fn $name(&mut self $(, $arg: $ty)*) $(-> $ret)? {
            match &mut self.0 {
                Kernels::Single(k) => k.$name($($arg),*),
                Kernels::Double(k) => k.$name($($arg),*),
            }
        }
    };
}

// After `forward!`, which the lattice kernel uses too.
#[cfg(test)]
mod conformance;
mod contact;
pub mod frame;
pub mod lattice;
mod row;
mod simd;
mod spring_passes;
#[cfg(target_arch = "x86_64")]
mod x86;

use contact::ContactRows;
use row::{
    Ctx, Particle, StepLanes, band_rows, integrate, project_out_of_sphere, row_portable,
    row_variant, run_bands, run_two_bands, spring,
};
use simd::{Portable, Simd};
use spring_passes::{SpringPass, SpringRule, SweepLines, spring_sweep, step_start};

impl GridCloth {
    /// Builds the cloth at rest, flat in the x-y plane (see [`GridSpec`]), in the
    /// spec's precision. Runs on one thread until [`GridCloth::set_threads`] is
    /// called. A width or height of 0 is taken as 1; pinned indices out of range are
    /// ignored.
    ///
    /// # Panics
    /// If the spec's integrator is not one the kernel has ([`GridCloth::supports`]).
    pub fn new(spec: GridSpec) -> Self {
        Self(match spec.precision {
            Precision::Single | Precision::Mixed => Kernels::Single(Kernel::new(spec)),
            Precision::Double => Kernels::Double(Kernel::new(spec)),
        })
    }

    /// Whether the kernel steps with `integrator`: symplectic Euler, explicit Euler
    /// and position Verlet (the methods with one force evaluation per step).
    pub fn supports(integrator: Integrator) -> bool {
        matches!(
            integrator,
            Integrator::SymplecticEuler
                | Integrator::ExplicitEuler
                | Integrator::Verlet
                | Integrator::Xpbd
        )
    }

    /// Changes coefficients in place (stiffness, damping, mass, rest length, wind,
    /// gravity, drag, air damping, colliders, stretch limit) without rebuilding the
    /// arrays or the thread pool. Returns `false`, changing nothing, when `spec` has
    /// another shape, integrator or precision: then build a new cloth. The particles'
    /// inverse masses are reset to the new mass (pins included: pin them again).
    pub fn respec(&mut self, spec: GridSpec) -> bool {
        if spec.precision != self.spec().precision {
            return false;
        }
        match &mut self.0 {
            Kernels::Single(k) => k.respec(spec),
            Kernels::Double(k) => k.respec(spec),
        }
    }

    forward!(
        /// The spec the cloth was built from (with the current wind and gravity).
        fn spec(&self) -> &GridSpec
    );
    forward!(
        /// Number of particles.
        fn len(&self) -> usize
    );
    forward!(
        /// True if the cloth has no particles (never: a grid has at least one).
        fn is_empty(&self) -> bool
    );
    forward!(
        /// Use `n` threads (at least 1) for grids of [`PARALLEL_MIN_PARTICLES`]
        /// particles or more; smaller grids always run on the calling thread. Builds
        /// a rayon pool of `n` threads (this allocates; the steps do not).
        fn set_threads(&mut self, n: usize)
    );
    forward!(
        /// Threads asked for with [`GridCloth::set_threads`].
        fn threads(&self) -> usize
    );
    forward!(
        /// True if steps run on several threads (enough threads and a large grid).
        fn is_parallel(&self) -> bool
    );
    forward!(
        /// The SIMD level the loops run with.
        fn simd_level(&self) -> SimdLevel
    );
    forward!(
        /// The unit (m) of the fixed-point positions now: the spec's
        /// ([`GridSpec::fixed_unit`]) or, once the cloth has spread past what that
        /// holds, a coarser one; `None` on float positions.
        fn position_unit(&self) -> Option<f64>
    );
    forward!(
        /// Force a SIMD level (for tests and benches). A level this CPU lacks is
        /// ignored.
        fn set_simd_level(&mut self, level: SimdLevel)
    );
    forward!(
        /// Change the wind (m/s), e.g. every step for gusts.
        fn set_wind(&mut self, wind: DVec3)
    );
    forward!(
        /// Change gravity (m/s²).
        fn set_gravity(&mut self, gravity: DVec3)
    );
    forward!(
        /// Advance by one step of `dt` seconds.
        fn step(&mut self, dt: f64)
    );
    forward!(
        /// Advance by `n` steps of `dt` seconds. On several threads the pool is
        /// entered once for all `n` steps, so prefer this to calling
        /// [`GridCloth::step`] in a loop.
        fn steps(&mut self, dt: f64, n: usize)
    );
    /// Advance by `n` steps of `dt` seconds in a gusty wind: step `i` blows
    /// `wind.at(start_time + i dt)`.
    pub fn steps_in_wind(&mut self, dt: f64, n: usize, start_time: f64, wind: &Wind) {
        match &mut self.0 {
            Kernels::Single(k) => k.steps_in_wind(dt, n, Some((start_time, wind))),
            Kernels::Double(k) => k.steps_in_wind(dt, n, Some((start_time, wind))),
        }
    }
    forward!(
        /// Copy the positions (m) of particles `0..out.len()` into `out`.
        fn positions_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// Copy the velocities (m/s) of particles `0..out.len()` into `out`.
        fn velocities_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// Position Verlet's velocities of the last position update,
        /// `(x - x_prev) / h` (m/s), of particles `0..out.len()`; nothing for the
        /// other integrators.
        fn update_velocities_into(&self, out: &mut [DVec3])
    );
    forward!(
        /// Sets position Verlet's velocities of the last position update (m/s);
        /// ignored for the other integrators.
        fn set_update_velocities(&mut self, u: &[DVec3])
    );
    forward!(
        /// Floats per row in the arrays of [`GridCloth::raw_positions`] (width
        /// rounded up, plus ghost columns): particle `(r, c)` is at
        /// `r * row_stride() + c`.
        fn row_stride(&self) -> usize
    );
    forward!(
        /// The padded position arrays `[x, y, z]` in m, copied
        /// to f64 (exactly) for inspection (see [`GridCloth::row_stride`]).
        fn raw_positions(&self) -> [Vec<f64>; 3]
    );
    forward!(
        /// The padded velocity arrays `[vx, vy, vz]` in m/s, copied to f64.
        fn raw_velocities(&self) -> [Vec<f64>; 3]
    );
    forward!(
        /// The largest squared speed (m²/s²) and squared distance from `center`
        /// (m²) of any particle, infinite if anything is NaN: a cheap scan for the
        /// divergence check.
        fn extremes(&self, center: DVec3) -> (f64, f64)
    );
    forward!(
        /// Overwrite the state of particle `i` (ignored if out of range), e.g. for
        /// dragging it with the mouse.
        fn set_particle(&mut self, i: usize, position: DVec3, velocity: DVec3)
    );
    forward!(
        /// Overwrite positions and velocities of particles `0..len` from f64 vectors
        /// (extra entries are ignored, missing ones left unchanged).
        fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3])
    );
    forward!(
        /// Pin (`true`: inverse mass 0, velocity 0) or free particle `i`.
        fn set_pinned(&mut self, i: usize, pinned: bool)
    );
    forward!(
        /// Pairs of particles the last self-collision pass pushed apart.
        fn self_collision_contacts(&self) -> usize
    );
    forward!(
        /// Sets which springs and triangles are left: per particle in cloth order,
        /// bit `d < 6` for its spring in stencil direction `d`
        /// ([`super::springs::STENCIL_DIRECTIONS`]), bits 6 and 7 for the triangles
        /// `(a, b, d)` and `(b, e, d)` of the cell it is the top left corner of;
        /// `None`: the whole stencil and every triangle.
        fn set_springs_left(&mut self, bits: Option<Vec<u8>>)
    );
    forward!(
        /// The springs torn since the last call, as (particle in cloth order,
        /// stencil direction).
        fn take_torn(&mut self) -> Vec<(usize, usize)>
    );
}

/// Whether a particle moving at `[vx, vy, vz]` is faster than `sqrt(limit2)`, in
/// the kernel's precision (the speed limit's cheap test).
#[inline(always)]
fn faster<E: Real>([vx, vy, vz]: [E; 3], limit2: E) -> bool {
    vx * vx + vy * vy + vz * vz > limit2
}

/// Whether any of the particles with velocities `[vx, vy, vz]` is [`faster`] than
/// `sqrt(limit2)`: a plain loop for the compiler to vectorise, the verdict an
/// integer OR.
#[inline(always)]
fn any_faster<E: Real>([vx, vy, vz]: [&[E]; 3], limit2: E) -> bool {
    let (vy, vz) = (&vy[..vx.len()], &vz[..vx.len()]);
    let mut any = 0u8;
    for c in 0..vx.len() {
        any |= u8::from(faster([vx[c], vy[c], vz[c]], limit2));
    }
    any != 0
}

/// The largest squared speed (m²/s²) and squared distance from `center` (m²) of
/// the particles at `x` with velocities `v`, infinite when any is NaN: every fast
/// engine's cheap scan for the divergence check. A square is at least 0 or NaN,
/// and the bits of floats with the sign bit clear order as their values do, a
/// NaN's above infinity's (a NaN with the sign bit set above all): integer maxima,
/// which the compiler vectorises, give the largest squares and whether any is NaN
/// at once.
fn runaway_scan<E: Real>(frame: &Frame, x: [&[E]; 3], v: [&[E]; 3], center: DVec3) -> (f64, f64) {
    if frame.fixed {
        extremes_in::<E, true>(frame, x, v, center)
    } else {
        extremes_in::<E, false>(frame, x, v, center)
    }
}

/// [`runaway_scan`] with positions in fixed point (`FIXED`) or floats.
#[inline(always)]
fn extremes_in<E: Real, const FIXED: bool>(
    frame: &Frame,
    [x, y, z]: [&[E]; 3],
    [vx, vy, vz]: [&[E]; 3],
    center: DVec3,
) -> (f64, f64) {
    // A coordinate less the centre: `n unit + (frame centre - center)` in fixed
    // point, `x - center` for floats.
    let offset: [E; 3] = std::array::from_fn(|a| E::of(frame.centre[a] - center[a]));
    let unit = E::of(frame.unit);
    let from_center = |p: E, a: usize| {
        if FIXED {
            E::fixed_sub(p, E::ZERO) * unit + offset[a]
        } else {
            p + offset[a]
        }
    };
    let n = x.len();
    let (y, z, vx, vy, vz) = (&y[..n], &z[..n], &vx[..n], &vy[..n], &vz[..n]);
    let (mut speed2, mut dist2) = (E::ZERO.bits(), E::ZERO.bits());
    for i in 0..n {
        let v2 = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
        let (dx, dy, dz) = (
            from_center(x[i], 0),
            from_center(y[i], 1),
            from_center(z[i], 2),
        );
        let d2 = dx * dx + dy * dy + dz * dz;
        speed2 = speed2.max(v2.bits());
        dist2 = dist2.max(d2.bits());
    }
    let infinity = E::of(f64::INFINITY).bits();
    if speed2 > infinity || dist2 > infinity {
        return (f64::INFINITY, f64::INFINITY);
    }
    (E::from_bits(speed2).f64(), E::from_bits(dist2).f64())
}

/// [`runaway_scan`] of the mesh engine's float64 arrays.
pub(crate) fn runaway_scan_f64(x: [&[f64]; 3], v: [&[f64]; 3], center: DVec3) -> (f64, f64) {
    runaway_scan(&Frame::FLOAT, x, v, center)
}

/// Whether any spring from `a .. a + len` to `b .. b + len` (array indices in
/// `state`) that `alive` keeps (all without a mask) is longer than `sqrt(scan2)`,
/// in the state's precision and units, with positions in fixed point (`FIXED`) or
/// floats. Written as a plain loop over slices for the compiler to vectorise.
#[inline(always)]
fn row_may_tear<E: Real, const FIXED: bool>(
    state: &State<E>,
    (a, b, len): (usize, usize, usize),
    alive: Option<&[E]>,
    scan2: E,
) -> bool {
    fn ends<E: Real>(p: &Buf<E>, a: usize, b: usize, len: usize) -> (&[E], &[E]) {
        let p = p.as_slice();
        (&p[a..a + len], &p[b..b + len])
    }
    let ends = |p| ends(p, a, b, len);
    let [(xa, xb), (ya, yb), (za, zb)] = state.x.each_ref().map(ends);
    // Every slice `len` long, in the compiler's sight, so the loops below carry no
    // bounds checks and vectorise; the verdict is an integer OR. (A macro, not a
    // closure: a closure is not inlined into the AVX2 entry point.)
    let [xa, xb, ya, yb, za, zb] = [xa, xb, ya, yb, za, zb].map(|s| &s[..len]);
    macro_rules! l2 {
        ($j:expr) => {{
            let j = $j;
            let (dx, dy, dz) = if FIXED {
                (
                    E::fixed_sub(xa[j], xb[j]),
                    E::fixed_sub(ya[j], yb[j]),
                    E::fixed_sub(za[j], zb[j]),
                )
            } else {
                (xa[j] - xb[j], ya[j] - yb[j], za[j] - zb[j])
            };
            dx * dx + dy * dy + dz * dz
        }};
    }
    let mut over = 0u8;
    match alive {
        Some(alive) => {
            for (j, &m) in alive[..len].iter().enumerate() {
                over |= u8::from(l2!(j) * m > scan2);
            }
        }
        None => {
            for j in 0..len {
                over |= u8::from(l2!(j) > scan2);
            }
        }
    }
    over != 0
}

/// One row of positions (m) in `frame` from array index `start` on, into `out`
/// (as many particles as it holds).
fn row_to_f64<E: Real>(out: &mut [DVec3], frame: &Frame, x: &[Buf<E>; 3], start: usize) {
    let at = start..start + out.len();
    let [x, y, z] = x.each_ref().map(|a| &a.as_slice()[at.clone()]);
    for (c, p) in out.iter_mut().enumerate() {
        *p = DVec3::new(
            frame.decode(x[c], 0),
            frame.decode(y[c], 1),
            frame.decode(z[c], 2),
        );
    }
}

/// [`row_may_tear`] with the best code this CPU has.
fn row_may_tear_dispatch<E: Real>(
    simd: SimdLevel,
    state: &State<E>,
    fixed: bool,
    ends: (usize, usize, usize),
    alive: Option<&[E]>,
    scan2: E,
) -> bool {
    macro_rules! scan {
        ($lo:literal) => {
            match simd {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the level is AVX-512 only when the CPU has AVX-512F/VL, AVX2
                // and FMA.
                SimdLevel::Avx512 => unsafe {
                    x86::row_may_tear_avx512::<E, $lo>(state, ends, alive, scan2)
                },
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the level is AVX2 only when the CPU has AVX2 and FMA.
                SimdLevel::Avx2 => unsafe {
                    x86::row_may_tear_avx2::<E, $lo>(state, ends, alive, scan2)
                },
                _ => row_may_tear::<E, $lo>(state, ends, alive, scan2),
            }
        };
    }
    if fixed { scan!(true) } else { scan!(false) }
}

/// One direction of the grid's stencil.
#[derive(Clone, Copy)]
struct Stencil {
    /// (row, column) from a spring's first end to its second.
    offset: (usize, isize),
    /// Rest length in m.
    rest: f64,
    /// Whether the cloth has springs of this kind.
    present: bool,
    coefficients: SpringCoefficients,
}
