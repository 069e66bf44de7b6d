//! Property tests over random loop topologies: planar four-bars, slider-cranks and gear trains attached at
//! random bodies of random trees (fixed and floating roots). At random consistent states the O(N)
//! embedded forward dynamics equals the Lagrange-multiplier (KKT) solution, or the call refuses with the
//! singular-constraint error — never a NaN, never a panic (issue 8).
//!
//! Every mechanism is assembled at q = 0 by construction (its cut frames are placed where the tree puts
//! them at q = 0), and states are sampled near it by completion, so most cases are regular; the test
//! counts them and requires that they are the majority, so it cannot pass by refusing everything.

use crate::common;

use common::{random_tree, Rng};
use embedyn::constraints::{
    complete_configuration, complete_velocity, constraint_condition, Constraint, ConstraintKind,
    LoopClosure, LoopType,
};
use embedyn::nalgebra::{Matrix3, Vector3};
use embedyn::{
    aba, kkt_forward_dynamics, relative_error, DynamicsError, JointType, Model, ModelBuilder,
    SpatialInertia, Transform, Workspace,
};
use proptest::prelude::*;

/// A random, physically valid inertia (principal moments of a box, rotated; mass 0.05–2 kg).
fn inertia(rng: &mut Rng) -> SpatialInertia<f64> {
    let mass = rng.uniform(0.05, 2.0);
    let (x, y, z) = (
        rng.uniform(0.02, 0.3),
        rng.uniform(0.02, 0.3),
        rng.uniform(0.02, 0.3),
    );
    let d = Matrix3::from_diagonal(&Vector3::new(y * y + z * z, x * x + z * z, x * x + y * y))
        * (mass / 12.0);
    let r = Transform::<f64>::from_xyz_rpy([0.0; 3], [rng.uniform(-3.0, 3.0), 0.4, -0.7]).rotation;
    let com = Vector3::new(
        rng.uniform(-0.1, 0.1),
        rng.uniform(-0.1, 0.1),
        rng.uniform(-0.1, 0.1),
    );
    SpatialInertia::from_com(mass, com, r * d * r.transpose())
}

/// A rotation about the plane normal y by `angle`.
fn about_y(angle: f64) -> Transform<f64> {
    Transform::from_xyz_rpy([0.0; 3], [0.0, angle, 0.0])
}

fn at(x: f64, z: f64) -> Transform<f64> {
    Transform::from_xyz_rpy([x, 0.0, z], [0.0; 3])
}

/// The tree of `base` as builder input: bodies re-added in order so that mechanisms can hang from them.
fn rebuild(base: &Model<f64>, name: &str) -> ModelBuilder<f64> {
    let mut b = Model::<f64>::builder(name);
    for (j, body) in base.joints.iter().zip(&base.bodies) {
        b.add_body(
            j.parent,
            j.name.clone(),
            j.joint_type,
            j.axis,
            j.placement,
            body.name.clone(),
            body.inertia,
        )
        .unwrap();
    }
    b
}

