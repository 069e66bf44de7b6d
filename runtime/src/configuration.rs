//! The configuration space: `integrate(q, v)` = q ⊕ v, `difference(q0, q1)` = q1 ⊖ q0 and random
//! configurations (docs/conventions.md, "Configuration space").
//!
//! A revolute, continuous or prismatic coordinate is a plain number (continuous joints are angles, not
//! cos/sin pairs): `integrate` adds, `difference` subtracts. A floating joint's `q = [x y z qx qy qz qw]`
//! is a pose M = (R, p) of SE(3) and its `v = [v_lin ω]` a twist in the body frame; as in Pinocchio,
//! `integrate` is M ⊕ v = M · exp(v) and `difference` is log(M0⁻¹ M1), the twist of least rotation
//! (angle ≤ π: a quaternion and its negative are the same configuration).
//!
//! Every function is allocation-free, generic over [`Real`] and free of branches on values: small-angle
//! series and the choice of the shorter rotation are [`Real::select_gt`]s, so the code generator traces
//! them into straight-line code (`integrate` and `difference` of `embedyn::robot!`). The angle of a
//! rotation is computed from its quaternion by an arctangent built from square roots and a series
//! (exact to the scalar's precision), without `acos` of a trace, so `difference` keeps full precision at
//! angles near 0 and near π.

use crate::algorithms::{check_configuration, check_input, DynamicsError};
use crate::model::{quaternion_to_rotation, JointType, Model};
use crate::random::SplitMix64;
use crate::Real;
use nalgebra::Vector3;

/// Below this rotation angle (rad) the coefficients of the SE(3) exponential and logarithm come from
/// their Taylor series (to θ⁸: truncation below 10⁻¹⁹), above it from their closed forms.
const SERIES_BELOW: f64 = 0.1;

/// `q_out = integrate(q, v)` = q ⊕ v: every revolute, continuous and prismatic coordinate plus its
/// velocity; every floating joint's pose M moved to M · exp(v) by the SE(3) exponential of its body-frame
/// twist `[v_lin ω]` (Pinocchio's `integrate`). The result's quaternions have unit norm, with the sign
/// Pinocchio gives them (the one nearer `q`'s). Integrating a velocity `v` for a time `dt` is
/// `integrate(q, dt · v)`.
///
/// `q`'s quaternions may have any non-zero norm (their rotation is used); the spanning tree's coordinates
/// of a model with loops, couplings or mimic joints are integrated one by one (the result satisfies the
/// constraints only to first order in `v`; `complete` projects it back).
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// # let model = embedyn::Model::<f64>::builder("one").build().unwrap();
/// let q = model.neutral_configuration();
/// let v = vec![0.0; model.nv()];
/// let mut q_out = vec![0.0; model.nq()];
/// embedyn::integrate(&model, &q, &v, &mut q_out).unwrap();
/// assert_eq!(q_out, q);
/// ```
///
/// # Errors
/// [`DynamicsError::WrongLength`] if `q` or `q_out` is not [`Model::nq`] long or `v` not [`Model::nv`];
/// [`DynamicsError::NonFiniteInput`] for a NaN or infinite entry; [`DynamicsError::InvalidQuaternion`] for a
/// zero quaternion.
pub fn integrate<T: Real>(
    model: &Model<T>,
    q: &[T],
    v: &[T],
    q_out: &mut [T],
) -> Result<(), DynamicsError> {
    check_configuration(model, q)?;
    check_input("v", v, model.nv())?;
    crate::algorithms::check_len("q_out", q_out.len(), model.nq())?;
    for j in &model.joints {
        let (iq, iv) = (j.q_index, j.v_index);
        match j.joint_type {
            JointType::Floating => {
                integrate_se3(&q[iq..iq + 7], &v[iv..iv + 6], &mut q_out[iq..iq + 7])
            }
            _ => q_out[iq] = q[iq] + v[iv],
        }
    }
    Ok(())
}

