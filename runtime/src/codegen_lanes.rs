// The lane types of generated lane modules (`lanes = N`: `f64x4`, …), beside the helpers of
// codegen_support.rs (whose `Float` they implement). Compiled into embedyn-runtime's `codegen_support`, and
// copied into a standalone crate generated with lanes (which then depends on `wide`).

/// The `Float` items of a lane type about pairs: lane functions are not paired (their lanes are states), so
/// a pair is two values side by side, `ArrayPair`.
macro_rules! lane_pairs {
    () => {
        type Pair = ArrayPair<Self>;
        #[inline(always)]
        fn pair(first: Self, second: Self) -> ArrayPair<Self> {
            ArrayPair::new(first, second)
        }
        #[inline(always)]
        fn first(pair: ArrayPair<Self>) -> Self {
            pair.first()
        }
        #[inline(always)]
        fn second(pair: ArrayPair<Self>) -> Self {
            pair.second()
        }
        #[inline(always)]
        fn negate_second(pair: ArrayPair<Self>) -> ArrayPair<Self> {
            pair.negate_second()
        }
    };
}

/// `N` numbers of one scalar type in one SIMD value, one per state: the scalar `S` of generated lane
/// modules (`f64x4`, …), which evaluate `N` states in one call. Every operation acts lane by lane with the
/// scalar's own arithmetic (IEEE add, subtract, multiply, divide and square root, no fused multiply-add,
/// the scalar sine and cosine), so lane `k` of a lane function's result is bit-identical to the scalar
/// function's result for state `k`. The SIMD width is the build's: with AVX (`-C target-cpu=native`,
/// `-C target-feature=+avx`) an `F64x4` is one 256-bit register, on baseline x86-64 two 128-bit ones
/// (where the CPU has AVX, the generated lane functions' AVX twins compute over `AvxF64x4`, one register).
macro_rules! lanes_type {
    ($name:ident, $wide:ident, $t:ident, $n:literal) => {
        #[doc = concat!("`", stringify!($n), "` `", stringify!($t), "` lanes in one SIMD value (see the module's lane types).")]
        #[derive(Clone, Copy, Default)]
        #[repr(transparent)]
        pub struct $name(pub wide::$wide);

        impl $name {
            /// Every lane `x` (how lane functions write a constant).
            #[inline(always)]
            pub fn splat(x: $t) -> Self {
                $name(wide::$wide::splat(x))
            }
            /// Lane `k` is `lanes[k]`.
            #[inline(always)]
            pub fn new(lanes: [$t; $n]) -> Self {
                $name(wide::$wide::from(lanes))
            }
            /// The lanes as an array.
            #[inline(always)]
            pub fn to_array(self) -> [$t; $n] {
                self.0.to_array()
            }
        }

        impl From<[$t; $n]> for $name {
            #[inline(always)]
            fn from(lanes: [$t; $n]) -> Self {
                $name::new(lanes)
            }
        }

        impl core::fmt::Debug for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                self.to_array().fmt(f)
            }
        }

        /// Lane by lane, as `==` on the scalar (NaN lanes differ).
        impl PartialEq for $name {
            fn eq(&self, other: &Self) -> bool {
                self.to_array() == other.to_array()
            }
        }

        impl core::ops::Add for $name {
            type Output = Self;
            #[inline(always)]
            fn add(self, rhs: Self) -> Self {
                $name(self.0 + rhs.0)
            }
        }
        impl core::ops::Sub for $name {
            type Output = Self;
            #[inline(always)]
            fn sub(self, rhs: Self) -> Self {
                $name(self.0 - rhs.0)
            }
        }
        impl core::ops::Mul for $name {
            type Output = Self;
            #[inline(always)]
            fn mul(self, rhs: Self) -> Self {
                $name(self.0 * rhs.0)
            }
        }
        impl core::ops::Div for $name {
            type Output = Self;
            #[inline(always)]
            fn div(self, rhs: Self) -> Self {
                $name(self.0 / rhs.0)
            }
        }
        /// The sign bit flipped, as the scalar `-x` does (`0 − x` would turn `-0.0` into `0.0`).
        impl core::ops::Neg for $name {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                $name(self.0 ^ wide::$wide::splat(-0.0))
            }
        }

        impl Float for $name {
            #[inline(always)]
            fn sincos(self) -> (Self, Self) {
                let x = self.to_array();
                let (mut s, mut c) = (x, x);
                for k in 0..$n {
                    (s[k], c[k]) = x[k].sincos();
                }
                ($name::new(s), $name::new(c))
            }
            /// Lane by lane as the scalar batch computes them: for `f64` lanes the scalar kernel's
            /// operations on whole SIMD values (`sincos_batch_simd`), else each lane's angles through the
            /// scalar batch.
            #[inline(always)]
            fn sincos_batch<const M: usize>(x: [Self; M]) -> ([Self; M], [Self; M]) {
                if let Some(result) = $name::sincos_batch_simd(&x) {
                    return result;
                }
                let lanes = x.map($name::to_array);
                let (mut s, mut c) = (lanes, lanes);
                for k in 0..$n {
                    let (sk, ck) = <$t as Float>::sincos_batch(lanes.map(|v| v[k]));
                    for m in 0..M {
                        s[m][k] = sk[m];
                        c[m][k] = ck[m];
                    }
                }
                (s.map($name::new), c.map($name::new))
            }
            /// IEEE square root (correctly rounded, as the scalar one).
            #[inline(always)]
            fn sqrt(self) -> Self {
                $name(self.0.sqrt())
            }
            #[inline(always)]
            fn abs(self) -> Self {
                $name(self.0.abs())
            }
            #[inline(always)]
            fn select_gt(lhs: Self, rhs: Self, then: Self, otherwise: Self) -> Self {
                // An ordered comparison: false where either side is NaN, as the scalar `>`.
                $name(wide::CmpGt::cmp_gt(lhs.0, rhs.0).blend(then.0, otherwise.0))
            }
            lane_pairs!();
        }
    };
}
lanes_type!(F64x2, f64x2, f64, 2);
lanes_type!(F64x4, f64x4, f64, 4);
lanes_type!(F32x4, f32x4, f32, 4);
lanes_type!(F32x8, f32x8, f32, 8);