/// Adds a planar four-bar (`slider = false`) or slider-crank (`slider = true`) hanging from body `attach`
/// in a plane of random orientation: crank and rocker (or slider) on `attach`, the coupler on the crank, a
/// revolute cut between the coupler's far end and the rocker (slider). Returns the number of bodies added.
fn add_linkage(
    b: &mut ModelBuilder<f64>,
    rng: &mut Rng,
    attach: Option<usize>,
    tag: usize,
    slider: bool,
) -> usize {
    // The mechanism's plane: the x-z plane of a random frame on the attachment body.
    let plane = Transform::from_xyz_rpy(
        [
            rng.uniform(-0.2, 0.2),
            rng.uniform(-0.2, 0.2),
            rng.uniform(-0.2, 0.2),
        ],
        [
            rng.uniform(-3.0, 3.0),
            rng.uniform(-1.5, 1.5),
            rng.uniform(-3.0, 3.0),
        ],
    );
    let y = Vector3::y();
    let crank_len = rng.uniform(0.05, 0.15);
    let coupler_len = rng.uniform(0.25, 0.4);
    // Crank pivot at the plane's origin, pointing at a random angle; coupler folded back by another.
    let crank_pose = plane.compose(&about_y(rng.uniform(-3.0, 3.0)));
    let coupler_pose_in_crank = at(crank_len, 0.0).compose(&about_y(rng.uniform(0.5, 2.5)));
    let crank = b
        .add_body(
            attach,
            format!("crank{tag}"),
            JointType::Revolute,
            y,
            crank_pose,
            format!("crank_link{tag}"),
            inertia(rng),
        )
        .unwrap();
    let coupler = b
        .add_body(
            Some(crank),
            format!("coupler{tag}"),
            JointType::Revolute,
            y,
            coupler_pose_in_crank,
            format!("coupler_link{tag}"),
            inertia(rng),
        )
        .unwrap();
    // The cut: the coupler's far end, and the point of the rocker (slider) that is there at q = 0.
    let pin_in_coupler = at(coupler_len, 0.0);
    let pin_in_attach = crank_pose
        .compose(&coupler_pose_in_crank)
        .compose(&pin_in_coupler);
    let (last_pose, joint_type, axis) = if slider {
        // The slider moves along the direction from the crank pivot to the pin at q = 0.
        let d = pin_in_attach.translation - crank_pose.translation;
        let along = plane.rotation.transpose() * d;
        let angle = (-along.z).atan2(along.x);
        (
            plane.compose(&about_y(angle)),
            JointType::Prismatic,
            Vector3::x(),
        )
    } else {
        // Rocker pivot elsewhere in the plane, towards the pin.
        let pivot = plane.compose(&at(rng.uniform(0.15, 0.3), rng.uniform(-0.1, 0.1)));
        (
            pivot.compose(&about_y(rng.uniform(-3.0, 3.0))),
            JointType::Revolute,
            y,
        )
    };
    let last = b
        .add_body(
            attach,
            format!("rocker{tag}"),
            joint_type,
            axis,
            last_pose,
            format!("rocker_link{tag}"),
            inertia(rng),
        )
        .unwrap();
    let pin_in_last = last_pose.inverse().compose(&pin_in_attach);
    b.add_constraint(Constraint {
        name: format!("pin{tag}"),
        kind: ConstraintKind::Loop(LoopClosure::new(
            LoopType::Revolute,
            Some(coupler),
            pin_in_coupler,
            Some(last),
            pin_in_last,
            y,
        )),
    });
    3
}

/// Adds a gear train at revolute body `driven`: a rotor beside it (same parent) turning `ratio` times as
/// fast, and sometimes a second stage driven by the first rotor. Returns the number of bodies added.
fn add_gears(
    b: &mut ModelBuilder<f64>,
    rng: &mut Rng,
    driven: usize,
    parent: Option<usize>,
    tag: usize,
) -> usize {
    let mut source = driven;
    let stages = 1 + (rng.next_u64() % 2) as usize;
    for stage in 0..stages {
        let axis = Vector3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        );
        let small = SpatialInertia::from_com(
            rng.uniform(0.01, 0.2),
            Vector3::zeros(),
            Matrix3::from_diagonal(&Vector3::new(1e-5, 1.2e-5, 2e-5)),
        );
        let rotor = b
            .add_body(
                parent,
                format!("rotor{tag}_{stage}"),
                JointType::Revolute,
                axis,
                Transform::from_xyz_rpy([0.05, 0.0, 0.02 * stage as f64], [0.3, 0.0, 0.1]),
                format!("rotor_link{tag}_{stage}"),
                small,
            )
            .unwrap();
        let ratio = rng.uniform(2.0, 50.0)
            * if rng.next_u64().is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
        // rotor = ratio · source (+ an offset, as a <mimic> may carry).
        b.add_constraint(Constraint {
            name: format!("gear{tag}_{stage}"),
            kind: ConstraintKind::Linear {
                terms: vec![(rotor, 1.0), (source, -ratio)],
                offset: rng.uniform(-0.1, 0.1),
            },
        });
        b.declare_dependent(rotor);
        source = rotor;
    }
    stages
}

/// A random tree with one to three mechanisms; `None` when the builder refuses it (e.g. a linkage built
/// at its own toggle), which the caller counts.
fn random_model(rng: &mut Rng) -> Result<Model<f64>, embedyn::ModelError> {
    let n = 2 + (rng.next_u64() % 6) as usize;
    let floating = rng.next_u64().is_multiple_of(3);
    let tree = random_tree(rng, n, floating);
    let mut b = rebuild(&tree, "random_loops");
    let mut count = tree.nbodies();
    let mechanisms = 1 + (rng.next_u64() % 3) as usize;
    for tag in 0..mechanisms {
        let attach = match rng.next_u64() % (count as u64 + 1) {
            0 => None,
            k => Some(k as usize - 1),
        };
        match rng.next_u64() % 3 {
            0 => count += add_linkage(&mut b, rng, attach, tag, false),
            1 => count += add_linkage(&mut b, rng, attach, tag, true),
            _ => {
                // Gears on a revolute joint of the tree that no other gear drives yet.
                let candidates: Vec<usize> = (0..tree.nbodies())
                    .filter(|&i| tree.joints[i].joint_type == JointType::Revolute)
                    .collect();
                if candidates.is_empty() {
                    continue;
                }
                let driven = candidates[(rng.next_u64() % candidates.len() as u64) as usize];
                count += add_gears(&mut b, rng, driven, tree.joints[driven].parent, tag);
            }
        }
    }
    b.build()
}