/// `v_out = difference(q0, q1)` = q1 ⊖ q0, the velocity that [`integrate`] takes from `q0` to `q1`:
/// every revolute, continuous and prismatic coordinate `q1 − q0` (no wrapping of angles: a continuous
/// joint's angle is a plain number); every floating joint's body-frame twist log(M0⁻¹ M1) (Pinocchio's
/// `difference`), of the least rotation (angle ≤ π, whatever the signs of the two quaternions).
///
/// # Errors
/// [`DynamicsError::WrongLength`] if `q0` or `q1` is not [`Model::nq`] long or `v_out` not [`Model::nv`];
/// [`DynamicsError::NonFiniteInput`] for a NaN or infinite entry; [`DynamicsError::InvalidQuaternion`] for a
/// zero quaternion.
pub fn difference<T: Real>(
    model: &Model<T>,
    q0: &[T],
    q1: &[T],
    v_out: &mut [T],
) -> Result<(), DynamicsError> {
    check_configuration(model, q0)?;
    check_configuration(model, q1).map_err(|e| match e {
        DynamicsError::NonFiniteInput { index, value, .. } => DynamicsError::NonFiniteInput {
            name: "q1",
            index,
            value,
        },
        DynamicsError::WrongLength { got, expected, .. } => DynamicsError::WrongLength {
            name: "q1",
            got,
            expected,
        },
        other => other,
    })?;
    crate::algorithms::check_len("v_out", v_out.len(), model.nv())?;
    for j in &model.joints {
        let (iq, iv) = (j.q_index, j.v_index);
        match j.joint_type {
            JointType::Floating => {
                difference_se3(&q0[iq..iq + 7], &q1[iq..iq + 7], &mut v_out[iv..iv + 6])
            }
            _ => v_out[iv] = q1[iq] - q0[iq],
        }
    }
    Ok(())
}

/// The default bounds of [`random_configuration`] for a coordinate without limits: ±π rad for a
/// revolute or continuous joint, ±1 m for a prismatic joint and a floating joint's position.
pub const DEFAULT_ANGLE_BOUND: f64 = core::f64::consts::PI;
/// See [`DEFAULT_ANGLE_BOUND`].
pub const DEFAULT_DISPLACEMENT_BOUND: f64 = 1.0;

/// A random configuration into `q_out`: each revolute, continuous and prismatic coordinate and each
/// coordinate of a floating joint's position uniform in `[lower[i], upper[i])`; each floating joint's
/// quaternion uniform on the unit sphere of rotations (Shoemake's method). `lower` and `upper` are over
/// `q` (length [`Model::nq`]; their quaternion entries are ignored); a bound that is not finite (an
/// absent limit: pass ±∞) is replaced by the default, ±[`DEFAULT_ANGLE_BOUND`] for angles and
/// ±[`DEFAULT_DISPLACEMENT_BOUND`] for displacements. The same seed gives the same configuration.
///
/// A model with loops, couplings or mimic joints gets random spanning coordinates: complete them
/// (`constraints::complete`) to a consistent configuration.
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::nalgebra::{Matrix3, Vector3};
/// use embedyn::{random_configuration, JointType, Model, SpatialInertia, SplitMix64, Transform};
/// let mut b = Model::<f64>::builder("pendulum");
/// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
/// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), Transform::identity(), "bob", inertia)
///     .unwrap();
/// let model = b.build().unwrap();
/// let (mut q1, mut q2) = ([0.0], [0.0]);
/// random_configuration(&model, &mut SplitMix64::new(7), &[-1.0], &[1.0], &mut q1).unwrap();
/// random_configuration(&model, &mut SplitMix64::new(7), &[-1.0], &[1.0], &mut q2).unwrap();
/// assert_eq!(q1, q2);
/// assert!((-1.0..1.0).contains(&q1[0]));
/// ```
///
/// # Errors
/// [`DynamicsError::WrongLength`] if `lower`, `upper` or `q_out` is not [`Model::nq`] long.
pub fn random_configuration<T: Real>(
    model: &Model<T>,
    rng: &mut SplitMix64,
    lower: &[f64],
    upper: &[f64],
    q_out: &mut [T],
) -> Result<(), DynamicsError> {
    use crate::algorithms::check_len;
    check_len("lower", lower.len(), model.nq())?;
    check_len("upper", upper.len(), model.nq())?;
    check_len("q_out", q_out.len(), model.nq())?;
    draw_configuration(model, rng, |i| (lower[i], upper[i]), q_out);
    Ok(())
}

