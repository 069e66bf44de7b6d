// The lane types of generated lane modules (`lanes = N`: `f64x4`, …), beside the helpers of
// codegen_support.rs (whose `Float` they implement). Compiled into embedyn-runtime's `codegen_support`, and
// copied into a standalone crate generated with lanes (which then depends on `wide`).

/// `N` numbers of one scalar type in one SIMD value, one per state: the scalar `S` of generated lane
/// modules (`f64x4`, …), which evaluate `N` states in one call. Every operation acts lane by lane with the
/// scalar's own arithmetic (IEEE add, subtract, multiply, divide and square root, no fused multiply-add,
/// the scalar sine and cosine), so lane `k` of a lane function's result is bit-identical to the scalar
/// function's result for state `k`. The SIMD width is the build's: with AVX (`-C target-cpu=native`,
/// `-C target-feature=+avx`) an `F64x4` is one 256-bit register, on baseline x86-64 two 128-bit ones.
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
            /// Lane by lane: lane `k`'s angles through the scalar batch, as the scalar function computes
            /// them.
            #[inline(always)]
            fn sincos_batch<const M: usize>(x: [Self; M]) -> ([Self; M], [Self; M]) {
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
        }
    };
}
lanes_type!(F64x2, f64x2, f64, 2);
lanes_type!(F64x4, f64x4, f64, 4);
lanes_type!(F32x4, f32x4, f32, 4);
lanes_type!(F32x8, f32x8, f32, 8);

/// The lane type of `N` lanes of a scalar, for the lane modules' `type S`.
pub const LANE_TYPES: [(&str, usize, &str); 4] = [
    ("f64", 2, "F64x2"),
    ("f64", 4, "F64x4"),
    ("f32", 4, "F32x4"),
    ("f32", 8, "F32x8"),
];

