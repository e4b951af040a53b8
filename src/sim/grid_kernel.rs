//! The fast engine for regular grid cloths: a stencil kernel for damped springs,
//! gravity, per-triangle aero drag, air damping and a ground, stepped with
//! symplectic Euler, explicit Euler or position Verlet, then constrained by a sphere
//! collider and Provot's stretch limit. With XPBD the fused pass predicts with every
//! force but the springs, and the springs become distance constraints corrected
//! after it (`Kernel::xpbd_pass`, in the f64 engine's colour classes).
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
//! to the velocity, as in `super::constraints`.
//!
//! # Precision
//! * Positions are double-floats: a high and a low part, so that `x += h v` keeps
//!   every bit however small the move against the position. Plain float32
//!   positions lost the move's low bits each step, and the lost bits times `k` were
//!   force noise that heated stiff cloth (0.15 J in 200 steps of a k = 1e7 N/m
//!   cloth that the f64 engine keeps at 2e-6 J). A spring's `d` subtracts high and
//!   low parts separately, so it is accurate to its own length.
//! * The arithmetic is float32 ([`Precision::Single`]) when the noise of float32
//!   spring lengths, about `2^-23 L` per spring, times `k / m` summed over a
//!   particle's springs, stays under 1% of gravity; otherwise the same code runs in
//!   float64 ([`Precision::Double`]), at half the lanes. `tests/fast_engine.rs`
//!   shows both: float32 heats the stiff cloth, and the engine's choice follows
//!   the f64 engine's kinetic energy to 1% from k = 1e3 to 1e9 N/m.
//!
//! # How it is fast
//! * Structure of arrays (`x`, `y`, `z` and their low parts, `vx`, `vy`, `vz`,
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
//!   the compiler vectorises for SSE2 or NEON). The best one this CPU has is picked
//!   at run time; the binary runs on any x86-64 or aarch64 machine.
//! * Nothing is allocated inside a step.

use std::sync::OnceLock;

use bytemuck::Pod;
use glam::DVec3;

use super::constraints;
use super::duo::{Duo, run_in_pool};
use super::springs::STENCIL_DIRECTIONS;
use super::{Ground, Integrator, SelfCollision, Sphere, Wind};

/// Squared spring length (m²) under which a spring is treated as degenerate and
/// gives no force.
const EPS2: f32 = 1e-24;
/// `|v_rel|² |2A|²` (m⁶/s²) under which a triangle gives no drag (degenerate
/// triangle or no relative wind).
const TINY: f32 = 1e-30;

/// Grids with fewer particles than this run on the calling thread even when
/// several threads are allowed (threading costs more than it saves there).
pub const PARALLEL_MIN_PARTICLES: usize = 48 * 48;

/// Grids with at least this many particles hand their second band (and the
/// stretch limit its second half) over by spinning ([`Duo`]) rather than with
/// `rayon::join`, when no pass after the step uses rayon's parallel iterators. Measured on two AVX-512 cores (best of 3 runs of 960 steps, old and
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
    /// [`constraints::Contact::resolve`]); with friction on either the sphere is
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
    /// Speed limit in m/s, if any ([`constraints::speed_limit`]).
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
    /// Float32 arithmetic on double-float positions (a high and a low float, `x +=
    /// h v` exact, a spring's `d` accurate to its length): noise `~ k 2^-23 L / m`.
    Mixed,
    /// Float64 positions and arithmetic (the same code at half the lanes).
    Double,
}

impl Precision {
    /// Largest acceleration noise (m/s²) float32 may add to a particle: 1% of
    /// standard gravity.
    pub const NOISE_LIMIT: f64 = 0.0981;

    /// The precision a grid cloth needs whose coordinates stay within `reach` (m)
    /// of the origin: `Single` when float32 positions keep the noise under the
    /// limit, else `Mixed` when float32 spring lengths do, else `Double`.
    pub fn needed(spec: &GridSpec, reach: f64) -> Self {
        // XPBD's springs are not forces: a position's round-off moves a particle by
        // about that much, not k times it, so float32 positions do at any k.
        if spec.integrator == Integrator::Xpbd {
            return Self::Single;
        }
        Self::cheapest(|r| Self::float32_noise(spec, r), reach)
    }

    /// The cheapest level whose float32 noise (`noise(Some(reach))` with float32
    /// positions, `noise(None)` with double-float ones) stays under the limit.
    pub fn cheapest(noise: impl Fn(Option<f64>) -> f64, reach: f64) -> Self {
        if noise(Some(reach)) <= Self::NOISE_LIMIT {
            Self::Single
        } else if noise(None) <= Self::NOISE_LIMIT {
            Self::Mixed
        } else {
            Self::Double
        }
    }

    /// The acceleration noise (m/s²) of float32 on `spec`'s cloth, `sum_kinds 4 k
    /// 2^-23 r / m` (a particle has up to 4 springs of each kind), with `r` the
    /// position's size `reach` for float32 positions, or each kind's rest length
    /// for double-float positions (`None`).
    pub fn float32_noise(spec: &GridSpec, reach: Option<f64>) -> f64 {
        let h = spec.spacing.abs();
        let rests = [h, std::f64::consts::SQRT_2 * h, 2.0 * h];
        let kinds = [spec.structural, spec.shear, spec.bend];
        let springs = (kinds.iter().zip(rests)).map(|(kind, rest)| (kind.k, 4.0, rest));
        Self::spring_noise(springs, spec.particle_mass, reach)
    }

    /// `sum count k 2^-23 r / m` over a particle's springs, given as `(k, count,
    /// rest length)` of each kind, with `r` as in [`Precision::float32_noise`].
    pub fn spring_noise(
        springs: impl Iterator<Item = (f64, f64, f64)>,
        mass: f64,
        reach: Option<f64>,
    ) -> f64 {
        let ulp = f32::EPSILON as f64;
        let noise: f64 = springs
            .map(|(k, count, rest)| count * k.abs() * ulp * reach.unwrap_or(rest).abs())
            .sum();
        if mass > 0.0 {
            noise / mass
        } else {
            f64::INFINITY
        }
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

/// Which compiled version of the loops runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdLevel {
    /// Portable code (vectorised by the compiler for the baseline target: SSE2 on
    /// x86-64, NEON on aarch64).
    Baseline,
    /// x86-64 with AVX2 and FMA, 8 lanes.
    Avx2,
    /// x86-64 with AVX-512F/VL and FMA, 16 lanes.
    Avx512,
}

impl SimdLevel {
    /// The best level this CPU supports (detected once).
    pub fn detect() -> Self {
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
}

/// Rows are padded to a multiple of this many floats (the widest SIMD block).
const BLOCK: usize = 16;

/// The float type a kernel computes in: `f32`, or `f64` where float32 cannot
/// resolve the springs (see [`Precision`]).
trait Real:
    Copy
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
    /// Squared spring length (m²) under which a spring is degenerate (no force).
    const EPS2: Self;
    /// `|v_rel|² |2A|²` (m⁶/s²) under which a triangle gives no drag.
    const TINY: Self;
    /// The float's bits as an unsigned integer.
    type Bits: Copy + Ord;
    fn of(x: f64) -> Self;
    fn f64(self) -> f64;
    fn sqrt(self) -> Self;
    fn bits(self) -> Self::Bits;
    fn from_bits(bits: Self::Bits) -> Self;
    /// `self * a + b`, fused where the build target has FMA (aarch64 always does).
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// Runs one band of a step, with the best code this CPU has for this type.
    fn band_dispatch(ctx: &Ctx<Self>, band: &mut Band<Self>, out: Out<Self>);
    /// Runs one band of a lattice's step, likewise.
    fn lattice_band(ctx: &lattice::Ctx<Self>, band: &mut lattice::Band<Self>, out: Out<Self>);
    /// Runs [`stretch_limit_sweep`], likewise.
    fn stretch_sweep(
        simd: SimdLevel,
        out: &mut Out<Self>,
        base: usize,
        inv_mass: &[Self],
        alive: Option<&[Self]>,
        lines: &SweepLines<Self>,
    );
}

/// `Real` for a float type: its constants and the row functions of each SIMD level.
macro_rules! real {
    ($t:ident, bits: $bits:ty, eps2: $eps2:expr, tiny: $tiny:expr, avx512: $avx512:ident, avx2: $avx2:ident,
     lattice: $lattice512:ident, $lattice2:ident, stretch: $stretch512:ident, $stretch2:ident) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const LOWEST: Self = $t::MIN;
            const EPS2: Self = $eps2;
            const TINY: Self = $tiny;
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
            fn band_dispatch(ctx: &Ctx<Self>, band: &mut Band<Self>, out: Out<Self>) {
                match ctx.simd {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: the level is Avx512 only when the CPU has AVX-512F/VL, AVX2
                    // and FMA.
                    SimdLevel::Avx512 => {
                        band_rows(ctx, band, out, |ctx, band, row, out, lo, own| unsafe {
                            x86::$avx512(ctx, band, row, out, lo, own)
                        })
                    }
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: the level is Avx2 only when the CPU has AVX2 and FMA.
                    SimdLevel::Avx2 => {
                        band_rows(ctx, band, out, |ctx, band, row, out, lo, own| unsafe {
                            x86::$avx2(ctx, band, row, out, lo, own)
                        })
                    }
                    _ => band_rows(ctx, band, out, row_portable::<$t>),
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
            fn stretch_sweep(
                simd: SimdLevel,
                out: &mut Out<Self>,
                base: usize,
                inv_mass: &[Self],
                alive: Option<&[Self]>,
                lines: &SweepLines<Self>,
            ) {
                fn at<const LO: bool>(
                    simd: SimdLevel,
                    out: &mut Out<$t>,
                    base: usize,
                    inv_mass: &[$t],
                    alive: Option<&[$t]>,
                    lines: &SweepLines<$t>,
                ) {
                    match simd {
                        #[cfg(target_arch = "x86_64")]
                        // SAFETY: as above.
                        SimdLevel::Avx512 => unsafe {
                            x86::$stretch512::<LO>(out, base, inv_mass, alive, lines)
                        },
                        #[cfg(target_arch = "x86_64")]
                        // SAFETY: as above.
                        SimdLevel::Avx2 => unsafe {
                            x86::$stretch2::<LO>(out, base, inv_mass, alive, lines)
                        },
                        _ => {
                            let portable = Portable::<$t>::default();
                            stretch_limit_sweep::<_, LO>(
                                portable, out, base, inv_mass, alive, lines,
                            )
                        }
                    }
                }
                // Positions with low parts (`compensated`) or without.
                if lines.sweep.compensated() {
                    at::<true>(simd, out, base, inv_mass, alive, lines)
                } else {
                    at::<false>(simd, out, base, inv_mass, alive, lines)
                }
            }
        }
    };
}

// Float32: the intrinsics of `x86`. Float64: the portable lanes compiled for each
// level's features.
real!(f32, bits: u32, eps2: EPS2, tiny: TINY, avx512: row_avx512, avx2: row_avx2,
      lattice: lattice_band_avx512, lattice_band_avx2,
      stretch: stretch_limit_sweep_avx512, stretch_limit_sweep_avx2);
real!(f64, bits: u64, eps2: 1e-24, tiny: 1e-30, avx512: row_avx512_f64, avx2: row_avx2_f64,
      lattice: lattice_band_avx512_f64, lattice_band_avx2_f64,
      stretch: stretch_limit_sweep_avx512_f64, stretch_limit_sweep_avx2_f64);

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
    /// `ρ C_d / 12`: a third of the drag force with `A = |m| / 2`.
    drag: E,
    dt: E,
    /// `-c` of the air damping `-c v`.
    neg_air: E,
    /// Ground height, penalty stiffness and damping (height `f32::MIN`: no ground).
    ground: [E; 3],
    /// 1 for explicit Euler (positions move with the old velocity), else 0.
    explicit: E,
    /// `h/2` for position Verlet's velocity estimate `u + h/2 a`, else 0.
    verlet_half_dt: E,
    /// Whether the velocity of the last position update `u` is its own array (Verlet).
    verlet: bool,
    /// Whether positions have low parts ([`Precision::Mixed`]).
    compensated: bool,
    /// Sphere centre, radius and squared radius, projected onto inside the fused step.
    sphere: Option<([E; 3], E, E)>,
}

