//! Long simulations and singular configurations of loop models: 10,000 steps with the position
//! completion applied after every step (loop residual stays ≤ 1e-10, energy drift shrinks at RK4's order
//! when the step halves), and a parallelogram four-bar approaching its toggle: accurate 1e-3 rad away,
//! an error quoting cond(Y1) at the toggle, never NaN.

use crate::common;

use common::{load_model, Rng};
use embedyn::constraints::{complete_configuration, complete_velocity, constraint_violation};
use embedyn::{
    aba, forward_kinematics, kinetic_energy, kkt_forward_dynamics, potential_energy,
    relative_error, DynamicsError, Model, Workspace,
};

fn energy(model: &Model<f64>, ws: &mut Workspace<f64>, q: &[f64], v: &[f64]) -> f64 {
    forward_kinematics(model, ws, q, v).unwrap();
    kinetic_energy(model, ws) + potential_energy(model, ws)
}

/// Simulates `steps` RK4 steps of size `h` from (q0, v0), τ = 0, projecting onto the constraints after
/// each step. Returns (largest energy change, largest loop residual).
fn simulate(model: &Model<f64>, q0: &[f64], v0: &[f64], h: f64, steps: usize) -> (f64, f64) {
    let mut ws = Workspace::new(model);
    let (nq, nv) = (model.nq(), model.nv());
    let tau = vec![0.0; nv];
    let (mut q, mut v) = (q0.to_vec(), v0.to_vec());
    let e0 = energy(model, &mut ws, &q, &v);
    let (mut drift, mut residual) = (0.0f64, 0.0f64);
    let axpy = |x: &[f64], d: &[f64], s: f64| -> Vec<f64> {
        x.iter().zip(d).map(|(a, b)| a + s * b).collect()
    };
    for _ in 0..steps {
        let mut deriv = |q: &[f64], v: &[f64]| -> (Vec<f64>, Vec<f64>) {
            let mut qd = vec![0.0; nq];
            model.configuration_rate(q, v, &mut qd);
            (qd, aba(model, &mut ws, q, v, &tau).unwrap().to_vec())
        };
        let (k1q, k1v) = deriv(&q, &v);
        let (k2q, k2v) = deriv(&axpy(&q, &k1q, h / 2.0), &axpy(&v, &k1v, h / 2.0));
        let (k3q, k3v) = deriv(&axpy(&q, &k2q, h / 2.0), &axpy(&v, &k2v, h / 2.0));
        let (k4q, k4v) = deriv(&axpy(&q, &k3q, h), &axpy(&v, &k3v, h));
        for i in 0..nq {
            q[i] += h / 6.0 * (k1q[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + k4q[i]);
        }
        for i in 0..nv {
            v[i] += h / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
        }
        model.normalize_configuration(&mut q);
        complete_configuration(model, &mut ws, &mut q).unwrap();
        complete_velocity(model, &mut ws, &q, &mut v).unwrap();
        let (pos, vel) = constraint_violation(model, &mut ws, &q, &v).unwrap();
        residual = common::worse(residual, common::worse(pos, vel));
        drift = common::worse(drift, (energy(model, &mut ws, &q, &v) - e0).abs());
    }
    (drift, residual)
}

#[test]
fn ten_thousand_steps_stay_on_the_constraints_and_conserve_energy() {
    let model = load_model::<f64>("models/loops/four_bar_internal.urdf", false);
    let mut ws = Workspace::new(&model);
    let mut q = model.neutral_configuration();
    let mut rng = Rng::new(4);
    for j in 0..model.joints.len() {
        if model.is_independent(j) {
            q[model.joints[j].q_index] = rng.uniform(-0.2, 0.2);
        }
    }
    complete_configuration(&model, &mut ws, &mut q).unwrap();
    let mut v = rng.vec(model.nv(), -0.5, 0.5);
    complete_velocity(&model, &mut ws, &q, &mut v).unwrap();
    let (d1, r1) = simulate(&model, &q, &v, 1e-3, 10_000);
    let (d2, r2) = simulate(&model, &q, &v, 5e-4, 20_000);
    let ratio = d1 / d2;
    eprintln!("four-bar, 10 s: energy drift {d1:.2e} J (h = 1 ms, 10,000 steps), {d2:.2e} J (h = 0.5 ms); ratio {ratio:.1}; loop residual ≤ {:.1e}", r1.max(r2));
    assert!(r1 <= 1e-10 && r2 <= 1e-10, "loop residual {r1:e} / {r2:e}");
    assert!(
        (11.0..23.0).contains(&ratio),
        "energy drift ratio {ratio} is not RK4's 16"
    );
    assert!(d1 < 1e-5, "energy drift {d1:e} J");
}

/// Moves the crank of the parallelogram four-bar to `target` in small steps, completing each time (so the
/// linkage stays on its assembly branch), and returns the final configuration.
fn crank_to(model: &Model<f64>, ws: &mut Workspace<f64>, target: f64) -> Vec<f64> {
    let crank = model.joint_index("crank_joint").unwrap();
    let mut q = model.neutral_configuration();
    let steps = 200;
    for k in 1..=steps {
        q[model.joints[crank].q_index] = target * k as f64 / steps as f64;
        complete_configuration(model, ws, &mut q).unwrap();
    }
    q
}

#[test]
fn parallelogram_toggle_is_solved_near_it_and_refused_at_it() {
    let model = load_model::<f64>("models/loops/singular_four_bar.urdf", false);
    let mut ws = Workspace::new(&model);
    // The toggle: the crank lines up with the ground, at ±π/3 from the zero pose (its origin pitch).
    let toggle = std::f64::consts::FRAC_PI_3;
    let zero = vec![0.0; model.nv()];
    let tau = vec![0.3; model.nv()];
    // 1e-3 rad away: an accurate answer (KKT agrees) although Y1 is ill-conditioned.
    let q_near = crank_to(&model, &mut ws, toggle - 1e-3);
    let (pos, _) = constraint_violation(&model, &mut ws, &q_near, &zero).unwrap();
    assert!(pos <= 1e-12, "near-toggle completion residual {pos:e}");
    let cond = embedyn::constraints::y1_condition(&model, &mut ws, &q_near, 0).unwrap();
    let qdd = aba(&model, &mut ws, &q_near, &zero, &tau).unwrap().to_vec();
    let qdd_kkt = kkt_forward_dynamics(&model, &mut ws, &q_near, &zero, &tau).unwrap();
    let e = relative_error(&qdd, &qdd_kkt);
    eprintln!("1e-3 rad from the toggle: cond(Y1) = {cond:.2e}, embedded vs KKT {e:.1e}");
    assert!(
        (1e2..1e5).contains(&cond),
        "cond(Y1) = {cond:e} 1e-3 rad from the toggle"
    );
    assert!(
        e <= 1e-9,
        "near the toggle the embedded answer is off by {e:e}"
    );
    // At the toggle (the flat parallelogram, exact coordinates): the call fails with an error quoting
    // cond(Y1), not NaN.
    let q_at = common::parallelogram_toggle(&model);
    let (pos, _) = constraint_violation(&model, &mut ws, &q_at, &zero).unwrap();
    assert!(
        pos <= 1e-12,
        "the toggle configuration is assembled: residual {pos:e}"
    );
    match aba(&model, &mut ws, &q_at, &zero, &tau) {
        Err(DynamicsError::SingularConstraint { condition, .. }) => {
            assert!(condition >= 1e10, "condition {condition:e}");
            let msg = aba(&model, &mut ws, &q_at, &zero, &tau)
                .unwrap_err()
                .to_string();
            assert!(
                msg.contains("cond(Y1)") && msg.contains("coupler_rocker_pin"),
                "{msg}"
            );
        }
        other => panic!("at the toggle: expected a singularity error, got {other:?}"),
    }
}
