"""Reference data with armature (issue 10), computed by Pinocchio (PyPI `pin`), in the schema of the other
JSON files of this folder (README.md), so that tests/pinocchio_reference.rs checks them alike.

Pinocchio's URDF parser does not read armature; this script reads it as docs/model-format.md defines it —
`<dynamics armature>` plus r² · I for each transmission actuator with Drake's `<drake:rotor_inertia>`, r its
`<drake:gear_ratio>`, else its `<mechanicalReduction>` (or the transmission's), else 1 — and sets
`model.armature`, so the loader's reading is checked too.

Run from the repository root: python3 tests/data/pinocchio/armature.py
"""
import json
import re
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

HERE = "tests/data/pinocchio"


def local(tag):
    return tag.split("}")[-1]


def read_armature(path):
    root = ET.parse(path).getroot()
    arm = {}
    for j in root.findall("joint"):
        d = j.find("dynamics")
        arm[j.get("name")] = float(d.get("armature", "0")) if d is not None else 0.0
    for t in root.findall("transmission"):
        jn = t.find("joint")
        for a in t.findall("actuator"):
            kids = {local(c.tag): c for c in a}
            if "rotor_inertia" not in kids:
                continue
            inertia = float(kids["rotor_inertia"].get("value"))
            if "gear_ratio" in kids:
                r = float(kids["gear_ratio"].get("value"))
            elif "mechanicalReduction" in kids:
                r = float(kids["mechanicalReduction"].text)
            else:
                mr = [c for c in t if local(c.tag) == "mechanicalReduction"]
                r = float(mr[0].text) if mr else 1.0
            arm[jn.get("name")] += r * r * inertia
    return arm


def solo12_with_armature():
    """solo12.urdf with <dynamics armature> on each of its 12 joints (0.01, 0.02, 0.03 kg·m² in turn)."""
    text = open(f"{HERE}/solo12.urdf").read()
    count = [0]

    def add(m):
        k = count[0]
        count[0] += 1
        return m.group(0) + f'\n    <dynamics armature="{0.01 * (1 + k % 3):.2f}" damping="0"/>'

    text = re.sub(r'<joint name="[^"]*" type="revolute">', add, text)
    assert count[0] == 12, count[0]
    # The joints' own <dynamics damping="0.0" friction="0.0"/> (zeros): one <dynamics> per joint, as URDF has.
    text, dropped = re.subn(r'\n\s*<dynamics damping="0.0" friction="0.0"/>', "", text)
    assert dropped >= 12, dropped
    path = f"{HERE}/solo12_armature_floating.urdf"
    open(path, "w").write(text)
    return path


def reference(name, urdf, floating, seed):
    model = (
        pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
        if floating
        else pin.buildModelFromUrdf(urdf)
    )
    arm = read_armature(urdf)
    for jid in range(1, model.njoints):
        jn = model.names[jid]
        if jn in arm:
            j = model.joints[jid]
            model.armature[j.idx_v : j.idx_v + j.nv] = arm[jn]
    data = model.createData()
    rng = np.random.default_rng(seed)
    # Joints without limits (and the free-flyer's position) drawn in [-1, 1].
    lower = np.where(np.abs(model.lowerPositionLimit) < 10, model.lowerPositionLimit, -1.0)
    upper = np.where(np.abs(model.upperPositionLimit) < 10, model.upperPositionLimit, 1.0)
    joints = []
    for jid in range(1, model.njoints):
        j = model.joints[jid]
        joints.append(
            {
                "name": model.names[jid],
                "nq": j.nq,
                "nv": j.nv,
                "idx_q": j.idx_q,
                "idx_v": j.idx_v,
                "idx_q_angle": j.idx_q,
                "armature": float(model.armature[j.idx_v]),
            }
        )
    samples = []
    for _ in range(20):
        q = pin.randomConfiguration(model, lower, upper)
        v = rng.uniform(-1, 1, model.nv)
        tau = rng.uniform(-1, 1, model.nv)
        a = rng.uniform(-1, 1, model.nv)
        qdd = pin.aba(model, data, q, v, tau).copy()
        tau_rnea = pin.rnea(model, data, q, v, a).copy()
        nle = pin.rnea(model, data, q, v, np.zeros(model.nv)).copy()
        M = pin.crba(model, data, q).copy()
        M = np.triu(M) + np.triu(M, 1).T
        residual = np.abs(M @ qdd + nle - tau).max() / max(1.0, np.abs(tau).max())
        assert residual < 1e-9, residual
        samples.append(
            {
                "q_angle": q.tolist(),
                "v": v.tolist(),
                "tau": tau.tolist(),
                "qdd": qdd.tolist(),
                "qdd_for_rnea": a.tolist(),
                "tau_rnea": tau_rnea.tolist(),
                "nle": nle.tolist(),
                "M": M.tolist(),
            }
        )
    doc = {
        "robot": name,
        "pinocchio_version": pin.__version__,
        "urdf_copy": urdf.split("/")[-1],
        "root": "free-flyer root_joint" if floating else "fixed",
        "nq": model.nq,
        "nv": model.nv,
        "nq_angle": model.nq,
        "armature": "read by this script as docs/model-format.md defines it, set as model.armature",
        "joints": joints,
        "samples": samples,
    }
    json.dump(doc, open(f"{HERE}/{name}.json", "w"))


# The arm of tests/data/armature.urdf (armature from <dynamics> and from transmissions), copied here.
open(f"{HERE}/armature_arm.urdf", "w").write(open("tests/data/armature.urdf").read())
reference("armature_arm", f"{HERE}/armature_arm.urdf", False, 1)
reference("solo12_armature_floating", solo12_with_armature(), True, 2)
