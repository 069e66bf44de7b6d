//! `embedyn info`.

use super::CliError;
use embedyn_codegen::{Loaded, ModelOptions};
use serde_json::{json, Value};

pub fn info(loaded: &Loaded, options: &ModelOptions) -> Result<Value, CliError> {
    let model = loaded.model::<f64>(options)?;
    let joints: Vec<Value> = model
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            json!({
                "name": j.name,
                "type": j.joint_type.as_str(),
                "nq": j.nq(),
                "nv": j.nv(),
                "q_index": j.q_index,
                "v_index": j.v_index,
                "independent": model.is_independent(i),
                "lower": j.limits.lower,
                "upper": j.limits.upper,
                "velocity": j.limits.velocity,
                "effort": j.limits.effort,
                "armature": j.armature,
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
    let robot = &*loaded.scene(options)?;
    // The rotors `--rotors reflected` removed (by their joints' names), or would remove.
    let reflected: Vec<&str> = if options.rotors == embedyn_codegen::Rotors::Reflected {
        embedyn_codegen::geared_rotors(&loaded.robot)
            .iter()
            .map(|r| loaded.robot.joints[r.joint].name.as_str())
            .collect()
    } else {
        Vec::new()
    };
    let link = |l: usize| robot.links[l].name.clone();
    let loops: Vec<Value> = robot
        .loops
        .iter()
        .map(|l| json!({"name": l.name, "type": format!("{:?}", l.kind).to_lowercase(), "predecessor": link(l.predecessor.link), "successor": link(l.successor.link)}))
        .collect();
    let couplings: Vec<Value> = robot
        .couplings
        .iter()
        .map(|c| json!({"name": c.name, "predecessor": link(c.predecessor), "successor": link(c.successor), "ratio": c.ratio}))
        .collect();
    let joint_names = |js: &[usize]| -> Vec<String> {
        js.iter().map(|&j| model.joints[j].name.clone()).collect()
    };
    let groups: Vec<Value> = model
        .groups
        .iter()
        .map(|g| {
            json!({
                "bodies": g.bodies.iter().map(|&b| model.bodies[b].name.clone()).collect::<Vec<_>>(),
                "parent": g.parent.map(|p| model.bodies[p].name.clone()),
                "constraints": g.constraints.iter().map(|&c| model.constraints[c].name.clone()).collect::<Vec<_>>(),
                "spanning": joint_names(&g.bodies),
                "independent": joint_names(&g.independent),
                "dependent": joint_names(&g.dependent),
                "equations": g.rows.len(),
                "redundant_equations": g.constraints.iter().map(|&c| model.constraints[c].raw_rows()).sum::<usize>() - g.rows.len(),
                "independent_chosen_by_embedyn": g.chosen,
            })
        })
        .collect();
    Ok(json!({
        "name": model.name,
        "nq": model.nq(),
        "nv": model.nv(),
        "joints": joints,
        "bodies": bodies,
        "loops": loops,
        "couplings": couplings,
        "groups": groups,
        // Every link of the file, merged ones and those fixed to the world included (CONTRACT §2 frames).
        "frames": robot.links.iter().map(|l| l.name.as_str()).collect::<Vec<_>>(),
        "independent_nv": model.independent_nv(),
        "scene": {
            "floating": options.floating,
            "gravity": options.gravity,
            "locked": options.locks.iter().map(|l| json!({"joint": l.joint, "value": l.value})).collect::<Vec<_>>(),
            "rotors": options.rotors.as_str(),
            "reflected_rotors": reflected,
        },
    }))
}
