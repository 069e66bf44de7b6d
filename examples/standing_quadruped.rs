//! A floating quadruped standing on a compliant ground: every millisecond, the generated frame functions
//! give each foot's pose and Jacobian, a spring–damper ground with Coulomb friction turns penetration and
//! foot velocity into a contact force, and the generated `aba_ext` takes the four forces (in the feet's own
//! frames) with the joint torques of a PD around the standing pose plus the torques that hold it — no heap,
//! no tables, every index a named constant. Then the same robot class with closed-loop knees (four-bar
//! linkages driven from cranks at the hips), whose generated `aba_ext` embeds each knee linkage as an
//! aggregate link and whose state stays on the loops through the generated `complete` and `embedding`.
//!
//! The holding torques and the pose come from the interpreted solver once, before the loop: vertical foot
//! forces that carry the weight with no moment about the centre of mass, and `rnea_ext` at rest.
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

/// ANYbotics' ANYmal B (example-robot-data), its base made free: wrenches on the four feet (which the file
/// merges into the shanks by fixed joints) and a frame function per foot.
mod anymal {
    embedyn::robot!(
        "models/peers/anymal_b.urdf",
        floating,
        f64_only,
        only(aba_ext, frame, integrate),
        wrenches(LF_FOOT, RF_FOOT, LH_FOOT, RH_FOOT),
        frames(LF_FOOT, RF_FOOT, LH_FOOT, RH_FOOT)
    );
}

/// A 12 kg quadruped whose knees are four-bar linkages (URDF+ `<loop>`): 26 spanning coordinates, 18
/// independent ones.
mod loop_knees {
    embedyn::robot!(
        "models/loops/quadruped_loop_knees.urdf",
        f64_only,
        only(aba_ext, frame, integrate, complete, embedding),
        wrenches(FL_foot, FR_foot, HL_foot, HR_foot),
        frames(FL_foot, FR_foot, HL_foot, HR_foot)
    );
}

/// A generated frame function: `(q, v, pose, jacobian, bias)`.
type FrameFn<const NQ: usize, const NV: usize> =
    fn(&[f64; NQ], &[f64; NV], &mut [f64; 12], &mut [[f64; NV]; 6], &mut [f64; 6]);

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

// 5 kHz: the explicit step must resolve the stiff contact on the light feet (k/m_foot and c/m_foot).
const DT: f64 = 2e-4; // s
const STEPS: usize = 5000; // 1 s

/// A spring–damper ground at z = 0 with Coulomb friction: each foot in contact is held to an anchor point
/// by a tangential spring–damper, and the anchor slides along when the force would leave the friction cone.
struct Ground {
    stiffness: f64, // N/m, normal and tangential
    damping: f64,   // N·s/m, normal and tangential
    friction: f64,  // μ
}

impl Ground {
    /// The world force on a foot at `p` moving at `v` (world), zero off the ground; `anchor` is where the
    /// foot sticks (moved on touch-down and while sliding).
    fn force(&self, p: [f64; 3], v: [f64; 3], anchor: &mut Option<[f64; 2]>) -> [f64; 3] {
        if p[2] >= 0.0 {
            *anchor = None;
            return [0.0; 3];
        }
        let normal = (-self.stiffness * p[2] - self.damping * v[2]).max(0.0);
        let a = anchor.get_or_insert([p[0], p[1]]);
        let mut f = [0.0; 2];
        for k in 0..2 {
            f[k] = -self.stiffness * (p[k] - a[k]) - self.damping * v[k];
        }
        let tangential = (f[0] * f[0] + f[1] * f[1]).sqrt();
        if tangential > self.friction * normal {
            // Sliding: the force on the cone, the anchor where the spring gives it.
            let s = self.friction * normal / tangential;
            for k in 0..2 {
                f[k] *= s;
                a[k] = p[k] + (f[k] + self.damping * v[k]) / self.stiffness;
            }
        }
        [f[0], f[1], normal]
    }
}

