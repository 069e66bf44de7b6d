//! A floating quadruped standing on four feet: its contact forces given, the generated `aba_ext` computes
//! the accelerations in a fixed-step loop (1 kHz, semi-implicit Euler, a joint PD around the standing pose)
//! without touching the heap — then the same robot class with closed-loop knees (four-bar linkages driven
//! from cranks at the hips), whose generated `aba_ext` embeds each knee linkage as an aggregate link.
//!
//! The contact forces are those of static equilibrium, computed once with the interpreted solver: vertical
//! forces on the four feet that carry the weight with no moment about the centre of mass, and the joint
//! torques that hold the pose (`rnea_ext` at rest). In the loop they stay vertical in the world, so each
//! step rotates them into the feet's frames (where `aba_ext` takes them) with the generated `kinematics`.
//!
//! `cargo run --release --example standing_quadruped`

use embedyn::constraints::complete_configuration;
use embedyn::nalgebra::{DMatrix, DVector, Vector3};
use embedyn::{
    aba_ext, center_of_mass, embedding_map, forward_kinematics, frame_placement, load,
    relative_error, rnea_ext, LinkWrench, Model, ModelOptions, Workspace,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// ANYbotics' ANYmal B (example-robot-data), its base made free: wrenches on the four feet, which the
/// file merges into the shanks by fixed joints.
mod anymal {
    embedyn::robot!(
        "models/peers/anymal_b.urdf",
        floating,
        f64_only,
        only(aba_ext, kinematics, integrate),
        wrenches(LF_FOOT, RF_FOOT, LH_FOOT, RH_FOOT)
    );
}

/// A 12 kg quadruped whose knees are four-bar linkages (URDF+ `<loop>`): 26 spanning coordinates, 18
/// independent ones.
mod loop_knees {
    embedyn::robot!(
        "models/loops/quadruped_loop_knees.urdf",
        f64_only,
        only(aba_ext, kinematics, integrate, complete, embedding),
        wrenches(FL_foot, FR_foot, HL_foot, HR_foot)
    );
}

/// Counts heap allocations, to show that the control loop makes none.
struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}
#[global_allocator]
static GLOBAL: Counting = Counting;

const DT: f64 = 1e-3;
const STEPS: usize = 1000;
// Joint PD gains (N·m/rad, N·m·s/rad) of the 30 kg ANYmal and of the 12 kg loop-knee quadruped.
const ANYMAL_PD: (f64, f64) = (300.0, 8.0);
const LOOP_KNEES_PD: (f64, f64) = (40.0, 2.0);

/// A standing pose and what holds it: `q` (feet on the ground z = 0), the joint torques `tau` over the
/// spanning coordinates (zero on the base and on dependent joints) and each foot's vertical force (N).
struct Standing {
    q: Vec<f64>,
    tau: Vec<f64>,
    forces: Vec<f64>,
}