/// The scalar kernel of `sincos_kernel` (codegen_support.rs) on whole SIMD values: the same operations in
/// the same order, lane by lane, so every lane equals the scalar result bit for bit (tests/generated_lanes.rs
/// holds the two to that). `None` where an angle of a lane is NaN or beyond the reduction's range (the
/// scalar batch then takes its libm path for that lane).
macro_rules! sincos_simd {
    ($name:ident, $float:ident, $bits:ident, $n:literal) => {
        impl $name {
            #[inline(always)]
            fn sincos_batch_simd<const M: usize>(x: &[Self; M]) -> Option<([Self; M], [Self; M])> {
                use wide::{$bits, $float};
                let limit = $float::splat(REDUCTION_LIMIT);
                for v in x {
                    // NaN compares false and leaves the fast path, as in the scalar batch.
                    if !wide::CmpLt::cmp_lt(v.0.abs(), limit).all() {
                        return None;
                    }
                }
                // The scalar kernel's constants (codegen_support.rs), splat.
                let c = |v: f64| $float::splat(v);
                let bits = |v: $float| $bits::from(v.to_array().map(f64::to_bits));
                let float = |v: $bits| $float::from(v.to_array().map(f64::from_bits));
                // In three passes over the values, as the scalar batch: the chains run side by side.
                let (mut sines, mut cosines) = (*x, *x);
                let mut quadrant = [$bits::splat(0); M];
                let mut reduced = [c(0.0); M];
                for m in 0..M {
                    let x = x[m].0;
                    let shifted = x * c(TWO_OVER_PI) + c(SHIFTER);
                    quadrant[m] = bits(shifted);
                    let k = shifted - c(SHIFTER);
                    reduced[m] =
                        (((x - k * c(PIO2_1)) - k * c(PIO2_2)) - k * c(PIO2_3)) - k * c(PIO2_3T);
                }
                for m in 0..M {
                    let r = reduced[m];
                    let z = r * r;
                    let sr = c(S2) + z * (c(S3) + z * (c(S4) + z * (c(S5) + z * c(S6))));
                    sines[m] = $name(r + z * r * (c(S1) + z * sr));
                    let cr = z * (c(C1) + z * (c(C2) + z * (c(C3) + z * (c(C4) + z * (c(C5) + z * c(C6))))));
                    let hz = c(0.5) * z;
                    let w = c(1.0) - hz;
                    cosines[m] = $name(w + (((c(1.0) - w) - hz) + z * cr));
                }
                for m in 0..M {
                    let n = quadrant[m];
                    let one = $bits::splat(1);
                    let two = $bits::splat(2);
                    let swap = $bits::splat(0) - (n & one);
                    let (sb, cb) = (bits(sines[m].0), bits(cosines[m].0));
                    let a = (sb & !swap) | (cb & swap);
                    let b = (cb & !swap) | (sb & swap);
                    let sin_sign = (n & two) << 62;
                    let cos_sign = ((n + one) & two) << 62;
                    sines[m] = $name(float(a ^ sin_sign));
                    cosines[m] = $name(float(b ^ cos_sign));
                }
                Some((sines, cosines))
            }
        }
    };
}
sincos_simd!(F64x2, f64x2, u64x2, 2);
sincos_simd!(F64x4, f64x4, u64x4, 4);

