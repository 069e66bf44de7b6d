//! `Model::with_origins_on_joint_axes`, which generated joint-space functions are traced on: the same
//! dynamics and the same link poses as the file's frames, with more zeros in the joint translations where
//! the recursions cross them most.

use crate::common::*;
use embedyn::{
    aba, crba, forward_kinematics, frame_placement, mass_matrix_inverse, rnea, Model, Workspace,
};

fn relative(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// The moved model against the original: `aba`, `rnea`, `crba`, `M⁻¹` and every link's world pose.
fn assert_equivalent(model: &Model<f64>, rng: &mut Rng) -> f64 {
    let moved = model.with_origins_on_joint_axes();
    assert!(moved.weighted_translation_zeros() >= model.weighted_translation_zeros());
    let (mut a, mut b) = (Workspace::new(model), Workspace::new(&moved));
    let mut worst = 0.0f64;
    for _ in 0..3 {
        let q = rng.configuration(model);
        let v = rng.vec(model.nv(), -2.0, 2.0);
        let tau = rng.vec(model.nv(), -5.0, 5.0);
        let pairs = [
            (
                aba(model, &mut a, &q, &v, &tau).unwrap().to_vec(),
                aba(&moved, &mut b, &q, &v, &tau).unwrap().to_vec(),
            ),
            (
                rnea(model, &mut a, &q, &v, &tau).unwrap().to_vec(),
                rnea(&moved, &mut b, &q, &v, &tau).unwrap().to_vec(),
            ),
            (
                crba(model, &mut a, &q).unwrap().as_slice().to_vec(),
                crba(&moved, &mut b, &q).unwrap().as_slice().to_vec(),
            ),
            (
                mass_matrix_inverse(model, &mut a, &q)
                    .unwrap()
                    .as_slice()
                    .to_vec(),
                mass_matrix_inverse(&moved, &mut b, &q)
                    .unwrap()
                    .as_slice()
                    .to_vec(),
            ),
        ];
        for (x, y) in &pairs {
            worst = worst.max(relative(x, y));
        }
        forward_kinematics(model, &mut a, &q, &v).unwrap();
        forward_kinematics(&moved, &mut b, &q, &v).unwrap();
        for frame in model.frames() {
            let x = frame_placement(model, &a, frame).unwrap();
            let y = frame_placement(&moved, &b, frame).unwrap();
            let x: Vec<f64> = x
                .rotation
                .iter()
                .chain(x.translation.iter())
                .copied()
                .collect();
            let y: Vec<f64> = y
                .rotation
                .iter()
                .chain(y.translation.iter())
                .copied()
                .collect();
            worst = worst.max(relative(&x, &y));
        }
    }
    worst
}

#[test]
fn moved_origins_keep_the_dynamics_and_the_link_poses_of_random_trees() {
    let mut rng = Rng::new(20261203);
    let mut worst = 0.0f64;
    for t in 0..120 {
        let model = random_tree(&mut rng, 2 + t % 14, t % 3 == 0);
        worst = worst.max(assert_equivalent(&model, &mut rng));
    }
    eprintln!("random trees: worst relative difference {worst:e}");
    // The moves change the rounding only.
    assert!(worst < 1e-13, "worst relative difference {worst:e}");
}

#[test]
fn moved_origins_add_zeros_to_the_bundled_robots_and_keep_their_dynamics() {
    let mut rng = Rng::new(7);
    for (file, floating) in [
        ("models/humanoid34.urdf", true),
        ("models/quadruped.urdf", false),
        ("models/arm7.urdf", false),
        ("models/peers/anymal_b.urdf", true),
        ("models/peers/z1.urdf", false),
    ] {
        let model = load_model::<f64>(file, floating);
        let moved = model.with_origins_on_joint_axes();
        let (before, after) = (
            model.weighted_translation_zeros(),
            moved.weighted_translation_zeros(),
        );
        assert!(after > before, "{file}: {before} → {after} zeros");
        let worst = assert_equivalent(&model, &mut rng);
        assert!(worst < 1e-12, "{file}: worst relative difference {worst:e}");
        // A free flyer's body keeps its origin: the base velocity is measured there.
        if floating {
            assert_eq!(moved.joints[0].placement, model.joints[0].placement);
            assert_eq!(moved.bodies[0].inertia, model.bodies[0].inertia);
        }
    }
}

#[test]
fn a_model_with_constraints_keeps_its_frames() {
    let model = load_model::<f64>("models/loops/four_bar_internal.urdf", false);
    assert!(!model.constraints.is_empty());
    let moved = model.with_origins_on_joint_axes();
    for (a, b) in model.joints.iter().zip(&moved.joints) {
        assert_eq!(a.placement, b.placement);
    }
}

/// A 10 kg body of 1e-6 kg·m² on a joint 1 km out along its own axis (an attacker's trial): moved along
/// a tilted axis, its inertia about the axis came back as a difference of terms of size m·t², and `aba`
/// lost 2.4e-4 relative. Tilted axes keep their origins; along a coordinate axis the move is exact.
#[test]
fn a_tilted_axis_keeps_its_origin_and_a_coordinate_axis_moves_exactly() {
    use embedyn::nalgebra::{Matrix3, Vector3};
    use embedyn::{JointType, SpatialInertia, Transform};
    let pendulum = |axis: Vector3<f64>, xyz: [f64; 3]| {
        let mut b = Model::<f64>::builder("far");
        let inertia = SpatialInertia::from_com(10.0, Vector3::zeros(), Matrix3::identity() * 1e-6);
        let placement = Transform::from_xyz_rpy(xyz, [0.0; 3]);
        b.add_body(
            None,
            "j1",
            JointType::Revolute,
            axis,
            placement,
            "l1",
            inertia,
        )
        .unwrap();
        b.build().unwrap()
    };
    let tilted = pendulum(Vector3::new(0.6, 0.0, 0.8), [600.0, 0.0, 800.0]);
    let moved = tilted.with_origins_on_joint_axes();
    assert_eq!(moved.joints[0].placement, tilted.joints[0].placement);
    let along_x = pendulum(Vector3::x(), [1000.0, 0.0, 0.5]);
    let moved = along_x.with_origins_on_joint_axes();
    assert_eq!(
        moved.joints[0].placement.translation,
        Vector3::new(0.0, 0.0, 0.5)
    );
    let (q, v, tau) = ([0.3], [0.7], [0.5]);
    let mut a = Workspace::new(&along_x);
    let mut b = Workspace::new(&moved);
    let exact = aba(&along_x, &mut a, &q, &v, &tau).unwrap()[0];
    let traced = aba(&moved, &mut b, &q, &v, &tau).unwrap()[0];
    // q̈ = τ / I_xx = 0.5 / 1e-6.
    assert_eq!(exact, 500_000.0);
    assert_eq!(traced, exact);
}

/// A chain of 20,000 bodies, in a thread with a 2 MB stack (a spawned thread's default): the search for
/// the moves keeps its own stack (it recursed once per body and overflowed from about 10,000 bodies), and
/// the moved chain has the original's forward dynamics.
#[test]
fn a_chain_of_twenty_thousand_bodies_moves_its_origins_on_a_small_stack() {
    use embedyn::nalgebra::{Matrix3, Vector3};
    use embedyn::{JointType, SpatialInertia, Transform};
    let worker = std::thread::Builder::new().stack_size(2 << 20).spawn(|| {
        let n = 20_000;
        let mut b = Model::<f64>::builder("chain");
        let inertia = SpatialInertia::from_com(
            1.0,
            Vector3::new(0.0, 0.0, 0.05),
            Matrix3::identity() * 1e-2,
        );
        let mut parent = None;
        for i in 0..n {
            let axis = [Vector3::x(), Vector3::y(), Vector3::z()][i % 3];
            let placement = Transform::new(Matrix3::identity(), Vector3::new(0.01, 0.02, 0.1));
            let link = format!("l{i}");
            let body = format!("b{i}");
            let id = b
                .add_body(
                    parent,
                    &link,
                    JointType::Revolute,
                    axis,
                    placement,
                    &body,
                    inertia,
                )
                .unwrap();
            parent = Some(id);
        }
        let model = b.build().unwrap();
        let moved = model.with_origins_on_joint_axes();
        // Each joint's translation has a component along its axis, which the move cancels.
        assert!(moved.weighted_translation_zeros() > model.weighted_translation_zeros());
        let mut rng = Rng::new(20_000);
        let q = rng.configuration(&model);
        let v = rng.vec(model.nv(), -0.1, 0.1);
        let tau = rng.vec(model.nv(), -1.0, 1.0);
        let (mut a, mut b) = (Workspace::new(&model), Workspace::new(&moved));
        let original = aba(&model, &mut a, &q, &v, &tau).unwrap().to_vec();
        let shifted = aba(&moved, &mut b, &q, &v, &tau).unwrap().to_vec();
        relative(&original, &shifted)
    });
    let difference = worker.unwrap().join().unwrap();
    assert!(
        difference < 1e-9,
        "moved chain's aba differs by {difference:e}"
    );
}
