//! The readers of frames, the centre of mass and the centroidal momentum check that the workspace holds
//! the sweep they read (`Workspace::sweep`): a missing `forward_kinematics` or
//! `forward_kinematics_acceleration` — a new workspace, or another algorithm since — is
//! `DynamicsError::KinematicsNotComputed`, never another state's numbers; and the right sequences give
//! the same numbers as before, whatever ran earlier (docs/conventions.md, "Contacts, frames and
//! momentum").

use crate::common::{load_model, Rng};
use crate::constraint_embedding::{consistent_state, LOOP_MODELS};
use embedyn::constraints::{complete_configuration, complete_velocity, constraint_violation};
use embedyn::nalgebra::{Matrix3xX, Matrix6xX};
use embedyn::{
    aba, aba_ext, center_of_mass, centroidal_momentum, centroidal_momentum_matrix,
    centroidal_momentum_rate, com_jacobian, constraint_kinematics, crba, embedding_map_in,
    forward_kinematics, forward_kinematics_acceleration, frame_classical_acceleration,
    frame_jacobian, frame_placement, frame_velocity, gravity, kkt_forward_dynamics,
    mass_matrix_inverse, nle, reduced_mass_matrix_in, rnea, DynamicsError, FrameId, Model,
    Reference, Sweep, Workspace,
};

/// Every reader, by name, with the state it needs.
const READERS: [(&str, Sweep); 9] = [
    ("frame_placement", Sweep::Placements),
    ("frame_jacobian", Sweep::Placements),
    ("com_jacobian", Sweep::Placements),
    ("centroidal_momentum_matrix", Sweep::Placements),
    ("frame_velocity", Sweep::Velocities),
    ("center_of_mass", Sweep::Velocities),
    ("centroidal_momentum", Sweep::Velocities),
    ("frame_classical_acceleration", Sweep::Accelerations),
    ("centroidal_momentum_rate", Sweep::Accelerations),
];

/// Calls the reader `name` on `ws` (about `frame`, in world axes), its result reduced to `Ok(())`.
fn read(
    model: &Model<f64>,
    ws: &mut Workspace<f64>,
    name: &str,
    frame: FrameId,
) -> Result<(), DynamicsError> {
    let nv = model.nv();
    let r = Reference::LocalWorldAligned;
    match name {
        "frame_placement" => frame_placement(model, ws, frame).map(drop),
        "frame_jacobian" => frame_jacobian(model, ws, frame, r, &mut Matrix6xX::zeros(nv)),
        "com_jacobian" => com_jacobian(model, ws, &mut Matrix3xX::zeros(nv)).map(drop),
        "centroidal_momentum_matrix" => {
            centroidal_momentum_matrix(model, ws, &mut Matrix6xX::zeros(nv)).map(drop)
        }
        "frame_velocity" => frame_velocity(model, ws, frame, r).map(drop),
        "center_of_mass" => center_of_mass(model, ws).map(drop),
        "centroidal_momentum" => centroidal_momentum(model, ws).map(drop),
        "frame_classical_acceleration" => {
            frame_classical_acceleration(model, ws, frame, r).map(drop)
        }
        "centroidal_momentum_rate" => centroidal_momentum_rate(model, ws).map(drop),
        _ => unreachable!("{name}"),
    }
}

/// Every reader on `ws`, which holds `holds`: those that need more fail naming themselves, what they need
/// and what the workspace holds; the others succeed. `after` says what ran, for the messages.
fn check_readers(
    model: &Model<f64>,
    ws: &mut Workspace<f64>,
    frame: FrameId,
    holds: Sweep,
    after: &str,
) {
    assert_eq!(ws.sweep(), holds, "after {after}");
    for (reader, needs) in READERS {
        let got = read(model, ws, reader, frame);
        if holds >= needs {
            assert_eq!(got, Ok(()), "{reader} after {after}");
        } else {
            assert_eq!(
                got,
                Err(DynamicsError::KinematicsNotComputed {
                    reader,
                    needs,
                    holds
                }),
                "{reader} after {after}"
            );
        }
        // A reader changes no kinematics, failing or not.
        assert_eq!(ws.sweep(), holds, "{reader} after {after}");
    }
}