/// Static equilibrium by the interpreted solver: the pose from `joints` (others at zero, dependent ones
/// completed), lowered until the lowest foot touches z = 0; the least-norm vertical foot forces with
/// total m g and no moment about the centre of mass; the holding torques `Xᵀ rnea_ext(q, 0, 0, f)` put
/// on the independent joints.
fn standing(
    model: &Model<f64>,
    joints: &[(&str, f64)],
    feet: &[&str],
) -> Result<Standing, Box<dyn std::error::Error>> {
    let mut ws = Workspace::new(model);
    let mut q = model.neutral_configuration();
    for &(name, value) in joints {
        let j = model.joint_index(name).ok_or(format!("no joint {name}"))?;
        q[model.joints[j].q_index] = value;
    }
    if model.has_constraints() {
        complete_configuration(model, &mut ws, &mut q)?;
    }
    let zero = vec![0.0; model.nv()];
    let frames: Vec<_> = feet.iter().map(|f| model.frame(f).expect("foot")).collect();
    forward_kinematics(model, &mut ws, &q, &zero)?;
    let lowest = frames
        .iter()
        .map(|&f| frame_placement(model, &ws, f).map(|x| x.translation.z))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    q[2] -= lowest; // the base's z
    forward_kinematics(model, &mut ws, &q, &zero)?;
    let com = center_of_mass(model, &ws)?;
    // Σ f = m g; Σ f (x − c_x) = Σ f (y − c_y) = 0: three equations, four forces, least norm.
    let mut a = DMatrix::zeros(3, feet.len());
    for (k, &f) in frames.iter().enumerate() {
        let p = frame_placement(model, &ws, f)?.translation;
        a[(0, k)] = 1.0;
        a[(1, k)] = p.x - com.com.x;
        a[(2, k)] = p.y - com.com.y;
    }
    let b = DVector::from_vec(vec![-model.gravity.z * com.mass, 0.0, 0.0]);
    let forces = a.transpose() * (&a * a.transpose()).try_inverse().ok_or("feet on a line")? * b;
    let wrenches = wrenches_in_feet(model, &ws, &frames, forces.as_slice())?;
    let tau = rnea_ext(model, &mut ws, &q, &zero, &zero, &wrenches)?.to_vec();
    // Only Xᵀ τ acts: the base must need nothing (the forces balance), the independent joints take it all.
    let x = if model.has_constraints() {
        embedding_map(model, &mut ws, &q)?
    } else {
        DMatrix::identity(model.nv(), model.nv())
    };
    let tau_independent = x.transpose() * DVector::from_column_slice(&tau);
    let mut held = vec![0.0; model.nv()];
    let mut col = 0;
    for j in model.independent_joints() {
        let joint = &model.joints[j];
        for k in 0..joint.nv() {
            if joint.joint_type != embedyn::JointType::Floating {
                held[joint.v_index + k] = tau_independent[col + k];
            } else {
                let base = tau_independent[col + k].abs();
                assert!(base < 1e-9, "the base needs {base:e}: not in equilibrium");
            }
        }
        col += joint.nv();
    }
    Ok(Standing {
        q,
        tau: held,
        forces: forces.as_slice().to_vec(),
    })
}

/// Vertical world forces as wrenches in the feet's own frames.
fn wrenches_in_feet(
    model: &Model<f64>,
    ws: &Workspace<f64>,
    frames: &[embedyn::FrameId],
    forces: &[f64],
) -> Result<Vec<LinkWrench<f64>>, embedyn::DynamicsError> {
    frames
        .iter()
        .zip(forces)
        .map(|(&f, &fz)| {
            let r = frame_placement(model, ws, f)?.rotation;
            Ok(LinkWrench::new(
                f,
                r.transpose() * Vector3::new(0.0, 0.0, fz),
                Vector3::zeros(),
            ))
        })
        .collect()
}

