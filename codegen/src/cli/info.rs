//! `embedyn info`.

use super::CliError;
use crate::{Loaded, ModelOptions};
use serde_json::{json, Value};

pub fn info(loaded: &Loaded, options: &ModelOptions) -> Result<Value, CliError> {
    let model = loaded.model::<f64>(options)?;
    let joints: Vec<Value> = model
        .joints
        .iter()
        .map(|j| {
            json!({
                "name": j.name,
                "type": j.joint_type.as_str(),
                "nq": j.nq(),
                "nv": j.nv(),
                "q_index": j.q_index,
                "v_index": j.v_index,
                "independent": true,
            })
        })
        .collect();
    let bodies: Vec<Value> = model
        .bodies
        .iter()
        .zip(&model.joints)
        .map(|(b, j)| {
            let com = b.inertia.com();
            json!({
                "name": b.name,
                "joint": j.name,
                "parent": j.parent.map(|p| model.bodies[p].name.clone()),
                "links": b.links,
                "mass": b.inertia.mass,
                "com": [com.x, com.y, com.z],
            })
        })
        .collect();
    Ok(json!({
        "name": model.name,
        "nq": model.nq(),
        "nv": model.nv(),
        "joints": joints,
        "bodies": bodies,
        "loops": [],
        "couplings": [],
        "independent_nv": model.nv(),
    }))
}