/// One foot's contact from its generated frame function (`local_world_aligned`: the Jacobian's linear rows
/// give the foot origin's world velocity): the ground's force as an `f_ext` row in the foot's frame, and
/// the foot's height.
fn foot_contact<const NV: usize>(
    ground: &Ground,
    pose: &[f64; 12],
    jacobian: &[[f64; NV]; 6],
    v: &[f64; NV],
    anchor: &mut Option<[f64; 2]>,
) -> ([f64; 6], f64) {
    let mut velocity = [0.0; 3];
    for (r, row) in jacobian.iter().take(3).enumerate() {
        velocity[r] = row.iter().zip(v).map(|(j, x)| j * x).sum();
    }
    let f = ground.force([pose[9], pose[10], pose[11]], velocity, anchor);
    // pose = [R row-major, origin]: the force in the foot's frame is Rᵀ f.
    let local = |c: usize| pose[c] * f[0] + pose[3 + c] * f[1] + pose[6 + c] * f[2];
    ([local(0), local(1), local(2), 0.0, 0.0, 0.0], pose[11])
}

/// A standing pose and what holds it: `q` (feet `sink` below the ground, where the springs carry the
/// weight), the joint torques `tau` over the spanning coordinates (zero on the base and on dependent joints).
struct Standing {
    q: Vec<f64>,
    tau: Vec<f64>,
    forces: Vec<f64>,
}

