//! The few vector operations the kernel's loops are written over, and their portable
//! version ([`Portable`]); the AVX2 and AVX-512 ones are in [`super::x86`].

use super::Real;
use crate::sim::lanes::{Floats, Lanes};

/// The few vector operations the kernel needs. Implemented by zero-sized tokens that
/// exist only where the CPU supports the instructions.
pub(super) trait Simd: Copy {
    /// The float type of a lane.
    type E: Real;
    /// A vector of `LANES` floats.
    type V: Copy;
    const LANES: usize;
    /// Whether the row pass writes its loop over the three axes out when the step
    /// is not plain (see `row::block`). On AVX2 the loop, which the compiler kept,
    /// went through the stack: written out, the sheet ran 1.10x as fast on an AMD
    /// EPYC. On AVX-512 the drape ran 0.91x as fast written out (Intel Xeon), so
    /// the loop stays there; the plain step's loop came out better as a loop on both.
    const UNROLL_AXES: bool = false;
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
    /// `1 / sqrt(x)`, for `x` positive and finite only (0, infinity or NaN give
    /// NaN or infinity on some levels).
    fn rsqrt(self, x: Self::V) -> Self::V;
    /// `1 / sqrt(x)` where `x > eps`, else 0.
    fn rsqrt_or_zero(self, x: Self::V, eps: Self::E) -> Self::V;
    /// `a` where `m > 0`, else 0.
    fn keep_if_positive(self, m: Self::V, a: Self::V) -> Self::V;
    /// `a / b`.
    fn div(self, a: Self::V, b: Self::V) -> Self::V;
    /// Whether any lane of `m` is positive.
    fn any_positive(self, m: Self::V) -> bool;
    /// Per lane, a yes or no: a comparison's result.
    type Mask: Copy;
    /// `a < b`, `a <= b` and `a > b` in each lane (no where either is NaN).
    fn lt(self, a: Self::V, b: Self::V) -> Self::Mask;
    fn le(self, a: Self::V, b: Self::V) -> Self::Mask;
    fn gt(self, a: Self::V, b: Self::V) -> Self::Mask;
    /// `a` in the lanes where `m` says yes, else `b`.
    fn select(self, m: Self::Mask, a: Self::V, b: Self::V) -> Self::V;
    /// Yes where both `a` and `b` say yes; where `a` does and `b` does not.
    fn both(self, a: Self::Mask, b: Self::Mask) -> Self::Mask;
    fn but_not(self, a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// Yes where `a` or `b` says yes.
    fn either(self, a: Self::Mask, b: Self::Mask) -> Self::Mask;
    /// Whether any lane of `m` says yes, and whether every lane does.
    fn any(self, m: Self::Mask) -> bool;
    fn all(self, m: Self::Mask) -> bool;
    /// The square root of each lane, correctly rounded.
    fn sqrt(self, a: Self::V) -> Self::V;
    /// Fixed-point positions (integers held in the floats' bits): `a - b` as a float.
    fn fixed_sub(self, a: Self::V, b: Self::V) -> Self::V;
    /// Fixed-point position `x` moved by `t` units (rounded to the nearest).
    fn fixed_add(self, x: Self::V, t: Self::V) -> Self::V;
    /// Lanes `l` and `l ^ DC` exchanged, for `DC` 1 or 2: `[v1, v0, v3, v2, ..]`
    /// or `[v2, v3, v0, v1, ..]` (within each 128-bit part; bits moved as they are).
    fn swap_pairs<const DC: usize>(self, v: Self::V) -> Self::V;
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
    fn rsqrt(self, x: Self::V) -> Self::V {
        std::array::from_fn(|i| E::ONE / x[i].sqrt())
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
    // The comparisons, select and root of `Floats`, the shared physics' lanes.
    type Mask = <Floats<E, PL> as Lanes>::Mask;
    #[inline(always)]
    fn lt(self, a: Self::V, b: Self::V) -> Self::Mask {
        Floats(a).lt(Floats(b))
    }
    #[inline(always)]
    fn le(self, a: Self::V, b: Self::V) -> Self::Mask {
        Floats(a).le(Floats(b))
    }
    #[inline(always)]
    fn gt(self, a: Self::V, b: Self::V) -> Self::Mask {
        Floats(a).gt(Floats(b))
    }
    #[inline(always)]
    fn select(self, m: Self::Mask, a: Self::V, b: Self::V) -> Self::V {
        Floats::select(m, Floats(a), Floats(b)).0
    }
    #[inline(always)]
    fn both(self, a: Self::Mask, b: Self::Mask) -> Self::Mask {
        std::array::from_fn(|i| a[i] & b[i])
    }
    #[inline(always)]
    fn but_not(self, a: Self::Mask, b: Self::Mask) -> Self::Mask {
        std::array::from_fn(|i| a[i] & !b[i])
    }
    #[inline(always)]
    fn either(self, a: Self::Mask, b: Self::Mask) -> Self::Mask {
        std::array::from_fn(|i| a[i] | b[i])
    }
    #[inline(always)]
    fn any(self, m: Self::Mask) -> bool {
        Floats::<E, PL>::any(m)
    }
    #[inline(always)]
    fn all(self, m: Self::Mask) -> bool {
        Floats::<E, PL>::all(m)
    }
    #[inline(always)]
    fn sqrt(self, a: Self::V) -> Self::V {
        Floats(a).sqrt().0
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
    fn swap_pairs<const DC: usize>(self, v: Self::V) -> Self::V {
        std::array::from_fn(|i| v[i ^ DC])
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

/// A kernel's vector as [`Lanes`] (with its SIMD level's token), for the laws
/// that every engine shares ([`crate::sim::laws`]) to run on the kernel's own
/// registers: the same IEEE operations as on [`Lanes`]' other kinds, with
/// [`Lanes::mul_add`] fused and the reciprocal root the level's estimate.
#[derive(Clone, Copy)]
pub(super) struct Vector<S: Simd>(pub(super) S, pub(super) S::V);

macro_rules! vector_op {
    ($trait:ident, $method:ident) => {
        impl<S: Simd> std::ops::$trait for Vector<S> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, other: Self) -> Self {
                Vector(self.0, self.0.$method(self.1, other.1))
            }
        }
    };
}
vector_op!(Add, add);
vector_op!(Sub, sub);
vector_op!(Mul, mul);
vector_op!(Div, div);

/// A comparison of [`Vector`]s, with the token.
#[derive(Clone, Copy)]
pub(super) struct VectorMask<S: Simd>(pub(super) S, pub(super) S::Mask);

impl<S: Simd> Lanes for Vector<S> {
    type Mask = VectorMask<S>;
    #[inline(always)]
    fn splat(self, x: f64) -> Self {
        Vector(self.0, self.0.splat(S::E::of(x)))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Vector(self.0, self.0.sqrt(self.1))
    }
    #[inline(always)]
    fn lt(self, other: Self) -> VectorMask<S> {
        VectorMask(self.0, self.0.lt(self.1, other.1))
    }
    #[inline(always)]
    fn le(self, other: Self) -> VectorMask<S> {
        VectorMask(self.0, self.0.le(self.1, other.1))
    }
    #[inline(always)]
    fn gt(self, other: Self) -> VectorMask<S> {
        VectorMask(self.0, self.0.gt(self.1, other.1))
    }
    #[inline(always)]
    fn any(m: VectorMask<S>) -> bool {
        m.0.any(m.1)
    }
    #[inline(always)]
    fn all(m: VectorMask<S>) -> bool {
        m.0.all(m.1)
    }
    #[inline(always)]
    fn select(m: VectorMask<S>, a: Self, b: Self) -> Self {
        Vector(m.0, m.0.select(m.1, a.1, b.1))
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        Vector(self.0, self.0.mul_add(self.1, b.1, c.1))
    }
    #[inline(always)]
    fn mul_sub(self, b: Self, c: Self) -> Self {
        Vector(self.0, self.0.mul_sub(self.1, b.1, c.1))
    }
    #[inline(always)]
    fn rsqrt_or_zero(self, eps2: f64) -> Self {
        Vector(self.0, self.0.rsqrt_or_zero(self.1, S::E::of(eps2)))
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        Vector(self.0, self.0.rsqrt(self.1))
    }
    #[inline(always)]
    fn keep_if_positive(self, a: Self) -> Self {
        Vector(self.0, self.0.keep_if_positive(self.1, a.1))
    }
    #[inline(always)]
    fn both(a: VectorMask<S>, b: VectorMask<S>) -> VectorMask<S> {
        VectorMask(a.0, a.0.both(a.1, b.1))
    }

    const WIDTH: usize = S::LANES;
    #[inline(always)]
    fn lane(self, i: usize) -> f64 {
        self.lanes()[i].f64()
    }
    #[inline(always)]
    fn with_lane(self, i: usize, x: f64) -> Self {
        let mut lanes = self.lanes();
        lanes[i] = S::E::of(x);
        // SAFETY: `lanes` holds `MAX_LANES >= S::LANES` floats.
        Vector(self.0, unsafe { self.0.load(lanes.as_ptr()) })
    }
    #[inline(always)]
    fn lane_says(m: VectorMask<S>, i: usize) -> bool {
        let one = m.0.splat(S::E::ONE);
        let yes = Vector(m.0, m.0.select(m.1, one, m.0.splat(S::E::ZERO)));
        yes.lane(i) > 0.0
    }
}

/// Most lanes a kernel's vector has (16 float32 in AVX-512).
const MAX_LANES: usize = 16;

impl<S: Simd> Vector<S> {
    /// Its lanes, in the first `S::LANES` of an array.
    #[inline(always)]
    fn lanes(self) -> [S::E; MAX_LANES] {
        const { assert!(S::LANES <= MAX_LANES) };
        let mut lanes = [S::E::ZERO; MAX_LANES];
        // SAFETY: `lanes` holds `MAX_LANES >= S::LANES` floats.
        unsafe { self.0.store(lanes.as_mut_ptr(), self.1) };
        lanes
    }
}

/// Holds the frame of the function this is inlined into on a cache line (a
/// 64-byte aligned local that the compiler must keep), and so the vectors that
/// function spills to it. In a frame aligned to 16 bytes, as the compiler left the
/// row pass's, half the 32-byte spills straddled two lines: the drape ran 0.93x as
/// fast (AMD EPYC, AVX2).
#[inline(always)]
pub(super) fn align_frame() {
    #[repr(C, align(64))]
    struct Line([u8; 64]);
    let mut line = Line([0; 64]);
    std::hint::black_box(&mut line);
}
