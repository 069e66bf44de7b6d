// The helpers generated code calls: sine and cosine (a range-reduced polynomial, branch-light, within a few
// ulps of libm, next to multiples of π/2 too; much faster than the platform libm for the angles a robot sees;
// the sine of −0 is +0) and the square root.
// `no_std`, no allocation, no panics. The same text is compiled into embedyn-runtime and copied into every
// standalone crate `embedyn generate` writes, so both paths compute bit-identical results.

/// The scalar operations generated code needs, for `f64`, `f32` and the lane types of them (`F64x4`, …).
pub trait Float: Copy {
    fn sincos(self) -> (Self, Self);
    /// Sines and cosines of `N` angles at once (see [`sincos_batch_f64`]).
    fn sincos_batch<const N: usize>(x: [Self; N]) -> ([Self; N], [Self; N]);
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// `if lhs > rhs { then } else { otherwise }` (lane by lane for the lane types).
    fn select_gt(lhs: Self, rhs: Self, then: Self, otherwise: Self) -> Self;
    /// Two values of this type side by side (see [`PairF64`]).
    type Pair: Copy
        + core::ops::Add<Output = Self::Pair>
        + core::ops::Sub<Output = Self::Pair>
        + core::ops::Mul<Output = Self::Pair>
        + core::ops::Div<Output = Self::Pair>
        + core::ops::Neg<Output = Self::Pair>;
    /// `(first, second)` side by side.
    fn pair(first: Self, second: Self) -> Self::Pair;
    /// The first of a pair.
    fn first(pair: Self::Pair) -> Self;
    /// The second of a pair.
    fn second(pair: Self::Pair) -> Self;
    /// `(first, -second)`: a mirrored branch's value whose sign is the other way (exact, as `-x` is).
    fn negate_second(pair: Self::Pair) -> Self::Pair;
}

/// `x ← −a x` for a symmetric `a` (`N × N`) and an `x` whose column `c` is zero but in the rows
/// `rows[starts[c]..starts[c + 1]]` (at least one): a forward-dynamics derivative `−M⁻¹ ∂τ` from its
/// factors, where `∂τ`'s column of a joint is zero but in its ancestors' and its subtree's rows. A loop,
/// not straight-line code: the product of a 38-DoF humanoid is 100k operations, and each row of `a`
/// read as a column (symmetry) is a contiguous run the compiler vectorizes: with AVX where the CPU has it
/// (a copy compiled with AVX, chosen as the twins of generated functions are, by `dispatch`; the same
/// operations in the same order, so the same bits): the floating ANYmal B's `aba_derivatives` 0.66× the
/// time of the baseline (2026-12-03).
#[inline(always)]
pub fn minus_symmetric_times_sparse<S, const N: usize>(
    a: &[[S; N]; N],
    x: &mut [[S; N]; N],
    rows: &[u32],
    starts: &[u32],
) where
    S: Copy + core::ops::Add<Output = S> + core::ops::Mul<Output = S> + core::ops::Neg<Output = S>,
{
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2", not(target_feature = "avx")))]
    if dispatch::avx() {
        // SAFETY: the CPU has AVX (`dispatch::avx` asked it), the one requirement of the function.
        #[allow(unused_unsafe)]
        return unsafe { dispatch::with_avx(|| symmetric_product(a, x, rows, starts)) };
    }
    symmetric_product(a, x, rows, starts)
}

/// The loop of [`minus_symmetric_times_sparse`]: a function of its own, inlined, so that the small
/// closure handed to `dispatch::with_avx` is inlined there with the loop (a closure holding the loop
/// itself stayed a call, compiled without AVX: 1.2× the time).
#[inline(always)]
fn symmetric_product<S, const N: usize>(
    a: &[[S; N]; N],
    x: &mut [[S; N]; N],
    rows: &[u32],
    starts: &[u32],
) where
    S: Copy + core::ops::Add<Output = S> + core::ops::Mul<Output = S> + core::ops::Neg<Output = S>,
{
    for c in 0..N {
        let column = &rows[starts[c] as usize..starts[c + 1] as usize];
        let Some((&first, rest)) = column.split_first() else {
            continue;
        };
        let (first, d) = (first as usize, x[first as usize][c]);
        let mut sum: [S; N] = core::array::from_fn(|i| a[first][i] * d);
        for &r in rest {
            let (r, d) = (r as usize, x[r as usize][c]);
            for (s, &m) in sum.iter_mut().zip(&a[r]) {
                *s = *s + m * d;
            }
        }
        for (row, s) in x.iter_mut().zip(sum) {
            row[c] = -s;
        }
    }
}

