//! Contact wrenches, frame kinematics, centre of mass and centroidal momentum (issue 11) against
//! Pinocchio 4.1 (tests/data/pinocchio/contact.py → `<robot>_contact.json`: a fixed UR5, a floating Solo-12
//! and a floating ANYmal B), to 1e-9 relative: `aba`, `rnea`, `nle` with wrenches on feet, tool flanges
//! (links merged by fixed joints) and body links; frame placements, Jacobians, velocities and classical
//! accelerations in the three references; com, vcom, J_com, A_g, h_g and Ȧ_g v.

use crate::common::load_model;
use crate::pinocchio_reference::{coordinate_maps, reference, vecf};
use embedyn::nalgebra::{Const, Dyn, Matrix3xX, Matrix6xX, OMatrix, Vector3};
use embedyn::{
    aba_ext, center_of_mass, centroidal_momentum, centroidal_momentum_matrix,
    centroidal_momentum_rate, com_jacobian, forward_kinematics, forward_kinematics_acceleration,
    frame_classical_acceleration, frame_jacobian, frame_placement, frame_velocity, nle_ext,
    relative_error, rnea_ext, LinkWrench, Model, Reference, Workspace,
};
use serde_json::Value;

const TOL: f64 = 1e-9;

/// The three reference robots: (reference name, URDF, floating).
pub const ROBOTS: [(&str, &str, bool); 3] = [
    ("ur5", "tests/data/pinocchio/ur5.urdf", false),
    (
        "solo12_floating",
        "tests/data/pinocchio/solo12_floating.urdf",
        true,
    ),
    (
        "anymal_b_floating",
        "tests/data/pinocchio/anymal_b.urdf",
        true,
    ),
];

pub fn rows(v: &Value) -> Vec<Vec<f64>> {
    v.as_array().unwrap().iter().map(vecf).collect()
}

/// One robot's reference: the model, the JSON and the coordinate maps (ours → Pinocchio's).
pub struct Contact {
    pub name: &'static str,
    pub model: Model<f64>,
    pub json: Value,
    pub q_map: Vec<usize>,
    pub v_map: Vec<usize>,
}

impl Contact {
    pub fn load(name: &'static str, urdf: &str, floating: bool) -> Contact {
        let json = reference(&format!("{name}_contact"));
        let model = load_model::<f64>(urdf, floating);
        let (q_map, v_map) = coordinate_maps(name, &model, &json);
        Contact {
            name,
            model,
            json,
            q_map,
            v_map,
        }
    }

    pub fn samples(&self) -> &[Value] {
        self.json["samples"].as_array().unwrap()
    }

    /// A vector of the sample in our coordinate order.
    pub fn q(&self, s: &Value) -> Vec<f64> {
        let x = vecf(&s["q_angle"]);
        self.q_map.iter().map(|&i| x[i]).collect()
    }

    pub fn v_vec(&self, x: &Value) -> Vec<f64> {
        let x = vecf(x);
        self.v_map.iter().map(|&i| x[i]).collect()
    }

    /// A matrix with nv columns (Pinocchio's column order) in our column order, row-major.
    pub fn columns(&self, m: &Value) -> Vec<f64> {
        rows(m)
            .iter()
            .flat_map(|r| self.v_map.iter().map(move |&i| r[i]))
            .collect()
    }

    /// The sample's external wrenches (those on links fixed to the world included: they act on nothing).
    pub fn wrenches(&self, s: &Value) -> Vec<LinkWrench<f64>> {
        s["f_ext"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(link, w)| {
                let frame = self
                    .model
                    .frame(link)
                    .unwrap_or_else(|| panic!("{}: no frame {link}", self.name));
                let f = vecf(&w["force"]);
                let t = vecf(&w["torque"]);
                LinkWrench::new(
                    frame,
                    Vector3::new(f[0], f[1], f[2]),
                    Vector3::new(t[0], t[1], t[2]),
                )
            })
            .collect()
    }
}

