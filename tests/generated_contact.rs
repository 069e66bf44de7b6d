//! Generated contact functions (issue 11): `aba_ext`, `rnea_ext`, `nle_ext` with the wrenches of links
//! named at generation time, one `frame_<link>` per named link (pose, Jacobian, bias) in each of the three
//! references, `com`, `centroidal` and `centroidal_bias` — against the interpreted solver (f64 to 1e-12 relative) on a
//! floating ANYmal B (feet and the IMU merged into their bodies by fixed joints), a fixed UR5 (a link
//! fixed to the world among the named ones) and a four-bar linkage (constraint embedding); and against
//! Pinocchio 4.1 on UR5 (local), floating Solo-12 (world) and floating ANYmal B (local_world_aligned)
//! (tests/data/pinocchio/*_contact.json, the `Contact` reference of contact.rs) to 1e-9.

use crate::common::{load_model, Rng, UNWRITTEN};
use crate::constraint_embedding::consistent_state;
use crate::contact::{linear_angular, row_major, Contact};
use crate::pinocchio_reference::vecf;
use embedyn::nalgebra::{Matrix3xX, Matrix6xX, Vector3};
use embedyn::{
    aba, aba_ext, center_of_mass, centroidal_momentum, centroidal_momentum_matrix,
    centroidal_momentum_rate, com_jacobian, forward_kinematics, forward_kinematics_acceleration,
    frame_classical_acceleration, frame_jacobian, frame_placement, nle_ext, relative_error,
    rnea_ext, LinkWrench, Model, Reference, Workspace,
};

mod anymal {
    embedyn::robot!(
        "tests/data/pinocchio/anymal_b.urdf",
        floating,
        f64_only,
        only(
            aba_ext,
            rnea_ext,
            nle_ext,
            frame,
            com,
            centroidal,
            centroidal_bias
        ),
        wrenches(LF_FOOT, RF_FOOT, LH_FOOT, RH_FOOT, base, imu_link),
        frames(LF_FOOT, RF_FOOT, LH_FOOT, RH_FOOT, base, LF_THIGH)
    );
}
mod ur5 {
    embedyn::robot!(
        "tests/data/pinocchio/ur5.urdf",
        f64_only,
        only(aba_ext, rnea_ext, frame, com, centroidal, centroidal_bias),
        wrenches(tool0, wrist_2_link, base_link),
        frames(tool0, wrist_3_link, forearm_link, ee_link, base_link),
        reference = local
    );
}
mod solo12 {
    embedyn::robot!(
        "tests/data/pinocchio/solo12_floating.urdf",
        floating,
        f64_only,
        only(aba_ext, rnea_ext, frame, com, centroidal, centroidal_bias),
        wrenches(FL_FOOT, FR_FOOT, HL_FOOT, HR_FOOT, base_link),
        frames(FL_FOOT, HR_FOOT, base_link, FL_UPPER_LEG),
        reference = world
    );
}
mod four_bar {
    embedyn::robot!(
        "models/loops/four_bar_internal.urdf",
        f64_only,
        only(aba_ext, rnea_ext, frame, com, centroidal, centroidal_bias),
        wrenches(tip, coupler),
        frames(tip, rocker),
        reference = world
    );
}

/// What `aba_ext` returns: the singularity measure of a model with constraints, nothing for a tree.
trait Measure {
    fn measure(self) -> Option<f64>;
}
impl Measure for () {
    fn measure(self) -> Option<f64> {
        None
    }
}
impl Measure for f64 {
    fn measure(self) -> Option<f64> {
        Some(self)
    }
}

type FrameFn = fn(&[f64], &[f64], &mut [f64; 12], &mut [f64], &mut [f64; 6]);
type AbaExtFn = fn(&[f64], &[f64], &[f64], &[[f64; 6]], &mut [f64]) -> Option<f64>;
type RneaExtFn = fn(&[f64], &[f64], &[f64], &[[f64; 6]], &mut [f64]);
type NleExtFn = fn(&[f64], &[f64], &[[f64; 6]], &mut [f64]);
type ComFn = fn(&[f64], &[f64], &mut [f64; 3], &mut [f64; 3], &mut [f64]);
type CentroidalFn = fn(&[f64], &[f64], &mut [f64; 6], &mut [f64], &mut [f64; 6]);

/// One module's generated functions over slices (matrices row-major).
struct Generated {
    wrench_links: &'static [&'static str],
    reference: Reference,
    aba_ext: AbaExtFn,
    rnea_ext: RneaExtFn,
    nle_ext: Option<NleExtFn>,
    frames: Vec<(&'static str, FrameFn)>,
    com: ComFn,
    centroidal: CentroidalFn,
}