/// A foot of the quadruped, its floating base on, and a random state.
fn quadruped() -> (Model<f64>, FrameId, Vec<f64>, Vec<f64>, Vec<f64>) {
    let model = load_model::<f64>("tests/data/pinocchio/anymal_b.urdf", true);
    let frame = model.frame("LF_FOOT").expect("a foot");
    let mut rng = Rng::new(5);
    let q = rng.configuration(&model);
    let v = rng.vec(model.nv(), -1.5, 1.5);
    let qdd = rng.vec(model.nv(), -3.0, 3.0);
    (model, frame, q, v, qdd)
}

#[test]
fn every_reader_fails_on_a_new_workspace() {
    let (model, frame, ..) = quadruped();
    let mut ws = Workspace::new(&model);
    check_readers(&model, &mut ws, frame, Sweep::None, "nothing");
    let message = frame_jacobian(
        &model,
        &ws,
        frame,
        Reference::World,
        &mut Matrix6xX::zeros(model.nv()),
    )
    .unwrap_err()
    .to_string();
    assert!(
        message.starts_with("frame_jacobian needs forward_kinematics(q, v) first; the workspace holds no world placements"),
        "{message}"
    );
}

#[test]
fn each_algorithm_leaves_what_it_says() {
    let (model, frame, q, v, qdd) = quadruped();
    let mut ws = Workspace::new(&model);
    let tau = vec![0.5; model.nv()];
    forward_kinematics(&model, &mut ws, &q, &v).unwrap();
    check_readers(
        &model,
        &mut ws,
        frame,
        Sweep::Velocities,
        "forward_kinematics",
    );
    let message = frame_classical_acceleration(&model, &ws, frame, Reference::World)
        .unwrap_err()
        .to_string();
    assert!(
        message.starts_with("frame_classical_acceleration needs forward_kinematics_acceleration(q, v, qdd) first; the workspace holds placements and velocities"),
        "{message}"
    );
    forward_kinematics_acceleration(&model, &mut ws, &q, &v, &qdd).unwrap();
    check_readers(
        &model,
        &mut ws,
        frame,
        Sweep::Accelerations,
        "forward_kinematics_acceleration",
    );
    // Accelerations with gravity, parent placements without world placements, or both.
    type Run = fn(&Model<f64>, &mut Workspace<f64>, &[f64], &[f64], &[f64]);
    let runs: [(&str, Run); 8] = [
        ("aba", |m, ws, q, v, t| assert!(aba(m, ws, q, v, t).is_ok())),
        ("aba_ext", |m, ws, q, v, t| {
            assert!(aba_ext(m, ws, q, v, t, &[]).is_ok())
        }),
        ("rnea", |m, ws, q, v, t| {
            assert!(rnea(m, ws, q, v, t).is_ok())
        }),
        ("nle", |m, ws, q, v, _| assert!(nle(m, ws, q, v).is_ok())),
        ("gravity", |m, ws, q, _, _| {
            assert!(gravity(m, ws, q).is_ok())
        }),
        ("crba", |m, ws, q, _, _| assert!(crba(m, ws, q).is_ok())),
        ("mass_matrix_inverse", |m, ws, q, _, _| {
            assert!(mass_matrix_inverse(m, ws, q).is_ok())
        }),
        ("rnea_with_gravity", |m, ws, q, v, t| {
            assert!(embedyn::rnea_with_gravity(m, ws, q, v, t, false).is_ok())
        }),
    ];
    for (name, run) in runs {
        forward_kinematics_acceleration(&model, &mut ws, &q, &v, &qdd).unwrap();
        run(&model, &mut ws, &q, &v, &tau);
        check_readers(&model, &mut ws, frame, Sweep::None, name);
    }
    // An input error writes nothing, so the workspace keeps what it had.
    forward_kinematics_acceleration(&model, &mut ws, &q, &v, &qdd).unwrap();
    assert!(aba(&model, &mut ws, &q, &v[1..], &tau).is_err());
    assert!(forward_kinematics(&model, &mut ws, &q[1..], &v).is_err());
    check_readers(&model, &mut ws, frame, Sweep::Accelerations, "input errors");
}

