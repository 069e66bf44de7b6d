//! No algorithm call touches the heap once the workspace exists (what a real-time loop needs).
//! A counting global allocator watches every allocation made while the algorithms run.

mod common;

use common::{load_model, Rng};
use embedyn::constraints::{complete_configuration, complete_velocity};
use embedyn::nalgebra::{Matrix3xX, Matrix6xX, Vector3};
use embedyn::{
    aba, aba_derivative_factors, aba_derivatives, aba_derivatives_independent, aba_ext,
    center_of_mass, centroidal_momentum, centroidal_momentum_matrix, centroidal_momentum_rate,
    com_jacobian, crba, difference, embedding_map_in, forward_kinematics,
    forward_kinematics_acceleration, frame_classical_acceleration, frame_jacobian, frame_placement,
    frame_velocity, gravity, integrate, mass_matrix_inverse, nle, nle_ext, random_configuration,
    reduced_mass_matrix_in, rnea, rnea_derivatives, rnea_ext, step, step_derivatives,
    AbaDerivativeFactors, AbaDerivatives, DerivativeMethod, DerivativeWorkspace, DynamicsError,
    LinkWrench, ManifoldDerivatives, Reference, RneaDerivatives, StepDerivatives, Workspace,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// Counts the allocations of the thread that makes them: the test harness runs other tests (those of
/// `common`) on other threads at the same time, and their allocations are not the algorithms'.
struct Counting;

thread_local! {
    // `const` initialisation: reading these never allocates, so the allocator may use them.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
    static BYTES: Cell<usize> = const { Cell::new(0) };
}

fn count(bytes: usize) {
    // `try_with`: a thread being torn down has no counters left, and its allocations are not ours.
    let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
    let _ = BYTES.try_with(|b| b.set(b.get() + bytes));
}

/// Allocations made by this thread so far.
fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Bytes this thread has asked for so far.
fn bytes() -> usize {
    BYTES.with(Cell::get)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count(layout.size());
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count(new_size);
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn algorithm_calls_do_not_allocate() {
    for (path, floating) in [
        ("models/arm7.urdf", false),
        ("models/humanoid34.urdf", true),
        ("models/quadruped.urdf", false),
    ] {
        let model = load_model::<f64>(path, floating);
        let mut ws = Workspace::new(&model);
        ws.reserve_all(&model);
        let mut rng = Rng::new(1);
        let q = rng.configuration(&model);
        let v = rng.vec(model.nv(), -1.0, 1.0);
        let tau = rng.vec(model.nv(), -1.0, 1.0);
        // The configuration space: q ⊕ v, q1 ⊖ q0, a random configuration.
        let (mut q_out, mut v_out) = (vec![0.0; model.nq()], vec![0.0; model.nv()]);
        let (lower, upper) = (vec![-1.0; model.nq()], vec![1.0; model.nq()]);
        let mut draws = embedyn::random::SplitMix64::new(3);
        // Contacts, frames and momentum: wrenches on the last two links, Jacobians in caller-owned storage.
        let frames: Vec<embedyn::FrameId> = model.frames().collect();
        let wrenches = [frames[frames.len() - 1], frames[frames.len() / 2]]
            .map(|f| LinkWrench::new(f, Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.1, 0.2, 0.3)));
        let mut jacobian = Matrix6xX::zeros(model.nv());
        let mut j_com = Matrix3xX::zeros(model.nv());
        // Derivatives: one workspace and the outputs, made once.
        let mut dws = DerivativeWorkspace::new(&model);
        let mut forward = AbaDerivatives::new(&model);
        let mut factors = AbaDerivativeFactors::new(&model);
        let mut inverse = RneaDerivatives::new(&model);
        let mut stepped = StepDerivatives::new(&model);
        let (mut q_next, mut v_next) = (vec![0.0; model.nq()], vec![0.0; model.nv()]);
        let before = allocations();
        for _ in 0..3 {
            step(
                &model,
                &mut ws,
                &q,
                &v,
                &tau,
                1e-3,
                &wrenches,
                &mut q_next,
                &mut v_next,
            )
            .unwrap();
            step_derivatives(
                &model,
                &mut dws,
                &q,
                &v,
                &tau,
                1e-3,
                &wrenches,
                &mut stepped,
            )
            .unwrap();
            aba_derivatives(&model, &mut dws, &q, &v, &tau, &wrenches, &mut forward).unwrap();
            aba_derivative_factors(&model, &mut dws, &q, &v, &tau, &wrenches, &mut factors)
                .unwrap();
            // The other method, dual numbers, allocates nothing either.
            dws.set_method(DerivativeMethod::DualNumbers);
            aba_derivatives(&model, &mut dws, &q, &v, &tau, &wrenches, &mut forward).unwrap();
            dws.set_method(DerivativeMethod::Analytical);
            rnea_derivatives(&model, &mut dws, &q, &v, &tau, &wrenches, &mut inverse).unwrap();
            let _ = aba_ext(&model, &mut ws, &q, &v, &tau, &wrenches).unwrap();
            let _ = rnea_ext(&model, &mut ws, &q, &v, &tau, &wrenches).unwrap();
            let _ = nle_ext(&model, &mut ws, &q, &v, &wrenches).unwrap();
            forward_kinematics_acceleration(&model, &mut ws, &q, &v, &tau).unwrap();
            for reference in [
                Reference::Local,
                Reference::LocalWorldAligned,
                Reference::World,
            ] {
                frame_jacobian(&model, &ws, wrenches[0].frame, reference, &mut jacobian).unwrap();
                frame_classical_acceleration(&model, &ws, wrenches[0].frame, reference).unwrap();
                frame_velocity(&model, &ws, wrenches[0].frame, reference).unwrap();
            }
            let _ = frame_placement(&model, &ws, wrenches[1].frame).unwrap();
            center_of_mass(&model, &ws).unwrap();
            centroidal_momentum(&model, &mut ws).unwrap();
            centroidal_momentum_rate(&model, &mut ws).unwrap();
            com_jacobian(&model, &mut ws, &mut j_com).unwrap();
            centroidal_momentum_matrix(&model, &mut ws, &mut jacobian).unwrap();
            integrate(&model, &q, &v, &mut q_out).unwrap();
            difference(&model, &q, &q_out, &mut v_out).unwrap();
            random_configuration(&model, &mut draws, &lower, &upper, &mut q_out).unwrap();
            forward_kinematics(&model, &mut ws, &q, &v).unwrap();
            let _ = aba(&model, &mut ws, &q, &v, &tau).unwrap();
            let _ = rnea(&model, &mut ws, &q, &v, &tau).unwrap();
            let _ = gravity(&model, &mut ws, &q).unwrap();
            let _ = nle(&model, &mut ws, &q, &v).unwrap();
            let _ = crba(&model, &mut ws, &q).unwrap();
            let _ = mass_matrix_inverse(&model, &mut ws, &q).unwrap();
            // The error of a reader called after the wrong sweep allocates nothing either.
            let e = frame_jacobian(
                &model,
                &ws,
                wrenches[0].frame,
                Reference::World,
                &mut jacobian,
            );
            assert!(matches!(
                e,
                Err(DynamicsError::KinematicsNotComputed { .. })
            ));
        }
        let after = allocations();
        assert_eq!(
            after - before,
            0,
            "{path}: {} allocations inside algorithm calls",
            after - before
        );
    }
    // Models with loops and couplings: embedded forward dynamics, inverse dynamics (and at rest: gravity,
    // nonlinear effects), the tree's M, the embedding map, XᵀMX, position completion (from a guess near
    // the assembly) and velocity projection.
    for path in [
        "models/loops/four_bar_internal.urdf",
        "models/loops/biped_floating.urdf",
        "models/loops/differential_wrist.urdf",
        "models/loops/rotor_chain_10.urdf",
    ] {
        let model = load_model::<f64>(path, false);
        let mut ws = Workspace::new(&model);
        ws.reserve_all(&model);
        let mut q = model.neutral_configuration();
        complete_configuration(&model, &mut ws, &mut q).unwrap();
        let mut v = vec![0.3; model.nv()];
        complete_velocity(&model, &mut ws, &q, &mut v).unwrap();
        let tau = vec![0.2; model.nv()];
        let mut guess = q.clone();
        let frames: Vec<embedyn::FrameId> = model.frames().collect();
        let wrenches = [LinkWrench::new(
            frames[1],
            Vector3::new(1.0, 2.0, 3.0),
            Vector3::zeros(),
        )];
        let mut jacobian = Matrix6xX::zeros(model.nv());
        let mut dws = DerivativeWorkspace::new(&model);
        let mut forward = AbaDerivatives::new(&model);
        let mut manifold = ManifoldDerivatives::new(&model);
        let before = allocations();
        for _ in 0..3 {
            aba_derivatives(&model, &mut dws, &q, &v, &tau, &wrenches, &mut forward).unwrap();
            aba_derivatives_independent(&model, &mut dws, &q, &v, &tau, &wrenches, &mut manifold)
                .unwrap();
            let _ = aba(&model, &mut ws, &q, &v, &tau).unwrap();
            let _ = aba_ext(&model, &mut ws, &q, &v, &tau, &wrenches).unwrap();
            let _ = rnea_ext(&model, &mut ws, &q, &v, &tau, &wrenches).unwrap();
            // (The readers need a forward kinematics of their own: rnea_ext leaves no world placements.)
            forward_kinematics(&model, &mut ws, &q, &v).unwrap();
            frame_jacobian(&model, &ws, frames[1], Reference::Local, &mut jacobian).unwrap();
            centroidal_momentum_matrix(&model, &mut ws, &mut jacobian).unwrap();
            let _ = rnea(&model, &mut ws, &q, &v, &tau).unwrap();
            let _ = gravity(&model, &mut ws, &q).unwrap();
            let _ = nle(&model, &mut ws, &q, &v).unwrap();
            let _ = crba(&model, &mut ws, &q).unwrap();
            let _ = embedding_map_in(&model, &mut ws, &q).unwrap();
            let _ = reduced_mass_matrix_in(&model, &mut ws, &q).unwrap();
            let r = complete_configuration(&model, &mut ws, &mut guess).unwrap();
            assert!(r <= 1e-12);
            complete_velocity(&model, &mut ws, &q, &mut v).unwrap();
        }
        let after = allocations();
        assert_eq!(
            after - before,
            0,
            "{path}: {} allocations inside algorithm calls",
            after - before
        );
    }
    // Memory in proportion to what is called: a 20,000-body chain's workspace is O(N) (an nv × nv mass
    // matrix alone would be 3.2 GB), and `aba` on it allocates nothing more.
    let chain = long_chain(20_000);
    let before = bytes();
    let mut ws = Workspace::new(&chain);
    let q = vec![0.1; chain.nq()];
    let zeros = vec![0.0; chain.nv()];
    let qdd = aba(&chain, &mut ws, &q, &zeros, &zeros).unwrap();
    assert!(qdd.iter().all(|x| x.is_finite()));
    let per_body = (bytes() - before) / chain.nbodies();
    assert!(
        per_body < 2_000,
        "Workspace::new + aba allocated {per_body} bytes per body"
    );
}

/// A chain of `n` bodies hanging from each other by revolute joints about x, y, z in turn.
fn long_chain(n: usize) -> embedyn::Model<f64> {
    use embedyn::nalgebra::{Matrix3, Vector3};
    use embedyn::{JointType, Model, SpatialInertia, Transform};
    let mut b = Model::<f64>::builder("chain");
    let axes = [Vector3::x(), Vector3::y(), Vector3::z()];
    let inertia = SpatialInertia::from_com(
        0.1,
        Vector3::new(0.0, 0.0, 0.05),
        Matrix3::from_diagonal(&Vector3::new(1e-4, 2e-4, 3e-4)),
    );
    let step = Transform::from_xyz_rpy([0.0, 0.0, 0.1], [0.0; 3]);
    for i in 0..n {
        let parent = i.checked_sub(1);
        b.add_body(
            parent,
            format!("j{i}"),
            JointType::Revolute,
            axes[i % 3],
            step,
            format!("l{i}"),
            inertia,
        )
        .unwrap();
    }
    b.build().unwrap()
}