macro_rules! generated {
    ($m:ident, $reference:expr, nle_ext: $nle:expr, frames: [$($link:literal => $f:ident),*]) => {
        Generated {
            wrench_links: &$m::WRENCH_LINKS,
            reference: $reference,
            aba_ext: |q, v, tau, f, qdd| {
                let f: &[[f64; 6]; $m::WRENCH_LINKS.len()] = f.try_into().unwrap();
                $m::f64::aba_ext(
                    q.try_into().unwrap(),
                    v.try_into().unwrap(),
                    tau.try_into().unwrap(),
                    f,
                    qdd.try_into().unwrap(),
                )
                .measure()
            },
            rnea_ext: |q, v, qdd, f, tau| {
                $m::f64::rnea_ext(
                    q.try_into().unwrap(),
                    v.try_into().unwrap(),
                    qdd.try_into().unwrap(),
                    f.try_into().unwrap(),
                    tau.try_into().unwrap(),
                )
            },
            nle_ext: $nle,
            frames: vec![$(($link, |q, v, pose, j, bias| {
                let mut jacobian = [[UNWRITTEN; $m::NV]; 6];
                $m::f64::$f(q.try_into().unwrap(), v.try_into().unwrap(), pose, &mut jacobian, bias);
                j.copy_from_slice(jacobian.as_flattened());
            })),*],
            com: |q, v, com, vcom, j| {
                let mut j_com = [[UNWRITTEN; $m::NV]; 3];
                $m::f64::com(q.try_into().unwrap(), v.try_into().unwrap(), com, vcom, &mut j_com);
                j.copy_from_slice(j_com.as_flattened());
            },
            centroidal: |q, v, h_g, a, dh_g| {
                let mut a_g = [[UNWRITTEN; $m::NV]; 6];
                $m::f64::centroidal(q.try_into().unwrap(), v.try_into().unwrap(), h_g, &mut a_g);
                $m::f64::centroidal_bias(q.try_into().unwrap(), v.try_into().unwrap(), dh_g);
                a.copy_from_slice(a_g.as_flattened());
            },
        }
    };
}

fn anymal() -> Generated {
    generated!(anymal, Reference::LocalWorldAligned,
        nle_ext: Some(|q, v, f, tau| {
            anymal::f64::nle_ext(
                q.try_into().unwrap(),
                v.try_into().unwrap(),
                f.try_into().unwrap(),
                tau.try_into().unwrap(),
            )
        }),
        frames: ["LF_FOOT" => frame_lf_foot, "RF_FOOT" => frame_rf_foot, "LH_FOOT" => frame_lh_foot,
                 "RH_FOOT" => frame_rh_foot, "base" => frame_base, "LF_THIGH" => frame_lf_thigh])
}

fn ur5_functions() -> Generated {
    generated!(ur5, Reference::Local, nle_ext: None,
        frames: ["tool0" => frame_tool0, "wrist_3_link" => frame_wrist_3_link,
                 "forearm_link" => frame_forearm_link, "ee_link" => frame_ee_link,
                 "base_link" => frame_base_link])
}

/// The wrenches of `rows` on `links`, as the interpreted solver takes them.
fn wrenches(model: &Model<f64>, links: &[&str], rows: &[[f64; 6]]) -> Vec<LinkWrench<f64>> {
    links
        .iter()
        .zip(rows)
        .map(|(link, w)| {
            LinkWrench::new(
                model.frame(link).unwrap(),
                Vector3::new(w[0], w[1], w[2]),
                Vector3::new(w[3], w[4], w[5]),
            )
        })
        .collect()
}

