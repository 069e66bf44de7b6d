#!/usr/bin/env python3
"""Pinocchio reference answers for the models of this folder that embedyn must load: `<model>.json`.

For each model, Pinocchio 4.1 (`pip install pin==4.1.0`) builds it from the URDF copy here
(`pin.buildModelFromUrdf`, fixed base) and evaluates four seeded random states: ABA, RNEA, the
non-linear effects, and the mass matrix applied to a random vector (M·w: a full nv × nv matrix per
sample would make the files large, and M·w differs wherever M does). tests/pinocchio_reference.rs
compares embedyn with these numbers. Run from anywhere; the numbers are Pinocchio's.

Original to this project. Licence: MIT OR Apache-2.0.
"""

import json
import os

import numpy as np
import pinocchio as pin

HERE = os.path.dirname(os.path.abspath(__file__))
MODELS = ["icub", "mobile_manipulator_antenna"]
SAMPLES = 4


def joint_table(model):
    """Pinocchio's joints with embedyn's q layout (one angle per continuous joint)."""
    joints, q_angle = [], 0
    for j in range(1, model.njoints):
        jm = model.joints[j]
        continuous = jm.shortname().startswith("JointModelRUB")
        nq_angle = 1 if continuous else jm.nq
        joints.append({"name": model.names[j], "nq": jm.nq, "nv": jm.nv, "idx_q": jm.idx_q,
                       "idx_v": jm.idx_v, "idx_q_angle": q_angle, "continuous": continuous})
        q_angle += nq_angle
    return joints, q_angle


def main():
    for name in MODELS:
        path = os.path.join(HERE, f"{name}.urdf")
        model = pin.buildModelFromUrdf(path)
        data = model.createData()
        joints, nq_angle = joint_table(model)
        rng = np.random.default_rng(8)
        samples = []
        for _ in range(SAMPLES):
            q = pin.neutral(model)
            q_angle = np.zeros(nq_angle)
            for j in joints:
                angle = rng.uniform(-np.pi, np.pi)
                if j["continuous"]:
                    q[j["idx_q"]:j["idx_q"] + 2] = [np.cos(angle), np.sin(angle)]
                elif j["nq"] == 1:
                    lo = model.lowerPositionLimit[j["idx_q"]]
                    hi = model.upperPositionLimit[j["idx_q"]]
                    if np.isfinite(lo) and np.isfinite(hi) and hi > lo:
                        angle = rng.uniform(lo, hi)
                    q[j["idx_q"]] = angle
                q_angle[j["idx_q_angle"]] = angle
            v = rng.uniform(-2, 2, model.nv)
            tau = rng.uniform(-10, 10, model.nv)
            a = rng.uniform(-5, 5, model.nv)
            w = rng.uniform(-1, 1, model.nv)
            qdd = pin.aba(model, data, q, v, tau).copy()
            tau_rnea = pin.rnea(model, data, q, v, a).copy()
            nle = pin.nonLinearEffects(model, data, q, v).copy()
            m = pin.crba(model, data, q)
            m = np.triu(m) + np.triu(m, 1).T
            samples.append({"q_angle": q_angle.tolist(), "v": v.tolist(), "tau": tau.tolist(),
                            "qdd": qdd.tolist(), "qdd_for_rnea": a.tolist(), "tau_rnea": tau_rnea.tolist(),
                            "nle": nle.tolist(), "w": w.tolist(), "M_w": (m @ w).tolist()})
        out = {
            "robot": name,
            "pinocchio_version": pin.__version__,
            "urdf_copy": f"{name}.urdf",
            "root": "fixed (pin.buildModelFromUrdf(path))",
            "nq_angle": nq_angle,
            "nv": model.nv,
            "conventions": "q_angle: embedyn's layout (one angle per continuous joint), index with "
                           "joints[].idx_q_angle; v, tau, qdd, qdd_for_rnea, tau_rnea, nle, w, M_w in "
                           "Pinocchio's v order (joints[].idx_v); qdd = aba(q, v, tau); tau_rnea = "
                           "rnea(q, v, qdd_for_rnea); nle = nonLinearEffects(q, v); M_w = crba(q) @ w",
            "joints": joints,
            "samples": samples,
        }
        with open(os.path.join(HERE, f"{name}.json"), "w") as f:
            json.dump(out, f, separators=(",", ":"))
            f.write("\n")
        print(f"{name}.json: nv {model.nv}, {os.path.getsize(os.path.join(HERE, name + '.json'))} bytes")


if __name__ == "__main__":
    main()
