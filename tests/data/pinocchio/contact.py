#!/usr/bin/env python3
"""External wrenches, frame Jacobians / velocities / accelerations, centre of mass and centroidal momentum
from Pinocchio for three reference robots: `<robot>_contact.json`.

Robots: `ur5` (fixed base, samples 0-4 of ur5.json), `solo12_floating` (free-flyer root, samples 0-4 of
solo12_floating.json) and `anymal_b_floating` (anymal_b.urdf, a byte-identical copy of
models/peers/anymal_b.urdf, free-flyer root, 5 samples drawn here with fixed seeds). Per sample, random
external wrenches (one per chosen link, expressed in that link's URDF frame, about the link origin, applied by
the environment to the link) are converted to Pinocchio's per-joint `fext` and fed to aba / rnea; frame
quantities, centre of mass and centroidal momentum are Pinocchio's. The script asserts consistency checks
(printed) before writing anything.

Run from this folder with the `pin` wheel installed (`pip install pin==4.1.0`): python3 contact.py
"""
import hashlib
import json
import os
import shutil
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

ANYMAL_SRC = "../../../models/peers/anymal_b.urdf"
ANYMAL_SHA256 = "9f85de351af569eec3af82477535e0e4a483c9e03edd8095e342292f315316e2"  # models/peers/README.md
NSAMPLES = 5
REFS = [("local", pin.LOCAL), ("local_world_aligned", pin.LOCAL_WORLD_ALIGNED), ("world", pin.WORLD)]

ROBOTS = [
    {
        "name": "ur5",
        "urdf": "ur5.urdf",
        "floating": False,
        "samples_from": "ur5.json",
        "wrench_links": ["tool0", "wrist_2_link", "base_link"],
        "frame_links": ["tool0", "wrist_3_link", "forearm_link", "ee_link"],
        "seed": 11,
    },
    {
        "name": "solo12_floating",
        "urdf": "solo12_floating.urdf",
        "floating": True,
        "samples_from": "solo12_floating.json",
        "wrench_links": ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT", "base_link"],
        "frame_links": ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT", "base_link", "FL_UPPER_LEG"],
        "seed": 12,
    },
    {
        "name": "anymal_b_floating",
        "urdf": "anymal_b.urdf",
        "floating": True,
        "samples_from": None,
        "wrench_links": ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT", "base"],
        "frame_links": ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT", "base", "LF_THIGH"],
        "seed": 13,
    },
]

CONVENTIONS = {
    "q": "Pinocchio layout; free-flyer -> (x, y, z, qx, qy, qz, qw). No joint of these robots is continuous, "
    "so q_angle == q",
    "v": "free-flyer: (vx, vy, vz, wx, wy, wz) in the root body frame, then the revolute joints",
    "f_ext": "dict link name -> {force: [3] N, torque: [3] N m}: wrench applied BY THE ENVIRONMENT to the link, "
    "expressed in THAT LINK's own URDF frame, about the link origin. Converted for Pinocchio as: frame = "
    "model.frames[BODY frame of the link]; fext[frame.parentJoint] += frame.placement.act(pin.Force(force, "
    "torque)) (one pin.Force per joint, in the joint frame, about its origin). Wrenches on links whose "
    "parentJoint is 0 (fixed to the world, listed in f_ext_world_fixed_links) are dropped: no effect",
    "qdd_ext": "pin.aba(q, v, tau, fext)",
    "tau_rnea_ext": "pin.rnea(q, v, qdd_for_rnea, fext)",
    "nle_ext": "pin.rnea(q, v, 0, fext) = C(q,v) v + g(q) - sum J_link^T w_link",
    "qdd": "pin.aba(q, v, tau) without fext",
    "frames": "dict link name -> {placement: {R: world rotation, list of rows (columns = link axes in the world), "
    "p: origin in the world} (data.oMf after framesForwardKinematics), local / local_world_aligned / world: "
    "{J: computeFrameJacobian(q, fid, ref), 6 x nv list of rows, rows linear (3) then angular (3); velocity: "
    "getFrameVelocity(fid, ref) after forwardKinematics(q, v) + updateFramePlacements, [linear(3), "
    "angular(3)]; classical_acceleration: getFrameClassicalAcceleration(fid, ref) after forwardKinematics(q, v, "
    "0) (qdd = 0, no gravity in data.a), [linear(3), angular(3)]}; local_world_aligned also has dJ_v = "
    "getFrameJacobianTimeVariation(fid, LOCAL_WORLD_ALIGNED) @ v after computeJointJacobiansTimeVariation(q, "
    "v), [linear(3), angular(3)]. LOCAL: link frame axes, at the link origin; LOCAL_WORLD_ALIGNED: world "
    "axes, at the link origin; WORLD: world axes, spatial (about the world origin)",
    "com": "centerOfMass(q, v): com = data.com[0], vcom = data.vcom[0] (world); mass = data.mass[0]; see com_note",
    "J_com": "jacobianCenterOfMass(q), 3 x nv list of rows; J_com @ v == vcom",
    "A_g": "ccrba(q, v): centroidal momentum matrix, 6 x nv list of rows, rows linear (3) then angular (3), "
    "world axes, angular momentum about the centre of mass",
    "h_g": "data.hg after ccrba, [linear(3), angular(3)]; A_g @ v == h_g",
    "dA_g_v": "data.dAg @ v after dccrba(q, v), [linear(3), angular(3)]",
    "dh_g": "computeCentroidalMomentumTimeVariation(q, v, 0), [linear(3), angular(3)]; equals dA_g_v",
}