/// An `R × nv` matrix (a Jacobian, `A_g`, `J_com`) row-major, as the reference files write matrices.
pub fn row_major<const R: usize>(m: &OMatrix<f64, Const<R>, Dyn>) -> Vec<f64> {
    (0..R)
        .flat_map(|r| (0..m.ncols()).map(move |c| m[(r, c)]))
        .collect()
}

/// A six-vector as the reference files write it: linear, then angular.
pub fn linear_angular(linear: &Vector3<f64>, angular: &Vector3<f64>) -> Vec<f64> {
    linear.iter().chain(angular.iter()).copied().collect()
}

/// `aba`, `rnea` and `nle` with wrenches on feet, flanges, body links and a link fixed to the world.
#[test]
fn dynamics_with_external_wrenches_match_pinocchio() {
    for (name, urdf, floating) in ROBOTS {
        let r = Contact::load(name, urdf, floating);
        let mut ws = Workspace::new(&r.model);
        let mut worst = [0.0f64; 3];
        for s in r.samples() {
            let (q, v) = (r.q(s), r.v_vec(&s["v"]));
            let f_ext = r.wrenches(s);
            let qdd = aba_ext(&r.model, &mut ws, &q, &v, &r.v_vec(&s["tau"]), &f_ext)
                .unwrap()
                .to_vec();
            worst[0] = worst[0].max(relative_error(&qdd, &r.v_vec(&s["qdd_ext"])));
            let tau = rnea_ext(
                &r.model,
                &mut ws,
                &q,
                &v,
                &r.v_vec(&s["qdd_for_rnea"]),
                &f_ext,
            )
            .unwrap()
            .to_vec();
            worst[1] = worst[1].max(relative_error(&tau, &r.v_vec(&s["tau_rnea_ext"])));
            let nle = nle_ext(&r.model, &mut ws, &q, &v, &f_ext).unwrap().to_vec();
            worst[2] = worst[2].max(relative_error(&nle, &r.v_vec(&s["nle_ext"])));
        }
        println!(
            "{name}: aba_ext {:.1e}, rnea_ext {:.1e}, nle_ext {:.1e}",
            worst[0], worst[1], worst[2]
        );
        assert!(worst.iter().all(|&e| e < TOL), "{name}: {worst:?}");
    }
}

/// Placements, Jacobians, velocities and classical accelerations of feet, flanges and bodies in the
/// three references.
#[test]
fn frame_kinematics_match_pinocchio() {
    let references = [
        ("local", Reference::Local),
        ("local_world_aligned", Reference::LocalWorldAligned),
        ("world", Reference::World),
    ];
    for (name, urdf, floating) in ROBOTS {
        let r = Contact::load(name, urdf, floating);
        let model = &r.model;
        let mut ws = Workspace::new(model);
        let mut j = Matrix6xX::zeros(model.nv());
        let mut worst = [0.0f64; 4];
        for s in r.samples() {
            let (q, v) = (r.q(s), r.v_vec(&s["v"]));
            forward_kinematics_acceleration(model, &mut ws, &q, &v, &vec![0.0; model.nv()])
                .unwrap();
            for (link, f) in s["frames"].as_object().unwrap() {
                let frame = model.frame(link).unwrap();
                let x = frame_placement(model, &ws, frame).unwrap();
                let p_ref = vecf(&f["placement"]["p"]);
                let r_ref: Vec<f64> = rows(&f["placement"]["R"]).concat();
                let r_ours: Vec<f64> = (0..3)
                    .flat_map(|i| (0..3).map(move |k| x.rotation[(i, k)]))
                    .collect();
                worst[0] = worst[0]
                    .max(relative_error(x.translation.as_slice(), &p_ref))
                    .max(relative_error(&r_ours, &r_ref));
                for (key, reference) in references {
                    let want = &f[key];
                    frame_jacobian(model, &ws, frame, reference, &mut j).unwrap();
                    let e = relative_error(&row_major(&j), &r.columns(&want["J"]));
                    worst[1] = worst[1].max(e);
                    assert!(e < TOL, "{name} {link} {key}: J {e:e}");
                    let vel = frame_velocity(model, &ws, frame, reference).unwrap();
                    worst[2] = worst[2].max(relative_error(
                        &linear_angular(&vel.linear, &vel.angular),
                        &vecf(&want["velocity"]),
                    ));
                    let acc = frame_classical_acceleration(model, &ws, frame, reference).unwrap();
                    let e = relative_error(
                        &linear_angular(&acc.linear, &acc.angular),
                        &vecf(&want["classical_acceleration"]),
                    );
                    worst[3] = worst[3].max(e);
                    assert!(e < TOL, "{name} {link} {key}: classical acceleration {e:e}");
                }
            }
        }
        println!(
            "{name}: placement {:.1e}, J {:.1e}, velocity {:.1e}, classical acceleration {:.1e}",
            worst[0], worst[1], worst[2], worst[3]
        );
        assert!(worst.iter().all(|&e| e < TOL), "{name}: {worst:?}");
    }
}

