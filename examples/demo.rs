//! The main job: load a bundled robot, print its structure, solve its forward dynamics with the
//! interpreted O(N) solver, check it against an independent algorithm, then run the straight-line code
//! `embedyn::robot!` generated for the same model at compile time, compare the two, and time both; then
//! the same for a floating biped with geared hips and four-bar knees (constraint embedding), against the
//! Lagrange-multiplier solution.
//!
//! `cargo run --release --example demo [MODEL.urdf] [--floating]` (the generated part uses the bundled
//! 34-DoF humanoid; another model runs the interpreted part only).

/// Generated at compile time from the bundled humanoid.
mod humanoid34 {
    embedyn::robot!("models/humanoid34.urdf");
}

/// A floating biped whose hips are geared rotors and whose knees are four-bar linkages (URDF+): every
/// local loop becomes an aggregate link, embedded inline in the generated `aba`.
mod biped {
    embedyn::robot!("models/loops/biped_floating.urdf", f64_only);
}

use embedyn::constraints::{complete_configuration, complete_velocity, constraint_violation};
use embedyn::linalg::solve_spd;
use embedyn::{
    aba, crba, kkt_forward_dynamics, load, mass_matrix_inverse, relative_error, rnea, ModelOptions,
    Workspace,
};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let floating = args.iter().any(|a| a == "--floating");
    let path = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .cloned()
        .unwrap_or_else(|| {
            concat!(env!("CARGO_MANIFEST_DIR"), "/models/humanoid34.urdf").to_string()
        });

    let loaded = load(path.as_ref())?;
    for w in &loaded.warnings {
        eprintln!("{w}");
    }
    let model = loaded.model::<f64>(&ModelOptions {
        floating,
        ..Default::default()
    })?;
    println!(
        "{}: {} bodies, nq = {}, nv = {}  ({path})",
        model.name,
        model.nbodies(),
        model.nq(),
        model.nv()
    );
    println!(
        "{:>3}  {:<20} {:<11} {:<20} {:>9}  merged links",
        "#", "joint", "type", "parent body", "mass kg"
    );
    for (i, (j, b)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let parent = j
            .parent
            .map_or("(world)", |p| model.bodies[p].name.as_str());
        println!(
            "{i:>3}  {:<20} {:<11} {:<20} {:>9.3}  {}",
            j.name,
            j.joint_type.as_str(),
            parent,
            b.inertia.mass,
            b.links.join(", ")
        );
    }

    // One state: every joint at 0.3 rad (or m), a gentle velocity, a small torque.
    let mut q = model.neutral_configuration();
    for j in &model.joints {
        if j.nq() == 1 {
            q[j.q_index] = 0.3;
        }
    }
    let v: Vec<f64> = (0..model.nv())
        .map(|i| 0.1 * ((i % 5) as f64 - 2.0))
        .collect();
    let tau: Vec<f64> = (0..model.nv())
        .map(|i| 0.5 * ((i % 3) as f64 - 1.0))
        .collect();
    let mut ws = Workspace::new(&model);
    let qdd = aba(&model, &mut ws, &q, &v, &tau)?.to_vec();

    // Independent check: M(q)⁻¹ (τ − C − g) with CRBA + Cholesky, and RNEA of the result.
    let nle = rnea(&model, &mut ws, &q, &v, &vec![0.0; model.nv()])?.to_vec();
    let m = crba(&model, &mut ws, &q)?.clone();
    let rhs: Vec<f64> = tau.iter().zip(&nle).map(|(t, n)| t - n).collect();
    let qdd_chol = solve_spd(&m, &rhs).ok_or("M is not positive definite")?;
    let back = rnea(&model, &mut ws, &q, &v, &qdd)?.to_vec();

    println!("\nforward dynamics (ABA, paper Eq. 9) at q = 0.3:");
    for (j, chunk) in model
        .joints
        .iter()
        .map(|j| (j, &qdd[j.v_index..j.v_index + j.nv()]))
    {
        let vals: Vec<String> = chunk.iter().map(|x| format!("{x:+.6}")).collect();
        println!("  {:<20} qdd = {}", j.name, vals.join(" "));
    }
    println!(
        "\nchecks: ABA vs CRBA+Cholesky {:.1e}, RNEA(ABA) vs tau {:.1e} (relative)",
        relative_error(&qdd, &qdd_chol),
        relative_error(&back, &tau)
    );

    // Timing: median of batches, each over many calls, in-process.
    let time = |f: &mut dyn FnMut()| -> f64 {
        let mut batches = Vec::new();
        for _ in 0..31 {
            let start = Instant::now();
            for _ in 0..200 {
                f();
            }
            batches.push(start.elapsed().as_nanos() as f64 / 200.0);
        }
        batches.sort_by(|a, b| a.partial_cmp(b).unwrap());
        batches[batches.len() / 2]
    };
    let t_aba = time(&mut || {
        std::hint::black_box(aba(&model, &mut ws, std::hint::black_box(&q), &v, &tau).unwrap());
    });
    let t_rnea = time(&mut || {
        std::hint::black_box(rnea(&model, &mut ws, std::hint::black_box(&q), &v, &qdd).unwrap());
    });
    let t_crba = time(&mut || {
        std::hint::black_box(crba(&model, &mut ws, std::hint::black_box(&q)).unwrap());
    });
    ws.reserve_inverse(&model);
    let t_minv = time(&mut || {
        std::hint::black_box(
            mass_matrix_inverse(&model, &mut ws, std::hint::black_box(&q)).unwrap(),
        );
    });
    println!("\ninterpreted solver, f64, median ns per call: aba {t_aba:.0}, rnea {t_rnea:.0}, crba {t_crba:.0}, M⁻¹ (Eq. 6) {t_minv:.0}");

    if model.name != "humanoid34" || floating {
        println!("(generated code is compiled in for the bundled humanoid34 only)");
        return Ok(());
    }
    // The generated code: same model, same state, fixed-size arrays, no allocation.
    const NQ: usize = humanoid34::NQ;
    const NV: usize = humanoid34::NV;
    let (qa, va, ta): ([f64; NQ], [f64; NV], [f64; NV]) = (
        q.clone().try_into().unwrap(),
        v.clone().try_into().unwrap(),
        tau.clone().try_into().unwrap(),
    );
    let mut qdd_gen = [0.0; NV];
    humanoid34::f64::aba(&qa, &va, &ta, &mut qdd_gen);
    let mut qdd_gen32 = [0.0f32; NV];
    humanoid34::f32::aba(
        &qa.map(|x| x as f32),
        &va.map(|x| x as f32),
        &ta.map(|x| x as f32),
        &mut qdd_gen32,
    );
    println!(
        "\ngenerated code (embedyn::robot!): qdd vs interpreted: f64 {:.1e}, f32 {:.1e} (relative)",
        relative_error(&qdd_gen, &qdd),
        relative_error(&qdd_gen32.map(|x| x as f64), &qdd)
    );
    let mut out = [0.0; NV];
    let mut mat = [[0.0; NV]; NV];
    let g_aba = time(&mut || humanoid34::f64::aba(std::hint::black_box(&qa), &va, &ta, &mut out));
    let g_rnea = time(&mut || humanoid34::f64::rnea(std::hint::black_box(&qa), &va, &ta, &mut out));
    let g_crba = time(&mut || humanoid34::f64::crba(std::hint::black_box(&qa), &mut mat));
    std::hint::black_box((&out, &mat));
    println!(
        "generated code, f64, median ns per call: aba {g_aba:.0} ({:.1}× faster), rnea {g_rnea:.0} ({:.1}×), crba {g_crba:.0} ({:.1}×)",
        t_aba / g_aba,
        t_rnea / g_rnea,
        t_crba / g_crba
    );
    loops(&time)
}