/// `f_ext` rows for the generated `aba_ext`: the vertical forces rotated into the feet's frames, read
/// from the generated `kinematics` poses (rotation row-major: its rows are the world axes in the foot
/// frame's columns, so Rᵀ e_z is its third row).
fn foot_rows<const K: usize>(
    poses: &[[f64; 12]],
    feet: &[usize; K],
    forces: &[f64],
) -> [[f64; 6]; K] {
    let mut rows = [[0.0; 6]; K];
    for (k, &i) in feet.iter().enumerate() {
        let r = &poses[i];
        rows[k] = [
            r[6] * forces[k],
            r[7] * forces[k],
            r[8] * forces[k],
            0.0,
            0.0,
            0.0,
        ];
    }
    rows
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // ANYmal B: hips slightly abducted, legs in an X.
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/peers/anymal_b.urdf");
    let options = ModelOptions {
        floating: true,
        ..Default::default()
    };
    let model = load(path.as_ref())?.model::<f64>(&options)?;
    let feet = ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"];
    let pose = [
        ("LF_HFE", 0.4),
        ("LF_KFE", -0.8),
        ("RF_HFE", 0.4),
        ("RF_KFE", -0.8),
        ("LH_HFE", -0.4),
        ("LH_KFE", 0.8),
        ("RH_HFE", -0.4),
        ("RH_KFE", 0.8),
    ];
    let stand = standing(&model, &pose, &feet)?;
    println!(
        "ANYmal B standing: base {:.3} m high, foot forces {:.1?} N (weight {:.1} N)",
        stand.q[2],
        stand.forces,
        stand.forces.iter().sum::<f64>()
    );
    let foot_frames = feet.map(|f| {
        anymal::FRAMES
            .iter()
            .position(|&n| n == f)
            .expect("a foot is a frame")
    });
    let mut q: [f64; anymal::NQ] = stand.q.clone().try_into().expect("NQ");
    let mut v = [0.0; anymal::NV];
    let q_ref = q;
    let mut poses = [[0.0; 12]; anymal::FRAMES.len()];
    let (mut qdd, mut tau, mut step_v, mut q_next) = (
        [0.0; anymal::NV],
        [0.0; anymal::NV],
        [0.0; anymal::NV],
        [0.0; anymal::NQ],
    );
    // At the equilibrium, the accelerations vanish.
    anymal::f64::kinematics(&q, &mut poses);
    let f_ext = foot_rows(&poses, &foot_frames, &stand.forces);
    anymal::f64::aba_ext(&q, &v, stand.tau.as_slice().try_into()?, &f_ext, &mut qdd);
    println!(
        "  qdd at the equilibrium: max |qdd| = {:.1e}",
        qdd.iter().fold(0.0f64, |m, x| m.max(x.abs()))
    );
    // Knock the knees, then let the PD bring them back while the feet keep pushing.
    for k in [8, 11, 14, 17] {
        v[k] = 0.5;
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let start = Instant::now();
    for _ in 0..STEPS {
        anymal::f64::kinematics(&q, &mut poses);
        let f_ext = foot_rows(&poses, &foot_frames, &stand.forces);
        for i in 6..anymal::NV {
            let (kp, kd) = ANYMAL_PD;
            tau[i] = stand.tau[i] + kp * (q_ref[i + 1] - q[i + 1]) - kd * v[i];
        }
        anymal::f64::aba_ext(&q, &v, &tau, &f_ext, &mut qdd);
        for i in 0..anymal::NV {
            v[i] += DT * qdd[i];
            step_v[i] = DT * v[i];
        }
        anymal::f64::integrate(&q, &step_v, &mut q_next);
        q = q_next;
    }
    let elapsed = start.elapsed();
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    let worst = (7..anymal::NQ).fold(0.0f64, |m, i| m.max((q[i] - q_ref[i]).abs()));
    println!(
        "  {STEPS} steps of 1 ms: {:.2} µs per step (kinematics + aba_ext + integrate), {allocations} allocations; \
         joints within {worst:.1e} rad of the pose, base at {:.4} m",
        elapsed.as_secs_f64() * 1e6 / STEPS as f64,
        q[2]
    );
    assert_eq!(allocations, 0, "the loop allocated");
    // The generated accelerations against the interpreted solver at the last state.
    let mut ws = Workspace::new(&model);
    forward_kinematics(&model, &mut ws, &q, &v)?;
    let frames: Vec<_> = feet.iter().map(|f| model.frame(f).expect("foot")).collect();
    let wrenches = wrenches_in_feet(&model, &ws, &frames, &stand.forces)?;
    let interpreted = aba_ext(&model, &mut ws, &q, &v, &tau, &wrenches)?.to_vec();
    anymal::f64::kinematics(&q, &mut poses);
    anymal::f64::aba_ext(
        &q,
        &v,
        &tau,
        &foot_rows(&poses, &foot_frames, &stand.forces),
        &mut qdd,
    );
    let error = relative_error(&qdd, &interpreted);
    println!("  generated vs interpreted aba_ext at the last state: {error:.1e}");
    assert!(error < 1e-12);

    closed_loop_knees()
}

/// The same with four-bar knees: the state lives on the loop constraints, so each step integrates all
/// coordinates, completes the dependent ones (generated `complete`) and projects the velocity through
/// the generated embedding map `X` (`v = X v_independent`).
fn closed_loop_knees() -> Result<(), Box<dyn std::error::Error>> {
    use loop_knees::{f64 as gen, NI, NQ, NV};
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/loops/quadruped_loop_knees.urdf"
    );
    let model = load(path.as_ref())?.model::<f64>(&ModelOptions::default())?;
    let feet = ["FL_foot", "FR_foot", "HL_foot", "HR_foot"];
    let stand = standing(&model, &[], &feet)?;
    println!(
        "Quadruped with four-bar knees standing: base {:.3} m high, foot forces {:.1?} N",
        stand.q[2], stand.forces
    );
    let foot_frames = feet.map(|f| {
        loop_knees::FRAMES
            .iter()
            .position(|&n| n == f)
            .expect("foot")
    });
    let independent: Vec<usize> = model
        .independent_joints()
        .iter()
        .flat_map(|&j| {
            let joint = &model.joints[j];
            joint.v_index..joint.v_index + joint.nv()
        })
        .collect();
    let actuated: Vec<usize> = independent.iter().copied().filter(|&i| i >= 6).collect();
    let mut q: [f64; NQ] = stand.q.clone().try_into().expect("NQ");
    let q_ref = q;
    let mut v = [0.0; NV];
    let mut poses = [[0.0; 12]; loop_knees::FRAMES.len()];
    let (mut qdd, mut tau, mut step_v, mut q_next) = ([0.0; NV], [0.0; NV], [0.0; NV], [0.0; NQ]);
    let mut x = [[0.0; NI]; NV];
    let mut v_independent = [0.0; NI];
    gen::kinematics(&q, &mut poses);
    let cond = gen::aba_ext(
        &q,
        &v,
        stand.tau.as_slice().try_into()?,
        &foot_rows(&poses, &foot_frames, &stand.forces),
        &mut qdd,
    );
    println!(
        "  qdd at the equilibrium: max |qdd| = {:.1e} (cond(Y1) = {cond:.1})",
        qdd.iter().fold(0.0f64, |m, x| m.max(x.abs()))
    );
    // Knock the knee cranks.
    for &i in actuated.iter().skip(2).step_by(3) {
        v_independent[independent
            .iter()
            .position(|&k| k == i)
            .expect("independent")] = 0.5;
    }
    let _ = gen::embedding(&q, &mut x);
    for (r, row) in x.iter().enumerate() {
        v[r] = row.iter().zip(&v_independent).map(|(a, b)| a * b).sum();
    }
    let q_of = |vi: usize| vi + 1; // a joint's q index: one past its v index (behind the quaternion)
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let start = Instant::now();
    let (mut worst_cond, mut worst_residual) = (0.0f64, 0.0f64);
    for _ in 0..STEPS {
        gen::kinematics(&q, &mut poses);
        let f_ext = foot_rows(&poses, &foot_frames, &stand.forces);
        for &i in &actuated {
            let (kp, kd) = LOOP_KNEES_PD;
            tau[i] = stand.tau[i] + kp * (q_ref[q_of(i)] - q[q_of(i)]) - kd * v[i];
        }
        let cond = gen::aba_ext(&q, &v, &tau, &f_ext, &mut qdd);
        assert!(
            cond < gen::SINGULARITY_THRESHOLD,
            "a knee linkage at its toggle"
        );
        worst_cond = worst_cond.max(cond);
        for (k, &i) in independent.iter().enumerate() {
            v_independent[k] = v[i] + DT * qdd[i];
        }
        for i in 0..NV {
            step_v[i] = DT * (v[i] + DT * qdd[i]);
        }
        gen::integrate(&q, &step_v, &mut q_next);
        // Back onto the loops: dependent angles solved, velocities through X.
        worst_residual = worst_residual.max(gen::complete(&q_next, &mut q));
        let _ = gen::embedding(&q, &mut x);
        for (r, row) in x.iter().enumerate() {
            v[r] = row.iter().zip(&v_independent).map(|(a, b)| a * b).sum();
        }
    }
    let elapsed = start.elapsed();
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    let worst = actuated
        .iter()
        .fold(0.0f64, |m, &i| m.max((q[q_of(i)] - q_ref[q_of(i)]).abs()));
    println!(
        "  {STEPS} steps of 1 ms: {:.2} µs per step (kinematics + aba_ext + integrate + complete + embedding), \
         {allocations} allocations; loops closed to {worst_residual:.1e}, cond(Y1) ≤ {worst_cond:.1}; \
         actuated joints within {worst:.1e} rad of the pose",
        elapsed.as_secs_f64() * 1e6 / STEPS as f64
    );
    assert_eq!(allocations, 0, "the loop allocated");
    let mut ws = Workspace::new(&model);
    forward_kinematics(&model, &mut ws, &q, &v)?;
    let frames: Vec<_> = feet.iter().map(|f| model.frame(f).expect("foot")).collect();
    let wrenches = wrenches_in_feet(&model, &ws, &frames, &stand.forces)?;
    let interpreted = aba_ext(&model, &mut ws, &q, &v, &tau, &wrenches)?.to_vec();
    gen::kinematics(&q, &mut poses);
    let _ = gen::aba_ext(
        &q,
        &v,
        &tau,
        &foot_rows(&poses, &foot_frames, &stand.forces),
        &mut qdd,
    );
    let error = relative_error(&qdd, &interpreted);
    println!("  generated vs interpreted aba_ext at the last state: {error:.1e}");
    assert!(error < 1e-10);
    Ok(())
}
