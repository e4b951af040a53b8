//! AVX2 and AVX-512 versions of [`Simd`], and the entry points compiled for them.

use std::arch::x86_64::*;

use super::contact::RowsPass;
use super::row::{RowMode, row_step};
use super::{
    Band, Ctx, Out, Real, Simd, State, SweepLines, any_faster, lattice, row_may_tear, row_variant,
    spring_sweep,
};

/// Token for AVX2 + FMA; only built inside `band_avx2`.
#[derive(Clone, Copy)]
pub(super) struct Avx2(());

/// Token for AVX-512F/VL + FMA; only built inside `band_avx512`.
#[derive(Clone, Copy)]
pub(super) struct Avx512(());

/// Token for AVX-512F/VL + FMA in float64; only built inside the `_avx512_f64`
/// entry points.
#[derive(Clone, Copy)]
pub(super) struct Avx512F64(());

/// Token for AVX2 + FMA in float64; only built inside the `_avx2_f64` entry
/// points.
#[derive(Clone, Copy)]
pub(super) struct Avx2F64(());

/// The row pass's entry points for a SIMD level and precision: `name` runs one
/// row (see `row_step`) in the scene's mode, each mode compiled as a function of
/// its own with the level's features ([`super::row::RowMode`]):
/// `name, modes: target features, float type, lanes`.
macro_rules! row_entries {
    ($($name:ident, $modes:ident: $features:literal, $t:ty, $lanes:expr;)*) => {$(
        /// `row_step` in one mode with these lanes and target features.
        ///
        /// # Safety
        /// The CPU must have the target features.
        #[target_feature(enable = $features)]
        #[inline(never)]
        unsafe fn $modes<const DRAG: bool, const OWN: bool, const PLAIN: bool, const FIXED: bool>(
            ctx: &Ctx<$t>,
            band: &mut Band<$t>,
            row: usize,
            out: &mut Out<$t>,
            lo: usize,
        ) {
            row_step::<_, DRAG, OWN, PLAIN, FIXED>($lanes, ctx, band, row, out, lo);
        }

        /// One row with these lanes and target features, in the scene's mode.
        ///
        /// # Safety
        /// The CPU must have the target features.
        pub(super) unsafe fn $name(
            ctx: &Ctx<$t>,
            band: &mut Band<$t>,
            row: usize,
            out: &mut Out<$t>,
            lo: usize,
            own: bool,
        ) {
            /// Proof that the CPU has the features, for `RowMode`'s safe method.
            #[derive(Clone, Copy)]
            struct Rows(());
            impl RowMode<$t> for Rows {
                #[inline(always)]
                fn row<const DRAG: bool, const OWN: bool, const PLAIN: bool, const FIXED: bool>(
                    self,
                    ctx: &Ctx<$t>,
                    band: &mut Band<$t>,
                    row: usize,
                    out: &mut Out<$t>,
                    lo: usize,
                ) {
                    // SAFETY: a `Rows` exists only inside `$name`, whose caller
                    // promises the features.
                    unsafe { $modes::<DRAG, OWN, PLAIN, FIXED>(ctx, band, row, out, lo) }
                }
            }
            row_variant(Rows(()), ctx, band, row, out, lo, own);
        }
    )*};
}
row_entries! {
    row_avx512, row_modes_avx512: "avx512f,avx512vl,avx2,fma", f32, Avx512(());
    row_avx512_f64, row_modes_avx512_f64: "avx512f,avx512vl,avx2,fma", f64, Avx512F64(());
    row_avx2, row_modes_avx2: "avx2,fma", f32, Avx2(());
    row_avx2_f64, row_modes_avx2_f64: "avx2,fma", f64, Avx2F64(());
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
    lattice_band_avx512_f64: "avx512f,avx512vl,avx2,fma", f64, Avx512F64(());
    lattice_band_avx2_f64: "avx2,fma", f64, Avx2F64(());
}