/// `(first, second)` as one pair: generated code computes the isomorphic branches of a tree (a robot's
/// left and right legs) side by side (see [`PairF64`]).
#[inline(always)]
pub fn pair<S: Float>(first: S, second: S) -> S::Pair {
    S::pair(first, second)
}

/// `(x, x)` as one pair.
#[inline(always)]
pub fn splat<S: Float>(x: S) -> S::Pair {
    S::pair(x, x)
}

/// The first value of a pair (`first::<S>(p)`).
#[inline(always)]
pub fn first<S: Float>(pair: S::Pair) -> S {
    S::first(pair)
}

/// The second value of a pair (`second::<S>(p)`).
#[inline(always)]
pub fn second<S: Float>(pair: S::Pair) -> S {
    S::second(pair)
}

/// `(first, -second)` of a pair (`negate_second::<S>(p)`).
#[inline(always)]
pub fn negate_second<S: Float>(pair: S::Pair) -> S::Pair {
    S::negate_second(pair)
}

/// `if lhs > rhs { then } else { otherwise }`, lane by lane for the lane types: generated lane functions
/// write their run-time pivoting with it.
#[inline(always)]
pub fn select_gt<S: Float>(lhs: S, rhs: S, then: S, otherwise: S) -> S {
    S::select_gt(lhs, rhs, then, otherwise)
}

/// Sine and cosine of `x` together.
#[inline(always)]
pub fn sincos<S: Float>(x: S) -> (S, S) {
    x.sincos()
}

/// Sines and cosines of all the joint angles of a function at once, at its start.
#[inline(always)]
pub fn sincos_batch<S: Float, const N: usize>(x: [S; N]) -> ([S; N], [S; N]) {
    S::sincos_batch(x)
}

#[inline(always)]
pub fn sqrt<S: Float>(x: S) -> S {
    x.sqrt()
}

#[inline(always)]
pub fn abs<S: Float>(x: S) -> S {
    x.abs()
}

impl Float for f64 {
    #[inline(always)]
    fn sincos(self) -> (f64, f64) {
        sincos_f64(self)
    }
    #[inline(always)]
    fn sincos_batch<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
        sincos_batch_f64(x)
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        libm::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> f64 {
        libm::fabs(self)
    }
    #[inline(always)]
    fn select_gt(lhs: f64, rhs: f64, then: f64, otherwise: f64) -> f64 {
        if lhs > rhs {
            then
        } else {
            otherwise
        }
    }
    type Pair = PairF64;
    #[inline(always)]
    fn pair(first: f64, second: f64) -> PairF64 {
        PairF64::new(first, second)
    }
    #[inline(always)]
    fn first(pair: PairF64) -> f64 {
        pair.first()
    }
    #[inline(always)]
    fn second(pair: PairF64) -> f64 {
        pair.second()
    }
    #[inline(always)]
    fn negate_second(pair: PairF64) -> PairF64 {
        pair.negate_second()
    }
}

impl Float for f32 {
    /// Evaluated in f64 and rounded once: accurate to the last f32 bit.
    #[inline(always)]
    fn sincos(self) -> (f32, f32) {
        let (s, c) = sincos_f64(self as f64);
        (s as f32, c as f32)
    }
    #[inline(always)]
    fn sincos_batch<const N: usize>(x: [f32; N]) -> ([f32; N], [f32; N]) {
        let (s, c) = sincos_batch_f64(x.map(|v| v as f64));
        (s.map(|v| v as f32), c.map(|v| v as f32))
    }
    #[inline(always)]
    fn sqrt(self) -> f32 {
        libm::sqrtf(self)
    }
    #[inline(always)]
    fn abs(self) -> f32 {
        libm::fabsf(self)
    }
    #[inline(always)]
    fn select_gt(lhs: f32, rhs: f32, then: f32, otherwise: f32) -> f32 {
        if lhs > rhs {
            then
        } else {
            otherwise
        }
    }
    type Pair = PairF32;
    #[inline(always)]
    fn pair(first: f32, second: f32) -> PairF32 {
        PairF32::new(first, second)
    }
    #[inline(always)]
    fn first(pair: PairF32) -> f32 {
        pair.first()
    }
    #[inline(always)]
    fn second(pair: PairF32) -> f32 {
        pair.second()
    }
    #[inline(always)]
    fn negate_second(pair: PairF32) -> PairF32 {
        pair.negate_second()
    }
}

