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