/// Static equilibrium by the interpreted solver: the pose from `joints` (others at zero, dependent ones
/// completed), lowered so that the mean foot height is −`sink`; the least-norm vertical foot forces with
/// total m g and no moment about the centre of mass; the holding torques `Xᵀ rnea_ext(q, 0, 0, f)` put on
/// the independent joints.
fn standing(
    model: &Model<f64>,
    joints: &[(&str, f64)],
    feet: &[&str],
    sink: f64,
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
    let mut mean = 0.0;
    for &f in &frames {
        mean += frame_placement(model, &ws, f)?.translation.z / frames.len() as f64;
    }
    q[2] -= mean + sink; // the base's z
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
    let mut wrenches = Vec::new();
    for (&f, &fz) in frames.iter().zip(forces.iter()) {
        let r = frame_placement(model, &ws, f)?.rotation;
        wrenches.push(LinkWrench::new(
            f,
            r.transpose() * Vector3::new(0.0, 0.0, fz),
            Vector3::zeros(),
        ));
    }
    let tau = rnea_ext(model, &mut ws, &q, &zero, &zero, &wrenches)?.to_vec();
    // Only Xᵀ τ acts: the base must need nothing (the forces balance), the independent joints take it all.
    let x = match model.has_constraints() {
        true => embedding_map(model, &mut ws, &q)?,
        false => DMatrix::identity(model.nv(), model.nv()),
    };
    let tau_independent = x.transpose() * DVector::from_column_slice(&tau);
    let mut held = vec![0.0; model.nv()];
    let mut col = 0;
    for j in model.independent_joints() {
        let joint = &model.joints[j];
        for k in 0..joint.nv() {
            match joint.joint_type {
                embedyn::JointType::Floating => assert!(tau_independent[col + k].abs() < 1e-9),
                _ => held[joint.v_index + k] = tau_independent[col + k],
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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    use anymal::{f64 as gen, q_index as qi, v_index as vi, NQ, NV};
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/peers/anymal_b.urdf");
    let options = ModelOptions {
        floating: true,
        ..Default::default()
    };
    let model = load(path.as_ref())?.model::<f64>(&options)?;
    let ground = Ground {
        stiffness: 1e4,
        damping: 100.0,
        friction: 0.8,
    };
    // Legs in an X; the springs carry a quarter of the weight each at the start.
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
    let feet = ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"];
    let stand = standing(&model, &pose, &feet, 300.0 / 4.0 / ground.stiffness)?;
    println!(
        "ANYmal B: base {:.3} m high, equilibrium foot forces {:.1?} N",
        stand.q[2], stand.forces
    );
    // The twelve joints as (q index, v index): firmware names joints, it does not count.
    let actuated = [
        (qi::LF_HAA, vi::LF_HAA),
        (qi::LF_HFE, vi::LF_HFE),
        (qi::LF_KFE, vi::LF_KFE),
        (qi::RF_HAA, vi::RF_HAA),
        (qi::RF_HFE, vi::RF_HFE),
        (qi::RF_KFE, vi::RF_KFE),
        (qi::LH_HAA, vi::LH_HAA),
        (qi::LH_HFE, vi::LH_HFE),
        (qi::LH_KFE, vi::LH_KFE),
        (qi::RH_HAA, vi::RH_HAA),
        (qi::RH_HFE, vi::RH_HFE),
        (qi::RH_KFE, vi::RH_KFE),
    ];
    let foot_functions: [FrameFn<NQ, NV>; 4] = [
        gen::frame_lf_foot,
        gen::frame_rf_foot,
        gen::frame_lh_foot,
        gen::frame_rh_foot,
    ];
    let mut q: [f64; NQ] = stand.q.clone().try_into().expect("NQ");
    let q_ref = q;
    let mut v = [0.0; NV];
    // Knock the knees.
    for k in [vi::LF_KFE, vi::RF_KFE, vi::LH_KFE, vi::RH_KFE] {
        v[k] = 1.0;
    }
    let (kp, kd) = (300.0, 8.0);
    let (mut qdd, mut tau, mut step, mut q_next) = ([0.0; NV], [0.0; NV], [0.0; NV], [0.0; NQ]);
    let (mut pose, mut jacobian, mut bias) = ([0.0; 12], [[0.0; NV]; 6], [0.0; 6]);
    let mut f_ext = [[0.0; 6]; 4];
    let mut anchors = [None; 4];
    let start_feet = feet_xy(&q, &v, &foot_functions);
    let mut lowest = 0.0f64;
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let start = Instant::now();
    for _ in 0..STEPS {
        for (k, foot) in foot_functions.iter().enumerate() {
            foot(&q, &v, &mut pose, &mut jacobian, &mut bias);
            let (row, z) = foot_contact(&ground, &pose, &jacobian, &v, &mut anchors[k]);
            f_ext[k] = row;
            lowest = lowest.min(z);
        }
        for &(iq, iv) in &actuated {
            tau[iv] = stand.tau[iv] + kp * (q_ref[iq] - q[iq]) - kd * v[iv];
        }
        gen::aba_ext(&q, &v, &tau, &f_ext, &mut qdd);
        for i in 0..NV {
            v[i] += DT * qdd[i];
            step[i] = DT * v[i];
        }
        gen::integrate(&q, &step, &mut q_next);
        q = q_next;
    }
    let elapsed = start.elapsed();
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    let (slip, worst) = settled(
        &start_feet,
        &feet_xy(&q, &v, &foot_functions),
        (&q, &q_ref),
        &actuated,
    );
    println!(
        "  1 s at {} kHz: {:.2} µs per step (4 × frame_<foot> + aba_ext + integrate), {allocations} allocations;\n  \
         joints back within {worst:.1e} rad of the pose, base at {:.4} m, deepest foot {:.1} mm, foot slip ≤ {:.1} mm",
        1e-3 / DT,
        elapsed.as_secs_f64() * 1e6 / STEPS as f64,
        q[2],
        lowest * 1e3,
        slip * 1e3
    );
    assert_eq!(allocations, 0, "the loop allocated");
    assert!(worst < 0.05 && slip < 0.01, "the robot did not stand");
    gen::aba_ext(&q, &v, &tau, &f_ext, &mut qdd);
    against_interpreted(&model, &feet, &f_ext, (&q, &v, &tau), &qdd, 1e-12)?;

    closed_loop_knees(&ground)
}

/// The feet's world (x, y) from their frame functions.
fn feet_xy<const NQ: usize, const NV: usize>(
    q: &[f64; NQ],
    v: &[f64; NV],
    feet: &[FrameFn<NQ, NV>; 4],
) -> [[f64; 2]; 4] {
    let (mut pose, mut jacobian, mut bias) = ([0.0; 12], [[0.0; NV]; 6], [0.0; 6]);
    feet.map(|foot| {
        foot(q, v, &mut pose, &mut jacobian, &mut bias);
        [pose[9], pose[10]]
    })
}

/// How far the feet slid (m) and the actuated joints `(q index, v index)` ended from the pose (rad).
fn settled(
    start_feet: &[[f64; 2]; 4],
    end_feet: &[[f64; 2]; 4],
    (q, q_ref): (&[f64], &[f64]),
    actuated: &[(usize, usize)],
) -> (f64, f64) {
    let slip = start_feet
        .iter()
        .zip(end_feet)
        .fold(0.0f64, |m, (a, b)| m.max((a[0] - b[0]).hypot(a[1] - b[1])));
    let worst = actuated
        .iter()
        .fold(0.0f64, |m, &(iq, _)| m.max((q[iq] - q_ref[iq]).abs()));
    (slip, worst)
}

/// The same with four-bar knees: the state lives on the loop constraints, so each step integrates all
/// coordinates, completes the dependent ones (generated `complete`) and projects the velocity through the
/// generated embedding map `X` (`v = X v_independent`).
fn closed_loop_knees(ground: &Ground) -> Result<(), Box<dyn std::error::Error>> {
    use loop_knees::{f64 as gen, q_index as qi, v_index as vi, NI, NQ, NV};
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/loops/quadruped_loop_knees.urdf"
    );
    let model = load(path.as_ref())?.model::<f64>(&ModelOptions::default())?;
    let feet = ["FL_foot", "FR_foot", "HL_foot", "HR_foot"];
    let stand = standing(&model, &[], &feet, 118.0 / 4.0 / ground.stiffness)?;
    println!(
        "Quadruped with four-bar knees: base {:.3} m high, equilibrium foot forces {:.1?} N",
        stand.q[2], stand.forces
    );
    // The actuated (independent) joints as (q index, v index); the knee rod and knee angles follow.
    let actuated = [
        (qi::FL_HIP_ABDUCTION, vi::FL_HIP_ABDUCTION),
        (qi::FL_HIP_FLEXION, vi::FL_HIP_FLEXION),
        (qi::FL_KNEE_CRANK_JOINT, vi::FL_KNEE_CRANK_JOINT),
        (qi::FR_HIP_ABDUCTION, vi::FR_HIP_ABDUCTION),
        (qi::FR_HIP_FLEXION, vi::FR_HIP_FLEXION),
        (qi::FR_KNEE_CRANK_JOINT, vi::FR_KNEE_CRANK_JOINT),
        (qi::HL_HIP_ABDUCTION, vi::HL_HIP_ABDUCTION),
        (qi::HL_HIP_FLEXION, vi::HL_HIP_FLEXION),
        (qi::HL_KNEE_CRANK_JOINT, vi::HL_KNEE_CRANK_JOINT),
        (qi::HR_HIP_ABDUCTION, vi::HR_HIP_ABDUCTION),
        (qi::HR_HIP_FLEXION, vi::HR_HIP_FLEXION),
        (qi::HR_KNEE_CRANK_JOINT, vi::HR_KNEE_CRANK_JOINT),
    ];
    // The independent velocities (the base's six, then the actuated joints), the columns of X.
    let independent: Vec<usize> = model.independent_coordinates().collect();
    assert_eq!(independent.len(), NI);
    let foot_functions: [FrameFn<NQ, NV>; 4] = [
        gen::frame_fl_foot,
        gen::frame_fr_foot,
        gen::frame_hl_foot,
        gen::frame_hr_foot,
    ];
    let mut q: [f64; NQ] = stand.q.clone().try_into().expect("NQ");
    let q_ref = q;
    let mut v = [0.0; NV];
    let mut x = [[0.0; NI]; NV];
    let mut v_independent = [0.0; NI];
    // Knock the knee cranks.
    for k in [2, 5, 8, 11] {
        v_independent[6 + k] = 1.0;
    }
    let _ = gen::embedding(&q, &mut x);
    for (r, row) in x.iter().enumerate() {
        v[r] = row.iter().zip(&v_independent).map(|(a, b)| a * b).sum();
    }
    let (kp, kd) = (40.0, 2.0);
    let (mut qdd, mut tau, mut step, mut q_next) = ([0.0; NV], [0.0; NV], [0.0; NV], [0.0; NQ]);
    let (mut pose, mut jacobian, mut bias) = ([0.0; 12], [[0.0; NV]; 6], [0.0; 6]);
    let mut f_ext = [[0.0; 6]; 4];
    let mut anchors = [None; 4];
    let start_feet = feet_xy(&q, &v, &foot_functions);
    let (mut worst_cond, mut worst_residual) = (0.0f64, 0.0f64);
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let start = Instant::now();
    for _ in 0..STEPS {
        for (k, foot) in foot_functions.iter().enumerate() {
            foot(&q, &v, &mut pose, &mut jacobian, &mut bias);
            f_ext[k] = foot_contact(ground, &pose, &jacobian, &v, &mut anchors[k]).0;
        }
        for &(iq, iv) in &actuated {
            tau[iv] = stand.tau[iv] + kp * (q_ref[iq] - q[iq]) - kd * v[iv];
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
            step[i] = DT * (v[i] + DT * qdd[i]);
        }
        gen::integrate(&q, &step, &mut q_next);
        // Back onto the loops: dependent angles solved, velocities through X.
        worst_residual = worst_residual.max(gen::complete(&q_next, &mut q));
        let _ = gen::embedding(&q, &mut x);
        for (r, row) in x.iter().enumerate() {
            v[r] = row.iter().zip(&v_independent).map(|(a, b)| a * b).sum();
        }
    }
    let elapsed = start.elapsed();
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    let (slip, worst) = settled(
        &start_feet,
        &feet_xy(&q, &v, &foot_functions),
        (&q, &q_ref),
        &actuated,
    );
    println!(
        "  1 s at {} kHz: {:.2} µs per step (4 × frame_<foot> + aba_ext + integrate + complete + embedding), \
         {allocations} allocations;\n  loops closed to {worst_residual:.1e}, cond(Y1) ≤ {worst_cond:.1}; \
         actuated joints back within {worst:.1e} rad, base at {:.4} m, foot slip ≤ {:.1} mm",
        1e-3 / DT,
        elapsed.as_secs_f64() * 1e6 / STEPS as f64,
        q[2],
        slip * 1e3
    );
    assert_eq!(allocations, 0, "the loop allocated");
    assert!(worst < 0.05 && slip < 0.01, "the robot did not stand");
    let _ = gen::aba_ext(&q, &v, &tau, &f_ext, &mut qdd);
    against_interpreted(&model, &feet, &f_ext, (&q, &v, &tau), &qdd, 1e-10)
}

/// The generated accelerations `qdd` at the last state `(q, v, tau)` with the feet's `f_ext` rows against
/// the interpreted solver's `aba_ext`, to `tolerance`.
fn against_interpreted(
    model: &Model<f64>,
    feet: &[&str],
    f_ext: &[[f64; 6]],
    (q, v, tau): (&[f64], &[f64], &[f64]),
    qdd: &[f64],
    tolerance: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let wrenches: Vec<_> = feet
        .iter()
        .zip(f_ext)
        .map(|(f, w)| {
            LinkWrench::new(
                model.frame(f).expect("foot"),
                Vector3::new(w[0], w[1], w[2]),
                Vector3::new(w[3], w[4], w[5]),
            )
        })
        .collect();
    let mut ws = Workspace::new(model);
    let interpreted = aba_ext(model, &mut ws, q, v, tau, &wrenches)?;
    let error = relative_error(qdd, interpreted);
    println!("  generated vs interpreted aba_ext at the last state: {error:.1e}");
    assert!(error < tolerance);
    Ok(())
}