/// Two numbers side by side, each operated on with the scalar's own IEEE arithmetic (no fused
/// multiply-add), so each is bit-identical to the scalar computation: what [`PairF64`] is where the target
/// has no two-lane SIMD type here, and the pair of the lane types.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ArrayPair<T>(pub [T; 2]);

macro_rules! array_pair_op {
    ($trait:ident, $method:ident, $op:tt) => {
        impl<T: Copy + core::ops::$trait<Output = T>> core::ops::$trait for ArrayPair<T> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, rhs: Self) -> Self {
                ArrayPair([self.0[0] $op rhs.0[0], self.0[1] $op rhs.0[1]])
            }
        }
    };
}
array_pair_op!(Add, add, +);
array_pair_op!(Sub, sub, -);
array_pair_op!(Mul, mul, *);
array_pair_op!(Div, div, /);
impl<T: Copy + core::ops::Neg<Output = T>> core::ops::Neg for ArrayPair<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        ArrayPair([-self.0[0], -self.0[1]])
    }
}

impl<T: Copy> ArrayPair<T> {
    /// `(first, second)`.
    #[inline(always)]
    pub fn new(first: T, second: T) -> Self {
        ArrayPair([first, second])
    }
    /// The first value.
    #[inline(always)]
    pub fn first(self) -> T {
        self.0[0]
    }
    /// The second value.
    #[inline(always)]
    pub fn second(self) -> T {
        self.0[1]
    }
}

impl<T: Copy + core::ops::Neg<Output = T>> ArrayPair<T> {
    /// `(first, -second)`.
    #[inline(always)]
    pub fn negate_second(self) -> Self {
        ArrayPair([self.0[0], -self.0[1]])
    }
}

/// Two `f64` in one SIMD register, for the isomorphic branches of a tree (a robot's left and right legs,
/// or arms) that generated code computes side by side: one instruction does the same step of both
/// branches. Each lane is the scalar's IEEE arithmetic (SSE2 `addpd`, `mulpd`, … are exact like `addsd`,
/// `mulsd`), so the results are bit-identical to the scalar code's. On x86-64 an SSE2 register (every
/// x86-64 has SSE2); elsewhere an [`ArrayPair`], which the compiler may or may not vectorize.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct PairF64(core::arch::x86_64::__m128d);

/// Two `f32` side by side (see [`PairF64`]): on x86-64 the two low lanes of an SSE register.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct PairF32(core::arch::x86_64::__m128);

// SSE2 is part of x86-64, so these intrinsics are always available; they take no pointers. (`unsafe` for
// the compilers before intrinsics of enabled target features became safe to call.)
#[cfg(target_arch = "x86_64")]
#[allow(unused_unsafe)]
mod pair_sse2 {
    use super::{PairF32, PairF64};
    use core::arch::x86_64::*;