/// The tear scan's `row_may_tear`, compiled for AVX2 and FMA.
///
/// # Safety
/// As for `row_avx2`.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn row_may_tear_avx2<E: Real, const FIXED: bool>(
    state: &State<E>,
    ends: (usize, usize, usize),
    alive: Option<&[E]>,
    scan2: E,
) -> bool {
    row_may_tear::<E, FIXED>(state, ends, alive, scan2)
}

/// The tear scan's `row_may_tear`, compiled for AVX-512.
///
/// # Safety
/// As for `row_avx512`.
#[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
pub(super) unsafe fn row_may_tear_avx512<E: Real, const FIXED: bool>(
    state: &State<E>,
    ends: (usize, usize, usize),
    alive: Option<&[E]>,
    scan2: E,
) -> bool {
    row_may_tear::<E, FIXED>(state, ends, alive, scan2)
}

/// `any_faster`, compiled for AVX2.
///
/// # Safety
/// As for `row_avx2`.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn any_faster_avx2<E: Real>(v: [&[E]; 3], limit2: E) -> bool {
    any_faster(v, limit2)
}

/// A pass over rows (`RowsPass::resolve`: contact, the colliders), compiled for
/// AVX2 and FMA.
///
/// # Safety
/// As for `row_avx2`.
#[target_feature(enable = "avx2,fma")]
#[inline(never)]
pub(super) unsafe fn rows_avx2<E: Real, P: RowsPass<E> + ?Sized>(
    pass: &P,
    out: &mut Out<E>,
    first: usize,
    rows: impl Iterator<Item = usize>,
) {
    pass.rows(out, first, rows)
}

/// A pass over rows (`RowsPass::resolve`), compiled for AVX-512.
///
/// # Safety
/// As for `row_avx512`.
#[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
#[inline(never)]
pub(super) unsafe fn rows_avx512<E: Real, P: RowsPass<E> + ?Sized>(
    pass: &P,
    out: &mut Out<E>,
    first: usize,
    rows: impl Iterator<Item = usize>,
) {
    pass.rows(out, first, rows)
}

/// The spring passes' `spring_sweep` compiled for a SIMD level, in each precision:
/// `name: target features, float type, lanes`.
macro_rules! spring_sweeps {
    ($($name:ident: $features:literal, $t:ty, $lanes:expr;)*) => {$(
        /// `spring_sweep` with these lanes and target features.
        ///
        /// # Safety
        /// The CPU must have the target features.
        #[target_feature(enable = $features)]
        #[inline(never)]
        pub(super) unsafe fn $name<const FIXED: bool>(
            out: &mut Out<$t>,
            base: usize,
            lines: &SweepLines<$t>,
        ) {
            spring_sweep::<_, FIXED>($lanes, out, base, lines)
        }
    )*};
}
spring_sweeps! {
    spring_sweep_avx2: "avx2,fma", f32, Avx2(());
    spring_sweep_avx2_f64: "avx2,fma", f64, Avx2F64(());
    spring_sweep_avx512: "avx512f,avx512vl,avx2,fma", f32, Avx512(());
    spring_sweep_avx512_f64: "avx512f,avx512vl,avx2,fma", f64, Avx512F64(());
}

/// The members of a [`Simd`] impl that are one intrinsic each: the lane type,
/// vector type and count, then the intrinsics for `splat`, `load`, `store`,
/// `add`, `sub`, `mul`, `mul_add`, `mul_sub` and `div`.
macro_rules! lanes {
    ($e:ty, $v:ty, $lanes:expr; $set1:ident, $load:ident, $store:ident, $add:ident, $sub:ident,
     $mul:ident, $fmadd:ident, $fmsub:ident, $div:ident) => {
        type E = $e;
        type V = $v;
        const LANES: usize = $lanes;
        #[inline(always)]
        fn splat(self, a: $e) -> $v {
            unsafe { $set1(a) }
        }
        #[inline(always)]
        unsafe fn load(self, p: *const $e) -> $v {
            unsafe { $load(p) }
        }
        #[inline(always)]
        unsafe fn store(self, p: *mut $e, v: $v) {
            unsafe { $store(p, v) }
        }
        #[inline(always)]
        fn add(self, a: $v, b: $v) -> $v {
            unsafe { $add(a, b) }
        }
        #[inline(always)]
        fn sub(self, a: $v, b: $v) -> $v {
            unsafe { $sub(a, b) }
        }
        #[inline(always)]
        fn mul(self, a: $v, b: $v) -> $v {
            unsafe { $mul(a, b) }
        }
        #[inline(always)]
        fn mul_add(self, a: $v, b: $v, c: $v) -> $v {
            unsafe { $fmadd(a, b, c) }
        }
        #[inline(always)]
        fn mul_sub(self, a: $v, b: $v, c: $v) -> $v {
            unsafe { $fmsub(a, b, c) }
        }
        #[inline(always)]
        fn div(self, a: $v, b: $v) -> $v {
            unsafe { $div(a, b) }
        }
    };
}

