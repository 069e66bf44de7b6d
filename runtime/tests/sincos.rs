//! The sine/cosine that generated code calls, against the platform's `libm` (an independent
//! implementation): every quadrant, both signs, angles a robot sees and far beyond, and the exact
//! values at zero.

use embedyn_runtime::codegen_support::{sincos_f64, Float};

/// Error in units of the last place of the reference value (at least one ulp of 1e-300 near zero).
fn ulps(x: f64, reference: f64) -> f64 {
    let ulp = (reference.abs().max(1e-300) * f64::EPSILON).max(f64::MIN_POSITIVE);
    (x - reference).abs() / ulp
}

#[test]
fn matches_libm_to_a_few_ulps_in_every_quadrant() {
    let mut worst: f64 = 0.0;
    let mut x = -50.0;
    while x <= 50.0 {
        let (s, c) = sincos_f64(x);
        let (rs, rc) = (libm::sin(x), libm::cos(x));
        // Absolute error relative to the unit circle (sin near 0 compares against 1 ulp of 1).
        let e = ((s - rs).abs().max((c - rc).abs())) / f64::EPSILON;
        worst = worst.max(e);
        assert!(
            ulps(s, rs) < 4.0 || (s - rs).abs() < 2.0 * f64::EPSILON,
            "sin({x}) = {s}, libm {rs}"
        );
        assert!(
            ulps(c, rc) < 4.0 || (c - rc).abs() < 2.0 * f64::EPSILON,
            "cos({x}) = {c}, libm {rc}"
        );
        x += 0.000_731;
    }
    assert!(worst <= 1.0, "worst absolute error {worst} eps");
}

/// Next to a multiple of π/2 the sine or cosine is tiny and the reduction's cancellation exposes how much
/// of π/2 it knows: the doubles nearest k·π/2 and their neighbours, |k| up to 524,288 (|x| ≈ 8.2e5), are
/// within 2 ulps of libm relative to the value itself (without the reduction's tail term: 7 ulps at π, 43 at
/// 50π, 2.8 million at x = −642615.9188844458).
#[test]
fn relative_accuracy_next_to_multiples_of_half_pi() {
    let mut worst: f64 = 0.0;
    let mut check = |x: f64| {
        let (s, c) = sincos_f64(x);
        let e = ulps(s, libm::sin(x)).max(ulps(c, libm::cos(x)));
        assert!(
            e <= 2.0,
            "x = {x:e}: sin {s:e} (libm {:e}), cos {c:e} (libm {:e})",
            libm::sin(x),
            libm::cos(x)
        );
        worst = worst.max(e);
    };
    check(-642_615.918_884_445_8);
    check(core::f64::consts::PI);
    check(2.0 * core::f64::consts::PI);
    check(157.079_632_679_489_66);
    let mut k: i64 = 1;
    while k <= 524_288 {
        for sign in [1.0, -1.0] {
            let b = sign * k as f64 * core::f64::consts::FRAC_PI_2;
            for d in -2i64..=2 {
                check(f64::from_bits((b.to_bits() as i64 + d) as u64));
            }
        }
        k += 1 + k / 64;
    }
    assert!(worst <= 2.0);
}

#[test]
fn quadrant_boundaries_and_special_values() {
    assert_eq!(sincos_f64(0.0), (0.0, 1.0));
    // The sign of a zero angle's sine is not kept (it never matters for a joint).
    assert_eq!(sincos_f64(-0.0), (0.0, 1.0));
    for k in -8i32..=8 {
        for dx in [-1e-9, 0.0, 1e-9] {
            let x = f64::from(k) * core::f64::consts::FRAC_PI_2 + dx;
            let (s, c) = sincos_f64(x);
            assert!((s - libm::sin(x)).abs() <= 2.0 * f64::EPSILON, "sin({x})");
            assert!((c - libm::cos(x)).abs() <= 2.0 * f64::EPSILON, "cos({x})");
        }
    }
    // Far beyond the fast reduction, and non-finite input: libm's answer.
    for x in [1e6, -3.3e7, 1e300] {
        assert_eq!(sincos_f64(x), (libm::sin(x), libm::cos(x)));
    }
    let (s, c) = sincos_f64(f64::NAN);
    assert!(s.is_nan() && c.is_nan());
    let (s, c) = sincos_f64(f64::INFINITY);
    assert!(s.is_nan() && c.is_nan());
}