    impl PairF64 {
        /// `(first, second)`.
        #[inline(always)]
        pub fn new(first: f64, second: f64) -> Self {
            PairF64(unsafe { _mm_set_pd(second, first) })
        }
        /// The first value.
        #[inline(always)]
        pub fn first(self) -> f64 {
            unsafe { _mm_cvtsd_f64(self.0) }
        }
        /// The second value.
        #[inline(always)]
        pub fn second(self) -> f64 {
            unsafe { _mm_cvtsd_f64(_mm_unpackhi_pd(self.0, self.0)) }
        }
        /// `(first, -second)`: the second lane's sign bit flipped.
        #[inline(always)]
        pub fn negate_second(self) -> Self {
            PairF64(unsafe { _mm_xor_pd(self.0, _mm_set_pd(-0.0, 0.0)) })
        }
    }
    impl core::ops::Add for PairF64 {
        type Output = Self;
        #[inline(always)]
        fn add(self, rhs: Self) -> Self {
            PairF64(unsafe { _mm_add_pd(self.0, rhs.0) })
        }
    }
    impl core::ops::Sub for PairF64 {
        type Output = Self;
        #[inline(always)]
        fn sub(self, rhs: Self) -> Self {
            PairF64(unsafe { _mm_sub_pd(self.0, rhs.0) })
        }
    }
    impl core::ops::Mul for PairF64 {
        type Output = Self;
        #[inline(always)]
        fn mul(self, rhs: Self) -> Self {
            PairF64(unsafe { _mm_mul_pd(self.0, rhs.0) })
        }
    }
    impl core::ops::Div for PairF64 {
        type Output = Self;
        #[inline(always)]
        fn div(self, rhs: Self) -> Self {
            PairF64(unsafe { _mm_div_pd(self.0, rhs.0) })
        }
    }
    /// The sign bits flipped, as the scalar `-x` does.
    impl core::ops::Neg for PairF64 {
        type Output = Self;
        #[inline(always)]
        fn neg(self) -> Self {
            PairF64(unsafe { _mm_xor_pd(self.0, _mm_set1_pd(-0.0)) })
        }
    }

    impl PairF32 {
        /// `(first, second)` (the upper two lanes zero).
        #[inline(always)]
        pub fn new(first: f32, second: f32) -> Self {
            PairF32(unsafe { _mm_set_ps(0.0, 0.0, second, first) })
        }
        /// The first value.
        #[inline(always)]
        pub fn first(self) -> f32 {
            unsafe { _mm_cvtss_f32(self.0) }
        }
        /// The second value.
        #[inline(always)]
        pub fn second(self) -> f32 {
            unsafe { _mm_cvtss_f32(_mm_shuffle_ps::<0b01_01_01_01>(self.0, self.0)) }
        }
        /// `(first, -second)`: the second lane's sign bit flipped.
        #[inline(always)]
        pub fn negate_second(self) -> Self {
            PairF32(unsafe { _mm_xor_ps(self.0, _mm_set_ps(0.0, 0.0, -0.0, 0.0)) })
        }
    }
    impl core::ops::Add for PairF32 {
        type Output = Self;
        #[inline(always)]
        fn add(self, rhs: Self) -> Self {
            PairF32(unsafe { _mm_add_ps(self.0, rhs.0) })
        }
    }
    impl core::ops::Sub for PairF32 {
        type Output = Self;
        #[inline(always)]
        fn sub(self, rhs: Self) -> Self {
            PairF32(unsafe { _mm_sub_ps(self.0, rhs.0) })
        }
    }
    impl core::ops::Mul for PairF32 {
        type Output = Self;
        #[inline(always)]
        fn mul(self, rhs: Self) -> Self {
            PairF32(unsafe { _mm_mul_ps(self.0, rhs.0) })
        }
    }
    impl core::ops::Div for PairF32 {
        type Output = Self;
        #[inline(always)]
        fn div(self, rhs: Self) -> Self {
            PairF32(unsafe { _mm_div_ps(self.0, rhs.0) })
        }
    }
    /// The sign bits flipped, as the scalar `-x` does.
    impl core::ops::Neg for PairF32 {
        type Output = Self;
        #[inline(always)]
        fn neg(self) -> Self {
            PairF32(unsafe { _mm_xor_ps(self.0, _mm_set1_ps(-0.0)) })
        }
    }
}

/// Two `f64` side by side (see the x86-64 definition).
#[cfg(not(target_arch = "x86_64"))]
pub type PairF64 = ArrayPair<f64>;

/// Two `f32` side by side (see the x86-64 definition).
#[cfg(not(target_arch = "x86_64"))]
pub type PairF32 = ArrayPair<f32>;

/// Below this magnitude the three-part reduction is exact; beyond it [`sincos_f64`] defers to libm.
const REDUCTION_LIMIT: f64 = 823_550.0;