/// Constraint embedding: the biped with geared hips and four-bar knees, interpreted and generated, against
/// the Lagrange-multiplier (KKT) solution of the same dynamics.
fn loops(time: &dyn Fn(&mut dyn FnMut()) -> f64) -> Result<(), Box<dyn std::error::Error>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/loops/biped_floating.urdf"
    );
    let model = load(path.as_ref())?.model::<f64>(&ModelOptions::default())?;
    let mut ws = Workspace::new(&model);
    println!(
        "
{}: {} spanning joints, nv = {}, {} independent; aggregate links: {}",
        model.name,
        model.joints.len(),
        model.nv(),
        model.independent_nv(),
        model
            .groups
            .iter()
            .map(|g| {
                let names: Vec<&str> = g
                    .bodies
                    .iter()
                    .map(|&b| model.joints[b].name.as_str())
                    .collect();
                format!("[{}]", names.join(", "))
            })
            .collect::<Vec<_>>()
            .join(" ")
    );
    // A state on the loops: independent angles chosen, dependent ones completed, v projected.
    let mut q = model.neutral_configuration();
    for (j, joint) in model.joints.iter().enumerate() {
        if joint.nq() == 1 && model.is_independent(j) {
            q[joint.q_index] = 0.2 * ((j as f64) * 0.7).sin();
        }
    }
    complete_configuration(&model, &mut ws, &mut q)?;
    let mut v: Vec<f64> = (0..model.nv())
        .map(|k| 0.5 * ((k as f64) * 1.3).cos())
        .collect();
    complete_velocity(&model, &mut ws, &q, &mut v)?;
    let tau: Vec<f64> = (0..model.nv())
        .map(|k| 2.0 * ((k as f64) * 0.9).sin())
        .collect();
    let (pos, vel) = constraint_violation(&model, &mut ws, &q, &v)?;
    let qdd = aba(&model, &mut ws, &q, &v, &tau)?.to_vec();
    let qdd_kkt = kkt_forward_dynamics(&model, &mut ws, &q, &v, &tau)?;
    const NQ: usize = biped::NQ;
    const NV: usize = biped::NV;
    let (qa, va, ta): ([f64; NQ], [f64; NV], [f64; NV]) = (
        q.clone().try_into().unwrap(),
        v.clone().try_into().unwrap(),
        tau.clone().try_into().unwrap(),
    );
    let mut qdd_gen = [0.0; NV];
    let cond = biped::f64::aba(&qa, &va, &ta, &mut qdd_gen);
    println!(
        "loop residuals (relative): position {pos:.1e}, velocity {vel:.1e}; qdd embedded (O(N)) vs KKT {:.1e}, generated vs embedded {:.1e}; cond(Y1) {cond:.1} (singular at {:.0e})",
        relative_error(&qdd, &qdd_kkt),
        relative_error(&qdd_gen, &qdd),
        biped::f64::SINGULARITY_THRESHOLD
    );
    let t_embedded = time(&mut || {
        std::hint::black_box(aba(&model, &mut ws, std::hint::black_box(&q), &v, &tau).unwrap());
    });
    let t_kkt = time(&mut || {
        std::hint::black_box(
            kkt_forward_dynamics(&model, &mut ws, std::hint::black_box(&q), &v, &tau).unwrap(),
        );
    });
    let mut out = [0.0; NV];
    let t_gen = time(&mut || {
        std::hint::black_box(biped::f64::aba(
            std::hint::black_box(&qa),
            &va,
            &ta,
            &mut out,
        ));
    });
    println!(
        "forward dynamics, median ns per call: generated {t_gen:.0}, interpreted embedded {t_embedded:.0}, KKT {t_kkt:.0} ({:.1}× and {:.1}× the generated time)",
        t_embedded / t_gen,
        t_kkt / t_gen
    );
    Ok(())
}
