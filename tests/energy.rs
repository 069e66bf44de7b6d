//! Energy balance: a free robot (τ = 0) under gravity conserves kinetic + potential energy, so the drift of
//! a 4th-order integrator shrinks ~16× when the step halves; and at an instant dE/dt = τ·v.
//! The instantaneous check uses a central difference along (q + s q̇, v + s qdd); that straight path
//! shares the trajectory's first derivative, which is all dE/dt needs.

use crate::common;

use common::{load_model, Rng};
use embedyn::{aba, forward_kinematics, kinetic_energy, potential_energy, Model, Workspace};

fn energy(model: &Model<f64>, ws: &mut Workspace<f64>, q: &[f64], v: &[f64]) -> f64 {
    forward_kinematics(model, ws, q, v).unwrap();
    kinetic_energy(model, ws) + potential_energy(model, ws)
}

/// One classical Runge–Kutta step of (q, v) with qdd = ABA(q, v, τ).
fn rk4_step(
    model: &Model<f64>,
    ws: &mut Workspace<f64>,
    q: &mut [f64],
    v: &mut [f64],
    tau: &[f64],
    h: f64,
) {
    let (nq, nv) = (model.nq(), model.nv());
    let mut deriv = |q: &[f64], v: &[f64]| -> (Vec<f64>, Vec<f64>) {
        let mut qd = vec![0.0; nq];
        model.configuration_rate(q, v, &mut qd);
        let a = aba(model, ws, q, v, tau).unwrap().to_vec();
        (qd, a)
    };
    let axpy = |x: &[f64], d: &[f64], s: f64| -> Vec<f64> {
        x.iter().zip(d).map(|(a, b)| a + s * b).collect()
    };
    let (k1q, k1v) = deriv(q, v);
    let (k2q, k2v) = deriv(&axpy(q, &k1q, h / 2.0), &axpy(v, &k1v, h / 2.0));
    let (k3q, k3v) = deriv(&axpy(q, &k2q, h / 2.0), &axpy(v, &k2v, h / 2.0));
    let (k4q, k4v) = deriv(&axpy(q, &k3q, h), &axpy(v, &k3v, h));
    for i in 0..nq {
        q[i] += h / 6.0 * (k1q[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + k4q[i]);
    }
    for i in 0..nv {
        v[i] += h / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
    }
    model.normalize_configuration(q);
}

/// Largest |E(t) − E(0)| over a simulation of `duration` seconds with step `h`.
fn drift(model: &Model<f64>, q0: &[f64], v0: &[f64], h: f64, duration: f64) -> f64 {
    let mut ws = Workspace::new(model);
    let (mut q, mut v) = (q0.to_vec(), v0.to_vec());
    let tau = vec![0.0; model.nv()];
    let e0 = energy(model, &mut ws, &q, &v);
    let steps = (duration / h).round() as usize;
    let mut worst = 0.0f64;
    for _ in 0..steps {
        rk4_step(model, &mut ws, &mut q, &mut v, &tau, h);
        worst = common::worse(worst, (energy(model, &mut ws, &q, &v) - e0).abs());
    }
    worst
}

fn check_drift_order(path: &str, floating: bool, h: f64) {
    let model = load_model::<f64>(path, floating);
    let mut rng = Rng::new(3);
    let q = rng.configuration(&model);
    let v = rng.vec(model.nv(), -1.0, 1.0);
    let d1 = drift(&model, &q, &v, h, 0.5);
    let d2 = drift(&model, &q, &v, h / 2.0, 0.5);
    let ratio = d1 / d2;
    eprintln!("{path}: energy drift {d1:.3e} (h = {h}), {d2:.3e} (h/2), ratio {ratio:.1}");
    // RK4: the error shrinks 2⁴ = 16× per halving; accept 11–23 (the asymptotic regime is approached,
    // not reached exactly). A wrong acceleration would make energy drift at O(1), not shrink.
    assert!(
        (11.0..23.0).contains(&ratio),
        "{path}: drift ratio {ratio} is not 4th order"
    );
    assert!(d1 < 1e-4, "{path}: drift {d1:e} J too large");
}

#[test]
fn energy_is_conserved_at_the_integrators_order_arm() {
    check_drift_order("models/arm7.urdf", false, 2e-3);
}

#[test]
fn energy_is_conserved_at_the_integrators_order_quadruped() {
    check_drift_order("models/quadruped.urdf", false, 2e-3);
}

#[test]
fn power_balance_at_an_instant() {
    // dE/dt = τ·v, with dE/dt by a central difference along the motion qdd = ABA(q, v, τ).
    for (path, floating) in [
        ("models/arm7.urdf", false),
        ("models/humanoid34.urdf", false),
        ("models/quadruped.urdf", false),
    ] {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        let mut rng = Rng::new(17);
        let q = rng.configuration(&model);
        let v = rng.vec(model.nv(), -1.0, 1.0);
        let tau = rng.vec(model.nv(), -5.0, 5.0);
        let qdd = aba(&model, &mut ws, &q, &v, &tau).unwrap().to_vec();
        let mut qd = vec![0.0; model.nq()];
        model.configuration_rate(&q, &v, &mut qd);
        let h = 1e-4;
        let at = |s: f64, ws: &mut Workspace<f64>| {
            let mut qs: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + s * b).collect();
            model.normalize_configuration(&mut qs);
            let vs: Vec<f64> = v.iter().zip(&qdd).map(|(a, b)| a + s * b).collect();
            energy(&model, ws, &qs, &vs)
        };
        // Fourth-order central stencil: truncation O(h⁴), rounding O(ε E / h).
        let de = (-at(2.0 * h, &mut ws) + 8.0 * at(h, &mut ws) - 8.0 * at(-h, &mut ws)
            + at(-2.0 * h, &mut ws))
            / (12.0 * h);
        let power: f64 = tau.iter().zip(&v).map(|(t, w)| t * w).sum();
        let err = (de - power).abs() / power.abs().max(1.0);
        eprintln!("{path}: dE/dt {de:.9}, τ·v {power:.9}, relative difference {err:.1e}");
        assert!(err < 1e-7, "{path}: dE/dt = {de} but τ·v = {power}");
    }
}