/// sin and cos of `x`: Cody–Waite reduction by π/2 in three parts (exact products for |k| < 2²⁰) and a
/// fourth, the tail, for angles next to a multiple of π/2, then minimax polynomials on [−π/4, π/4] (the classic fdlibm kernels' coefficients). Beyond |x| ≈ 8e5 it
/// defers to libm's full reduction.
#[inline(always)]
pub fn sincos_f64(x: f64) -> (f64, f64) {
    if x.is_nan() || libm::fabs(x) >= REDUCTION_LIMIT {
        return (libm::sin(x), libm::cos(x));
    }
    sincos_kernel(x)
}

/// Sines and cosines of `N` angles. One range check for all of them, then branch-free kernels; the rare
/// libm fallback (a call, which would force every live value to the stack) sits in a separate cold
/// function, so the hot code keeps its values in registers.
#[inline(always)]
pub fn sincos_batch_f64<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut in_range = true;
    for v in x {
        // NaN compares false and takes the libm path.
        in_range &= libm::fabs(v) < REDUCTION_LIMIT;
    }
    if !in_range {
        return sincos_batch_fallback(x);
    }
    // The same passes compiled with AVX where the CPU has it: four angles per instruction instead of two,
    // the same operations, so the same bits (32 angles: 132 → 78 ns, 2026-12-03; see [`dispatch`]).
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2", not(target_feature = "avx")))]
    if N >= SINCOS_AVX_MIN && dispatch::avx() {
        // SAFETY: the CPU has AVX (`dispatch::avx` asked it), the one requirement of the function.
        #[allow(unused_unsafe)]
        return unsafe { dispatch::with_avx(|| sincos_passes(x)) };
    }
    sincos_passes(x)
}

/// Angles from which [`sincos_batch_f64`] calls its AVX copy (where the CPU has AVX). Alone, the copy pays
/// from 10 angles (2026-12-03, against the baseline: 8 angles 1.03×, 12 0.87×, 18 0.70×, 32 0.57×); inside
/// a generated function, though, whose first statements read the sines and cosines the copy has just
/// stored with 256-bit instructions, it cost more than it saved at 12: a floating Go2's `crba` 1.27× the
/// time (135 → 170 ns; its `rnea` the same), while the floating G1's (29 angles) took 0.97× (new user's and
/// own trials, 2026-12-03). In an AVX twin the copy is inlined and the question does not arise.
#[cfg(all(target_arch = "x86_64", target_feature = "sse2", not(target_feature = "avx")))]
const SINCOS_AVX_MIN: usize = 24;


/// The kernel over all the angles in three passes (reduce, the two polynomials, the quadrant), each a loop
/// the compiler unrolls and vectorizes: the angles' long dependency chains then run side by side instead of
/// one kernel after another (measured 49 → 34 ns for twelve angles; the same operations, so the same bits as
/// `sincos_kernel`). For |x| < [`REDUCTION_LIMIT`] only.
#[inline(always)]
fn sincos_passes<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut quadrant = [0.0; N];
    let mut reduced = [0.0; N];
    for ((v, n), r) in x.iter().zip(quadrant.iter_mut()).zip(reduced.iter_mut()) {
        (*n, *r) = reduce(*v);
    }
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    for ((r, s), c) in reduced.iter().zip(s.iter_mut()).zip(c.iter_mut()) {
        (*s, *c) = polynomials(*r);
    }
    for ((n, s), c) in quadrant.iter().zip(s.iter_mut()).zip(c.iter_mut()) {
        (*s, *c) = place_in_quadrant(*n, *s, *c);
    }
    (s, c)
}

#[cold]
#[inline(never)]
fn sincos_batch_fallback<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    for ((v, s), c) in x.iter().zip(s.iter_mut()).zip(c.iter_mut()) {
        (*s, *c) = sincos_f64(*v);
    }
    (s, c)
}

/// The branch-free body of [`sincos_f64`] for |x| < [`REDUCTION_LIMIT`].
#[inline(always)]
fn sincos_kernel(x: f64) -> (f64, f64) {
    let (n, r) = reduce(x);
    let (s, c) = polynomials(r);
    place_in_quadrant(n, s, c)
}

