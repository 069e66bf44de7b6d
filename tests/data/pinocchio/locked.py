"""Reference data for locked joints (issue 10, `--lock JOINT=VALUE`), computed by Pinocchio (PyPI `pin`) with
`buildReducedModel(model, [joints], q_ref)`, in the schema of the other JSON files of this folder (README.md),
so that tests/pinocchio_reference.rs checks them alike. Each file also records the locks (`locked`: joint name
and value) and, per sample, the generalized gravity `gravity_torque` = rnea(q, 0, 0).

Run from the repository root: python3 tests/data/pinocchio/locked.py
"""
import json

import numpy as np
import pinocchio as pin

HERE = "tests/data/pinocchio"


def reference(name, urdf, floating, locks, seed):
    full = (
        pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
        if floating
        else pin.buildModelFromUrdf(urdf)
    )
    q_ref = pin.neutral(full)
    ids = []
    for joint, value in locks:
        jid = full.getJointId(joint)
        assert jid < full.njoints, joint
        q_ref[full.joints[jid].idx_q] = value
        ids.append(jid)
    model = pin.buildReducedModel(full, ids, q_ref)
    data = model.createData()
    rng = np.random.default_rng(seed)
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
        nle = pin.nonLinearEffects(model, data, q, v).copy()
        gravity = pin.computeGeneralizedGravity(model, data, q).copy()
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
                "gravity_torque": gravity.tolist(),
                "M": M.tolist(),
            }
        )
    doc = {
        "robot": name,
        "pinocchio_version": pin.__version__,
        "urdf_copy": urdf.split("/")[-1],
        "root": "free-flyer root_joint" if floating else "fixed",
        "locked": [{"joint": j, "value": v} for j, v in locks],
        "reduction": "pin.buildReducedModel(model, locked joint ids, q_ref), q_ref = neutral with the locked values",
        "nq": model.nq,
        "nv": model.nv,
        "nq_angle": model.nq,
        "joints": joints,
        "samples": samples,
    }
    json.dump(doc, open(f"{HERE}/{name}.json", "w"))


# A fixed arm with its elbow and last wrist joint locked.
reference("ur5_locked", f"{HERE}/ur5.urdf", False, [("elbow_joint", -0.7), ("wrist_3_joint", 1.1)], 3)
# A floating quadruped with its four hip abduction joints locked (the legs in a plane) and one knee.
reference(
    "solo12_locked_floating",
    f"{HERE}/solo12.urdf",
    True,
    [("FL_HAA", 0.1), ("FR_HAA", -0.1), ("HL_HAA", 0.2), ("HR_HAA", -0.2), ("HR_KFE", -1.3)],
    4,
)