#[test]
fn classical_acceleration_after_the_wrong_sweep_is_an_error() {
    let (model, frame, q, v, qdd) = quadruped();
    let mut ws = Workspace::new(&model);
    let world = Reference::World;
    let needs = |holds| {
        Err(DynamicsError::KinematicsNotComputed {
            reader: "frame_classical_acceleration",
            needs: Sweep::Accelerations,
            holds,
        })
    };
    // forward_kinematics alone: velocities, no accelerations.
    forward_kinematics(&model, &mut ws, &q, &v).unwrap();
    assert_eq!(
        frame_classical_acceleration(&model, &ws, frame, world),
        needs(Sweep::Velocities)
    );
    // aba: accelerations with gravity.
    aba(&model, &mut ws, &q, &v, &vec![0.0; model.nv()]).unwrap();
    assert_eq!(
        frame_classical_acceleration(&model, &ws, frame, world),
        needs(Sweep::None)
    );
    assert!(matches!(
        centroidal_momentum_rate(&model, &mut ws),
        Err(DynamicsError::KinematicsNotComputed { .. })
    ));
    // forward_kinematics_acceleration at q, then forward_kinematics at q2: the accelerations are q's.
    forward_kinematics_acceleration(&model, &mut ws, &q, &v, &qdd).unwrap();
    let q2 = Rng::new(6).configuration(&model);
    forward_kinematics(&model, &mut ws, &q2, &v).unwrap();
    assert_eq!(
        frame_classical_acceleration(&model, &ws, frame, world),
        needs(Sweep::Velocities)
    );
    assert!(matches!(
        centroidal_momentum_rate(&model, &mut ws),
        Err(DynamicsError::KinematicsNotComputed { .. })
    ));
    // crba: parent placements only.
    forward_kinematics(&model, &mut ws, &q, &v).unwrap();
    crba(&model, &mut ws, &q2).unwrap();
    assert_eq!(
        frame_jacobian(&model, &ws, frame, world, &mut Matrix6xX::zeros(model.nv())),
        Err(DynamicsError::KinematicsNotComputed {
            reader: "frame_jacobian",
            needs: Sweep::Placements,
            holds: Sweep::None,
        })
    );
}

/// Every reader's numbers after `forward_kinematics_acceleration(q, v, qdd)`, as one vector.
fn all_readings(model: &Model<f64>, ws: &mut Workspace<f64>, frame: FrameId) -> Vec<f64> {
    let nv = model.nv();
    let mut out = Vec::new();
    for r in [
        Reference::Local,
        Reference::LocalWorldAligned,
        Reference::World,
    ] {
        let x = frame_placement(model, ws, frame).unwrap();
        out.extend(x.rotation.iter().chain(x.translation.iter()));
        let mut j = Matrix6xX::zeros(nv);
        frame_jacobian(model, ws, frame, r, &mut j).unwrap();
        out.extend(j.iter());
        let m = frame_velocity(model, ws, frame, r).unwrap();
        out.extend(m.angular.iter().chain(m.linear.iter()));
        let a = frame_classical_acceleration(model, ws, frame, r).unwrap();
        out.extend(a.angular.iter().chain(a.linear.iter()));
    }
    let c = center_of_mass(model, ws).unwrap();
    out.push(c.mass);
    out.extend(c.com.iter().chain(c.vcom.iter()));
    let mut j_com = Matrix3xX::zeros(nv);
    out.extend(com_jacobian(model, ws, &mut j_com).unwrap().iter());
    out.extend(j_com.iter());
    let mut a_g = Matrix6xX::zeros(nv);
    out.extend(
        centroidal_momentum_matrix(model, ws, &mut a_g)
            .unwrap()
            .iter(),
    );
    out.extend(a_g.iter());
    for f in [
        centroidal_momentum(model, ws).unwrap(),
        centroidal_momentum_rate(model, ws).unwrap(),
    ] {
        out.extend(f.angular.iter().chain(f.linear.iter()));
    }
    out
}