/// Every generated function of `g` against the interpreted solver at the states `(q, v)`, with random
/// wrenches and accelerations; returns the worst relative error of each function.
fn against_interpreted(
    g: &Generated,
    model: &Model<f64>,
    states: &[(Vec<f64>, Vec<f64>)],
    rng: &mut Rng,
) -> [f64; 5] {
    let nv = model.nv();
    let mut ws = Workspace::new(model);
    let mut out = vec![0.0; nv];
    // aba_ext, rnea_ext and nle_ext, frames, com, centroidal
    let mut worst = [0.0f64; 5];
    let zeros = vec![0.0; nv];
    for (q, v) in states {
        let rows: Vec<[f64; 6]> = g
            .wrench_links
            .iter()
            .map(|_| {
                let w = rng.vec(6, -20.0, 20.0);
                [w[0], w[1], w[2], w[3], w[4], w[5]]
            })
            .collect();
        let f_ext = wrenches(model, g.wrench_links, &rows);
        let tau = rng.vec(nv, -5.0, 5.0);
        let want = aba_ext(model, &mut ws, q, v, &tau, &f_ext)
            .unwrap()
            .to_vec();
        let measure = (g.aba_ext)(q, v, &tau, &rows, &mut out);
        assert_eq!(measure.is_some(), model.has_constraints());
        assert!(measure.is_none_or(|c| c < 1e10), "singular: {measure:?}");
        worst[0] = worst[0].max(relative_error(&out, &want));
        let qdd = rng.vec(nv, -5.0, 5.0);
        let want = rnea_ext(model, &mut ws, q, v, &qdd, &f_ext)
            .unwrap()
            .to_vec();
        (g.rnea_ext)(q, v, &qdd, &rows, &mut out);
        worst[0] = worst[0].max(relative_error(&out, &want));
        if let Some(nle) = g.nle_ext {
            let want = nle_ext(model, &mut ws, q, v, &f_ext).unwrap().to_vec();
            nle(q, v, &rows, &mut out);
            worst[0] = worst[0].max(relative_error(&out, &want));
        }
        forward_kinematics_acceleration(model, &mut ws, q, v, &zeros).unwrap();
        let mut j = Matrix6xX::zeros(nv);
        let (mut pose, mut jacobian, mut bias) = ([0.0; 12], vec![0.0; 6 * nv], [0.0; 6]);
        for (link, frame_fn) in &g.frames {
            let frame = model.frame(link).unwrap();
            frame_fn(q, v, &mut pose, &mut jacobian, &mut bias);
            let x = frame_placement(model, &ws, frame).unwrap();
            let want: Vec<f64> = (0..3)
                .flat_map(|r| (0..3).map(move |c| (r, c)))
                .map(|(r, c)| x.rotation[(r, c)])
                .chain(x.translation.iter().copied())
                .collect();
            worst[1] = worst[1].max(relative_error(&pose, &want));
            frame_jacobian(model, &ws, frame, g.reference, &mut j).unwrap();
            worst[1] = worst[1].max(relative_error(&jacobian, &row_major(&j)));
            let a = frame_classical_acceleration(model, &ws, frame, g.reference).unwrap();
            worst[1] = worst[1].max(relative_error(
                &bias,
                &linear_angular(&a.linear, &a.angular),
            ));
        }
        forward_kinematics(model, &mut ws, q, v).unwrap();
        let c = center_of_mass(model, &ws).unwrap();
        let mut j_com = Matrix3xX::zeros(nv);
        com_jacobian(model, &mut ws, &mut j_com).unwrap();
        let (mut com, mut vcom, mut j_out) = ([0.0; 3], [0.0; 3], vec![0.0; 3 * nv]);
        (g.com)(q, v, &mut com, &mut vcom, &mut j_out);
        worst[2] = worst[2]
            .max(relative_error(&com, c.com.as_slice()))
            .max(relative_error(&vcom, c.vcom.as_slice()))
            .max(relative_error(&j_out, &row_major(&j_com)));
        let mut a_g = Matrix6xX::zeros(nv);
        centroidal_momentum_matrix(model, &mut ws, &mut a_g).unwrap();
        let h = centroidal_momentum(model, &mut ws).unwrap();
        forward_kinematics_acceleration(model, &mut ws, q, v, &zeros).unwrap();
        let dh = centroidal_momentum_rate(model, &mut ws).unwrap();
        let (mut h_g, mut a_out, mut dh_g) = ([0.0; 6], vec![0.0; 6 * nv], [0.0; 6]);
        (g.centroidal)(q, v, &mut h_g, &mut a_out, &mut dh_g);
        worst[3] = worst[3]
            .max(relative_error(&h_g, &linear_angular(&h.linear, &h.angular)))
            .max(relative_error(&a_out, &row_major(&a_g)));
        worst[4] = worst[4].max(relative_error(
            &dh_g,
            &linear_angular(&dh.linear, &dh.angular),
        ));
    }
    worst
}