/// [`random_configuration`] within the model's own joint limits (`<limit lower upper>`, [`Joint::limits`]):
/// each bound the file gives is used, each it does not (a continuous joint, a floating joint's position)
/// falls back to the defaults of [`random_configuration`].
///
/// # Errors
/// [`DynamicsError::WrongLength`] if `q_out` is not [`Model::nq`] long.
///
/// [`Joint::limits`]: crate::Joint::limits
pub fn random_configuration_within_limits<T: Real>(
    model: &Model<T>,
    rng: &mut SplitMix64,
    q_out: &mut [T],
) -> Result<(), DynamicsError> {
    crate::algorithms::check_len("q_out", q_out.len(), model.nq())?;
    draw_configuration(
        model,
        rng,
        |i| {
            // Limits are per joint of one coordinate; a floating joint's coordinates have none.
            model
                .joints
                .iter()
                .find(|j| j.q_index == i && j.nq() == 1)
                .map_or((f64::NEG_INFINITY, f64::INFINITY), |j| {
                    (
                        j.limits.lower.map_or(f64::NEG_INFINITY, |x| x.to_f64()),
                        j.limits.upper.map_or(f64::INFINITY, |x| x.to_f64()),
                    )
                })
        },
        q_out,
    );
    Ok(())
}

/// The draw of [`random_configuration`], with the bounds of coordinate `i` from `bounds(i)`.
fn draw_configuration<T: Real>(
    model: &Model<T>,
    rng: &mut SplitMix64,
    bounds: impl Fn(usize) -> (f64, f64),
    q_out: &mut [T],
) {
    let draw = |rng: &mut SplitMix64, i: usize, default: f64| {
        let (lower, upper) = bounds(i);
        let lo = if lower.is_finite() { lower } else { -default };
        let hi = if upper.is_finite() { upper } else { default };
        T::from_f64(rng.uniform(lo, hi))
    };
    for j in &model.joints {
        let i = j.q_index;
        match j.joint_type {
            JointType::Floating => {
                for k in 0..3 {
                    q_out[i + k] = draw(rng, i + k, DEFAULT_DISPLACEMENT_BOUND);
                }
                // Shoemake, "Uniform random rotations" (Graphics Gems III, 1992).
                let (u1, u2, u3) = (rng.unit(), rng.unit(), rng.unit());
                let tau = 2.0 * core::f64::consts::PI;
                let (a, b) = (sqrt_f64(1.0 - u1), sqrt_f64(u1));
                let (s2, c2) = (T::from_f64(tau * u2)).sin_cos();
                let (s3, c3) = (T::from_f64(tau * u3)).sin_cos();
                let (a, b) = (T::from_f64(a), T::from_f64(b));
                q_out[i + 3] = a * s2;
                q_out[i + 4] = a * c2;
                q_out[i + 5] = b * s3;
                q_out[i + 6] = b * c3;
            }
            JointType::Prismatic => q_out[i] = draw(rng, i, DEFAULT_DISPLACEMENT_BOUND),
            JointType::Revolute | JointType::Continuous => {
                q_out[i] = draw(rng, i, DEFAULT_ANGLE_BOUND)
            }
        }
    }
}

/// √x in f64 without `std` (through the scalar trait's square root).
fn sqrt_f64(x: f64) -> f64 {
    Real::sqrt(x)
}

