//! The few vector operations the kernel's loops are written over, and their portable
//! version ([`Portable`]); the AVX2 and AVX-512 ones are in [`super::x86`].

use super::Real;

/// The few vector operations the kernel needs. Implemented by zero-sized tokens that
/// exist only where the CPU supports the instructions.
pub(super) trait Simd: Copy {
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
    /// Fixed-point positions (integers held in the floats' bits): `a - b` as a float.
    fn fixed_sub(self, a: Self::V, b: Self::V) -> Self::V;
    /// Fixed-point position `x` moved by `t` units (rounded to the nearest).
    fn fixed_add(self, x: Self::V, t: Self::V) -> Self::V;
    /// Lanes moved up by one: `[prev[LANES-1], cur[0], .., cur[LANES-2]]`.
    fn shift1(self, prev: Self::V, cur: Self::V) -> Self::V;
    /// Lanes moved up by two: `[prev[LANES-2], prev[LANES-1], cur[0], ..]`.
    fn shift2(self, prev: Self::V, cur: Self::V) -> Self::V;
}

/// Portable lanes: plain arrays, vectorised by the compiler for the build target
/// (or for the target features of the function they are inlined into).
#[derive(Clone, Copy, Default)]
pub(super) struct Portable<E>(std::marker::PhantomData<E>);

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
    fn fixed_sub(self, a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| E::fixed_sub(a[i], b[i]))
    }
    #[inline(always)]
    fn fixed_add(self, x: Self::V, t: Self::V) -> Self::V {
        std::array::from_fn(|i| E::fixed_add(x[i], t[i]))
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