#[test]
fn f32_is_the_rounded_f64_value() {
    let mut x = -20.0f32;
    while x <= 20.0 {
        let (s, c) = x.sincos();
        let (rs, rc) = sincos_f64(f64::from(x));
        assert_eq!((s, c), (rs as f32, rc as f32));
        x += 0.0137;
    }
}

#[test]
fn batch_is_the_single_call_bit_for_bit() {
    use embedyn_runtime::codegen_support::sincos_batch;
    let x = [0.3, -2.9, 4.7, 1e-9, -0.0, 3.0e5, 12.5];
    let (s, c) = sincos_batch(x);
    for k in 0..x.len() {
        assert_eq!((s[k], c[k]), sincos_f64(x[k]), "angle {}", x[k]);
    }
    // One angle out of the fast range sends the whole batch through libm's reduction: same answers.
    let y = [0.3, 1e7, -2.0];
    let (s, c) = sincos_batch(y);
    for k in 0..y.len() {
        assert_eq!((s[k], c[k]), sincos_f64(y[k]));
    }
    let (s, c) = sincos_batch([f64::NAN, 1.0]);
    assert!(s[0].is_nan() && c[0].is_nan());
    assert_eq!((s[1], c[1]), sincos_f64(1.0));
    let (s32, c32) = sincos_batch([0.5f32, -7.0]);
    assert_eq!((s32[1], c32[1]), (-7.0f32).sincos());
}

/// The batch (its passes over all the angles) against the one-angle
/// kernel, bit for bit, over dense sweeps: batches of 12 (a quadruped's joints) and of 5 (an odd tail for
/// the vectorized loops), angles from −8e5 to 8e5 on a log scale, both signs, and every quadrant
/// boundary k π/2 with its neighbours one ulp away.
#[test]
fn batch_equals_the_kernel_over_dense_sweeps() {
    let mut angles = Vec::new();
    let mut x = 1e-12f64;
    while x < 8.2e5 {
        angles.push(x);
        angles.push(-x);
        x *= 1.0173;
    }
    for k in -400i32..=400 {
        let b = f64::from(k) * core::f64::consts::FRAC_PI_2;
        angles.extend([
            b,
            f64::from_bits(b.to_bits() + 1),
            f64::from_bits(b.to_bits().saturating_sub(1)),
        ]);
    }
    fn check_batches<const N: usize>(angles: &[f64]) {
        use embedyn_runtime::codegen_support::sincos_batch;
        for chunk in angles.chunks_exact(N) {
            let batch: [f64; N] = chunk.try_into().unwrap();
            let (s, c) = sincos_batch(batch);
            for k in 0..N {
                let (es, ec) = sincos_f64(batch[k]);
                assert_eq!(
                    (s[k].to_bits(), c[k].to_bits()),
                    (es.to_bits(), ec.to_bits()),
                    "angle {:e}",
                    batch[k]
                );
            }
        }
    }
    check_batches::<12>(&angles);
    check_batches::<5>(&angles);
}