/// Outcomes of one model's states: (regular states checked, refusals).
fn check(seed: u64) -> Result<(usize, usize), TestCaseError> {
    let mut rng = Rng::new(seed);
    let model = match random_model(&mut rng) {
        Ok(m) => m,
        // Refused at load (a dependent choice that is singular where the builder assembled it): a clear
        // error is an allowed outcome; the majority check in the test keeps this honest.
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(
                msg.contains("cond(Y1)") || msg.contains("never meet"),
                "seed {seed}: unexpected load error {msg}"
            );
            return Ok((0, 1));
        }
    };
    let mut ws = Workspace::new(&model);
    let (mut regular, mut refused) = (0, 0);
    for _ in 0..4 {
        let mut q = model.neutral_configuration();
        for (j, joint) in model.joints.iter().enumerate() {
            match joint.joint_type {
                JointType::Floating => {
                    let quat = rng.vec(4, -1.0, 1.0);
                    q[joint.q_index + 3..joint.q_index + 7].copy_from_slice(&quat);
                }
                _ if model.is_independent(j) => q[joint.q_index] = rng.uniform(-0.25, 0.25),
                _ => {}
            }
        }
        model.normalize_configuration(&mut q);
        let residual = complete_configuration(&model, &mut ws, &mut q);
        let residual = match residual {
            Ok(r) => r,
            Err(DynamicsError::SingularConstraint { .. }) => {
                refused += 1;
                continue;
            }
            Err(e) => return Err(TestCaseError::fail(format!("seed {seed}: completion: {e}"))),
        };
        if residual.is_nan() || residual > 1e-12 {
            // The sampled independent coordinates are outside this linkage's range: no state to test.
            refused += 1;
            continue;
        }
        let mut v = rng.vec(model.nv(), -1.0, 1.0);
        let tau = rng.vec(model.nv(), -3.0, 3.0);
        let embedded = complete_velocity(&model, &mut ws, &q, &mut v)
            .and_then(|_| aba(&model, &mut ws, &q, &v, &tau).map(|x| x.to_vec()));
        match embedded {
            Ok(qdd) => {
                prop_assert!(
                    qdd.iter().all(|x| x.is_finite()),
                    "seed {seed}: non-finite qdd {qdd:?}"
                );
                let cond = constraint_condition(&ws);
                let kkt = kkt_forward_dynamics(&model, &mut ws, &q, &v, &tau)
                    .map_err(|e| TestCaseError::fail(format!("seed {seed}: KKT: {e}")))?;
                let e = relative_error(&qdd, &kkt);
                // Both solves are backward stable: they differ by the conditioning of the loops (cond)
                // and of the mass matrix and gear ratios (the 1e-9 floor covers ratios up to 50²).
                let tol = 1e-9 * cond.max(1.0);
                prop_assert!(
                    e <= tol,
                    "seed {seed}: embedded vs KKT {e:e} > {tol:e} (cond {cond:e})"
                );
                regular += 1;
            }
            Err(DynamicsError::SingularConstraint { condition, .. }) => {
                prop_assert!(condition >= 1e10 || condition.is_nan() || condition.is_infinite());
                refused += 1;
            }
            Err(e) => return Err(TestCaseError::fail(format!("seed {seed}: {e}"))),
        }
    }
    Ok((regular, refused))
}

#[test]
fn embedded_dynamics_equals_kkt_or_refuses_on_random_loop_topologies() {
    let (mut regular, mut refused) = (0usize, 0usize);
    let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig {
        cases: 160,
        failure_persistence: None,
        ..ProptestConfig::default()
    });
    let totals = std::cell::RefCell::new((0usize, 0usize));
    runner
        .run(&any::<u64>(), |seed| {
            let (r, s) = check(seed)?;
            let mut t = totals.borrow_mut();
            t.0 += r;
            t.1 += s;
            Ok(())
        })
        .unwrap();
    let t = totals.into_inner();
    regular += t.0;
    refused += t.1;
    eprintln!(
        "random loop topologies: {regular} regular states checked against KKT, {refused} refused"
    );
    assert!(
        regular > 3 * refused && regular > 300,
        "too few regular cases: {regular} checked, {refused} refused"
    );
}