def sha256(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def urdf_info(path):
    root = ET.parse(path).getroot()
    types = {j.get("name"): j.get("type") for j in root.findall("joint")}
    mass = 0.0
    for link in root.findall("link"):
        m = link.find("inertial/mass")
        if m is not None:
            mass += float(m.get("value"))
    return types, mass


def joints_list(model, urdf_types):
    joints = []
    for jid in range(1, model.njoints):
        j = model.joints[jid]
        name = model.names[jid]
        entry = {
            "name": name,
            "pinocchio_type": j.shortname(),
            "nq": j.nq,
            "nv": j.nv,
            "idx_q": j.idx_q,
            "idx_v": j.idx_v,
            "parent": model.names[model.parents[jid]],
            "continuous": urdf_types.get(name) == "continuous",
            "lower": model.lowerPositionLimit[j.idx_q : j.idx_q + j.nq].tolist(),
            "upper": model.upperPositionLimit[j.idx_q : j.idx_q + j.nq].tolist(),
        }
        if name in urdf_types:
            entry["urdf_type"] = urdf_types[name]
        entry["idx_q_angle"] = j.idx_q
        joints.append(entry)
    return joints


def body_frame(model, link):
    fid = model.getFrameId(link, pin.FrameType.BODY)
    assert fid < len(model.frames), link
    return fid


def six(m):
    return np.concatenate([m.linear, m.angular])


def rows(a):
    return [list(map(float, r)) for r in np.asarray(a)]


worst = {}  # (robot, check) -> worst value
CURRENT = [None]


def note(key, value):
    k = (CURRENT[0], key)
    worst[k] = max(worst.get(k, 0.0), float(value))


def build(robot):
    name = robot["name"]
    path = robot["urdf"]
    model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if robot["floating"] else pin.buildModelFromUrdf(path)
    if robot["floating"]:
        # Finite bounds for randomConfiguration (as in solo12_floating.json's root_joint): translation in [-1, 1].
        model.lowerPositionLimit[:3] = -1.0
        model.upperPositionLimit[:3] = 1.0
    return model


def make_samples(robot, model, rng):
    if robot["samples_from"]:
        ref = json.load(open(robot["samples_from"]))
        out = []
        for s in ref["samples"][:NSAMPLES]:
            out.append({k: np.array(s[k]) for k in ["q", "q_angle", "v", "tau", "qdd_for_rnea", "qdd"]})
        return ref, out
    pin.seed(robot["seed"])
    out = []
    for _ in range(NSAMPLES):
        q = pin.randomConfiguration(model)
        out.append(
            {
                "q": q,
                "q_angle": q.copy(),
                "v": rng.normal(0.0, 1.0, model.nv),
                "tau": rng.normal(0.0, 1.0, model.nv),
                "qdd_for_rnea": rng.normal(0.0, 1.0, model.nv),
            }
        )
    return None, out


def reference(robot):
    name = robot["name"]
    CURRENT[0] = name
    model = build(robot)
    data = model.createData()
    urdf_types, urdf_mass = urdf_info(robot["urdf"])
    assert not any(t == "continuous" for t in urdf_types.values()), name
    assert all(model.joints[j].nq == model.joints[j].nv or model.joints[j].shortname() == "JointModelFreeFlyer"
               for j in range(1, model.njoints)), name
    joints = joints_list(model, urdf_types)
    rng = np.random.default_rng(robot["seed"])
    ref, raw = make_samples(robot, model, rng)
    if ref is not None:
        # Same model as the existing reference: same joints, same answers.
        assert joints == ref["joints"], name
        assert ref["gravity"] == model.gravity.linear.tolist()

    wrench_fids = {l: body_frame(model, l) for l in robot["wrench_links"]}
    world_fixed = [l for l, fid in wrench_fids.items() if model.frames[fid].parentJoint == 0]
    frame_fids = {l: body_frame(model, l) for l in robot["frame_links"]}
    zeros = np.zeros(model.nv)

    samples = []
    for s in raw:
        q, v, tau, a = s["q"], s["v"], s["tau"], s["qdd_for_rnea"]
        assert np.array_equal(s["q_angle"], q)
        qdd = pin.aba(model, data, q, v, tau).copy()
        if "qdd" in s:
            note("qdd vs stored <robot>.json qdd", np.abs(qdd - s["qdd"]).max())
        # External wrenches.
        f_ext = {}
        fext = [pin.Force.Zero() for _ in range(model.njoints)]
        for link, fid in wrench_fids.items():
            force = rng.normal(0.0, 20.0, 3)
            torque = rng.normal(0.0, 2.0, 3)
            f_ext[link] = {"force": force.tolist(), "torque": torque.tolist()}
            frame = model.frames[fid]
            if frame.parentJoint == 0:
                continue
            fext[frame.parentJoint] += frame.placement.act(pin.Force(force, torque))
        fext_vec = pin.StdVec_Force()
        for f in fext:
            fext_vec.append(f)
        qdd_ext = pin.aba(model, data, q, v, tau, fext_vec).copy()
        tau_rnea_ext = pin.rnea(model, data, q, v, a, fext_vec).copy()
        nle_ext = pin.rnea(model, data, q, v, zeros, fext_vec).copy()
        back = pin.rnea(model, data, q, v, qdd_ext, fext_vec).copy()
        note("rnea(q,v,qdd_ext,fext) vs tau (relative)", np.abs(back - tau).max() / max(1.0, np.abs(tau).max()))
        # Independent check of the wrench conversion: generalized force = sum J_local(link)^T [force; torque].
        tau_rnea = pin.rnea(model, data, q, v, a).copy()
        gen = np.zeros(model.nv)
        for link, fid in wrench_fids.items():
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
            gen += J.T @ np.concatenate([f_ext[link]["force"], f_ext[link]["torque"]])
        note("tau_rnea_ext vs rnea - sum J_local^T w (relative)",
             np.abs(tau_rnea_ext - (tau_rnea - gen)).max() / max(1.0, np.abs(tau_rnea).max()))
        M = pin.crba(model, data, q).copy()
        M = np.triu(M) + np.triu(M, 1).T
        note("M qdd_ext + nle_ext vs tau (relative)", np.abs(M @ qdd_ext + nle_ext - tau).max() / max(1.0, np.abs(tau).max()))

        # Frames.
        frames = {}
        pin.framesForwardKinematics(model, data, q)
        for link, fid in frame_fids.items():
            m = data.oMf[fid]
            frames[link] = {"placement": {"R": rows(m.rotation), "p": m.translation.tolist()}}
        for link, fid in frame_fids.items():
            for key, rf in REFS:
                J = pin.computeFrameJacobian(model, data, q, fid, rf).copy()
                frames[link][key] = {"J": rows(J)}
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        for link, fid in frame_fids.items():
            for key, rf in REFS:
                vel = six(pin.getFrameVelocity(model, data, fid, rf))
                frames[link][key]["velocity"] = vel.tolist()
                J = np.array(frames[link][key]["J"])
                note(f"J({key}) @ v vs frame velocity", np.abs(J @ v - vel).max())
        pin.forwardKinematics(model, data, q, v, zeros)
        pin.updateFramePlacements(model, data)
        for link, fid in frame_fids.items():
            for key, rf in REFS:
                frames[link][key]["classical_acceleration"] = six(
                    pin.getFrameClassicalAcceleration(model, data, fid, rf)
                ).tolist()
        pin.computeJointJacobiansTimeVariation(model, data, q, v)
        pin.updateFramePlacements(model, data)
        for link, fid in frame_fids.items():
            dJ = pin.getFrameJacobianTimeVariation(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
            dJv = dJ @ v
            lwa = frames[link]["local_world_aligned"]
            lwa["dJ_v"] = dJv.tolist()
            ca = np.array(lwa["classical_acceleration"])
            note("|dJ_v - classical_acceleration| LWA, linear", np.abs(dJv[:3] - ca[:3]).max())
            note("|dJ_v - classical_acceleration| LWA, angular", np.abs(dJv[3:] - ca[3:]).max())
            # For reference in the report only: the other two frames (not written).
            for key, rf in [("local", pin.LOCAL), ("world", pin.WORLD)]:
                dJv_o = pin.getFrameJacobianTimeVariation(model, data, fid, rf) @ v
                ca_o = np.array(frames[link][key]["classical_acceleration"])
                note(f"(not written) |dJ_v - classical_acceleration| {key}", np.abs(dJv_o - ca_o).max())
                note(f"(not written) |dJ_v - spatial acceleration| {key}",
                     np.abs(dJv_o - six(pin.getFrameAcceleration(model, data, fid, rf))).max())
            note("(not written) |dJ_v - spatial acceleration| LWA",
                 np.abs(dJv - six(pin.getFrameAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED))).max())

        # Centre of mass.
        com = pin.centerOfMass(model, data, q, v).copy()
        vcom = data.vcom[0].copy()
        mass = float(data.mass[0])
        Jcom = pin.jacobianCenterOfMass(model, data, q).copy()
        note("J_com @ v vs vcom", np.abs(Jcom @ v - vcom).max())
        note("jacobianCenterOfMass com vs centerOfMass com", np.abs(data.com[0] - com).max())

        # Centroidal momentum.
        Ag = pin.ccrba(model, data, q, v).copy()
        hg = six(data.hg)
        note("A_g @ v vs h_g", np.abs(Ag @ v - hg).max())
        note("ccrba com vs centerOfMass com", np.abs(data.com[0] - com).max())
        note("h_g linear vs mass * vcom", np.abs(hg[:3] - mass * vcom).max())
        pin.dccrba(model, data, q, v)
        dAgv = data.dAg @ v
        dhg = six(pin.computeCentroidalMomentumTimeVariation(model, data, q, v, zeros))
        note("dA_g_v vs dh_g", np.abs(dAgv - dhg).max())

        samples.append(
            {
                "q": q.tolist(),
                "q_angle": q.tolist(),
                "v": v.tolist(),
                "tau": tau.tolist(),
                "qdd_for_rnea": a.tolist(),
                "f_ext": f_ext,
                "qdd": qdd.tolist(),
                "qdd_ext": qdd_ext.tolist(),
                "tau_rnea_ext": tau_rnea_ext.tolist(),
                "nle_ext": nle_ext.tolist(),
                "frames": frames,
                "com": com.tolist(),
                "vcom": vcom.tolist(),
                "J_com": rows(Jcom),
                "mass": mass,
                "A_g": rows(Ag),
                "h_g": hg.tolist(),
                "dA_g_v": dAgv.tolist(),
                "dh_g": dhg.tolist(),
            }
        )

    mass_moving = float(sum(I.mass for I in model.inertias[1:]))
    mass_all = float(sum(I.mass for I in model.inertias))
    assert abs(samples[0]["mass"] - mass_moving) < 1e-12
    if robot["floating"]:
        assert abs(mass_all - urdf_mass) < 1e-9 and float(model.inertias[0].mass) == 0.0
        com_note = (
            f"data.mass[0] = {samples[0]['mass']!r} kg = sum of model.inertias[1:].mass = sum of all URDF "
            f"<inertial> masses ({urdf_mass!r} kg): with a free-flyer root every link is on a moving joint "
            f"(the root link's inertia is on root_joint), so com, vcom, J_com, A_g and h_g count all links"
        )
    else:
        fixed_links = [f.name for f in model.frames if f.type == pin.FrameType.BODY and f.parentJoint == 0]
        com_note = (
            f"data.mass[0] = {samples[0]['mass']!r} kg = sum of model.inertias[1:].mass (the bodies of the "
            f"moving joints) only. The URDF's links total {urdf_mass!r} kg; the {float(model.inertias[0].mass)!r} "
            f"kg of the links fixed to the world ({', '.join(fixed_links)}; "
            f"merged into model.inertias[0], the universe) is NOT counted by centerOfMass, jacobianCenterOfMass, "
            f"ccrba or dccrba: com / vcom / J_com are those of the moving bodies, and A_g, h_g, dA_g_v, dh_g are "
            f"about that centre of mass"
        )

    doc = {
        "robot": name,
        "pinocchio_version": pin.__version__,
        "urdf_copy": robot["urdf"],
        "root": "free-flyer root_joint added by the loader (pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()))"
        if robot["floating"]
        else "fixed (pin.buildModelFromUrdf(path), no root joint)",
        "nq": model.nq,
        "nv": model.nv,
        "nq_angle": model.nq,
        "gravity": model.gravity.linear.tolist(),
        "samples_source": f"{robot['samples_from']} samples 0-{NSAMPLES - 1} (q, q_angle, v, tau, qdd_for_rnea)"
        if robot["samples_from"]
        else f"drawn here: pin.seed({robot['seed']}); q = pin.randomConfiguration(model) with the free-flyer "
        f"translation bounds set to [-1, 1] and the joints within their URDF limits; v, tau, qdd_for_rnea ~ "
        f"N(0, 1) from numpy.random.default_rng({robot['seed']})",
        "f_ext_source": f"per sample, per link in f_ext_links order: force ~ N(0, 20) N, torque ~ N(0, 2) N m "
        f"(numpy.random.default_rng({robot['seed']}), drawn after the samples' own numbers)",
        "f_ext_links": robot["wrench_links"],
        "f_ext_world_fixed_links": world_fixed,
        "frame_links": robot["frame_links"],
        "mass_pinocchio": samples[0]["mass"],
        "mass_sum_model_inertias_moving": mass_moving,
        "mass_sum_model_inertias_including_universe": mass_all,
        "mass_sum_urdf_links": urdf_mass,
        "com_note": com_note,
        "conventions": CONVENTIONS,
        "joints": joints,
        "samples": samples,
    }
    return doc


if not os.path.exists("anymal_b.urdf"):
    shutil.copyfile(ANYMAL_SRC, "anymal_b.urdf")
assert sha256("anymal_b.urdf") == ANYMAL_SHA256

docs = [reference(r) for r in ROBOTS]
for (robot, k), val in worst.items():
    print(f"{robot:18s} {k}: {val:.3e}")
limits = {
    "J(local_world_aligned) @ v vs frame velocity": 1e-12,
    "rnea(q,v,qdd_ext,fext) vs tau (relative)": 1e-9,
    "A_g @ v vs h_g": 1e-12,
    "J_com @ v vs vcom": 1e-12,
    "tau_rnea_ext vs rnea - sum J_local^T w (relative)": 1e-9,
    "M qdd_ext + nle_ext vs tau (relative)": 1e-9,
    "dA_g_v vs dh_g": 1e-9,
    "ccrba com vs centerOfMass com": 1e-12,
    "qdd vs stored <robot>.json qdd": 1e-9,
}
for (robot, k), val in worst.items():
    if k in limits:
        assert val <= limits[k], (robot, k, val)
assert all(any(k == key for _, key in worst) for k in limits)
for doc in docs:
    with open(f"{doc['robot']}_contact.json", "w") as fh:
        json.dump(doc, fh)
    print(doc["robot"], "written:", len(doc["samples"]), "samples")