impl<E: Real> Params<E> {
    /// Symplectic Euler with no air damping, ground or sphere in the step.
    fn is_plain(&self) -> bool {
        !self.verlet
            && self.explicit == E::ZERO
            && self.neg_air == E::ZERO
            && self.ground[0] == E::LOWEST
            && self.sphere.is_none()
    }

    /// The constants of `spec` (the step `dt` is set by each run).
    fn of(spec: &GridSpec) -> Self {
        let hs = spec.spacing;
        // XPBD's springs are constraints (`constrain`), not forces: the fused pass
        // predicts with every other force.
        let xpbd = spec.integrator == Integrator::Xpbd;
        let frictional = constraints::Contact {
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
        Params {
            ks: kinds.map(|(kind, _)| E::of(kind.k)),
            kls: kinds.map(|(kind, rest)| E::of(kind.k * rest)),
            bs: kinds.map(|(kind, _)| E::of(kind.b)),
            gravity: spec.gravity.map(E::of),
            wind: spec.wind.map(E::of),
            drag: E::of(spec.air_density * spec.drag_coefficient / 12.0),
            dt: E::ZERO,
            neg_air: E::of(-spec.air_damping),
            ground: spec.ground.map_or([E::LOWEST, E::ZERO, E::ZERO], |g| {
                [g.height, g.stiffness, g.damping].map(E::of)
            }),
            explicit: if spec.integrator == Integrator::ExplicitEuler {
                E::ONE
            } else {
                E::ZERO
            },
            verlet_half_dt: E::ZERO,
            verlet: spec.integrator == Integrator::Verlet,
            compensated: spec.precision == Precision::Mixed,
            // With a stretch limit or XPBD the sphere comes after them, in the
            // constraint pass, and so with friction (the sphere's or the ground's:
            // the pass resolves both, in the f64 engine's order).
            sphere: spec
                .sphere
                .filter(|_| spec.stretch_limit.is_none() && !xpbd && !frictional)
                .map(|s| {
                    let r = E::of(s.radius);
                    (s.center.to_array().map(E::of), r, r * r)
                }),
        }
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
}

impl<E: Real> Band<E> {
    fn new(r0: usize, r1: usize, grid: &Grid) -> Self {
        Band {
            r0,
            r1,
            acc: Buf::zeros(SLOTS * 3 * grid.nv),
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

/// Cloth state in padded f32 structure-of-arrays form. A position is the unevaluated
/// sum `x + xl` of two floats (a "double-float"), so that `x += h v` loses nothing
/// to round-off (see the module doc, "Precision").
#[derive(Clone, Debug)]
struct State<E> {
    x: [Buf<E>; 3],
    /// Low parts of the positions.
    xl: [Buf<E>; 3],
    v: [Buf<E>; 3],
    /// Position Verlet's velocity of the last position update, `(x - x_prev) / h`
    /// (empty for the Euler methods, whose positions move with `v`).
    u: [Buf<E>; 3],
}

impl<E: Real> State<E> {
    /// Every array, whole (ghost rows included), as [`Out`] rows from row 0.
    fn rows(&mut self) -> Out<'_, E> {
        let State { x, xl, v, u } = self;
        let [[x0, x1, x2], [l0, l1, l2], [v0, v1, v2], [u0, u1, u2]] =
            [x, xl, v, u].map(|a| a.each_mut().map(Buf::as_mut_slice));
        Out([x0, x1, x2, l0, l1, l2, v0, v1, v2, u0, u1, u2])
    }
}

/// Output rows of a band (or of several consecutive bands): `x`, `y`, `z`, their
/// low parts, `vx`, `vy`, `vz`, and (Verlet only, else empty) `ux`, `uy`, `uz`, each
/// starting at the band's first row.
struct Out<'a, E>([&'a mut [E]; 12]);

impl<'a, E> Out<'a, E> {
    fn split_at(self, at: usize) -> (Out<'a, E>, Out<'a, E>) {
        let mut lo: [&'a mut [E]; 12] = Default::default();
        let mut hi: [&'a mut [E]; 12] = Default::default();
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
    /// XPBD's and self-collision's scratch (empty without them).
    f64_copies_scratch: F64Copies,
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

/// Which kind of spring each stencil direction holds, as an index into
/// [`GridSpec::present`]: right, two right, down-left, down, down-right, two down.
const DIRECTION_KIND: [usize; 6] = [0, 2, 1, 0, 1, 2];

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
                    if present[DIRECTION_KIND[d]] && r + dr < h && (0..w as isize).contains(&cc) {
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

/// XPBD's and self-collision's f64 copies, per particle in cloth order (`p = row *
/// width + column`): positions as the constraint pass moves them, before it, at the
/// start of the step, and inverse masses.
#[derive(Clone, Debug, Default)]
struct F64Copies {
    moved: Vec<DVec3>,
    /// The positions before the pass.
    before: Vec<DVec3>,
    start: Vec<DVec3>,
    inv_mass: Vec<f64>,
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
            xl: std::array::from_fn(|_| Buf::zeros(grid.len())),
            v: std::array::from_fn(|_| Buf::zeros(grid.len())),
            u: std::array::from_fn(|_| Buf::zeros(if verlet { grid.len() } else { 0 })),
        };
        for p in 0..grid.w * grid.h {
            let (r, c) = (p / grid.w, p % grid.w);
            let i = grid.index(p);
            let start = [
                spec.origin[0] + c as f64 * spec.spacing,
                spec.origin[1] - r as f64 * spec.spacing,
                spec.origin[2],
            ];
            for (a, q) in start.into_iter().enumerate() {
                let hi = E::of(q);
                cur.x[a].as_mut_slice()[i] = hi;
                if spec.precision == Precision::Mixed {
                    cur.xl[a].as_mut_slice()[i] = E::of(q - hi.f64());
                }
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
        let params = Params::of(&spec);
        let drag_on = params.drag != E::ZERO;
        Kernel {
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
            f64_copies_scratch: F64Copies::default(),
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
        let dt = (self.params.dt, self.params.verlet_half_dt);
        self.params = Params::of(&spec);
        (self.params.dt, self.params.verlet_half_dt) = dt;
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

    /// Force a SIMD level (for tests and benches). A level this CPU lacks is
    /// ignored.
    pub fn set_simd_level(&mut self, level: SimdLevel) {
        let best = SimdLevel::detect();
        let ok = match level {
            SimdLevel::Baseline => true,
            SimdLevel::Avx2 => best != SimdLevel::Baseline,
            SimdLevel::Avx512 => best == SimdLevel::Avx512,
        };
        if ok {
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
        // second band (and the stretch limit's second half) is handed over by
        // spinning (`Duo`).
        let spin = parallel
            && self.par_bands.len() == 2
            && self.len() >= SPIN_MIN_PARTICLES
            && !self.has_pooled_constraints();
        let run = |duo: Option<&Duo>| {
            for i in 0..n {
                if let Some((t0, wind)) = wind {
                    self.set_wind(wind.at(t0 + i as f64 * dt));
                }
                self.one_step(parallel, duo);
                self.constrain(dt, parallel, duo);
            }
        };
        run_in_pool(pool.as_ref(), spin, run);
        self.pool = pool;
    }

    /// Whether a pass after the step splits its work with rayon's parallel
    /// iterators (XPBD's springs, self-collision, tearing), which need the pool's
    /// other thread free.
    fn has_pooled_constraints(&self) -> bool {
        self.spec.integrator == Integrator::Xpbd
            || self.spec.self_collision.is_some()
            || self.spec.tear_strain.is_some()
    }

    fn one_step(&mut self, parallel: bool, duo: Option<&Duo>) {
        let ctx = Ctx {
            grid: self.grid,
            p: self.params,
            x: self.cur.x.each_ref().map(Buf::as_slice),
            xl: self.cur.xl.each_ref().map(Buf::as_slice),
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
        };
        let real = self.grid.h * self.grid.stride;
        fn rows<E: Real>(arrays: &mut [Buf<E>; 3], real: usize) -> [&mut [E]; 3] {
            arrays.each_mut().map(|b| {
                let a = b.as_mut_slice();
                let len = real.min(a.len());
                &mut a[..len]
            })
        }
        let State { x, xl, v, u } = &mut self.next;
        let ([x0, x1, x2], [l0, l1, l2]) = (rows(x, real), rows(xl, real));
        let ([v0, v1, v2], [u0, u1, u2]) = (rows(v, real), rows(u, real));
        let out = Out([x0, x1, x2, l0, l1, l2, v0, v1, v2, u0, u1, u2]);
        if let Some(duo) = duo {
            run_two_bands(&ctx, &mut self.par_bands, out, duo);
        } else if parallel && self.par_bands.len() > 1 {
            run_bands(&ctx, &mut self.par_bands, out, true);
        } else {
            run_bands(&ctx, &mut self.seq_band, out, false);
        }
        std::mem::swap(&mut self.cur, &mut self.next);
    }

    /// The constraints the fused row pass leaves to after the step: XPBD's springs,
    /// Provot's stretch limit, then the colliders' contact with friction, as in the
    /// f64 engine. A move `δ` of a particle also adds `δ / h` to its velocity.
    /// With `duo`, the pool's other thread is serving it: the stretch limit hands
    /// it its second half, and the passes that would split their work with rayon
    /// run on this thread ([`Kernel::has_pooled_constraints`] keeps them out of
    /// that mode).
    fn constrain(&mut self, dt: f64, parallel: bool, duo: Option<&Duo>) {
        let parallel_pooled = parallel && duo.is_none();
        let xpbd = self.spec.integrator == Integrator::Xpbd;
        if xpbd {
            self.xpbd_pass(dt, parallel_pooled);
        }
        if let Some(tau) = self.spec.stretch_limit {
            self.stretch_limit_pass(tau, dt, parallel, duo);
        }
        let parallel = parallel_pooled;
        if let Some(thickness) = self.spec.self_collision {
            self.self_collision_pass(thickness, dt, parallel);
        }
        let contact = constraints::Contact {
            sphere: self.spec.sphere,
            ground: self.spec.ground,
            friction: self.spec.friction,
            dt,
        };
        // Without friction, stretch limit or XPBD the step itself projected the
        // particles out of the sphere.
        if contact.is_active() && self.params.sphere.is_none() {
            self.resolve_contact(&contact, parallel, duo);
        }
        if let Some(max_speed) = self.spec.max_speed {
            self.limit_speed(max_speed);
        }
        if let Some(tau) = self.spec.tear_strain {
            self.tear_pass(tau, parallel);
        }
    }

    /// The speed limit, as the f64 engine applies it ([`constraints::speed_limit`]):
    /// a cheap check in the kernel's precision, then the particle's velocity (and
    /// Verlet's update velocity) scaled in f64.
    fn limit_speed(&mut self, max_speed: f64) {
        let limit2 = E::of(max_speed * max_speed);
        let verlet = self.params.verlet;
        for p in 0..self.grid.w * self.grid.h {
            let i = self.grid.index(p);
            let [vx, vy, vz] = self.cur.v.each_ref().map(|a| a.as_slice()[i]);
            if vx * vx + vy * vy + vz * vz <= limit2 {
                continue;
            }
            let v = DVec3::new(vx.f64(), vy.f64(), vz.f64());
            let factor = constraints::speed_limit(v, max_speed);
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
    /// when `parallel`) finds the rows that may hold one, with a margin; there
    /// [`super::tearing::overstretched`] decides in f64, as in the f64 engine, in
    /// a fixed order, so the breaks do not depend on the threads.
    fn tear_pass(&mut self, tau: f64, parallel: bool) {
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        // Per direction: first column, columns, rows, rest length, scan bound.
        let lines = self.stencil().map(|((dr, dc), rest, present, _)| {
            let c0 = (-dc).max(0) as usize;
            let len = w.saturating_sub(dc.max(0) as usize).saturating_sub(c0);
            let longest = (1.0 + tau) * rest;
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
                *flag = row_may_tear_dispatch(simd, cur, (a, b, len), alive, scan2);
            };
            if parallel && w * h >= PARALLEL_MIN_PARTICLES {
                use rayon::prelude::*;
                flags
                    .par_iter_mut()
                    .enumerate()
                    .for_each(|(k, f)| scan(k, f));
            } else {
                flags.iter_mut().enumerate().for_each(|(k, f)| scan(k, f));
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

    /// The stencil in the order the springs sort (the f64 engine's order): (row,
    /// column) offsets, rest lengths, whether the kind exists, and its coefficients.
    fn stencil(&self) -> [Stencil; 6] {
        let spacing = self.spec.spacing;
        let [structural, shear, bend] = self.spec.present;
        let (sk, hk, bk) = (self.spec.structural, self.spec.shear, self.spec.bend);
        let diagonal = std::f64::consts::SQRT_2 * spacing;
        let [right, two_right, down_left, down, down_right, two_down] = STENCIL_DIRECTIONS;
        [
            (right, spacing, structural, sk),
            (two_right, 2.0 * spacing, bend, bk),
            (down_left, diagonal, shear, hk),
            (down, spacing, structural, sk),
            (down_right, diagonal, shear, hk),
            (two_down, 2.0 * spacing, bend, bk),
        ]
    }

    /// XPBD's springs: one Gauss-Seidel pass over the colour classes of
    /// [`super::springs::constraint_order`] (by stencil direction, then by the parity of
    /// the spring's step along it), each spring corrected by
    /// [`constraints::xpbd_correction`] against the positions at the start of the
    /// step (the other state buffer, after the swap). No two springs of a class
    /// share a particle, so a class splits into blocks of rows that no spring
    /// crosses, corrected on the pool's threads (`parallel`) with the same result
    /// as one at a time: the f64 engine's, which visits the same classes in order.
    ///
    /// The pass runs on f64 copies of the positions and writes each moved particle
    /// back once, with its move over `dt` added to its velocity.
    fn xpbd_pass(&mut self, dt: f64, parallel: bool) {
        let (w, h) = (self.grid.w, self.grid.h);
        let n = w * h;
        let mut s = self.f64_copies();
        let bits = self.torn.as_ref().map(|t| t.bits.as_slice());
        for (d, ((dr, dc), rest, present, kind)) in self.stencil().into_iter().enumerate() {
            if !present || kind.k <= 0.0 {
                continue;
            }
            let class = XpbdClass {
                width: w,
                dr,
                dc,
                spring: (rest, kind.k, kind.b),
                dt,
                left: bits.map(|bits| (bits, 1 << d)),
            };
            for colour in 0..2 {
                // Springs along rows stay in their row; the others' rows alternate
                // in runs of `dr`, so a block of `2 dr` rows from the colour's first
                // holds whole springs of the class.
                let (first_row, block_rows) = if dr == 0 {
                    (0, 1)
                } else {
                    (colour * dr, 2 * dr)
                };
                let from = (first_row * w).min(n);
                let size = block_rows * w;
                let correct = |k: usize, ((x, x0), m)| {
                    class.correct_block(x, x0, m, from + k * size, colour);
                };
                if parallel && n >= PARALLEL_MIN_PARTICLES {
                    use rayon::prelude::*;
                    let blocks = s.moved[from..]
                        .par_chunks_mut(size)
                        .zip(s.start[from..].par_chunks(size))
                        .zip(s.inv_mass[from..].par_chunks(size));
                    blocks.enumerate().for_each(|(k, block)| correct(k, block));
                } else {
                    let blocks = s.moved[from..]
                        .chunks_mut(size)
                        .zip(s.start[from..].chunks(size))
                        .zip(s.inv_mass[from..].chunks(size));
                    blocks.enumerate().for_each(|(k, block)| correct(k, block));
                }
            }
        }
        self.write_back(s, dt);
    }

    /// f64 copies of the positions, those at the start of the step and the inverse
    /// masses, in cloth order (the scratch taken out of `self`; see
    /// [`Self::write_back`]).
    fn f64_copies(&mut self) -> F64Copies {
        let (w, h, st) = (self.grid.w, self.grid.h, self.grid.stride);
        let mut s = std::mem::take(&mut self.f64_copies_scratch);
        s.moved.resize(w * h, DVec3::ZERO);
        s.start.resize(w * h, DVec3::ZERO);
        s.inv_mass.resize(w * h, 0.0);
        // Row by row, each array's row read as a slice.
        fn rows<E: Real>(
            out: &mut [DVec3],
            hi: &[Buf<E>; 3],
            lo: &[Buf<E>; 3],
            w: usize,
            st: usize,
        ) {
            for (r, out) in out.chunks_exact_mut(w).enumerate() {
                row_to_f64(out, hi, lo, r * st);
            }
        }
        rows(&mut s.moved, &self.cur.x, &self.cur.xl, w, st);
        rows(&mut s.start, &self.next.x, &self.next.xl, w, st);
        for (r, out) in s.inv_mass.chunks_exact_mut(w).enumerate() {
            let row = &self.inv_mass.as_slice()[r * st..r * st + w];
            out.iter_mut().zip(row).for_each(|(m, &e)| *m = e.f64());
        }
        s.before.clone_from(&s.moved);
        s
    }

    /// Moves each particle the pass moved to its copy's position (adding the move
    /// over `dt` to its velocity) and puts the scratch back.
    fn write_back(&mut self, s: F64Copies, dt: f64) {
        let (w, st) = (self.grid.w, self.grid.stride);
        for (p, (&to, &from)) in s.moved.iter().zip(&s.before).enumerate() {
            if to != from {
                self.move_particle((p / w) * st + p % w, to, dt);
            }
        }
        self.f64_copies_scratch = s;
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
        let mut x = std::mem::take(&mut self.f64_copies_scratch.moved);
        x.resize(n, DVec3::ZERO);
        let (hi, lo) = (&self.cur.x, &self.cur.xl);
        // Blocks of 8 rows, each row's arrays read as slices.
        let copy = |(k, out): (usize, &mut [DVec3])| {
            for (r, out) in out.chunks_exact_mut(width).enumerate() {
                row_to_f64(out, hi, lo, (8 * k + r) * st);
            }
        };
        if parallel {
            use rayon::prelude::*;
            x.par_chunks_mut(8 * width).enumerate().for_each(copy);
        } else {
            x.chunks_mut(8 * width).enumerate().for_each(copy);
        }

        // The stencil's directions whose kind of spring exists, and the springs
        // left when some tore.
        let springs = self
            .stencil()
            .map(|(direction, _, present, _)| (direction, present));
        let torn = self.torn.as_ref();
        let joined = |i: usize, j: usize| {
            let (a, b) = (i.min(j), i.max(j));
            let (dr, dc) = (
                b / width - a / width,
                (b % width) as isize - (a % width) as isize,
            );
            springs
                .iter()
                .position(|&s| s == ((dr, dc), true))
                .is_some_and(|d| torn.is_none_or(|t| t.has(a, d)))
        };
        // Each particle's position at the start of the step (the other state
        // buffer, after the swap) and inverse mass.
        let (start, start_lo, inv_mass) = (&self.next.x, &self.next.xl, &self.inv_mass);
        let particle = |i: usize| {
            let g = (i / width) * st + i % width;
            let start = DVec3::from_array(std::array::from_fn(|a| {
                start[a].as_slice()[g].f64() + start_lo[a].as_slice()[g].f64()
            }));
            (start, inv_mass.as_slice()[g].f64())
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
        self.f64_copies_scratch.moved = x;
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
        runaway_scan(x, self.cur.v.each_ref().map(Buf::as_slice), center)
    }

    fn read_into(&self, arrays: &[Buf<E>; 3], out: &mut [DVec3]) {
        let [x, y, z] = arrays.each_ref().map(Buf::as_slice);
        for (p, o) in out.iter_mut().enumerate().take(self.len()) {
            let i = self.grid.index(p);
            *o = DVec3::new(x[i].f64(), y[i].f64(), z[i].f64());
        }
    }

    /// Position of array index `i` in f64 (high plus low part).
    fn position_at(&self, i: usize) -> DVec3 {
        let (x, xl) = (&self.cur.x, &self.cur.xl);
        DVec3::from_array(std::array::from_fn(|a| {
            x[a].as_slice()[i].f64() + xl[a].as_slice()[i].f64()
        }))
    }

    /// Sets the position of array index `i` from f64, split into high and low parts.
    fn set_position_at(&mut self, i: usize, q: DVec3) {
        for a in 0..3 {
            let (hi, lo) = position_parts(q[a], self.params.compensated);
            self.cur.x[a].as_mut_slice()[i] = hi;
            self.cur.xl[a].as_mut_slice()[i] = lo;
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
        self.cur
            .x
            .each_ref()
            .map(|b| b.as_slice().iter().map(|x| x.f64()).collect())
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
mod contact;
pub mod lattice;
mod stretch_limit;

use contact::{ContactRows, Reach};
use stretch_limit::{SweepLines, largest_magnitude_bits, stretch_limit_sweep};

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
        /// The padded arrays of the positions' high parts `[x, y, z]` in m, copied
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

/// Read-only inputs of a step.
struct Ctx<'a, E> {
    grid: Grid,
    p: Params<E>,
    x: [&'a [E]; 3],
    xl: [&'a [E]; 3],
    v: [&'a [E]; 3],
    /// Verlet's update velocities (empty for the Euler methods).
    u: [&'a [E]; 3],
    inv_mass: &'a [E],
    col_mask: &'a [E],
    /// With springs missing, the masks of the springs a block evaluates and of its
    /// triangles (see [`block`]).
    torn: Option<[&'a [E]; 8]>,
    drag: bool,
    simd: SimdLevel,
}

/// Run the bands, splitting the output rows among them; in parallel with
/// `rayon::join` (inside the caller's pool) when `parallel`.
fn run_bands<E: Real>(ctx: &Ctx<E>, bands: &mut [Band<E>], out: Out<E>, parallel: bool) {
    if bands.len() == 1 {
        E::band_dispatch(ctx, &mut bands[0], out);
        return;
    }
    let mid = bands.len() / 2;
    let at = (bands[mid].r0 - bands[0].r0) * ctx.grid.stride;
    let (lo, hi) = bands.split_at_mut(mid);
    let (out_lo, out_hi) = out.split_at(at);
    if parallel {
        rayon::join(
            || run_bands(ctx, lo, out_lo, true),
            || run_bands(ctx, hi, out_hi, true),
        );
    } else {
        run_bands(ctx, lo, out_lo, false);
        run_bands(ctx, hi, out_hi, false);
    }
}

/// The two bands of `bands`, the second handed to the thread serving `duo`.
fn run_two_bands<E: Real>(ctx: &Ctx<E>, bands: &mut [Band<E>], out: Out<E>, duo: &Duo) {
    let at = (bands[1].r0 - bands[0].r0) * ctx.grid.stride;
    let (first, second) = bands.split_at_mut(1);
    let (out_first, out_second) = out.split_at(at);
    duo.fork_once(
        || E::band_dispatch(ctx, &mut second[0], out_second),
        || E::band_dispatch(ctx, &mut first[0], out_first),
    );
}

/// One row with the portable lanes.
#[inline(never)]
fn row_portable<E: Real>(
    ctx: &Ctx<E>,
    band: &mut Band<E>,
    row: usize,
    out: &mut Out<E>,
    lo: usize,
    own: bool,
) {
    row_variant(Portable::<E>::default(), ctx, band, row, out, lo, own);
}

/// [`row_step`] for the scene's drag setting, integrating the row if `own`.
#[inline(always)]
fn row_variant<S: Simd>(
    s: S,
    ctx: &Ctx<S::E>,
    band: &mut Band<S::E>,
    row: usize,
    out: &mut Out<S::E>,
    lo: usize,
    own: bool,
) {
    if ctx.p.compensated {
        row_modes::<S, true>(s, ctx, band, row, out, lo, own);
    } else {
        row_modes::<S, false>(s, ctx, band, row, out, lo, own);
    }
}

/// [`row_variant`] with (`LO`) or without the positions' low parts.
#[inline(always)]
fn row_modes<S: Simd, const LO: bool>(
    s: S,
    ctx: &Ctx<S::E>,
    band: &mut Band<S::E>,
    row: usize,
    out: &mut Out<S::E>,
    lo: usize,
    own: bool,
) {
    // A plain cloth (symplectic Euler, no air damping, ground or sphere) gets a
    // version of the step without them.
    let plain = ctx.p.is_plain();
    match (ctx.drag, own, plain) {
        (true, true, true) => row_step::<S, true, true, true, LO>(s, ctx, band, row, out, lo),
        (true, true, false) => row_step::<S, true, true, false, LO>(s, ctx, band, row, out, lo),
        (false, true, true) => row_step::<S, false, true, true, LO>(s, ctx, band, row, out, lo),
        (false, true, false) => row_step::<S, false, true, false, LO>(s, ctx, band, row, out, lo),
        (true, false, _) => row_step::<S, true, false, true, LO>(s, ctx, band, row, out, lo),
        (false, false, _) => row_step::<S, false, false, true, LO>(s, ctx, band, row, out, lo),
    }
}

/// The rows of one band: prime the accumulator ring with the two rows above the
/// band, then compute and integrate the band's rows one by one. Each row is one
/// call of `row`, compiled for the chosen SIMD level.
fn band_rows<E: Real>(
    ctx: &Ctx<E>,
    band: &mut Band<E>,
    mut out: Out<E>,
    row: impl Fn(&Ctx<E>, &mut Band<E>, usize, &mut Out<E>, usize, bool),
) {
    // Rows 0 and 1 get nothing from rows above the cloth.
    if band.r0 < 2 {
        band.acc.as_mut_slice().fill(E::ZERO);
    }
    for r in band.r0.saturating_sub(2)..band.r0 {
        row(ctx, band, r, &mut out, 0, false);
    }
    let st = ctx.grid.stride;
    for r in band.r0..band.r1 {
        row(ctx, band, r, &mut out, (r - band.r0) * st, true);
    }
}

/// The few vector operations the kernel needs. Implemented by zero-sized tokens that
/// exist only where the CPU supports the instructions.
trait Simd: Copy {
    /// The float type of a lane.
    type E: Real;
    /// A vector of `LANES` floats.
    type V: Copy;
    const LANES: usize;
    fn splat(self, a: Self::E) -> Self::V;
    /// # Safety
    /// `p .. p + LANES` must be readable.
    unsafe fn load(self, p: *const Self::E) -> Self::V;
    /// # Safety
    /// `p .. p + LANES` must be writable.
    unsafe fn store(self, p: *mut Self::E, v: Self::V);
    fn add(self, a: Self::V, b: Self::V) -> Self::V;
    fn sub(self, a: Self::V, b: Self::V) -> Self::V;
    fn mul(self, a: Self::V, b: Self::V) -> Self::V;
    /// `a * b + c` (fused where the ISA has FMA).
    fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    /// `a * b - c` (fused where the ISA has FMA).
    fn mul_sub(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V;
    /// `1 / sqrt(x)` where `x > eps`, else 0.
    fn rsqrt_or_zero(self, x: Self::V, eps: Self::E) -> Self::V;
    /// `a` where `m > 0`, else 0.
    fn keep_if_positive(self, m: Self::V, a: Self::V) -> Self::V;
    /// `a / b`.
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// Whether any lane of `m` is positive.
    fn any_positive(self, m: Self::V) -> bool;
    /// Lanes moved up by one: `[prev[LANES-1], cur[0], .., cur[LANES-2]]`.
    fn shift1(self, prev: Self::V, cur: Self::V) -> Self::V;
    /// Lanes moved up by two: `[prev[LANES-2], prev[LANES-1], cur[0], ..]`.
    fn shift2(self, prev: Self::V, cur: Self::V) -> Self::V;
}

/// Portable lanes: plain arrays, vectorised by the compiler for the build target
/// (or for the target features of the function they are inlined into).
#[derive(Clone, Copy, Default)]
struct Portable<E>(std::marker::PhantomData<E>);

/// Lanes of the portable path.
const PL: usize = 8;

impl<E: Real> Simd for Portable<E> {
    type E = E;
    type V = [E; PL];
    const LANES: usize = PL;
    #[inline(always)]
    fn splat(self, a: E) -> Self::V {
        [a; PL]
    }
    #[inline(always)]
    unsafe fn load(self, p: *const E) -> Self::V {
        // SAFETY: the caller guarantees PL readable floats.
        unsafe { p.cast::<[E; PL]>().read_unaligned() }
    }
    #[inline(always)]
    unsafe fn store(self, p: *mut E, v: Self::V) {
        // SAFETY: the caller guarantees PL writable floats.
        unsafe { p.cast::<[E; PL]>().write_unaligned(v) }
    }
    #[inline(always)]
    fn add(self, a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i] + b[i])
    }
    #[inline(always)]
    fn sub(self, a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i] - b[i])
    }
    #[inline(always)]
    fn mul(self, a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i] * b[i])
    }
    #[inline(always)]
    fn mul_add(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i].mul_add(b[i], c[i]))
    }
    #[inline(always)]
    fn mul_sub(self, a: Self::V, b: Self::V, c: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i].mul_add(b[i], E::ZERO - c[i]))
    }
    #[inline(always)]
    fn rsqrt_or_zero(self, x: Self::V, eps: E) -> Self::V {
        std::array::from_fn(|i| {
            if x[i] > eps {
                E::ONE / x[i].sqrt()
            } else {
                E::ZERO
            }
        })
    }
    #[inline(always)]
    fn keep_if_positive(self, m: Self::V, a: Self::V) -> Self::V {
        std::array::from_fn(|i| if m[i] > E::ZERO { a[i] } else { E::ZERO })
    }
    #[inline(always)]
    fn div(self, a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i] / b[i])
    }
    #[inline(always)]
    fn any_positive(self, m: Self::V) -> bool {
        m.iter().fold(false, |any, &m| any | (m > E::ZERO))
    }
    #[inline(always)]
    fn shift1(self, prev: Self::V, cur: Self::V) -> Self::V {
        std::array::from_fn(|i| if i >= 1 { cur[i - 1] } else { prev[PL - 1] })
    }
    #[inline(always)]
    fn shift2(self, prev: Self::V, cur: Self::V) -> Self::V {
        std::array::from_fn(|i| if i >= 2 { cur[i - 2] } else { prev[PL - 2 + i] })
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! AVX2 and AVX-512 versions of [`Simd`], and the entry points compiled for them.
    use std::arch::x86_64::*;

    use super::{
        Band, ContactRows, Ctx, Out, Portable, Real, Simd, State, SweepLines,
        largest_magnitude_bits, lattice, row_may_tear, row_variant, stretch_limit_sweep,
    };

    /// Token for AVX2 + FMA; only built inside `band_avx2`.
    #[derive(Clone, Copy)]
    pub(super) struct Avx2(());

    /// Token for AVX-512F/VL + FMA; only built inside `band_avx512`.
    #[derive(Clone, Copy)]
    pub(super) struct Avx512(());

    /// One row with AVX-512 (see `row_step`).
    ///
    /// # Safety
    /// The CPU must have AVX-512F, AVX-512VL, AVX2 and FMA.
    #[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
    #[inline(never)]
    pub(super) unsafe fn row_avx512(
        ctx: &Ctx<f32>,
        band: &mut Band<f32>,
        row: usize,
        out: &mut Out<f32>,
        lo: usize,
        own: bool,
    ) {
        row_variant(Avx512(()), ctx, band, row, out, lo, own);
    }

    /// One band of a lattice (see `lattice::band_steps`) compiled for a SIMD level,
    /// in each precision: `name: target features, float type, lanes`.
    macro_rules! lattice_bands {
        ($($name:ident: $features:literal, $t:ty, $lanes:expr;)*) => {$(
            /// `lattice::band_modes` with these lanes and target features.
            ///
            /// # Safety
            /// The CPU must have the target features.
            #[target_feature(enable = $features)]
            #[inline(never)]
            pub(super) unsafe fn $name(
                ctx: &lattice::Ctx<$t>,
                band: &mut lattice::Band<$t>,
                out: Out<$t>,
            ) {
                lattice::band_modes($lanes, ctx, band, out);
            }
        )*};
    }
    lattice_bands! {
        lattice_band_avx512: "avx512f,avx512vl,avx2,fma", f32, Avx512(());
        lattice_band_avx2: "avx2,fma", f32, Avx2(());
        lattice_band_avx512_f64: "avx512f,avx512vl,avx2,fma", f64, Portable::<f64>::default();
        lattice_band_avx2_f64: "avx2,fma", f64, Portable::<f64>::default();
    }

    /// The tear scan's `row_may_tear`, compiled for AVX2 and FMA.
    ///
    /// # Safety
    /// As for `row_avx2`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn row_may_tear_avx2<E: Real>(
        state: &State<E>,
        ends: (usize, usize, usize),
        alive: Option<&[E]>,
        scan2: E,
    ) -> bool {
        row_may_tear(state, ends, alive, scan2)
    }

    /// `largest_magnitude_bits`, compiled for AVX2.
    ///
    /// # Safety
    /// As for `row_avx2`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn largest_magnitude_bits_avx2(bits: &[u32]) -> u32 {
        largest_magnitude_bits(bits)
    }

    /// Contact with friction (`ContactRows::resolve`), compiled for AVX2 and FMA.
    ///
    /// # Safety
    /// As for `row_avx2`.
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    pub(super) unsafe fn contact_rows_avx2<E: Real>(
        ctx: &ContactRows<E>,
        out: &mut Out<E>,
        first: usize,
        rows: std::ops::Range<usize>,
    ) {
        ctx.resolve_rows(out, first, rows)
    }

    /// Contact with friction (`ContactRows::resolve`), compiled for AVX-512.
    ///
    /// # Safety
    /// As for `row_avx512`.
    #[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
    #[inline(never)]
    pub(super) unsafe fn contact_rows_avx512<E: Real>(
        ctx: &ContactRows<E>,
        out: &mut Out<E>,
        first: usize,
        rows: std::ops::Range<usize>,
    ) {
        ctx.resolve_rows(out, first, rows)
    }

    /// The stretch limit's `stretch_limit_sweep` compiled for a SIMD level, in each
    /// precision: `name: target features, float type, lanes`.
    macro_rules! stretch_limit_sweeps {
        ($($name:ident: $features:literal, $t:ty, $lanes:expr;)*) => {$(
            /// `stretch_limit_sweep` with these lanes and target features.
            ///
            /// # Safety
            /// The CPU must have the target features.
            #[target_feature(enable = $features)]
            #[inline(never)]
            pub(super) unsafe fn $name<const LO: bool>(
                out: &mut Out<$t>,
                base: usize,
                inv_mass: &[$t],
                alive: Option<&[$t]>,
                lines: &SweepLines<$t>,
            ) {
                stretch_limit_sweep::<_, LO>($lanes, out, base, inv_mass, alive, lines)
            }
        )*};
    }
    stretch_limit_sweeps! {
        stretch_limit_sweep_avx2: "avx2,fma", f32, Avx2(());
        stretch_limit_sweep_avx2_f64: "avx2,fma", f64, Portable::<f64>::default();
        stretch_limit_sweep_avx512: "avx512f,avx512vl,avx2,fma", f32, Avx512(());
        stretch_limit_sweep_avx512_f64: "avx512f,avx512vl,avx2,fma", f64, Portable::<f64>::default();
    }

    /// One row in float64 with the portable lanes, compiled for the same features
    /// (see `row_step`).
    ///
    /// # Safety
    /// As for `row_avx512`.
    #[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
    #[inline(never)]
    pub(super) unsafe fn row_avx512_f64(
        ctx: &Ctx<f64>,
        band: &mut Band<f64>,
        row: usize,
        out: &mut Out<f64>,
        lo: usize,
        own: bool,
    ) {
        row_variant(Portable::<f64>::default(), ctx, band, row, out, lo, own);
    }

    /// One row with AVX2 (see `row_step`).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    pub(super) unsafe fn row_avx2(
        ctx: &Ctx<f32>,
        band: &mut Band<f32>,
        row: usize,
        out: &mut Out<f32>,
        lo: usize,
        own: bool,
    ) {
        row_variant(Avx2(()), ctx, band, row, out, lo, own);
    }

    /// One row in float64 with the portable lanes, compiled for the same features
    /// (see `row_step`).
    ///
    /// # Safety
    /// As for `row_avx2`.
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    pub(super) unsafe fn row_avx2_f64(
        ctx: &Ctx<f64>,
        band: &mut Band<f64>,
        row: usize,
        out: &mut Out<f64>,
        lo: usize,
        own: bool,
    ) {
        row_variant(Portable::<f64>::default(), ctx, band, row, out, lo, own);
    }

    // SAFETY (all intrinsics below): an `Avx512` / `Avx2` value exists only inside
    // the entry points above, which run only on CPUs with those features.
    impl Simd for Avx512 {
        type E = f32;
        type V = __m512;
        const LANES: usize = 16;
        #[inline(always)]
        fn splat(self, a: f32) -> __m512 {
            unsafe { _mm512_set1_ps(a) }
        }
        #[inline(always)]
        unsafe fn load(self, p: *const f32) -> __m512 {
            unsafe { _mm512_loadu_ps(p) }
        }
        #[inline(always)]
        unsafe fn store(self, p: *mut f32, v: __m512) {
            unsafe { _mm512_storeu_ps(p, v) }
        }
        #[inline(always)]
        fn add(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_add_ps(a, b) }
        }
        #[inline(always)]
        fn sub(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_sub_ps(a, b) }
        }
        #[inline(always)]
        fn mul(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_mul_ps(a, b) }
        }
        #[inline(always)]
        fn mul_add(self, a: __m512, b: __m512, c: __m512) -> __m512 {
            unsafe { _mm512_fmadd_ps(a, b, c) }
        }
        #[inline(always)]
        fn mul_sub(self, a: __m512, b: __m512, c: __m512) -> __m512 {
            unsafe { _mm512_fmsub_ps(a, b, c) }
        }
        #[inline(always)]
        fn rsqrt_or_zero(self, x: __m512, eps: f32) -> __m512 {
            unsafe {
                // 14-bit estimate, then one Newton step: y (1.5 - 0.5 x y²).
                let y = _mm512_rsqrt14_ps(x);
                let hx = _mm512_mul_ps(x, _mm512_set1_ps(0.5));
                let t = _mm512_fnmadd_ps(_mm512_mul_ps(hx, y), y, _mm512_set1_ps(1.5));
                let y = _mm512_mul_ps(y, t);
                let ok = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(x, _mm512_set1_ps(eps));
                _mm512_maskz_mov_ps(ok, y)
            }
        }
        #[inline(always)]
        fn keep_if_positive(self, m: __m512, a: __m512) -> __m512 {
            unsafe {
                let ok = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(m, _mm512_setzero_ps());
                _mm512_maskz_mov_ps(ok, a)
            }
        }
        #[inline(always)]
        fn div(self, a: __m512, b: __m512) -> __m512 {
            unsafe { _mm512_div_ps(a, b) }
        }
        #[inline(always)]
        fn any_positive(self, m: __m512) -> bool {
            unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(m, _mm512_setzero_ps()) != 0 }
        }
        #[inline(always)]
        fn shift1(self, prev: __m512, cur: __m512) -> __m512 {
            unsafe {
                _mm512_castsi512_ps(_mm512_alignr_epi32::<15>(
                    _mm512_castps_si512(cur),
                    _mm512_castps_si512(prev),
                ))
            }
        }
        #[inline(always)]
        fn shift2(self, prev: __m512, cur: __m512) -> __m512 {
            unsafe {
                _mm512_castsi512_ps(_mm512_alignr_epi32::<14>(
                    _mm512_castps_si512(cur),
                    _mm512_castps_si512(prev),
                ))
            }
        }
    }

    impl Simd for Avx2 {
        type E = f32;
        type V = __m256;
        const LANES: usize = 8;
        #[inline(always)]
        fn splat(self, a: f32) -> __m256 {
            unsafe { _mm256_set1_ps(a) }
        }
        #[inline(always)]
        unsafe fn load(self, p: *const f32) -> __m256 {
            unsafe { _mm256_loadu_ps(p) }
        }
        #[inline(always)]
        unsafe fn store(self, p: *mut f32, v: __m256) {
            unsafe { _mm256_storeu_ps(p, v) }
        }
        #[inline(always)]
        fn add(self, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_add_ps(a, b) }
        }
        #[inline(always)]
        fn sub(self, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_sub_ps(a, b) }
        }
        #[inline(always)]
        fn mul(self, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_mul_ps(a, b) }
        }
        #[inline(always)]
        fn mul_add(self, a: __m256, b: __m256, c: __m256) -> __m256 {
            unsafe { _mm256_fmadd_ps(a, b, c) }
        }
        #[inline(always)]
        fn mul_sub(self, a: __m256, b: __m256, c: __m256) -> __m256 {
            unsafe { _mm256_fmsub_ps(a, b, c) }
        }
        #[inline(always)]
        fn rsqrt_or_zero(self, x: __m256, eps: f32) -> __m256 {
            unsafe {
                // 12-bit estimate, then one Newton step: y (1.5 - 0.5 x y²).
                let y = _mm256_rsqrt_ps(x);
                let hx = _mm256_mul_ps(x, _mm256_set1_ps(0.5));
                let t = _mm256_fnmadd_ps(_mm256_mul_ps(hx, y), y, _mm256_set1_ps(1.5));
                let y = _mm256_mul_ps(y, t);
                let ok = _mm256_cmp_ps::<_CMP_GT_OQ>(x, _mm256_set1_ps(eps));
                _mm256_and_ps(ok, y)
            }
        }
        #[inline(always)]
        fn keep_if_positive(self, m: __m256, a: __m256) -> __m256 {
            unsafe {
                let ok = _mm256_cmp_ps::<_CMP_GT_OQ>(m, _mm256_setzero_ps());
                _mm256_and_ps(ok, a)
            }
        }
        #[inline(always)]
        fn div(self, a: __m256, b: __m256) -> __m256 {
            unsafe { _mm256_div_ps(a, b) }
        }
        #[inline(always)]
        fn any_positive(self, m: __m256) -> bool {
            unsafe {
                let ok = _mm256_cmp_ps::<_CMP_GT_OQ>(m, _mm256_setzero_ps());
                _mm256_movemask_ps(ok) != 0
            }
        }
        #[inline(always)]
        fn shift1(self, prev: __m256, cur: __m256) -> __m256 {
            unsafe {
                // [prev 4..8, cur 0..4], then per 128-bit half take 3 floats up.
                let t = _mm256_permute2f128_ps::<0x21>(prev, cur);
                _mm256_castsi256_ps(_mm256_alignr_epi8::<12>(
                    _mm256_castps_si256(cur),
                    _mm256_castps_si256(t),
                ))
            }
        }
        #[inline(always)]
        fn shift2(self, prev: __m256, cur: __m256) -> __m256 {
            unsafe {
                let t = _mm256_permute2f128_ps::<0x21>(prev, cur);
                _mm256_castsi256_ps(_mm256_alignr_epi8::<8>(
                    _mm256_castps_si256(cur),
                    _mm256_castps_si256(t),
                ))
            }
        }
    }
}

/// The largest squared speed (m²/s²) and squared distance from `center` (m²) of
/// the particles at `x` with velocities `v`, infinite when any is NaN: every fast
/// engine's cheap scan for the divergence check. A square is at least 0 or NaN,
/// and the bits of floats with the sign bit clear order as their values do, a
/// NaN's above infinity's (a NaN with the sign bit set above all): integer maxima,
/// which the compiler vectorises, give the largest squares and whether any is NaN
/// at once.
fn runaway_scan<E: Real>(
    [x, y, z]: [&[E]; 3],
    [vx, vy, vz]: [&[E]; 3],
    center: DVec3,
) -> (f64, f64) {
    let [cx, cy, cz] = center.to_array().map(E::of);
    let n = x.len();
    let (y, z, vx, vy, vz) = (&y[..n], &z[..n], &vx[..n], &vy[..n], &vz[..n]);
    let (mut speed2, mut dist2) = (E::ZERO.bits(), E::ZERO.bits());
    for i in 0..n {
        let v2 = vx[i] * vx[i] + vy[i] * vy[i] + vz[i] * vz[i];
        let (dx, dy, dz) = (x[i] - cx, y[i] - cy, z[i] - cz);
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
    runaway_scan(x, v, center)
}

/// Whether any spring from `a .. a + len` to `b .. b + len` (array indices in
/// `state`) that `alive` keeps (all without a mask) is longer than `sqrt(scan2)`,
/// in the state's precision. Written as a plain loop over slices for the compiler
/// to vectorise.
#[inline(always)]
fn row_may_tear<E: Real>(
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
    // The low parts are zeros when the positions have none.
    let [(la, lb), (ma, mb), (na, nb)] = state.xl.each_ref().map(ends);
    // Every slice `len` long, in the compiler's sight, so the loops below carry no
    // bounds checks and vectorise; the verdict is an integer OR. (A macro, not a
    // closure: a closure is not inlined into the AVX2 entry point.)
    let [xa, xb, ya, yb, za, zb] = [xa, xb, ya, yb, za, zb].map(|s| &s[..len]);
    let [la, lb, ma, mb, na, nb] = [la, lb, ma, mb, na, nb].map(|s| &s[..len]);
    macro_rules! l2 {
        ($j:expr) => {{
            let j = $j;
            let dx = (xa[j] - xb[j]) + (la[j] - lb[j]);
            let dy = (ya[j] - yb[j]) + (ma[j] - mb[j]);
            let dz = (za[j] - zb[j]) + (na[j] - nb[j]);
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

/// A coordinate (m) as the kernel stores it: its high part, and the rest as a low
/// part when the positions are double-float (`compensated`), else zero.
fn position_parts<E: Real>(q: f64, compensated: bool) -> (E, E) {
    let hi = E::of(q);
    let lo = if compensated {
        E::of(q - hi.f64())
    } else {
        E::ZERO
    };
    (hi, lo)
}

/// One row of positions as f64 (high plus low part), from array index `start`
/// on, into `out` (as many particles as it holds).
fn row_to_f64<E: Real>(out: &mut [DVec3], hi: &[Buf<E>; 3], lo: &[Buf<E>; 3], start: usize) {
    let at = start..start + out.len();
    let [x, y, z] = hi.each_ref().map(|a| &a.as_slice()[at.clone()]);
    let [xl, yl, zl] = lo.each_ref().map(|a| &a.as_slice()[at.clone()]);
    for (c, p) in out.iter_mut().enumerate() {
        *p = DVec3::new(
            x[c].f64() + xl[c].f64(),
            y[c].f64() + yl[c].f64(),
            z[c].f64() + zl[c].f64(),
        );
    }
}

/// [`row_may_tear`] with the best code this CPU has.
fn row_may_tear_dispatch<E: Real>(
    simd: SimdLevel,
    state: &State<E>,
    ends: (usize, usize, usize),
    alive: Option<&[E]>,
    scan2: E,
) -> bool {
    match simd {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the level is AVX2 or AVX-512 only when the CPU has AVX2 and FMA.
        SimdLevel::Avx2 | SimdLevel::Avx512 => unsafe {
            x86::row_may_tear_avx2(state, ends, alive, scan2)
        },
        _ => row_may_tear(state, ends, alive, scan2),
    }
}

/// One colour class of XPBD's springs on a grid: the stencil direction `(dr, dc)`
/// and the spring `(rest length, k, b)` at step `dt`.
#[derive(Clone, Copy, Debug)]
struct XpbdClass<'a> {
    width: usize,
    dr: usize,
    dc: isize,
    spring: (f64, f64, f64),
    dt: f64,
    /// With springs missing, which are left ([`Torn::bits`]) and this direction's bit.
    left: Option<(&'a [u8], u8)>,
}

impl XpbdClass<'_> {
    /// Corrects the class's springs of colour `colour` inside one block of rows
    /// (`x` positions, `x0` at the start of the step, `w` inverse masses, the block's
    /// first row where the class's rows start, its first particle `first`): a row,
    /// for springs along rows, else `dr` rows of springs reaching `dr` rows down.
    /// No spring leaves the block.
    fn correct_block(&self, x: &mut [DVec3], x0: &[DVec3], w: &[f64], first: usize, colour: usize) {
        let width = self.width;
        let rows = x.len() / width;
        // Columns c with both ends on the cloth: 0 <= c + dc < width.
        let (c0, c1) = (
            (-self.dc).max(0) as usize,
            width.saturating_sub(self.dc.max(0) as usize),
        );
        let mut correct = |a: usize, b: usize| {
            if let Some((bits, bit)) = self.left
                && bits[first + a] & bit == 0
            {
                return;
            }
            let (rest, k, damping) = self.spring;
            if let Some(c) = constraints::xpbd_correction(
                [x[a], x[b]],
                [x0[a], x0[b]],
                w[a],
                w[b],
                (rest, k, damping),
                self.dt,
            ) {
                x[a] -= w[a] * c;
                x[b] += w[b] * c;
            }
        };
        if self.dr == 0 {
            // Along the row the springs alternate in runs of `dc` columns: the
            // class's start at columns `2 dc m + dc colour + j`, j < dc.
            let dc = self.dc as usize;
            for m in (0..width).step_by(2 * dc) {
                for c in (m + dc * colour..m + dc * colour + dc).filter(|&c| c + dc < width) {
                    correct(c, c + dc);
                }
            }
            return;
        }
        for r in 0..self.dr.min(rows.saturating_sub(self.dr)) {
            for c in c0..c1 {
                let a = r * width + c;
                correct(a, (a + self.dr * width).wrapping_add_signed(self.dc));
            }
        }
    }
}

/// One stencil direction: (row, column) offset, rest length, whether the kind
/// exists, and its coefficients.
type Stencil = ((usize, isize), f64, bool, SpringCoefficients);

/// A particle's position (high and low parts) and velocity, one per lane.
type Particle<'a, V> = (&'a [V; 3], &'a [V; 3], &'a [V; 3]);

/// Forces on the first ends of springs `i`-`j`, one per lane, times `mask` (if
/// any): `f = (k L / l - k - b (d·dv) / l²) d = ((-b (d·dv) / l + k L) / l - k) d`
/// with `d = x_i - x_j` (high parts and low parts subtracted separately, so that `d`
/// is accurate to its own size, not to that of the positions), `dv = v_i - v_j`.
/// `kind` is `[-k, k L, -b]`.
#[inline(always)]
fn spring<S: Simd, const LO: bool>(
    s: S,
    (xi, xli, vi): Particle<S::V>,
    (xj, xlj, vj): Particle<S::V>,
    [nk, kl, nb]: [S::V; 3],
    mask: Option<S::V>,
) -> [S::V; 3] {
    let d: [S::V; 3] = std::array::from_fn(|a| {
        if LO {
            s.add(s.sub(xi[a], xj[a]), s.sub(xli[a], xlj[a]))
        } else {
            s.sub(xi[a], xj[a])
        }
    });
    let u = [
        s.sub(vi[0], vj[0]),
        s.sub(vi[1], vj[1]),
        s.sub(vi[2], vj[2]),
    ];
    let l2 = s.mul_add(d[2], d[2], s.mul_add(d[1], d[1], s.mul(d[0], d[0])));
    let dd = s.mul_add(d[2], u[2], s.mul_add(d[1], u[1], s.mul(d[0], u[0])));
    let inv = s.rsqrt_or_zero(l2, S::E::EPS2);
    let a = s.mul_add(s.mul_add(s.mul(nb, dd), inv, kl), inv, nk);
    let a = match mask {
        Some(m) => s.mul(a, m),
        None => a,
    };
    [s.mul(a, d[0]), s.mul(a, d[1]), s.mul(a, d[2])]
}

/// Drag on each vertex of triangle `(p, q, d)` with relative air velocity `vr`, times
/// `mask`: `-(ρ C_d / 12) |v_rel| (v_rel·m) m / |m|` with `m = (q - p) × (d - p)`,
/// `|m| = 2A`; `|v_rel| / |m|` is computed as `|v_rel|² / sqrt(|v_rel|² |m|²)`.
#[inline(always)]
fn triangle<S: Simd>(
    s: S,
    [p, q, d]: [&[S::V; 3]; 3],
    vr: &[S::V; 3],
    neg_drag: S::V,
    mask: Option<S::V>,
) -> [S::V; 3] {
    let e1 = [s.sub(q[0], p[0]), s.sub(q[1], p[1]), s.sub(q[2], p[2])];
    let e2 = [s.sub(d[0], p[0]), s.sub(d[1], p[1]), s.sub(d[2], p[2])];
    let m = [
        s.mul_sub(e1[1], e2[2], s.mul(e1[2], e2[1])),
        s.mul_sub(e1[2], e2[0], s.mul(e1[0], e2[2])),
        s.mul_sub(e1[0], e2[1], s.mul(e1[1], e2[0])),
    ];
    let m2 = s.mul_add(m[2], m[2], s.mul_add(m[1], m[1], s.mul(m[0], m[0])));
    let vr2 = s.mul_add(vr[2], vr[2], s.mul_add(vr[1], vr[1], s.mul(vr[0], vr[0])));
    let vm = s.mul_add(vr[2], m[2], s.mul_add(vr[1], m[1], s.mul(vr[0], m[0])));
    let ratio = s.mul(vr2, s.rsqrt_or_zero(s.mul(vr2, m2), S::E::TINY));
    let a = s.mul(s.mul(neg_drag, vm), ratio);
    let a = match mask {
        Some(m) => s.mul(a, m),
        None => a,
    };
    [s.mul(a, m[0]), s.mul(a, m[1]), s.mul(a, m[2])]
}

/// Splatted constants and raw pointers of one row, shared by its blocks.
struct RowKernel<S: Simd> {
    s: S,
    /// What integrating a particle needs.
    step: StepLanes<S>,
    kinds: [[S::V; 3]; 3],
    neg_wind: [S::V; 3],
    third: S::V,
    neg_drag: S::V,
    down: S::V,
    down2: S::V,
    x: [*const S::E; 3],
    xl: [*const S::E; 3],
    v: [*const S::E; 3],
    inv_mass: *const S::E,
    col_mask: *const S::E,
    /// [`Ctx::torn`]'s masks.
    torn: Option<[*const S::E; 8]>,
    acc: *mut S::E,
    /// Array offsets of the rows `row`, `row + 1`, `row + 2`.
    b: [usize; 3],
    /// Accumulator offsets of the rows `row`, `row + 1`, `row + 2`.
    a: [usize; 3],
    nv: usize,
    stride: usize,
    lo: usize,
}

/// Splatted constants and raw pointers for [`integrate`] and
/// [`project_out_of_sphere`]: the step of a particle under its force, shared by the
/// grid's rows and the lattice's blocks ([`lattice`]).
struct StepLanes<S: Simd> {
    s: S,
    gravity: [S::V; 3],
    dt: S::V,
    zero: S::V,
    one: S::V,
    /// `-c` (air damping), ground height, `k_c`, damping, `explicit`, `h/2` (Verlet).
    neg_air: S::V,
    ground: [S::V; 3],
    explicit: S::V,
    verlet_half_dt: S::V,
    inv_dt: S::V,
    /// Sphere centre, radius and squared radius (when the step projects onto it).
    sphere: Option<SphereLanes<S::V>>,
    verlet: bool,
    /// Verlet's update velocities (the velocities for the other methods).
    u: [*const S::E; 3],
    /// [`Out`]'s twelve arrays.
    out: [*mut S::E; 12],
}

impl<S: Simd> StepLanes<S> {
    /// The lanes of `p`, reading Verlet's `u` from `u` (else from `v`) and writing
    /// to `out`. (Inlined: called once a row, it cost the drape 3% as a call.)
    #[inline(always)]
    fn new(s: S, p: &Params<S::E>, u: [&[S::E]; 3], v: [&[S::E]; 3], out: &mut Out<S::E>) -> Self {
        StepLanes {
            s,
            gravity: p.gravity.map(|w| s.splat(w)),
            dt: s.splat(p.dt),
            zero: s.splat(S::E::ZERO),
            one: s.splat(S::E::ONE),
            neg_air: s.splat(p.neg_air),
            ground: p.ground.map(|g| s.splat(g)),
            explicit: s.splat(p.explicit),
            verlet_half_dt: s.splat(p.verlet_half_dt),
            inv_dt: s.splat(S::E::ONE / p.dt),
            sphere: p
                .sphere
                .map(|(c, r, r2)| (c.map(|c| s.splat(c)), s.splat(r), s.splat(r2))),
            verlet: p.verlet,
            // Without Verlet's own array the update velocity is the velocity.
            u: if p.verlet { u } else { v }.map(<[S::E]>::as_ptr),
            out: out.0.each_mut().map(|o| o.as_mut_ptr()),
        }
    }
}

/// A sphere collider's centre, radius and squared radius, splatted.
type SphereLanes<V> = ([V; 3], V, V);

/// One row `row` of the cloth, in SIMD blocks of columns: evaluate the six springs
/// that start on each particle of the row, `(row, c)` to `(row, c+1)`, `(row, c+2)`,
/// `(row+1, c)`, `(row+1, c+1)`, `(row+2, c)`, and `(row, c+1)` to `(row+1, c)`,
/// and (with `DRAG`) the two triangles of cell `(row, c)`. Forces on the particles
/// of rows `row+1` and `row+2` are added to their accumulators in the ring; the
/// force on a particle of `row` is its accumulator (from the two rows above) plus
/// the forces just computed, and with `OWN` the particle is integrated at once:
/// `v' = v + dt (f / m + g)` (0 when pinned), `x' = x + dt v'`, written to `out`
/// at `lo + c`. Forces between columns of the same row reach the neighbouring
/// lanes through `shift1`/`shift2`, carried from block to block. Blocks that touch
/// the last two columns, and the last two rows, mask the springs and triangles
/// that reach ghost particles.
#[inline(always)]
fn row_step<S: Simd, const DRAG: bool, const OWN: bool, const PLAIN: bool, const LO: bool>(
    s: S,
    ctx: &Ctx<S::E>,
    band: &mut Band<S::E>,
    row: usize,
    out: &mut Out<S::E>,
    lo: usize,
) {
    let g = ctx.grid;
    let nv = g.nv;
    let acc = band.acc.as_mut_slice();
    let b = [row * g.stride, (row + 1) * g.stride, (row + 2) * g.stride];
    // Everything read or written by `block` lies inside these bounds.
    assert!(S::LANES <= BLOCK && nv.is_multiple_of(S::LANES) && acc.len() == SLOTS * 3 * nv);
    assert!(b[2] + nv + 2 <= g.len() && ctx.inv_mass.len() == g.len());
    assert!(ctx.col_mask.len() >= g.stride + nv);
    for mask in ctx.torn.iter().flatten() {
        // Read up to one past the row's last block (the other diagonal's).
        assert!(mask.len() > b[0] + nv);
    }
    for a in ctx.x.iter().chain(&ctx.xl).chain(&ctx.v) {
        assert_eq!(a.len(), g.len());
    }
    let verlet = ctx.p.verlet;
    if verlet {
        for a in &ctx.u {
            assert_eq!(a.len(), g.len());
        }
    }
    if OWN {
        for o in &out.0[..if verlet { 12 } else { 9 }] {
            assert!(lo + nv <= o.len());
        }
    }
    let slot = |r: usize| (r % SLOTS) * 3 * nv;
    let p = &ctx.p;
    let kind = |i: usize| [s.splat(-p.ks[i]), s.splat(p.kls[i]), s.splat(-p.bs[i])];
    let k = RowKernel {
        s,
        step: StepLanes::new(s, p, ctx.u, ctx.v, out),
        kinds: [kind(0), kind(1), kind(2)],
        neg_wind: p.wind.map(|w| s.splat(-w)),
        third: s.splat(S::E::of(1.0 / 3.0)),
        neg_drag: s.splat(-p.drag),
        down: s.splat(if row + 1 < g.h { S::E::ONE } else { S::E::ZERO }),
        down2: s.splat(if row + 2 < g.h { S::E::ONE } else { S::E::ZERO }),
        x: ctx.x.map(<[S::E]>::as_ptr),
        xl: ctx.xl.map(<[S::E]>::as_ptr),
        v: ctx.v.map(<[S::E]>::as_ptr),
        inv_mass: ctx.inv_mass.as_ptr(),
        col_mask: ctx.col_mask.as_ptr(),
        torn: ctx.torn.map(|t| t.map(<[S::E]>::as_ptr)),
        acc: acc.as_mut_ptr(),
        b,
        a: [slot(row), slot(row + 1), slot(row + 2)],
        nv,
        stride: g.stride,
        lo,
    };
    // Blocks from `c_mask` on hold a column >= w - 2; near the bottom all blocks
    // reach ghost rows; with springs missing every block is masked.
    let c_mask = if row + 2 < g.h && ctx.torn.is_none() {
        (g.w.saturating_sub(2) / S::LANES) * S::LANES
    } else {
        0
    };
    let mut carry = [[k.step.zero; 3]; 3];
    let mut c = 0;
    while c < c_mask {
        // SAFETY: c < nv, a multiple of LANES; bounds asserted above.
        unsafe { block::<S, DRAG, OWN, false, PLAIN, LO>(&k, c, &mut carry) };
        c += S::LANES;
    }
    while c < nv {
        // SAFETY: as above.
        unsafe { block::<S, DRAG, OWN, true, PLAIN, LO>(&k, c, &mut carry) };
        c += S::LANES;
    }
}

/// Columns `c .. c + LANES` of a row (see [`row_step`]).
///
/// # Safety
/// `c + LANES <= nv`, and the pointers and offsets of `k` are valid as asserted in
/// [`row_step`].
#[inline(always)]
unsafe fn block<
    S: Simd,
    const DRAG: bool,
    const OWN: bool,
    const MASK: bool,
    const PLAIN: bool,
    const LO: bool,
>(
    k: &RowKernel<S>,
    c: usize,
    carry: &mut [[S::V; 3]; 3],
) {
    let s = k.s;
    let zero = k.step.zero;
    // SAFETY: offsets are inside the arrays (caller's contract).
    let ld = |ptr: [*const S::E; 3], i: usize| unsafe {
        [
            s.load(ptr[0].add(i)),
            s.load(ptr[1].add(i)),
            s.load(ptr[2].add(i)),
        ]
    };
    let [b0, b1, b2] = k.b;
    // The positions' low parts, or zeros without them.
    let ldl = |i: usize| if LO { ld(k.xl, i) } else { [zero; 3] };
    let p00 = (&ld(k.x, b0 + c), &ldl(b0 + c), &ld(k.v, b0 + c));
    let p01 = (&ld(k.x, b0 + c + 1), &ldl(b0 + c + 1), &ld(k.v, b0 + c + 1));
    let p02 = (&ld(k.x, b0 + c + 2), &ldl(b0 + c + 2), &ld(k.v, b0 + c + 2));
    let p10 = (&ld(k.x, b1 + c), &ldl(b1 + c), &ld(k.v, b1 + c));
    let p11 = (&ld(k.x, b1 + c + 1), &ldl(b1 + c + 1), &ld(k.v, b1 + c + 1));
    let p20 = (&ld(k.x, b2 + c), &ldl(b2 + c), &ld(k.v, b2 + c));
    // Masks of the springs right, two right, down, down-right, the other diagonal,
    // two down, and of the two triangles.
    let masks: Option<[S::V; 8]> = if MASK {
        Some(match k.torn {
            // SAFETY: as above (the other diagonal's mask is read one column on).
            Some(t) => unsafe {
                std::array::from_fn(|m| s.load(t[m].add(b0 + c + usize::from(m == 4))))
            },
            None => {
                // SAFETY: as above.
                let (m1, m2) = unsafe {
                    (
                        s.load(k.col_mask.add(c)),
                        s.load(k.col_mask.add(k.stride + c)),
                    )
                };
                let m1d = s.mul(m1, k.down);
                [m1, m2, k.down, m1d, m1d, k.down2, m1d, m1d]
            }
        })
    } else {
        None
    };
    let mask = |m: usize| masks.map(|masks| masks[m]);
    let [structural, bend, shear] = k.kinds;
    let right = spring::<S, LO>(s, p00, p01, structural, mask(0));
    let right2 = spring::<S, LO>(s, p00, p02, bend, mask(1));
    let d = spring::<S, LO>(s, p00, p10, structural, mask(2));
    let dr = spring::<S, LO>(s, p00, p11, shear, mask(3));
    let anti = spring::<S, LO>(s, p01, p10, shear, mask(4));
    let d2 = spring::<S, LO>(s, p00, p20, bend, mask(5));
    let (t1, t2) = if DRAG {
        // Relative air velocity of (a, b, d) and (b, e, d): mean velocity - wind.
        let (va, vb, vd, ve) = (p00.2, p01.2, p10.2, p11.2);
        let bd: [S::V; 3] = std::array::from_fn(|i| s.add(vb[i], vd[i]));
        let vr1 = std::array::from_fn(|i| s.mul_add(s.add(bd[i], va[i]), k.third, k.neg_wind[i]));
        let vr2 = std::array::from_fn(|i| s.mul_add(s.add(bd[i], ve[i]), k.third, k.neg_wind[i]));
        (
            triangle(s, [p00.0, p01.0, p10.0], &vr1, k.neg_drag, mask(6)),
            triangle(s, [p01.0, p11.0, p10.0], &vr2, k.neg_drag, mask(7)),
        )
    } else {
        ([zero; 3], [zero; 3])
    };
    let nv = k.nv;
    // SAFETY: as above.
    let w = if OWN {
        unsafe { s.load(k.inv_mass.add(b0 + c)) }
    } else {
        zero
    };
    for i in 0..3 {
        // Terms for the lane to the right (column c+1), two to the right (c+2) and,
        // on the next row, one to the right.
        let mut l = s.sub(anti[i], right[i]);
        let q = s.sub(zero, right2[i]);
        let mut m = s.sub(zero, dr[i]);
        let mut in1 = s.sub(zero, s.add(d[i], anti[i]));
        if DRAG {
            let t = s.add(t1[i], t2[i]);
            l = s.add(l, t);
            m = s.add(m, t2[i]);
            in1 = s.add(in1, t);
        }
        let in1 = s.add(in1, s.shift1(carry[2][i], m));
        // SAFETY: accumulator rows a1, a2, component i, columns c .. c + LANES.
        unsafe {
            let pa1 = k.acc.add(k.a[1] + i * nv + c);
            s.store(pa1, s.add(s.load(pa1), in1));
            s.store(k.acc.add(k.a[2] + i * nv + c), s.sub(zero, d2[i]));
        }
        if OWN {
            let mut own = s.add(s.add(right[i], right2[i]), s.add(d[i], dr[i]));
            own = s.add(own, d2[i]);
            if DRAG {
                own = s.add(own, t1[i]);
            }
            own = s.add(
                own,
                s.add(s.shift1(carry[0][i], l), s.shift2(carry[1][i], q)),
            );
            // SAFETY: as above; outputs hold `lo + nv` floats.
            unsafe {
                let force = s.add(s.load(k.acc.add(k.a[0] + i * nv + c)), own);
                integrate::<S, PLAIN, LO>(&k.step, k.b[0] + c, k.lo + c, i, w, p00, force);
            }
        }
        carry[0][i] = l;
        carry[1][i] = q;
        carry[2][i] = m;
    }
    if OWN && !PLAIN && k.step.sphere.is_some() {
        // SAFETY: as above.
        unsafe { project_out_of_sphere::<S, LO>(&k.step, k.lo + c, w) };
    }
}

/// Integrates component `i` of the `LANES` particles at array index `at` (inverse
/// masses `w`) under `force` (springs and drag): adds air damping and, for `y`, the
/// ground penalty, then steps them (symplectic Euler, explicit Euler or position
/// Verlet) and writes the new state to the outputs at index `o`.
///
/// # Safety
/// As for [`block`], with `OWN`.
///
/// `PLAIN`: symplectic Euler with no air damping or ground (see `Params::is_plain`).
#[inline(always)]
unsafe fn integrate<S: Simd, const PLAIN: bool, const LO: bool>(
    k: &StepLanes<S>,
    at: usize,
    o: usize,
    i: usize,
    w: S::V,
    (x, xl, v): Particle<S::V>,
    force: S::V,
) {
    let s = k.s;
    if PLAIN {
        let a = s.mul_add(force, w, k.gravity[i]);
        let vn = s.keep_if_positive(w, s.mul_add(k.dt, a, v[i]));
        // SAFETY: outputs hold `lo + nv` floats.
        unsafe {
            if LO {
                let (xn, xnl) = add_double(s, (x[i], xl[i]), s.mul(k.dt, vn));
                s.store(k.out[i].add(o), xn);
                s.store(k.out[3 + i].add(o), xnl);
            } else {
                s.store(k.out[i].add(o), s.mul_add(k.dt, vn, x[i]));
            }
            s.store(k.out[6 + i].add(o), vn);
        }
        return;
    }
    // SAFETY: inside the arrays (caller's contract).
    let u = if k.verlet {
        unsafe { s.load(k.u[i].add(at)) }
    } else {
        v[i]
    };
    let mut force = s.mul_add(k.neg_air, v[i], force);
    if i == 1 {
        // Ground penalty `k_c d - c_g v_y` at depth `d = height - y > 0`.
        let [height, kc, cg] = k.ground;
        let depth = s.sub(height, x[1]);
        let push = s.mul_sub(kc, depth, s.mul(cg, v[1]));
        force = s.add(force, s.keep_if_positive(depth, push));
    }
    let a = s.mul_add(force, w, k.gravity[i]);
    let un = s.keep_if_positive(w, s.mul_add(k.dt, a, u));
    // Explicit Euler moves with the old velocity, the others with the new one.
    let moving = s.mul_add(k.explicit, s.sub(u, un), un);
    let (xn, xnl) = if LO {
        add_double(s, (x[i], xl[i]), s.mul(k.dt, moving))
    } else {
        (s.mul_add(k.dt, moving, x[i]), k.zero)
    };
    let vn = s.keep_if_positive(w, s.mul_add(k.verlet_half_dt, a, un));
    // SAFETY: outputs hold `lo + nv` floats (Verlet's `u` only with Verlet).
    unsafe {
        s.store(k.out[i].add(o), xn);
        if LO {
            s.store(k.out[3 + i].add(o), xnl);
        }
        s.store(k.out[6 + i].add(o), vn);
        if k.verlet {
            s.store(k.out[9 + i].add(o), un);
        }
    }
}

/// Projects the just integrated particles at output index `o` that are inside
/// the sphere (and free) onto its surface, `center + radius d / |d|`; the move `δ`
/// also changes their velocities by `δ / h`.
///
/// # Safety
/// As for [`integrate`], after it ran for all three components.
#[inline(always)]
unsafe fn project_out_of_sphere<S: Simd, const LO: bool>(k: &StepLanes<S>, o: usize, w: S::V) {
    let s = k.s;
    let Some((center, radius, radius2)) = k.sphere else {
        return;
    };
    // SAFETY: the outputs just written (caller's contract).
    let out = |j: usize| unsafe { s.load(k.out[j].add(o)) };
    let xn: [S::V; 3] = std::array::from_fn(out);
    let d: [S::V; 3] = std::array::from_fn(|i| s.sub(xn[i], center[i]));
    let d2 = s.mul_add(d[2], d[2], s.mul_add(d[1], d[1], s.mul(d[0], d[0])));
    let inside = s.keep_if_positive(w, s.keep_if_positive(s.sub(radius2, d2), k.one));
    let scale = s.mul(radius, s.rsqrt_or_zero(d2, S::E::EPS2));
    for i in 0..3 {
        let onto = s.mul_add(d[i], scale, center[i]);
        let dx = s.mul(inside, s.sub(onto, xn[i]));
        let xnl = if LO { out(3 + i) } else { k.zero };
        let dl = s.mul(inside, xnl);
        let dv = s.mul(s.sub(dx, dl), k.inv_dt);
        // SAFETY: as above.
        unsafe {
            s.store(k.out[i].add(o), s.add(xn[i], dx));
            if LO {
                s.store(k.out[3 + i].add(o), s.sub(xnl, dl));
            }
            s.store(k.out[6 + i].add(o), s.add(out(6 + i), dv));
            if k.verlet {
                s.store(k.out[9 + i].add(o), s.add(out(9 + i), dv));
            }
        }
    }
}

/// `(hi, lo) + t` as a new double-float `(hi', lo')` with `|lo'| <= ulp(hi') / 2`:
/// Dekker's fast two-sum of `hi + t` (exact when `|t| <= |hi|`, a step's move
/// against a position; otherwise `hi` is within a step of the origin and float
/// round-off there is already below `ulp(t)`), its error added to `lo`, then
/// renormalised.
#[inline(always)]
fn add_double<S: Simd>(s: S, (hi, lo): (S::V, S::V), t: S::V) -> (S::V, S::V) {
    let sum = s.add(hi, t);
    let error = s.sub(t, s.sub(sum, hi));
    let lo = s.add(lo, error);
    let hi = s.add(sum, lo);
    (hi, s.sub(lo, s.sub(hi, sum)))
}