/// [`Simd`]'s comparisons, select and root with AVX-512's mask registers:
/// `mask type, all lanes, compare, blend, sqrt`.
macro_rules! masked_compares {
    ($mask:ty, $all:expr, $cmp:ident, $blend:ident, $sqrt:ident) => {
        type Mask = $mask;
        #[inline(always)]
        fn lt(self, a: Self::V, b: Self::V) -> $mask {
            unsafe { $cmp::<_CMP_LT_OQ>(a, b) }
        }
        #[inline(always)]
        fn le(self, a: Self::V, b: Self::V) -> $mask {
            unsafe { $cmp::<_CMP_LE_OQ>(a, b) }
        }
        #[inline(always)]
        fn gt(self, a: Self::V, b: Self::V) -> $mask {
            unsafe { $cmp::<_CMP_GT_OQ>(a, b) }
        }
        #[inline(always)]
        fn select(self, m: $mask, a: Self::V, b: Self::V) -> Self::V {
            // (The blend takes its second operand where the mask is set.)
            unsafe { $blend(m, b, a) }
        }
        #[inline(always)]
        fn both(self, a: $mask, b: $mask) -> $mask {
            a & b
        }
        #[inline(always)]
        fn but_not(self, a: $mask, b: $mask) -> $mask {
            a & !b
        }
        #[inline(always)]
        fn either(self, a: $mask, b: $mask) -> $mask {
            a | b
        }
        #[inline(always)]
        fn any(self, m: $mask) -> bool {
            m != 0
        }
        #[inline(always)]
        fn all(self, m: $mask) -> bool {
            m == $all
        }
        #[inline(always)]
        fn sqrt(self, a: Self::V) -> Self::V {
            unsafe { $sqrt(a) }
        }
    };
}

/// [`Simd`]'s comparisons, select and root with AVX2's vector masks: `all
/// lanes' sign bits, compare, blend, sign bits, sqrt, and, and-not, or`.
macro_rules! vector_compares {
    ($all:expr, $cmp:ident, $blend:ident, $signs:ident, $sqrt:ident, $and:ident, $andnot:ident, $or:ident) => {
        type Mask = Self::V;
        #[inline(always)]
        fn lt(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { $cmp::<_CMP_LT_OQ>(a, b) }
        }
        #[inline(always)]
        fn le(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { $cmp::<_CMP_LE_OQ>(a, b) }
        }
        #[inline(always)]
        fn gt(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { $cmp::<_CMP_GT_OQ>(a, b) }
        }
        #[inline(always)]
        fn select(self, m: Self::V, a: Self::V, b: Self::V) -> Self::V {
            // (The blend takes its second operand where the mask is set.)
            unsafe { $blend(b, a, m) }
        }
        #[inline(always)]
        fn both(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { $and(a, b) }
        }
        #[inline(always)]
        fn but_not(self, a: Self::V, b: Self::V) -> Self::V {
            // (`andnot` negates its first operand.)
            unsafe { $andnot(b, a) }
        }
        #[inline(always)]
        fn either(self, a: Self::V, b: Self::V) -> Self::V {
            unsafe { $or(a, b) }
        }
        #[inline(always)]
        fn any(self, m: Self::V) -> bool {
            unsafe { $signs(m) != 0 }
        }
        #[inline(always)]
        fn all(self, m: Self::V) -> bool {
            unsafe { $signs(m) == $all }
        }
        #[inline(always)]
        fn sqrt(self, a: Self::V) -> Self::V {
            unsafe { $sqrt(a) }
        }
    };
}