fn assert_close(name: &str, worst: [f64; 5], tol: f64) {
    eprintln!(
        "{name}: generated vs interpreted: wrench dynamics {:.1e}, frames {:.1e}, com {:.1e}, centroidal {:.1e}, dA_g v {:.1e}",
        worst[0], worst[1], worst[2], worst[3], worst[4]
    );
    for (what, w) in ["wrench dynamics", "frames", "com", "centroidal", "dA_g v"]
        .iter()
        .zip(worst)
    {
        assert!(w <= tol, "{name}: generated {what} off by {w:e}");
    }
}

/// Random states of a tree.
fn tree_states(model: &Model<f64>, rng: &mut Rng, n: usize) -> Vec<(Vec<f64>, Vec<f64>)> {
    (0..n)
        .map(|_| (rng.configuration(model), rng.vec(model.nv(), -2.0, 2.0)))
        .collect()
}

/// Floating ANYmal B, local_world_aligned: wrenches on the feet (merged into the shanks), the base and
/// the IMU (merged into the base).
#[test]
fn generated_contact_functions_match_interpreted_on_anymal() {
    let model = load_model::<f64>("tests/data/pinocchio/anymal_b.urdf", true);
    assert_eq!((model.nq(), model.nv()), (anymal::NQ, anymal::NV));
    assert_eq!(anymal::wrench::IMU_LINK, 5);
    let mut rng = Rng::new(1101);
    let states = tree_states(&model, &mut rng, 10);
    assert_close(
        "anymal_b floating",
        against_interpreted(&anymal(), &model, &states, &mut rng),
        1e-12,
    );
}

/// The fixed UR5 in the local reference; among the named links `base_link`, fixed to the world: its
/// wrench acts on nothing, its pose is constant and its Jacobian and bias zero; with no wrench, `aba_ext` is
/// `aba`.
#[test]
fn generated_contact_functions_match_interpreted_on_ur5() {
    let model = load_model::<f64>("tests/data/pinocchio/ur5.urdf", false);
    let g = ur5_functions();
    assert_eq!(ur5::WRENCH_LINKS, ["tool0", "wrist_2_link", "base_link"]);
    let mut rng = Rng::new(1102);
    let states = tree_states(&model, &mut rng, 10);
    assert_close(
        "ur5",
        against_interpreted(&g, &model, &states, &mut rng),
        1e-12,
    );
    let (q, v) = &states[0];
    let tau = [0.5; ur5::NV];
    let mut qdd_ext = [0.0; ur5::NV];
    let (q, v): (&[f64; ur5::NQ], &[f64; ur5::NV]) =
        (q[..].try_into().unwrap(), v[..].try_into().unwrap());
    ur5::f64::aba_ext(q, v, &tau, &[[0.0; 6]; 3], &mut qdd_ext);
    let mut ws = Workspace::new(&model);
    let qdd = aba(&model, &mut ws, q, v, &tau).unwrap();
    assert!(relative_error(&qdd_ext, qdd) <= 1e-14);
    let (mut pose, mut j, mut bias) = ([0.0; 12], [[UNWRITTEN; ur5::NV]; 6], [0.0; 6]);
    ur5::f64::frame_base_link(q, v, &mut pose, &mut j, &mut bias);
    assert!(j.as_flattened().iter().chain(&bias).all(|&x| x == 0.0));
}

/// A four-bar linkage (constraint embedding), world reference, at consistent states: `aba_ext` returns
/// the singularity measure, Jacobians are over the spanning coordinates.
#[test]
fn generated_contact_functions_match_interpreted_on_a_four_bar() {
    let model = load_model::<f64>("models/loops/four_bar_internal.urdf", false);
    assert!(model.has_constraints());
    let g = generated!(four_bar, Reference::World, nle_ext: None,
        frames: ["tip" => frame_tip, "rocker" => frame_rocker]);
    let mut rng = Rng::new(1103);
    let mut ws = Workspace::new(&model);
    let states: Vec<_> = (0..10)
        .map(|_| consistent_state(&model, &mut ws, &mut rng))
        .collect();
    assert_close(
        "four_bar_internal",
        against_interpreted(&g, &model, &states, &mut rng),
        1e-12,
    );
}