#[test]
fn the_right_sweep_gives_the_same_numbers_whatever_ran_before() {
    let (model, frame, q, v, qdd) = quadruped();
    let mut fresh = Workspace::new(&model);
    forward_kinematics_acceleration(&model, &mut fresh, &q, &v, &qdd).unwrap();
    let expected = all_readings(&model, &mut fresh, frame);
    // Read twice: the readers leave the kinematics as they found them.
    assert_eq!(all_readings(&model, &mut fresh, frame), expected);
    let mut ws = Workspace::new(&model);
    let q2 = Rng::new(7).configuration(&model);
    aba(&model, &mut ws, &q2, &v, &vec![1.0; model.nv()]).unwrap();
    crba(&model, &mut ws, &q2).unwrap();
    forward_kinematics_acceleration(&model, &mut ws, &q, &v, &qdd).unwrap();
    assert_eq!(all_readings(&model, &mut ws, frame), expected);
}

#[test]
fn loop_models_record_their_sweeps() {
    let mut rng = Rng::new(8);
    for (path, floating) in LOOP_MODELS {
        let model = load_model::<f64>(path, floating);
        let frame = model.frames().last().expect("a link");
        let mut ws = Workspace::new(&model);
        ws.reserve_all(&model);
        let (q, v) = consistent_state(&model, &mut ws, &mut rng);
        let zeros = vec![0.0; model.nv()];
        // constraint_kinematics is forward_kinematics_acceleration at qdd = 0, to the bit.
        forward_kinematics_acceleration(&model, &mut ws, &q, &v, &zeros).unwrap();
        let expected = ws.kinematics().acceleration.to_vec();
        let bias = frame_classical_acceleration(&model, &ws, frame, Reference::World).unwrap();
        let mut other = Workspace::new(&model);
        constraint_kinematics(&model, &mut other, &q, &v).unwrap();
        assert_eq!(other.kinematics().acceleration, &expected[..], "{path}");
        check_readers(
            &model,
            &mut other,
            frame,
            Sweep::Accelerations,
            "constraint_kinematics",
        );
        assert_eq!(
            frame_classical_acceleration(&model, &other, frame, Reference::World),
            Ok(bias),
            "{path}"
        );
        // The embedded aba leaves accelerations with gravity, as the tree's does.
        aba(&model, &mut ws, &q, &v, &zeros).unwrap();
        check_readers(&model, &mut ws, frame, Sweep::None, path);
        // Position-level work: placements at q, velocities zero rather than the caller's.
        forward_kinematics_acceleration(&model, &mut ws, &q, &v, &zeros).unwrap();
        embedding_map_in(&model, &mut ws, &q).unwrap();
        check_readers(
            &model,
            &mut ws,
            frame,
            Sweep::Placements,
            "embedding_map_in",
        );
        let mut v_projected = v.clone();
        complete_velocity(&model, &mut ws, &q, &mut v_projected).unwrap();
        check_readers(
            &model,
            &mut ws,
            frame,
            Sweep::Placements,
            "complete_velocity",
        );
        reduced_mass_matrix_in(&model, &mut ws, &q).unwrap();
        check_readers(
            &model,
            &mut ws,
            frame,
            Sweep::None,
            "reduced_mass_matrix_in",
        );
        // Newton steps move q after its placements: none are left for the q returned.
        let mut q_completed = q.clone();
        complete_configuration(&model, &mut ws, &mut q_completed).unwrap();
        check_readers(
            &model,
            &mut ws,
            frame,
            Sweep::None,
            "complete_configuration",
        );
        // The oracles: placements and velocities at (q, v); accelerations at qdd = 0, not the qdd found.
        kkt_forward_dynamics(&model, &mut ws, &q, &v, &zeros).unwrap();
        check_readers(
            &model,
            &mut ws,
            frame,
            Sweep::Velocities,
            "kkt_forward_dynamics",
        );
        constraint_violation(&model, &mut ws, &q, &v).unwrap();
        check_readers(
            &model,
            &mut ws,
            frame,
            Sweep::Velocities,
            "constraint_violation",
        );
    }
}