/// The constants of the sine/cosine kernels, shared by the scalar kernel and the lanes' (codegen_lanes.rs),
/// which must compute the same bits.
const TWO_OVER_PI: f64 = core::f64::consts::FRAC_2_PI;
/// π/2 in three parts of 33 bits (fdlibm's), so that k times each is exact for |k| < 2²⁰ …
#[allow(clippy::excessive_precision)]
const PIO2_1: f64 = 1.570_796_326_734_125_6e0;
#[allow(clippy::excessive_precision)]
const PIO2_2: f64 = 6.077_100_506_303_966e-11;
#[allow(clippy::excessive_precision)]
const PIO2_3: f64 = 2.022_266_248_711_166_5e-21;
/// … and π/2 − PIO2_1 − PIO2_2 − PIO2_3: without it an angle next to a multiple of π/2 (where r is tiny
/// and the three exact subtractions cancel) keeps an absolute error of k·8.5e-32, 7 ulps of sin(π) and up
/// to 4e-10 relative near |x| = 6e5; with it r is good to a few parts in 1e-23 there.
#[allow(clippy::excessive_precision)]
const PIO2_3T: f64 = 8.478_427_660_368_899_569_97e-32;
/// Rounds to the nearest integer without `f64::round` (not in core): adding 1.5·2⁵² leaves k in the low
/// bits of the sum (two's complement), removing it again gives k as a float.
const SHIFTER: f64 = 6_755_399_441_055_744.0;
/// The sin kernel's minimax coefficients on [−π/4, π/4] (fdlibm's).
#[allow(clippy::excessive_precision)]
const S1: f64 = -1.666_666_666_666_663_2e-1;
#[allow(clippy::excessive_precision)]
const S2: f64 = 8.333_333_333_322_49e-3;
#[allow(clippy::excessive_precision)]
const S3: f64 = -1.984_126_982_985_795e-4;
#[allow(clippy::excessive_precision)]
const S4: f64 = 2.755_731_370_707_006_8e-6;
#[allow(clippy::excessive_precision)]
const S5: f64 = -2.505_076_025_340_686_3e-8;
#[allow(clippy::excessive_precision)]
const S6: f64 = 1.589_690_995_211_55e-10;
/// The cos kernel's (fdlibm's).
#[allow(clippy::excessive_precision)]
const C1: f64 = 4.166_666_666_666_660_2e-2;
#[allow(clippy::excessive_precision)]
const C2: f64 = -1.388_888_888_887_411e-3;
#[allow(clippy::excessive_precision)]
const C3: f64 = 2.480_158_728_947_673e-5;
#[allow(clippy::excessive_precision)]
const C4: f64 = -2.755_731_435_139_066_3e-7;
#[allow(clippy::excessive_precision)]
const C5: f64 = 2.087_572_321_298_175e-9;
#[allow(clippy::excessive_precision)]
const C6: f64 = -1.135_964_755_778_819_5e-11;

/// `x = k π/2 + r` with |r| ≤ π/4: returns k's residue `m = k − 4 round(k/4)` ∈ {−2, −1, 0, 1, 2} (the
/// quadrant, 2 and −2 alike) and r. Every step is exact: k and k/4 round by the same shifted addition.
///
/// The quadrant stays a float: the bits of `shifted` (whose low bits are k) were read as an integer until
/// rustc 1.95 (LLVM 22.1.2) at opt-level 3 vectorized that reading across the angles of a batch and gave
/// one angle another's quadrant (the arm7's generated `kinematics` in a release build: the cosine of joint 2
/// with the wrong sign, every link below it wrong by up to 2; opt-levels 1 and 2, debug builds and a newer
/// LLVM were right). Converting k to an integer instead (`k as i64`) was right but cost the floating G1's
/// `crba` 3.5 % (a scalar conversion per angle); floats keep the passes vectorized.
#[inline(always)]
fn reduce(x: f64) -> (f64, f64) {
    let shifted = x * TWO_OVER_PI + SHIFTER;
    let k = shifted - SHIFTER;
    let m = k - ((k * 0.25 + SHIFTER) - SHIFTER) * 4.0;
    (m, (((x - k * PIO2_1) - k * PIO2_2) - k * PIO2_3) - k * PIO2_3T)
}

/// sin r and cos r for |r| ≤ π/4.
#[inline(always)]
fn polynomials(r: f64) -> (f64, f64) {
    let z = r * r;
    let sr = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    let s = r + z * r * (S1 + z * sr);
    // The cos kernel, with the fdlibm correction that keeps 1 − z/2 exact.
    let cr = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let c = w + (((1.0 - w) - hz) + z * cr);
    (s, c)
}