/// Hamilton product `a ⊗ b` of quaternions `[x y z w]`.
#[inline(always)]
fn quaternion_product<T: Real>(a: [T; 4], b: [T; 4]) -> [T; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + bw * ax + ay * bz - az * by,
        aw * by + bw * ay + az * bx - ax * bz,
        aw * bz + bw * az + ax * by - ay * bx,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// `a × b`.
#[inline(always)]
fn cross<T: Real>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `c(x) = Σₖ coefficients[k] · xᵏ` by Horner's rule.
#[inline(always)]
fn polynomial<T: Real>(x: T, coefficients: &[f64]) -> T {
    let mut sum = T::zero();
    for &c in coefficients.iter().rev() {
        sum = sum * x + T::from_f64(c);
    }
    sum
}

/// M · exp(v) for one floating joint: `q` its 7 coordinates, `v` its 6 velocities.
#[inline(always)]
fn integrate_se3<T: Real>(q: &[T], v: &[T], out: &mut [T]) {
    let one = T::one();
    let half = T::from_f64(0.5);
    let w = [v[3], v[4], v[5]];
    let u = [v[0], v[1], v[2]];
    let theta2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    let theta = theta2.sqrt();
    let (sin_half, cos_half) = (theta * half).sin_cos();
    let small = T::from_f64(SERIES_BELOW);
    // h = sin(θ/2)/θ, so that the rotation's quaternion is [h ω, cos(θ/2)] and (1 − cos θ)/θ² = 2h².
    let h = theta.select_gt(
        small,
        sin_half / theta,
        polynomial(
            theta2,
            &[
                0.5,
                -1.0 / 48.0,
                1.0 / 3840.0,
                -1.0 / 645120.0,
                1.0 / 185794560.0,
            ],
        ),
    );
    // b = (θ − sin θ)/θ³.
    let b = theta.select_gt(
        small,
        (theta - theta.sin()) / (theta2 * theta),
        polynomial(
            theta2,
            &[
                1.0 / 6.0,
                -1.0 / 120.0,
                1.0 / 5040.0,
                -1.0 / 362880.0,
                1.0 / 39916800.0,
            ],
        ),
    );
    let a = T::from_f64(2.0) * h * h;
    // p_local = V v_lin, V = I + a [ω]× + b [ω]×².
    let wu = cross(w, u);
    let wwu = cross(w, wu);
    let local = Vector3::new(
        u[0] + a * wu[0] + b * wwu[0],
        u[1] + a * wu[1] + b * wwu[1],
        u[2] + a * wu[2] + b * wwu[2],
    );
    let quat = [q[3], q[4], q[5], q[6]];
    let moved = quaternion_to_rotation(quat) * local;
    out[0] = q[0] + moved.x;
    out[1] = q[1] + moved.y;
    out[2] = q[2] + moved.z;
    // Rotation: quat ⊗ [h ω, cos(θ/2)], signed so that it is the nearer to `quat` (Pinocchio's choice:
    // a non-negative dot product), and normalized.
    let turned = quaternion_product(quat, [h * w[0], h * w[1], h * w[2], cos_half]);
    let sign = T::zero().select_gt(cos_half, -one, one);
    let norm = (turned[0] * turned[0]
        + turned[1] * turned[1]
        + turned[2] * turned[2]
        + turned[3] * turned[3])
        .sqrt();
    let scale = sign / norm;
    for k in 0..4 {
        out[3 + k] = turned[k] * scale;
    }
}

/// log(M0⁻¹ M1) for one floating joint: `q0`, `q1` its 7 coordinates, `v` its 6 velocities.
#[inline(always)]
fn difference_se3<T: Real>(q0: &[T], q1: &[T], v: &mut [T]) {
    let one = T::one();
    let half = T::from_f64(0.5);
    let quat0 = [q0[3], q0[4], q0[5], q0[6]];
    let quat1 = [q1[3], q1[4], q1[5], q1[6]];
    // The relative rotation conj(quat0) ⊗ quat1, of non-negative scalar part: the shorter way round.
    let rel = quaternion_product([-quat0[0], -quat0[1], -quat0[2], quat0[3]], quat1);
    let sign = T::zero().select_gt(rel[3], -one, one);
    let (x, y, z, c) = (rel[0] * sign, rel[1] * sign, rel[2] * sign, rel[3] * sign);
    let s = (x * x + y * y + z * z).sqrt();
    // φ = θ/2 ∈ [0, π/2], the half angle; ω = θ · axis = (2φ/s) [x y z].
    let phi = atan2_nonnegative(s, c);
    let t = s / c;
    let t2 = t * t;
    let k = s.select_gt(
        T::from_f64(1e-4) * c,
        T::from_f64(2.0) * phi / s,
        T::from_f64(2.0) / c * polynomial(t2, &[1.0, -1.0 / 3.0, 1.0 / 5.0]),
    );
    let w = [k * x, k * y, k * z];
    let theta = T::from_f64(2.0) * phi;
    let theta2 = theta * theta;
    // V⁻¹ = I − ½ [ω]× + e [ω]×², e = (1 − (θ/2) cot(θ/2))/θ².
    let e = theta.select_gt(
        T::from_f64(SERIES_BELOW),
        (one - phi * c / s) / theta2,
        polynomial(
            theta2,
            &[
                1.0 / 12.0,
                1.0 / 720.0,
                1.0 / 30240.0,
                1.0 / 1209600.0,
                1.0 / 47900160.0,
            ],
        ),
    );
    // The translation of M0⁻¹ M1 in frame 0: R0ᵀ (p1 − p0).
    let dp = Vector3::new(q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]);
    let p = quaternion_to_rotation(quat0).transpose() * dp;
    let p = [p.x, p.y, p.z];
    let wp = cross(w, p);
    let wwp = cross(w, wp);
    for i in 0..3 {
        v[i] = p[i] - half * wp[i] + e * wwp[i];
        v[3 + i] = w[i];
    }
}