/// com, vcom, J_com, A_g, h_g and Ȧ_g v.
#[test]
fn center_of_mass_and_centroidal_momentum_match_pinocchio() {
    for (name, urdf, floating) in ROBOTS {
        let r = Contact::load(name, urdf, floating);
        let model = &r.model;
        let mut ws = Workspace::new(model);
        let mut j_com = Matrix3xX::zeros(model.nv());
        let mut a_g = Matrix6xX::zeros(model.nv());
        let mut worst = [0.0f64; 6];
        for s in r.samples() {
            let (q, v) = (r.q(s), r.v_vec(&s["v"]));
            forward_kinematics(model, &mut ws, &q, &v).unwrap();
            let c = center_of_mass(model, &ws).unwrap();
            let mass = s["mass"].as_f64().unwrap();
            assert!(
                (c.mass - mass).abs() < TOL * mass,
                "{name}: mass {} vs {mass}",
                c.mass
            );
            worst[0] = worst[0].max(relative_error(c.com.as_slice(), &vecf(&s["com"])));
            worst[1] = worst[1].max(relative_error(c.vcom.as_slice(), &vecf(&s["vcom"])));
            let com = com_jacobian(model, &mut ws, &mut j_com).unwrap();
            worst[0] = worst[0].max(relative_error(com.as_slice(), &vecf(&s["com"])));
            worst[2] = worst[2].max(relative_error(&row_major(&j_com), &r.columns(&s["J_com"])));
            centroidal_momentum_matrix(model, &mut ws, &mut a_g).unwrap();
            worst[3] = worst[3].max(relative_error(&row_major(&a_g), &r.columns(&s["A_g"])));
            let h = centroidal_momentum(model, &mut ws).unwrap();
            let h = linear_angular(&h.linear, &h.angular);
            worst[4] = worst[4].max(relative_error(&h, &vecf(&s["h_g"])));
            forward_kinematics_acceleration(model, &mut ws, &q, &v, &vec![0.0; model.nv()])
                .unwrap();
            let dh = centroidal_momentum_rate(model, &mut ws).unwrap();
            let dh = linear_angular(&dh.linear, &dh.angular);
            worst[5] = worst[5].max(relative_error(&dh, &vecf(&s["dA_g_v"])));
        }
        println!(
            "{name}: com {:.1e}, vcom {:.1e}, J_com {:.1e}, A_g {:.1e}, h_g {:.1e}, dA_g v {:.1e}",
            worst[0], worst[1], worst[2], worst[3], worst[4], worst[5]
        );
        assert!(worst.iter().all(|&e| e < TOL), "{name}: {worst:?}");
    }
}