/// The lane types' batch (the scalar kernel on whole SIMD values for f64 lanes, per lane for f32) equals
/// the scalar batch bit for bit, lane by lane: every quadrant and both signs, ±0, the boundaries of the
/// quadrants, and batches with an angle beyond the reduction's range or NaN in one lane (the libm path).
#[test]
fn lane_batches_equal_the_scalar_batch_bit_for_bit() {
    use embedyn_runtime::lanes::{F32x8, F64x2, F64x4};
    let mut angles: Vec<f64> = (-4000..=4000).map(|i| i as f64 * 0.0125).collect();
    for k in -8..=8 {
        let q = k as f64 * core::f64::consts::FRAC_PI_4;
        angles.extend([q, q.next_up(), q.next_down()]);
    }
    angles.extend([0.0, -0.0, 1e-300, -1e-300, 8.2e5, -8.2e5]);
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    for special in [None, Some(1e6), Some(f64::NAN)] {
        for chunk in angles.chunks_exact(12) {
            // Three angles per lane, lanes of four.
            let mut lanes: [[f64; 3]; 4] =
                std::array::from_fn(|k| std::array::from_fn(|m| chunk[3 * k + m]));
            if let Some(x) = special {
                lanes[2][1] = x;
            }
            let packed: [F64x4; 3] =
                std::array::from_fn(|m| F64x4::new(std::array::from_fn(|k| lanes[k][m])));
            let (s, c) = F64x4::sincos_batch(packed);
            let pair: [F64x2; 3] = std::array::from_fn(|m| F64x2::new([lanes[0][m], lanes[1][m]]));
            let (s2, c2) = F64x2::sincos_batch(pair);
            for (k, angles) in lanes.iter().enumerate() {
                let (rs, rc) = f64::sincos_batch(*angles);
                for m in 0..3 {
                    assert!(
                        same(s[m].to_array()[k], rs[m]) && same(c[m].to_array()[k], rc[m]),
                        "{angles:?}"
                    );
                    if k < 2 {
                        assert!(
                            same(s2[m].to_array()[k], rs[m]) && same(c2[m].to_array()[k], rc[m])
                        );
                    }
                }
            }
        }
    }
    // f32 lanes: lane by lane through the scalar f32 batch.
    let x: [F32x8; 2] = [
        F32x8::new([0.1, -2.0, 3.5, 0.0, -0.0, 7.0, -1.5, 100.0]),
        F32x8::splat(0.7),
    ];
    let (s, c) = F32x8::sincos_batch(x);
    for k in 0..8 {
        let (rs, rc) = f32::sincos_batch([x[0].to_array()[k], x[1].to_array()[k]]);
        for m in 0..2 {
            assert_eq!(s[m].to_array()[k].to_bits(), rs[m].to_bits());
            assert_eq!(c[m].to_array()[k].to_bits(), rc[m].to_bits());
        }
    }
}

/// The lane types' arithmetic is the scalar's, lane by lane, bit for bit: `-x` flips the sign of a zero
/// (as the scalar does; `0 − x` would not), `select_gt` is false on NaN, square root and absolute value.
#[test]
fn lane_arithmetic_is_the_scalar_arithmetic_lane_by_lane() {
    use embedyn_runtime::codegen_support::Float;
    use embedyn_runtime::lanes::F64x4;
    let a = [0.0, -0.0, 1.5, -2.25, f64::NAN, 1e308, -1e-310, 3.0];
    let b = [1.0, 0.0, -0.0, 7.5, 2.0, 1e308, 3.0, f64::NAN];
    let same = |l: [f64; 4], r: [f64; 4]| {
        l.iter()
            .zip(&r)
            .all(|(p, q)| p.to_bits() == q.to_bits() || (p.is_nan() && q.is_nan()))
    };
    for half in [0, 4] {
        let (a, b): ([f64; 4], [f64; 4]) = (
            std::array::from_fn(|k| a[half + k]),
            std::array::from_fn(|k| b[half + k]),
        );
        let (x, y) = (F64x4::new(a), F64x4::new(b));
        let each =
            |f: &dyn Fn(f64, f64) -> f64| -> [f64; 4] { std::array::from_fn(|k| f(a[k], b[k])) };
        assert!(same((x + y).to_array(), each(&|p, q| p + q)));
        assert!(same((x - y).to_array(), each(&|p, q| p - q)));
        assert!(same((x * y).to_array(), each(&|p, q| p * q)));
        assert!(same((x / y).to_array(), each(&|p, q| p / q)));
        assert!(same((-x).to_array(), each(&|p, _| -p)));
        assert!(same(x.abs().to_array(), each(&|p, _| p.abs())));
        assert!(same(x.sqrt().to_array(), each(&|p, _| p.sqrt())));
        let selected = F64x4::select_gt(x, y, x, y).to_array();
        assert!(same(selected, each(&|p, q| if p > q { p } else { q })));
    }
}