/// sin x and cos x from sin r and cos r and the quadrant's residue m ([`reduce`]): (s, c), (c, −s),
/// (−s, −c), (−c, s) for m = 0, 1, ±2, −1. Selected without branches (the quadrant of a joint angle is
/// unpredictable, and a mispredicted branch costs more than the kernels); a negation flips the sign bit
/// only, so the results are the bits of the lanes' version, which selects with bit masks.
#[inline(always)]
fn place_in_quadrant(m: f64, s: f64, c: f64) -> (f64, f64) {
    let odd = m == 1.0 || m == -1.0;
    let (a, b) = if odd { (c, s) } else { (s, c) };
    let sin_negative = m < 0.0 || m == 2.0;
    let cos_negative = m > 0.0 || m == -2.0;
    (
        if sin_negative { -a } else { a },
        if cos_negative { -b } else { b },
    )
}

/// Whether the generated functions that have an AVX twin run it (x86-64 only; see `use_avx`).
///
/// Large generated functions are compiled twice on x86-64: for the baseline target (SSE2) and, in a
/// module of their own, with AVX enabled. They run the AVX copy when the CPU has AVX (and the operating
/// system saves its registers), found out once with `cpuid` and cached. Lane functions of 256-bit
/// values, and a wide tree's smallest scalar functions, have a third copy compiled with AVX-512 F and
/// VL, which runs first where the CPU has them (`avx512`). The two copies compute the same
/// operations in the same order (AVX's three-operand encoding of them, no fused multiply-add), so their
/// results are the same bits (but for the sign and payload of a NaN, which x86 takes from the first
/// operand of the two, and the copies may order them differently); the AVX copy needs no
/// register-to-register copies, which SSE2's
/// two-operand instructions spend on every value read twice (measured: the floating TALOS's `aba` 0.53×
/// the time, docs/generated-code.md "AVX where the CPU has it").
#[cfg(target_arch = "x86_64")]
pub mod dispatch {
    use core::sync::atomic::{AtomicBool, AtomicU8, Ordering};

    /// What `cpuid` said: 0 not asked yet, 1 no AVX, 2 AVX, 3 AVX and AVX-512 (F and VL).
    static DETECTED: AtomicU8 = AtomicU8::new(0);
    /// Whether the AVX copies may run (see [`use_avx`]).
    static ALLOWED: AtomicBool = AtomicBool::new(true);
    /// Whether the AVX-512 copies may run (see [`use_avx512`]).
    static ALLOWED_512: AtomicBool = AtomicBool::new(true);

    /// The level `cpuid` found (see `DETECTED`), asked once.
    #[inline(always)]
    fn detected() -> u8 {
        match DETECTED.load(Ordering::Relaxed) {
            0 => detect(),
            level => level,
        }
    }

    /// Whether a generated function with an AVX twin runs it now: the CPU has AVX and [`use_avx`] did
    /// not turn it off. One relaxed atomic load after the first call.
    #[inline(always)]
    pub fn avx() -> bool {
        ALLOWED.load(Ordering::Relaxed) && detected() >= 2
    }

    /// Whether a function with an AVX-512 twin runs it now (a lane function of 256-bit values, or a scalar
    /// one of a model of 24 or more degrees of freedom): the CPU has AVX-512 F and VL (and the operating
    /// system saves their registers), and neither [`use_avx`] nor [`use_avx512`] turned the twins off.
    /// The twin computes what the AVX twin does, with 32 vector registers where AVX has 16
    /// (docs/generated-code.md, "AVX where the CPU has it").
    #[inline(always)]
    pub fn avx512() -> bool {
        ALLOWED.load(Ordering::Relaxed)
            && ALLOWED_512.load(Ordering::Relaxed)
            && detected() >= 3
    }

    /// Turns the AVX copies off (`false`: every function runs its baseline copy) or back on (`true`,
    /// the default: they run where the CPU has AVX). For comparing the two copies, or timing the baseline
    /// code on a CPU that has AVX. It holds for every function that calls these helpers: with the
    /// `robot!` macro every robot of the program (`embedyn::codegen_support`), with a standalone crate
    /// that crate's functions (each has its own `helpers`).
    pub fn use_avx(allowed: bool) {
        ALLOWED.store(allowed, Ordering::Relaxed);
    }