/// `f32` lanes take the scalar batch lane by lane (it evaluates in f64 and rounds once).
macro_rules! sincos_per_lane {
    ($name:ident) => {
        impl $name {
            #[inline(always)]
            fn sincos_batch_simd<const M: usize>(_: &[Self; M]) -> Option<([Self; M], [Self; M])> {
                None
            }
        }
    };
}
sincos_per_lane!(F32x4);
sincos_per_lane!(F32x8);

/// The 256-bit lane types of the AVX twins of lane functions (codegen/src/dispatch.rs): `AvxF64x4` and
/// `AvxF32x8` hold what `F64x4` and `F32x8` hold, with the same layout, and compute with AVX instructions
/// (`core::arch` intrinsics, one 256-bit instruction per operation; the same IEEE operations lane by lane,
/// so the same bits). A lane function's twin is its code with these as `S`, compiled with AVX; its public
/// function hands its arguments over (`dispatch::recast`) where `dispatch::avx()` says the CPU has AVX.
/// `wide`'s types could not do this: they pick their instructions when the crate is compiled, and the twin
/// of code over them kept two SSE2 halves per value (the Z1's 4-lane `aba` 137 ns per state either way).
///
/// Sound to use anywhere: a value is made only by `splat` and `new`, safe functions with AVX enabled, which
/// code without AVX (that is, anything but an AVX twin) can call only in `unsafe`, promising that the CPU
/// has AVX; the operations on a value, which are AVX instructions, then run where that promise holds.
#[cfg(all(target_arch = "x86_64", target_feature = "sse2", not(target_feature = "avx")))]
macro_rules! avx_lanes_type {
    ($name:ident, $plain:ident, $t:ident, $n:literal, $m:ident, $suffix:ident) => {
        #[doc = concat!("`", stringify!($plain), "` for AVX twins (see the module's AVX lane types).")]
        #[derive(Clone, Copy)]
        #[repr(transparent)]
        pub struct $name(core::arch::x86_64::$m);

        impl $name {
            /// Every lane `x` (AVX: callable safely only where AVX is enabled).
            #[target_feature(enable = "avx")]
            #[inline]
            pub fn splat(x: $t) -> Self {
                $name::new([x; $n])
            }
            /// Lane `k` is `lanes[k]` (AVX: callable safely only where AVX is enabled).
            #[target_feature(enable = "avx")]
            #[inline]
            pub fn new(lanes: [$t; $n]) -> Self {
                // SAFETY: an array of `N` numbers is a SIMD value of them, lane `k` element `k`.
                $name(unsafe { core::mem::transmute::<[$t; $n], core::arch::x86_64::$m>(lanes) })
            }
            /// The lanes as an array.
            #[inline(always)]
            pub fn to_array(self) -> [$t; $n] {
                // SAFETY: as in `new`.
                unsafe { core::mem::transmute::<core::arch::x86_64::$m, [$t; $n]>(self.0) }
            }
            /// The same lanes as the baseline lane type (the same layout).
            #[inline(always)]
            fn plain(self) -> $plain {
                $plain::new(self.to_array())
            }
            /// A value of `lanes` made where a value of this type exists (so the CPU has AVX: see the type).
            #[inline(always)]
            fn like(self, lanes: [$t; $n]) -> Self {
                let _ = self;
                // SAFETY: `self` exists, so a function with AVX made it: the CPU has AVX.
                unsafe { $name::new(lanes) }
            }
        }

        impl core::fmt::Debug for $name {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                self.to_array().fmt(f)
            }
        }

        avx_lanes_type!(@op $name, Add, add, add, $suffix);
        avx_lanes_type!(@op $name, Sub, sub, sub, $suffix);
        avx_lanes_type!(@op $name, Mul, mul, mul, $suffix);
        avx_lanes_type!(@op $name, Div, div, div, $suffix);

        /// The sign bit flipped, as the scalar `-x` does.
        impl core::ops::Neg for $name {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                use core::arch::x86_64::*;
                // SAFETY: `self` exists, so the CPU has AVX (see the type).
                $name(unsafe { avx_lanes_type!(@intrinsic xor, $suffix)(self.0, self.like([-0.0; $n]).0) })
            }
        }

        impl Float for $name {
            #[inline(always)]
            fn sincos(self) -> (Self, Self) {
                let (s, c) = self.plain().sincos();
                (self.like(s.to_array()), self.like(c.to_array()))
            }
            /// The baseline lane type's batch (the scalar kernel on `wide`'s values, in SSE2 instructions
            /// encoded with AVX here): the same bits as the baseline code.
            #[inline(always)]
            fn sincos_batch<const M: usize>(x: [Self; M]) -> ([Self; M], [Self; M]) {
                let Some(&any) = x.first() else {
                    return (x, x);
                };
                let (s, c) = <$plain as Float>::sincos_batch(x.map($name::plain));
                (
                    s.map(|v| any.like(v.to_array())),
                    c.map(|v| any.like(v.to_array())),
                )
            }
            /// IEEE square root (correctly rounded, as the scalar one).
            #[inline(always)]
            fn sqrt(self) -> Self {
                use core::arch::x86_64::*;
                // SAFETY: a value exists, so the CPU has AVX (see the type).
                $name(unsafe { avx_lanes_type!(@intrinsic sqrt, $suffix)(self.0) })
            }
            #[inline(always)]
            fn abs(self) -> Self {
                use core::arch::x86_64::*;
                // SAFETY: `self` exists, so the CPU has AVX (see the type).
                $name(unsafe { avx_lanes_type!(@intrinsic andnot, $suffix)(self.like([-0.0; $n]).0, self.0) })
            }
            #[inline(always)]
            fn select_gt(lhs: Self, rhs: Self, then: Self, otherwise: Self) -> Self {
                use core::arch::x86_64::*;
                // An ordered comparison: false where either side is NaN, as the scalar `>`.
                // SAFETY: a value exists, so the CPU has AVX (see the type).
                $name(unsafe {
                    let greater = avx_lanes_type!(@intrinsic cmp_gt, $suffix)(lhs.0, rhs.0);
                    avx_lanes_type!(@intrinsic blendv, $suffix)(otherwise.0, then.0, greater)
                })
            }
            lane_pairs!();
        }
    };
    (@op $name:ident, $trait:ident, $method:ident, $op:ident, $suffix:ident) => {
        impl core::ops::$trait for $name {
            type Output = Self;
            #[inline(always)]
            fn $method(self, rhs: Self) -> Self {
                use core::arch::x86_64::*;
                // SAFETY: a value exists, so the CPU has AVX (see the type).
                $name(unsafe { avx_lanes_type!(@intrinsic $op, $suffix)(self.0, rhs.0) })
            }
        }
    };
    (@intrinsic add, pd) => { _mm256_add_pd };
    (@intrinsic sub, pd) => { _mm256_sub_pd };
    (@intrinsic mul, pd) => { _mm256_mul_pd };
    (@intrinsic div, pd) => { _mm256_div_pd };
    (@intrinsic xor, pd) => { _mm256_xor_pd };
    (@intrinsic sqrt, pd) => { _mm256_sqrt_pd };
    (@intrinsic andnot, pd) => { _mm256_andnot_pd };
    (@intrinsic cmp_gt, pd) => { _mm256_cmp_pd::<_CMP_GT_OQ> };
    (@intrinsic blendv, pd) => { _mm256_blendv_pd };
    (@intrinsic add, ps) => { _mm256_add_ps };
    (@intrinsic sub, ps) => { _mm256_sub_ps };
    (@intrinsic mul, ps) => { _mm256_mul_ps };
    (@intrinsic div, ps) => { _mm256_div_ps };
    (@intrinsic xor, ps) => { _mm256_xor_ps };
    (@intrinsic sqrt, ps) => { _mm256_sqrt_ps };
    (@intrinsic andnot, ps) => { _mm256_andnot_ps };
    (@intrinsic cmp_gt, ps) => { _mm256_cmp_ps::<_CMP_GT_OQ> };
    (@intrinsic blendv, ps) => { _mm256_blendv_ps };
}
#[cfg(all(target_arch = "x86_64", target_feature = "sse2", not(target_feature = "avx")))]
avx_lanes_type!(AvxF64x4, F64x4, f64, 4, __m256d, pd);
#[cfg(all(target_arch = "x86_64", target_feature = "sse2", not(target_feature = "avx")))]
avx_lanes_type!(AvxF32x8, F32x8, f32, 8, __m256, ps);

/// The lane type of `N` lanes of a scalar, for the lane modules' `type S`.
/// (Eight f64 lanes as two `F64x4` measured 7–9 % slower per state than `F64x4` with AVX2 on the Z1 and
/// the floating ANYmal B, 2026-12-02: more live values, more spills; not offered.)
pub const LANE_TYPES: [(&str, usize, &str); 4] = [
    ("f64", 2, "F64x2"),
    ("f64", 4, "F64x4"),
    ("f32", 4, "F32x4"),
    ("f32", 8, "F32x8"),
];

