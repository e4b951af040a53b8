//! The float types the kernels compute in ([`Real`]: `f32`, or `f64` where float32
//! cannot resolve the springs) and the SIMD levels their loops are compiled for
//! ([`SimdLevel`]), with each type's entry points at each level.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicU8, Ordering};

use bytemuck::Pod;

use super::lattice;
#[cfg(target_arch = "x86_64")]
use super::x86;
use super::{Band, Ctx, Out, Portable, SweepLines, band_rows, row_portable, spring_sweep};
use crate::sim::lanes::LaneFloat;

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
pub(super) static SIMD_CAP: AtomicU8 = AtomicU8::new(u8::MAX);

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

/// The float type a kernel computes in: `f32`, or `f64` where float32 cannot
/// resolve the springs (see [`Precision`]).
pub(super) trait Real:
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
