//! Lanes for the physics every engine shares but the fast engines apply to many
//! particles at once (contact and friction, [`super::laws::Contact`]).
//! The physics is written once over [`Lanes`]: `f64` for one particle (the f64
//! engine), [`Floats`] for a block of them (the grid and lattice kernels). Branches
//! become per-lane selects, so each lane computes exactly what the `f64` version
//! computes for its particle (IEEE operations, no fused multiply-adds): in float64
//! lanes the fast engines' contact agrees with the f64 engine's bit for bit; in
//! float32 lanes (the ground's friction in a float32 kernel, whose velocities are
//! float32) it is the same arithmetic, rounded to float32.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

use glam::DVec3;

/// Numbers of one particle (`f64`) or of a block of particles ([`Floats`]).
pub(crate) trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// Per lane, a yes or no.
    type Mask: Copy;
    /// `x` in every lane, of lanes like `self` (whose value is not read: it
    /// stands for the kind of lanes, which for a fast kernel's vectors carries the
    /// proof that the CPU has their instructions).
    fn splat(self, x: f64) -> Self;
    fn sqrt(self) -> Self;
    fn lt(self, other: Self) -> Self::Mask;
    fn le(self, other: Self) -> Self::Mask;
    fn gt(self, other: Self) -> Self::Mask;
    /// Whether any lane says yes.
    fn any(m: Self::Mask) -> bool;
    /// Whether every lane says yes.
    fn all(m: Self::Mask) -> bool;

    /// `a` in the lanes where `m` says yes, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;

    /// `self * b + c`: rounded twice here, as the reference rounds; the vector
    /// kernels' lanes fuse it.
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        self * b + c
    }
    /// `self * b - c`, fused where [`Lanes::mul_add`] is.
    #[inline(always)]
    fn mul_sub(self, b: Self, c: Self) -> Self {
        self * b - c
    }
    /// `1 / sqrt(self)`, for `self` positive and finite; the vector kernels take
    /// an estimate refined by a Newton step.
    #[inline(always)]
    fn rsqrt(self) -> Self {
        self.splat(1.0) / self.sqrt()
    }
    /// [`Lanes::rsqrt`] where `self > eps2`, else 0 (a degenerate length has no
    /// direction).
    #[inline(always)]
    fn rsqrt_or_zero(self, eps2: f64) -> Self {
        Self::select(self.gt(self.splat(eps2)), self.rsqrt(), self.splat(0.0))
    }
    /// `a` where `self > 0`, else 0.
    #[inline(always)]
    fn keep_if_positive(self, a: Self) -> Self {
        Self::select(self.gt(self.splat(0.0)), a, self.splat(0.0))
    }
    /// The greater of the two (`other` on ties and NaN).
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        Self::select(self.gt(other), self, other)
    }
    /// The lesser of the two (`other` on ties and NaN).
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        Self::select(self.lt(other), self, other)
    }
    /// `-self` where `self < 0`, else `self`.
    #[inline(always)]
    fn abs(self) -> Self {
        Self::select(self.lt(self.splat(0.0)), self.splat(0.0) - self, self)
    }
    /// -1 where `self < 0`, else 1.
    #[inline(always)]
    fn sign(self) -> Self {
        Self::select(self.lt(self.splat(0.0)), self.splat(-1.0), self.splat(1.0))
    }

    /// Yes where both say yes.
    fn both(a: Self::Mask, b: Self::Mask) -> Self::Mask;

    /// How many lanes there are.
    const WIDTH: usize;
    /// Lane `i`'s value, as f64.
    fn lane(self, i: usize) -> f64;
    /// The lanes with lane `i` set to `x`.
    fn with_lane(self, i: usize, x: f64) -> Self;
    /// Whether lane `i` of `m` says yes.
    fn lane_says(m: Self::Mask, i: usize) -> bool;
}