/// atan2(s, c) for `s, c ≥ 0` (not both zero), in `[0, π/2]`, without branches: the octant by a select,
/// three argument halvings `atan t = 2 atan(t / (1 + √(1 + t²)))` down to `t ≤ tan(π/32)`, then the
/// arctangent's series to the scalar's precision.
#[inline(always)]
fn atan2_nonnegative<T: Real>(s: T, c: T) -> T {
    let one = T::one();
    let ratio = s.min(c) / s.max(c);
    let mut t = ratio;
    for _ in 0..3 {
        t = t / (one + (one + t * t).sqrt());
    }
    // Terms of Σ (−1)ᵏ t²ᵏ/(2k + 1) while t²ᵏ/(2k + 1) at t = tan(π/32) matters at the scalar's precision.
    let eps = T::epsilon().to_f64();
    let x2 = 0.0985_f64 * 0.0985;
    let mut n = 1;
    while n < 40 && powi(x2, n) / (2 * n + 1) as f64 > eps / 8.0 {
        n += 1;
    }
    let t2 = t * t;
    let mut sum = T::zero();
    for k in (0..n).rev() {
        let ck = T::one() / T::from_f64((2 * k + 1) as f64);
        sum = ck - t2 * sum;
    }
    let a = T::from_f64(8.0) * t * sum;
    // π/2 as a sum of two f64 (exact in a double-double scalar, the first alone in f64 and f32).
    let right = T::from_f64(core::f64::consts::FRAC_PI_2) + T::from_f64(6.123_233_995_736_766e-17);
    s.select_gt(c, right - a, a)
}

fn powi(x: f64, n: usize) -> f64 {
    (0..n).fold(1.0, |p, _| p * x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_arctangent_is_exact_to_the_last_bits() {
        for i in 0..=2000 {
            let angle = core::f64::consts::FRAC_PI_2 * i as f64 / 2000.0;
            let (s, c) = (angle.sin(), angle.cos());
            let got = atan2_nonnegative(s, c);
            let want = s.atan2(c);
            assert!(
                (got - want).abs() <= 4.0 * f64::EPSILON,
                "{angle}: {got} vs {want}"
            );
            // Any scale.
            assert!((atan2_nonnegative(3.0 * s, 3.0 * c) - want).abs() <= 4.0 * f64::EPSILON);
        }
        assert_eq!(atan2_nonnegative(1e-300, 1.0), 1e-300);
        assert_eq!(atan2_nonnegative(1.0, 0.0), core::f64::consts::FRAC_PI_2);
        let got = atan2_nonnegative(0.3f32, 0.4f32);
        assert!((got - 0.3f32.atan2(0.4)).abs() <= 2.0 * f32::EPSILON);
    }
}