/// The generated functions against Pinocchio 4.1 (its `aba` and `rnea` with `fext`, `getFrameJacobian`
/// and `getFrameClassicalAcceleration`, `centerOfMass`, `jacobianCenterOfMass`, `ccrba`, `dccrba`) to 1e-9:
/// a fixed UR5 (wrenches on the flange, a body link and the link fixed to the world; frames in `local`),
/// a floating Solo-12 (`world`) and a floating ANYmal B (`local_world_aligned`).
#[test]
fn generated_contact_functions_match_pinocchio() {
    let ur5 = ur5_functions();
    let solo12 = generated!(solo12, Reference::World, nle_ext: None,
        frames: ["FL_FOOT" => frame_fl_foot, "HR_FOOT" => frame_hr_foot, "base_link" => frame_base_link,
                 "FL_UPPER_LEG" => frame_fl_upper_leg]);
    for (name, urdf, floating) in crate::contact::ROBOTS {
        let g = match name {
            "ur5" => &ur5,
            "solo12_floating" => &solo12,
            _ => &anymal(),
        };
        against_pinocchio(&Contact::load(name, urdf, floating), g);
    }
}

fn against_pinocchio(r: &Contact, g: &Generated) {
    let nv = r.model.nv();
    let mut worst = [0.0f64; 6];
    let mut out = vec![0.0; nv];
    for s in r.samples() {
        let (q, v) = (r.q(s), r.v_vec(&s["v"]));
        // The sample's wrenches as rows of f_ext (zero on the links it leaves out).
        let mut rows = vec![[0.0; 6]; g.wrench_links.len()];
        for (link, w) in s["f_ext"].as_object().unwrap() {
            let k = g.wrench_links.iter().position(|l| l == link).unwrap();
            let (f, t) = (vecf(&w["force"]), vecf(&w["torque"]));
            rows[k] = [f[0], f[1], f[2], t[0], t[1], t[2]];
        }
        (g.aba_ext)(&q, &v, &r.v_vec(&s["tau"]), &rows, &mut out);
        worst[0] = worst[0].max(relative_error(&out, &r.v_vec(&s["qdd_ext"])));
        (g.rnea_ext)(&q, &v, &r.v_vec(&s["qdd_for_rnea"]), &rows, &mut out);
        worst[1] = worst[1].max(relative_error(&out, &r.v_vec(&s["tau_rnea_ext"])));
        if let Some(nle_ext) = g.nle_ext {
            nle_ext(&q, &v, &rows, &mut out);
            worst[1] = worst[1].max(relative_error(&out, &r.v_vec(&s["nle_ext"])));
        }
        let (mut pose, mut jacobian, mut bias) = ([0.0; 12], vec![0.0; 6 * nv], [0.0; 6]);
        for (link, frame_fn) in &g.frames {
            let want = &s["frames"][link];
            if want.is_null() {
                continue; // (a frame the reference data leaves out: UR5's base_link, fixed to the world)
            }
            frame_fn(&q, &v, &mut pose, &mut jacobian, &mut bias);
            let placement: Vec<f64> = crate::contact::rows(&want["placement"]["R"])
                .concat()
                .into_iter()
                .chain(vecf(&want["placement"]["p"]))
                .collect();
            worst[2] = worst[2].max(relative_error(&pose, &placement));
            let reference = &want[g.reference.as_str()];
            worst[2] = worst[2].max(relative_error(&jacobian, &r.columns(&reference["J"])));
            worst[3] = worst[3].max(relative_error(
                &bias,
                &vecf(&reference["classical_acceleration"]),
            ));
        }
        let (mut com, mut vcom, mut j_com) = ([0.0; 3], [0.0; 3], vec![0.0; 3 * nv]);
        (g.com)(&q, &v, &mut com, &mut vcom, &mut j_com);
        worst[4] = worst[4]
            .max(relative_error(&com, &vecf(&s["com"])))
            .max(relative_error(&vcom, &vecf(&s["vcom"])))
            .max(relative_error(&j_com, &r.columns(&s["J_com"])));
        let (mut h_g, mut a_g, mut dh_g) = ([0.0; 6], vec![0.0; 6 * nv], [0.0; 6]);
        (g.centroidal)(&q, &v, &mut h_g, &mut a_g, &mut dh_g);
        worst[5] = worst[5]
            .max(relative_error(&h_g, &vecf(&s["h_g"])))
            .max(relative_error(&a_g, &r.columns(&s["A_g"])))
            .max(relative_error(&dh_g, &vecf(&s["dA_g_v"])));
    }
    eprintln!(
        "{} ({}), generated vs Pinocchio: aba_ext {:.1e}, rnea_ext/nle_ext {:.1e}, pose/J {:.1e}, bias {:.1e}, com {:.1e}, centroidal {:.1e}",
        r.name,
        g.reference.as_str(),
        worst[0], worst[1], worst[2], worst[3], worst[4], worst[5]
    );
    assert!(worst.iter().all(|&e| e <= 1e-9), "{}: {worst:?}", r.name);
}