// SAFETY (all intrinsics below): an `Avx512`, `Avx2`, `Avx512F64` or `Avx2F64`
// value exists only inside the entry points above, which run only on CPUs with
// those features.
impl Simd for Avx512 {
    lanes!(f32, __m512, 16;
        _mm512_set1_ps, _mm512_loadu_ps, _mm512_storeu_ps, _mm512_add_ps, _mm512_sub_ps,
        _mm512_mul_ps, _mm512_fmadd_ps, _mm512_fmsub_ps, _mm512_div_ps);
    masked_compares!(
        __mmask16,
        0xffff,
        _mm512_cmp_ps_mask,
        _mm512_mask_blend_ps,
        _mm512_sqrt_ps
    );
    #[inline(always)]
    fn rsqrt(self, x: __m512) -> __m512 {
        unsafe {
            // 14-bit estimate, then one Newton step: y (1.5 - 0.5 x y²).
            let y = _mm512_rsqrt14_ps(x);
            let hx = _mm512_mul_ps(x, _mm512_set1_ps(0.5));
            let t = _mm512_fnmadd_ps(_mm512_mul_ps(hx, y), y, _mm512_set1_ps(1.5));
            _mm512_mul_ps(y, t)
        }
    }
    #[inline(always)]
    fn rsqrt_or_zero(self, x: __m512, eps: f32) -> __m512 {
        unsafe {
            let y = self.rsqrt(x);
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
    fn any_positive(self, m: __m512) -> bool {
        unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(m, _mm512_setzero_ps()) != 0 }
    }
    #[inline(always)]
    fn fixed_sub(self, a: __m512, b: __m512) -> __m512 {
        unsafe {
            _mm512_cvtepi32_ps(_mm512_sub_epi32(
                _mm512_castps_si512(a),
                _mm512_castps_si512(b),
            ))
        }
    }
    #[inline(always)]
    fn fixed_add(self, x: __m512, t: __m512) -> __m512 {
        unsafe {
            _mm512_castsi512_ps(_mm512_add_epi32(
                _mm512_castps_si512(x),
                _mm512_cvtps_epi32(t),
            ))
        }
    }
    #[inline(always)]
    fn swap_pairs<const DC: usize>(self, v: __m512) -> __m512 {
        unsafe {
            if DC == 1 {
                _mm512_permute_ps::<0xB1>(v)
            } else {
                _mm512_permute_ps::<0x4E>(v)
            }
        }
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
    const UNROLL_AXES: bool = true;
    lanes!(f32, __m256, 8;
        _mm256_set1_ps, _mm256_loadu_ps, _mm256_storeu_ps, _mm256_add_ps, _mm256_sub_ps,
        _mm256_mul_ps, _mm256_fmadd_ps, _mm256_fmsub_ps, _mm256_div_ps);
    vector_compares!(
        0xff,
        _mm256_cmp_ps,
        _mm256_blendv_ps,
        _mm256_movemask_ps,
        _mm256_sqrt_ps,
        _mm256_and_ps,
        _mm256_andnot_ps,
        _mm256_or_ps
    );
    #[inline(always)]
    fn rsqrt(self, x: __m256) -> __m256 {
        unsafe {
            // 12-bit estimate, then one Newton step: y (1.5 - 0.5 x y²).
            let y = _mm256_rsqrt_ps(x);
            let hx = _mm256_mul_ps(x, _mm256_set1_ps(0.5));
            let t = _mm256_fnmadd_ps(_mm256_mul_ps(hx, y), y, _mm256_set1_ps(1.5));
            _mm256_mul_ps(y, t)
        }
    }
    #[inline(always)]
    fn rsqrt_or_zero(self, x: __m256, eps: f32) -> __m256 {
        unsafe {
            let y = self.rsqrt(x);
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
    fn any_positive(self, m: __m256) -> bool {
        unsafe {
            let ok = _mm256_cmp_ps::<_CMP_GT_OQ>(m, _mm256_setzero_ps());
            _mm256_movemask_ps(ok) != 0
        }
    }
    #[inline(always)]
    fn fixed_sub(self, a: __m256, b: __m256) -> __m256 {
        unsafe {
            _mm256_cvtepi32_ps(_mm256_sub_epi32(
                _mm256_castps_si256(a),
                _mm256_castps_si256(b),
            ))
        }
    }
    #[inline(always)]
    fn fixed_add(self, x: __m256, t: __m256) -> __m256 {
        unsafe {
            _mm256_castsi256_ps(_mm256_add_epi32(
                _mm256_castps_si256(x),
                _mm256_cvtps_epi32(t),
            ))
        }
    }
    #[inline(always)]
    fn swap_pairs<const DC: usize>(self, v: __m256) -> __m256 {
        unsafe {
            if DC == 1 {
                _mm256_permute_ps::<0xB1>(v)
            } else {
                _mm256_permute_ps::<0x4E>(v)
            }
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

impl Simd for Avx512F64 {
    lanes!(f64, __m512d, 8;
        _mm512_set1_pd, _mm512_loadu_pd, _mm512_storeu_pd, _mm512_add_pd, _mm512_sub_pd,
        _mm512_mul_pd, _mm512_fmadd_pd, _mm512_fmsub_pd, _mm512_div_pd);
    masked_compares!(
        __mmask8,
        0xff,
        _mm512_cmp_pd_mask,
        _mm512_mask_blend_pd,
        _mm512_sqrt_pd
    );
    #[inline(always)]
    fn rsqrt(self, x: __m512d) -> __m512d {
        unsafe {
            // AVX-512's 14-bit estimate `y` and one fourth-order step: with `e = 1 -
            // x y²`, `y (1 + e/2 + 3e²/8 + 5e³/16)`, whose error `35/128 e⁴` is
            // under 2^-57. `y²` is taken exactly (as `hi + lo`) so that `e` is
            // good to far under an ulp, and the last sum's rounding leaves the
            // result within an ulp of `1 / sqrt(x)`: a square root and a division
            // had bound the float64 kernels on an Intel core.
            let y = _mm512_rsqrt14_pd(x);
            let hi = _mm512_mul_pd(y, y);
            let lo = _mm512_fmsub_pd(y, y, hi);
            let one = _mm512_set1_pd(1.0);
            let e = _mm512_fnmadd_pd(x, lo, _mm512_fnmadd_pd(x, hi, one));
            let p = _mm512_fmadd_pd(e, _mm512_set1_pd(5.0 / 16.0), _mm512_set1_pd(3.0 / 8.0));
            let p = _mm512_fmadd_pd(p, e, _mm512_set1_pd(0.5));
            _mm512_fmadd_pd(_mm512_mul_pd(y, e), p, y)
        }
    }
    #[inline(always)]
    fn rsqrt_or_zero(self, x: __m512d, eps: f64) -> __m512d {
        unsafe {
            let y = self.rsqrt(x);
            // 0 at or under `eps` (or NaN), and at infinity, as `1 / sqrt` gives
            // (where the step would give `inf · 0`, NaN).
            let ok = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(x, _mm512_set1_pd(eps));
            let ok = _mm512_mask_cmp_pd_mask::<_CMP_LT_OQ>(ok, x, _mm512_set1_pd(f64::INFINITY));
            _mm512_maskz_mov_pd(ok, y)
        }
    }
    #[inline(always)]
    fn keep_if_positive(self, m: __m512d, a: __m512d) -> __m512d {
        unsafe {
            let ok = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(m, _mm512_setzero_pd());
            _mm512_maskz_mov_pd(ok, a)
        }
    }
    #[inline(always)]
    fn any_positive(self, m: __m512d) -> bool {
        unsafe { _mm512_cmp_pd_mask::<_CMP_GT_OQ>(m, _mm512_setzero_pd()) != 0 }
    }
    // Float64 positions are floats in metres (`Precision::Double`): these two
    // are never on a hot path, so they go lane by lane.
    #[inline(always)]
    fn fixed_sub(self, a: __m512d, b: __m512d) -> __m512d {
        by_lanes::<_, 8>(a, b, f64::fixed_sub)
    }
    #[inline(always)]
    fn fixed_add(self, x: __m512d, t: __m512d) -> __m512d {
        by_lanes::<_, 8>(x, t, f64::fixed_add)
    }
    #[inline(always)]
    fn swap_pairs<const DC: usize>(self, v: __m512d) -> __m512d {
        unsafe {
            if DC == 1 {
                _mm512_permute_pd::<0x55>(v)
            } else {
                _mm512_shuffle_f64x2::<0xB1>(v, v)
            }
        }
    }
    #[inline(always)]
    fn shift1(self, prev: __m512d, cur: __m512d) -> __m512d {
        unsafe {
            _mm512_castsi512_pd(_mm512_alignr_epi64::<7>(
                _mm512_castpd_si512(cur),
                _mm512_castpd_si512(prev),
            ))
        }
    }
    #[inline(always)]
    fn shift2(self, prev: __m512d, cur: __m512d) -> __m512d {
        unsafe {
            _mm512_castsi512_pd(_mm512_alignr_epi64::<6>(
                _mm512_castpd_si512(cur),
                _mm512_castpd_si512(prev),
            ))
        }
    }
}

impl Simd for Avx2F64 {
    lanes!(f64, __m256d, 4;
        _mm256_set1_pd, _mm256_loadu_pd, _mm256_storeu_pd, _mm256_add_pd, _mm256_sub_pd,
        _mm256_mul_pd, _mm256_fmadd_pd, _mm256_fmsub_pd, _mm256_div_pd);
    vector_compares!(
        0xf,
        _mm256_cmp_pd,
        _mm256_blendv_pd,
        _mm256_movemask_pd,
        _mm256_sqrt_pd,
        _mm256_and_pd,
        _mm256_andnot_pd,
        _mm256_or_pd
    );
    #[inline(always)]
    fn rsqrt(self, x: __m256d) -> __m256d {
        // Correctly rounded, as the portable lanes: with a float32 estimate and
        // two steps to float64's 53 bits the jelly ran at 0.8x the speed (AVX2 on
        // an AMD EPYC).
        unsafe { _mm256_div_pd(_mm256_set1_pd(1.0), _mm256_sqrt_pd(x)) }
    }
    #[inline(always)]
    fn rsqrt_or_zero(self, x: __m256d, eps: f64) -> __m256d {
        unsafe {
            let y = self.rsqrt(x);
            let ok = _mm256_cmp_pd::<_CMP_GT_OQ>(x, _mm256_set1_pd(eps));
            _mm256_and_pd(ok, y)
        }
    }
    #[inline(always)]
    fn keep_if_positive(self, m: __m256d, a: __m256d) -> __m256d {
        unsafe {
            let ok = _mm256_cmp_pd::<_CMP_GT_OQ>(m, _mm256_setzero_pd());
            _mm256_and_pd(ok, a)
        }
    }
    #[inline(always)]
    fn any_positive(self, m: __m256d) -> bool {
        unsafe {
            let ok = _mm256_cmp_pd::<_CMP_GT_OQ>(m, _mm256_setzero_pd());
            _mm256_movemask_pd(ok) != 0
        }
    }
    // Float64 positions are floats in metres (`Precision::Double`): these two
    // are never on a hot path, so they go lane by lane.
    #[inline(always)]
    fn fixed_sub(self, a: __m256d, b: __m256d) -> __m256d {
        by_lanes::<_, 4>(a, b, f64::fixed_sub)
    }
    #[inline(always)]
    fn fixed_add(self, x: __m256d, t: __m256d) -> __m256d {
        by_lanes::<_, 4>(x, t, f64::fixed_add)
    }
    #[inline(always)]
    fn swap_pairs<const DC: usize>(self, v: __m256d) -> __m256d {
        unsafe {
            if DC == 1 {
                _mm256_permute_pd::<0b0101>(v)
            } else {
                _mm256_permute2f128_pd::<0x01>(v, v)
            }
        }
    }
    #[inline(always)]
    fn shift1(self, prev: __m256d, cur: __m256d) -> __m256d {
        unsafe {
            // [prev 2..4, cur 0..2], then per 128-bit half take 1 float up.
            let t = _mm256_permute2f128_pd::<0x21>(prev, cur);
            _mm256_castsi256_pd(_mm256_alignr_epi8::<8>(
                _mm256_castpd_si256(cur),
                _mm256_castpd_si256(t),
            ))
        }
    }
    #[inline(always)]
    fn shift2(self, prev: __m256d, cur: __m256d) -> __m256d {
        unsafe { _mm256_permute2f128_pd::<0x21>(prev, cur) }
    }
}

/// `f` of each pair of lanes of `a` and `b`, vectors of `N` float64 lanes.
#[inline(always)]
fn by_lanes<V: Copy, const N: usize>(a: V, b: V, f: impl Fn(f64, f64) -> f64) -> V {
    assert_eq!(size_of::<V>(), size_of::<[f64; N]>());
    // SAFETY: `V` is `N` float64 lanes (asserted: the same size), any bits valid.
    unsafe {
        let (a, b): ([f64; N], [f64; N]) =
            (std::mem::transmute_copy(&a), std::mem::transmute_copy(&b));
        std::mem::transmute_copy(&std::array::from_fn::<f64, N, _>(|i| f(a[i], b[i])))
    }
}

/// The AVX2 tokens (float32, float64) and the AVX-512 ones, where available.
#[cfg(test)]
pub(super) type Tokens = (Option<(Avx2, Avx2F64)>, Option<(Avx512, Avx512F64)>);

/// The four vector tokens, where this CPU has their instructions, for the
/// conformance suite that runs every law on every lane width
/// (`super::conformance`). Outside the entry points the intrinsics are called,
/// not inlined: slower, the same results.
#[cfg(test)]
pub(super) fn tokens() -> Tokens {
    let avx2 = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
    let avx512 =
        avx2 && is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl");
    (
        avx2.then_some((Avx2(()), Avx2F64(()))),
        avx512.then_some((Avx512(()), Avx512F64(()))),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lanes `0, 1, ..` of `N` lanes after `swap_pairs::<DC>` on level `s`.
    macro_rules! swapped {
        ($s:expr, $t:ty, $n:literal, $dc:literal) => {{
            let s = $s;
            let lanes: [$t; $n] = std::array::from_fn(|l| l as $t);
            let mut out = [0.0; $n];
            // SAFETY: `N` lanes read from and written to arrays of `N`.
            unsafe {
                s.store(
                    out.as_mut_ptr(),
                    s.swap_pairs::<$dc>(s.load(lanes.as_ptr())),
                )
            };
            out.map(|l| l as usize)
        }};
    }

    #[target_feature(enable = "avx2,fma")]
    fn swapped_avx2() -> [Vec<usize>; 4] {
        [
            swapped!(Avx2(()), f32, 8, 1).to_vec(),
            swapped!(Avx2(()), f32, 8, 2).to_vec(),
            swapped!(Avx2F64(()), f64, 4, 1).to_vec(),
            swapped!(Avx2F64(()), f64, 4, 2).to_vec(),
        ]
    }

    #[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
    fn swapped_avx512() -> [Vec<usize>; 4] {
        [
            swapped!(Avx512(()), f32, 16, 1).to_vec(),
            swapped!(Avx512(()), f32, 16, 2).to_vec(),
            swapped!(Avx512F64(()), f64, 8, 1).to_vec(),
            swapped!(Avx512F64(()), f64, 8, 2).to_vec(),
        ]
    }

    /// Each level's `swap_pairs` exchanges lanes `l` and `l ^ DC`, as the portable
    /// lanes do: the stretch limit along rows reads a spring's other end so.
    #[test]
    fn pairs_of_lanes_swap_as_the_rule_says() {
        let rule = |n: usize, dc: usize| (0..n).map(|l| l ^ dc).collect::<Vec<_>>();
        let expected = [rule(8, 1), rule(8, 2), rule(4, 1), rule(4, 2)];
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            // SAFETY: the CPU has the features (checked).
            assert_eq!(unsafe { swapped_avx2() }, expected);
        }
        if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl") {
            let expected = [rule(16, 1), rule(16, 2), rule(8, 1), rule(8, 2)];
            // SAFETY: as above.
            assert_eq!(unsafe { swapped_avx512() }, expected);
        }
    }

    /// `Avx512F64::rsqrt_or_zero` on the lanes of `x`.
    #[target_feature(enable = "avx512f,avx512vl,avx2,fma")]
    fn rsqrt_avx512_f64(x: [f64; 8], eps: f64) -> [f64; 8] {
        let s = Avx512F64(());
        // SAFETY: 8 float64 lanes read from and written to arrays of 8.
        unsafe {
            let y = s.rsqrt_or_zero(s.load(x.as_ptr()), eps);
            let mut out = [0.0; 8];
            s.store(out.as_mut_ptr(), y);
            out
        }
    }

    /// The AVX-512 float64 reciprocal square root (an estimate and one
    /// fourth-order step) is within an ulp of the exact `1 / sqrt(x)` over
    /// float64's range of squared lengths (measured 0.81 ulp; `1.0 / x.sqrt()`,
    /// which rounds twice, 1.46), and 0 at or under `eps`. A second-order (Newton)
    /// step in place of the fourth-order one leaves ~2^-28 relative error, about
    /// 2^25 ulp, and fails; so does `y²` rounded before `e` (1.12 ulp).
    #[test]
    fn float64_reciprocal_root_is_within_an_ulp() {
        if !(is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512vl")
            && is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("fma"))
        {
            println!("no AVX-512 on this CPU: nothing to test");
            return;
        }
        // How far `y` is from the exact `1 / sqrt(x)`, in ulps of `y`: its
        // relative error is about `ε / 2` with `ε = 1 - x y²`, computed exactly
        // enough (`y²` and `x hi` as sums of two floats) not to need a wider type.
        let ulps_from_exact = |x: f64, y: f64| {
            let hi = y * y;
            let lo = y.mul_add(y, -hi);
            let p = x * hi;
            let p_lo = x.mul_add(hi, -p);
            let eps = ((1.0 - p) - p_lo) - x * lo;
            let ulp = f64::from_bits(y.to_bits() + 1) - y;
            (0.5 * eps * y / ulp).abs()
        };
        // The correctly rounded reference, for scale: `1 / sqrt(x)` rounds twice.
        let mut reference: f64 = 0.0;
        let mut worst: f64 = 0.0;
        // Mantissas from a fixed sequence, exponents from 2^-1000 to 2^1000.
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        for _ in 0..200_000 / 8 {
            let x: [f64; 8] = std::array::from_fn(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let mantissa = 1.0 + (state >> 11) as f64 / (1u64 << 53) as f64;
                let exponent = ((state >> 3) % 2001) as i32 - 1000;
                mantissa * 2f64.powi(exponent)
            });
            // SAFETY: the CPU has the features (checked above).
            let y = unsafe { rsqrt_avx512_f64(x, 0.0) };
            for x in x {
                reference = reference.max(ulps_from_exact(x, 1.0 / x.sqrt()));
            }
            for (x, y) in x.into_iter().zip(y) {
                worst = worst.max(ulps_from_exact(x, y));
            }
        }
        println!("worst: {worst:.3} ulp from the exact value (1 / sqrt: {reference:.3})");
        assert!(worst <= 1.0, "{worst} ulp from 1 / sqrt(x)");
        // 0 where the portable lanes' `1 / sqrt` is 0 or the lane is left out:
        // at or under `eps`, NaN, infinity.
        let edges = [
            1e-20,
            0.5e-20,
            -1.0,
            f64::NAN,
            f64::INFINITY,
            2e-20,
            4.0,
            1e300,
        ];
        // SAFETY: as above.
        let y = unsafe { rsqrt_avx512_f64(edges, 1e-20) };
        assert_eq!(&y[..5], &[0.0; 5], "at or under eps, NaN, infinity");
        assert_eq!(y[6], 0.5);
        assert!(y[5..].iter().all(|&y| y > 0.0 && y.is_finite()));
    }
}