    /// Turns the AVX-512 twins off (`false`: those functions run their AVX twins, where the CPU has AVX)
    /// or back on (`true`, the default). For comparing the two, as [`use_avx`], or on a CPU that lowers
    /// its clock for 512-bit instructions (Skylake-SP-class Xeons), which LLVM may pick in these twins.
    pub fn use_avx512(allowed: bool) {
        ALLOWED_512.store(allowed, Ordering::Relaxed);
    }

    /// `x` as a `U` of the same size: the arguments and result of a lane function handed to its AVX
    /// twin, whose lane type (`AvxF64x4`) has the layout of the function's (`F64x4`).
    ///
    /// # Safety
    ///
    /// `T` and `U` have the same size and alignment, and every bit pattern of `T` is a valid `U` (lane
    /// arrays of one scalar, references to them, slices of plain numbers).
    #[inline(always)]
    pub unsafe fn recast<T, U>(x: T) -> U {
        const { assert!(core::mem::size_of::<T>() == core::mem::size_of::<U>()) };
        const { assert!(core::mem::align_of::<T>() == core::mem::align_of::<U>()) };
        let x = core::mem::ManuallyDrop::new(x);
        // SAFETY: same size and alignment (checked when compiled), valid bits (the caller's promise).
        unsafe { core::mem::transmute_copy(&*x) }
    }

    #[cold]
    fn detect() -> u8 {
        use core::arch::x86_64::__cpuid;
        // CPUID leaf 1, ECX: bit 27 OSXSAVE (the OS uses XSAVE, so XGETBV may be read), bit 28 AVX.
        #[allow(unused_unsafe)]
        let ecx = unsafe { __cpuid(1) }.ecx;
        let level = if ecx & (1 << 27) == 0 || ecx & (1 << 28) == 0 {
            1
        } else {
            // XCR0 bits 1 and 2: the OS saves the SSE and AVX (upper YMM) state on context switches;
            // bits 5, 6 and 7: the AVX-512 mask registers and the upper ZMM and ZMM16–31 state.
            // SAFETY: XGETBV exists because OSXSAVE is set (checked just above).
            let xcr0 = unsafe { xcr0() };
            if xcr0 & 0b110 != 0b110 {
                1
            } else if avx512_reported(ecx) && xcr0 & 0b1110_0110 == 0b1110_0110 {
                3
            } else {
                2
            }
        };
        DETECTED.store(level, Ordering::Relaxed);
        level
    }

    /// Whether `cpuid` reports AVX-512 F and VL, and AVX2 and FMA besides: Rust's `avx512f` implies
    /// those two, which the twin may then use (an AVX2 integer instruction, say), so a CPU (or a virtual
    /// machine) must report all four. `leaf1_ecx`: leaf 1's ECX (bit 12 FMA); leaf 7 (if the CPU has
    /// it), EBX: bit 5 AVX2, bit 16 AVX512F, bit 31 AVX512VL.
    fn avx512_reported(leaf1_ecx: u32) -> bool {
        use core::arch::x86_64::{__cpuid, __cpuid_count};
        #[allow(unused_unsafe)]
        let max_leaf = unsafe { __cpuid(0) }.eax;
        if max_leaf < 7 {
            return false;
        }
        #[allow(unused_unsafe)]
        let ebx = unsafe { __cpuid_count(7, 0) }.ebx;
        leaf1_ecx & (1 << 12) != 0
            && ebx & (1 << 5) != 0
            && ebx & (1 << 16) != 0
            && ebx & (1 << 31) != 0
    }

    /// `f()` compiled with AVX: the code of `f` (its closure, and what it calls inline) is inlined here,
    /// in a function with AVX enabled. For the helpers' own AVX copies (the batch of sines and cosines,
    /// the derivatives' product), called where [`avx`] says so.
    #[target_feature(enable = "avx")]
    #[inline]
    pub fn with_avx<R>(f: impl FnOnce() -> R) -> R {
        f()
    }

    /// The extended control register 0 (XGETBV with ECX = 0).
    #[target_feature(enable = "xsave")]
    unsafe fn xcr0() -> u64 {
        core::arch::x86_64::_xgetbv(0)
    }
}