impl Lanes for f64 {
    type Mask = bool;
    #[inline(always)]
    fn splat(self, x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn lt(self, other: Self) -> bool {
        self < other
    }
    #[inline(always)]
    fn le(self, other: Self) -> bool {
        self <= other
    }
    #[inline(always)]
    fn gt(self, other: Self) -> bool {
        self > other
    }
    #[inline(always)]
    fn any(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn all(m: bool) -> bool {
        m
    }

    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
    #[inline(always)]
    fn both(a: bool, b: bool) -> bool {
        a & b
    }

    const WIDTH: usize = 1;
    #[inline(always)]
    fn lane(self, _: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn with_lane(self, _: usize, x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn lane_says(m: bool, _: usize) -> bool {
        m
    }
}

/// A float a lane holds: `f64` or `f32`.
pub(crate) trait LaneFloat:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
{
    /// The float's bits as an unsigned integer of its width.
    type Word: Copy
        + Eq
        + BitAnd<Output = Self::Word>
        + BitOr<Output = Self::Word>
        + Not<Output = Self::Word>;
    /// All zeros and all ones.
    const NO: Self::Word;
    const YES: Self::Word;
    /// `x` rounded to this float.
    fn of_f64(x: f64) -> Self;
    /// This float as f64 (exact).
    fn to_f64(self) -> f64;
    fn root(self) -> Self;
    fn is_nan(self) -> bool;
    fn word(self) -> Self::Word;
    fn of_word(w: Self::Word) -> Self;
    /// All ones if `yes`, else all zeros.
    fn mask(yes: bool) -> Self::Word;

    /// `a` where `m` is all ones, `b` where it is all zeros, bit for bit: the
    /// select every lane and every fast engine's write uses (as arrays of `bool`
    /// and branches the compiler had made byte shuffles and jumps).
    #[inline(always)]
    fn pick(m: Self::Word, a: Self, b: Self) -> Self {
        Self::of_word((a.word() & m) | (b.word() & !m))
    }

    /// `a` if `yes`, else `b`, bit for bit, without a branch.
    #[inline(always)]
    fn select(yes: bool, a: Self, b: Self) -> Self {
        Self::pick(Self::mask(yes), a, b)
    }
}

macro_rules! lane_float {
    ($t:ty, $word:ty) => {
        impl LaneFloat for $t {
            type Word = $word;
            const NO: $word = 0;
            const YES: $word = !0;
            #[inline(always)]
            fn of_f64(x: f64) -> Self {
                x as $t
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                f64::from(self)
            }
            #[inline(always)]
            fn root(self) -> Self {
                self.sqrt()
            }
            #[inline(always)]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline(always)]
            fn word(self) -> $word {
                self.to_bits()
            }
            #[inline(always)]
            fn of_word(w: $word) -> Self {
                <$t>::from_bits(w)
            }
            #[inline(always)]
            fn mask(yes: bool) -> $word {
                <$word>::from(yes).wrapping_neg()
            }
        }
    };
}
lane_float!(f64, u64);
lane_float!(f32, u32);

/// `N` lanes of a float `F`: plain arrays, vectorised by the compiler for the
/// target features of the function they are inlined into.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Floats<F, const N: usize>(pub [F; N]);

impl<F: LaneFloat, const N: usize> Floats<F, N> {
    /// `x` (rounded to `F`) in every lane.
    #[inline(always)]
    pub(crate) fn of(x: f64) -> Self {
        Floats([F::of_f64(x); N])
    }
}

/// `N` lanes of f64.
#[cfg(test)]
pub(crate) type F64s<const N: usize> = Floats<f64, N>;

macro_rules! lanewise {
    ($trait:ident, $method:ident, $op:tt) => {
        impl<F: LaneFloat, const N: usize> $trait for Floats<F, N> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, other: Self) -> Self {
                Floats(std::array::from_fn(|i| self.0[i] $op other.0[i]))
            }
        }
    };
}
lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl<F: LaneFloat, const N: usize> Lanes for Floats<F, N> {
    /// All ones where yes, all zeros where no, as a vector compare gives them: the
    /// compiler turned masks of `bool`s into byte shuffles.
    type Mask = [F::Word; N];
    #[inline(always)]
    fn splat(self, x: f64) -> Self {
        Self::of(x)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // (`from_fn`, not `map`: `map` was left a call in the hot loop.)
        Floats(std::array::from_fn(|i| self.0[i].root()))
    }
    #[inline(always)]
    fn lt(self, other: Self) -> Self::Mask {
        std::array::from_fn(|i| F::mask(self.0[i] < other.0[i]))
    }
    #[inline(always)]
    fn le(self, other: Self) -> Self::Mask {
        std::array::from_fn(|i| F::mask(self.0[i] <= other.0[i]))
    }
    #[inline(always)]
    fn gt(self, other: Self) -> Self::Mask {
        std::array::from_fn(|i| F::mask(self.0[i] > other.0[i]))
    }
    #[inline(always)]
    fn any(m: Self::Mask) -> bool {
        m.iter().fold(F::NO, |any, &m| any | m) != F::NO
    }
    #[inline(always)]
    fn all(m: Self::Mask) -> bool {
        m.iter().fold(F::YES, |all, &m| all & m) == F::YES
    }

    #[inline(always)]
    fn select(m: Self::Mask, a: Self, b: Self) -> Self {
        Floats(std::array::from_fn(|i| F::pick(m[i], a.0[i], b.0[i])))
    }
    #[inline(always)]
    fn both(a: Self::Mask, b: Self::Mask) -> Self::Mask {
        std::array::from_fn(|i| a[i] & b[i])
    }

    const WIDTH: usize = N;
    #[inline(always)]
    fn lane(self, i: usize) -> f64 {
        self.0[i].to_f64()
    }
    #[inline(always)]
    fn with_lane(mut self, i: usize, x: f64) -> Self {
        self.0[i] = F::of_f64(x);
        self
    }
    #[inline(always)]
    fn lane_says(m: Self::Mask, i: usize) -> bool {
        m[i] != F::NO
    }
}

/// A 3-vector of lanes, with the operations of [`DVec3`] that the shared physics
/// uses, computed in the same order as glam computes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct V3<T> {
    pub x: T,
    pub y: T,
    pub z: T,
}

impl<T: Lanes> V3<T> {
    /// `v` in every lane, of lanes like `like` ([`Lanes::splat`]).
    #[inline(always)]
    pub fn splat(like: T, v: DVec3) -> Self {
        V3 {
            x: like.splat(v.x),
            y: like.splat(v.y),
            z: like.splat(v.z),
        }
    }
    /// `x x' + y y' + z z'`, summed in that order (fused where the lanes fuse).
    #[inline(always)]
    pub fn dot(self, o: Self) -> T {
        o.z.mul_add(self.z, o.y.mul_add(self.y, self.x * o.x))
    }
    /// The cross product, each component `a b - c d` fused where the lanes fuse.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3 {
            x: self.y.mul_sub(o.z, self.z * o.y),
            y: self.z.mul_sub(o.x, self.x * o.z),
            z: self.x.mul_sub(o.y, self.y * o.x),
        }
    }
    /// The components of `f(self, o)` axis by axis.
    #[inline(always)]
    pub fn zip(self, o: Self, f: impl Fn(T, T) -> T) -> Self {
        V3 {
            x: f(self.x, o.x),
            y: f(self.y, o.y),
            z: f(self.z, o.z),
        }
    }
    #[inline(always)]
    pub fn length(self) -> T {
        self.dot(self).sqrt()
    }
    #[inline(always)]
    pub fn scale(self, s: T) -> Self {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    pub fn over(self, s: T) -> Self {
        V3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
    /// Turned by the unit quaternion `q` (glam's formula: `v (w² - |b|²) + 2 (v·b)
    /// b + 2 w (b × v)`, with `b` the quaternion's vector part).
    #[inline(always)]
    pub fn rotated(self, q: glam::DQuat) -> Self {
        let like = self.x;
        let b = V3::splat(like, DVec3::new(q.x, q.y, q.z));
        let b2 = q.x * q.x + q.y * q.y + q.z * q.z;
        let along = self.dot(b) * like.splat(2.0);
        self.scale(like.splat(q.w * q.w - b2))
            + b.scale(along)
            + b.cross(self).scale(like.splat(2.0 * q.w))
    }
    /// `a` in the lanes where `m` says yes, else `b`.
    #[inline(always)]
    pub fn select(m: T::Mask, a: Self, b: Self) -> Self {
        V3 {
            x: T::select(m, a.x, b.x),
            y: T::select(m, a.y, b.y),
            z: T::select(m, a.z, b.z),
        }
    }
}

impl<T: Lanes> Add for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<T: Lanes> Sub for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl From<DVec3> for V3<f64> {
    #[inline(always)]
    fn from(v: DVec3) -> Self {
        V3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

impl From<V3<f64>> for DVec3 {
    #[inline(always)]
    fn from(v: V3<f64>) -> Self {
        DVec3::new(v.x, v.y, v.z)
    }
}
