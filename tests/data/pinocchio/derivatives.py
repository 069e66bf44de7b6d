#!/usr/bin/env python3
"""Analytical derivatives of forward and inverse dynamics from Pinocchio (Carpentier and Mansard, RSS 2018):
`<robot>_derivatives.json`.

Robots: a fixed arm (`ur5`), two floating quadrupeds (`solo12_floating`, `anymal_b_floating`) and a floating
humanoid (`talos_reduced_floating`: tests/data/erd/talos_reduced.urdf, a slimmed copy, nv = 38). The quadrupeds and the arm take the states and
external wrenches of `<robot>_contact.json` (samples 0-2: q, v, tau, qdd_for_rnea, f_ext); the humanoid has
two states drawn here with fixed seeds and no wrench (its matrices are 38 x 38). Per sample:

- `computeABADerivatives(q, v, tau[, fext])`: qdd, dqdd_dq, dqdd_dv, dqdd_dtau (= Minv, symmetrized from the
  upper triangle Pinocchio fills);
- `computeRNEADerivatives(q, v, qdd_for_rnea[, fext])`: tau, dtau_dq, dtau_dv, dtau_dqdd (= M, symmetrized).
- for `ur5`, `without_f_ext`: the same eight fields at the same state without the wrenches.

Matrices are lists of rows, nv x nv, in Pinocchio's v order (the joints list maps it); derivatives with
respect to q are in the tangent space (column k along integrate(q, eps e_k)). The script checks each set
against central finite differences and the invariants (Minv M = I, dqdd_dq = -Minv dtau_dq at qdd = aba)
before writing anything.

Run from this folder with the `pin` wheel installed (`pip install pin==4.1.0`): python3 derivatives.py
"""
import json

import numpy as np
import pinocchio as pin

NSAMPLES = 3

ROBOTS = [
    {"name": "ur5", "urdf": "ur5.urdf", "floating": False, "contact": "ur5_contact.json", "plain": True},
    {"name": "solo12_floating", "urdf": "solo12_floating.urdf", "floating": True,
     "contact": "solo12_floating_contact.json"},
    {"name": "anymal_b_floating", "urdf": "anymal_b.urdf", "floating": True,
     "contact": "anymal_b_floating_contact.json"},
    {"name": "talos_reduced_floating", "urdf": "../erd/talos_reduced.urdf", "floating": True, "contact": None,
     "seed": 31, "samples": 2},
]

CONVENTIONS = {
    "q": "Pinocchio layout; free-flyer -> (x, y, z, qx, qy, qz, qw); no joint of these robots is continuous",
    "v": "free-flyer: (vx, vy, vz, wx, wy, wz) in the root body frame, then the revolute joints",
    "f_ext": "as in <robot>_contact.json: link name -> {force, torque} applied by the environment, in the "
    "link's own frame about its origin (absent: no wrench)",
    "aba": "computeABADerivatives(q, v, tau[, fext]): qdd = data.ddq, dqdd_dq = data.ddq_dq, dqdd_dv = "
    "data.ddq_dv, dqdd_dtau = data.Minv symmetrized",
    "rnea": "computeRNEADerivatives(q, v, qdd_for_rnea[, fext]): tau = rnea(...), dtau_dq = data.dtau_dq, "
    "dtau_dv = data.dtau_dv, dtau_dqdd = data.M symmetrized",
    "matrices": "lists of rows; row i = output i, column k = direction k, both in Pinocchio's v order; d/dq in "
    "the tangent space: column k is the derivative along integrate(q, eps e_k)",
}


def rows(a):
    return [list(map(float, r)) for r in np.asarray(a)]


def symmetric(upper):
    u = np.triu(upper)
    return u + u.T - np.diag(np.diag(u))


def build(robot):
    path = robot["urdf"]
    model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if robot["floating"] else pin.buildModelFromUrdf(path)
    if robot["floating"]:
        model.lowerPositionLimit[:3] = -1.0
        model.upperPositionLimit[:3] = 1.0
    return model


def joints_list(model):
    out = []
    for jid in range(1, model.njoints):
        j = model.joints[jid]
        out.append({"name": model.names[jid], "nq": j.nq, "nv": j.nv, "idx_q": j.idx_q, "idx_v": j.idx_v,
                    "idx_q_angle": j.idx_q})
    return out


def fext_of(model, f_ext):
    fext = [pin.Force.Zero() for _ in range(model.njoints)]
    for link, w in f_ext.items():
        frame = model.frames[model.getFrameId(link, pin.FrameType.BODY)]
        if frame.parentJoint == 0:
            continue
        fext[frame.parentJoint] += frame.placement.act(pin.Force(np.array(w["force"]), np.array(w["torque"])))
    vec = pin.StdVec_Force()
    for f in fext:
        vec.append(f)
    return vec


def central(model, f, x, along_q, h):
    cols = []
    for k in range(model.nv):
        e = np.zeros(model.nv)
        e[k] = h
        if along_q:
            plus, minus = f(pin.integrate(model, x, e)), f(pin.integrate(model, x, -e))
        else:
            plus, minus = f(x + e), f(x - e)
        cols.append((plus - minus) / (2 * h))
    return np.array(cols).T


def rel(a, b):
    return np.abs(a - b).max() / max(1.0, np.abs(b).max())


worst = {}


def note(robot, key, value):
    worst[(robot, key)] = max(worst.get((robot, key), 0.0), float(value))


def reference(robot):
    name = robot["name"]
    model = build(robot)
    data = model.createData()
    if robot["contact"]:
        contact = json.load(open(robot["contact"]))
        raw = [{"q": np.array(s["q"]), "v": np.array(s["v"]), "tau": np.array(s["tau"]),
                "a": np.array(s["qdd_for_rnea"]), "f_ext": s["f_ext"]} for s in contact["samples"][:NSAMPLES]]
    else:
        pin.seed(robot["seed"])
        rng = np.random.default_rng(robot["seed"])
        raw = [{"q": pin.randomConfiguration(model), "v": rng.normal(0.0, 1.0, model.nv),
                "tau": rng.normal(0.0, 1.0, model.nv), "a": rng.normal(0.0, 1.0, model.nv), "f_ext": None}
               for _ in range(robot.get("samples", NSAMPLES))]
    samples = []
    for s in raw:
        q, v, tau, a = s["q"], s["v"], s["tau"], s["a"]
        extra = [fext_of(model, s["f_ext"])] if s["f_ext"] else []
        pin.computeABADerivatives(model, data, q, v, tau, *extra)
        qdd = data.ddq.copy()
        dqdd_dq, dqdd_dv = data.ddq_dq.copy(), data.ddq_dv.copy()
        minv = symmetric(data.Minv)
        pin.computeRNEADerivatives(model, data, q, v, a, *extra)
        dtau_dq, dtau_dv, m = data.dtau_dq.copy(), data.dtau_dv.copy(), symmetric(data.M)
        tau_a = pin.rnea(model, data, q, v, a, *extra).copy()
        # Checks: finite differences (h = 1e-6 along q; quadratic in v and linear in tau, where a larger
        # step keeps rounding small), Minv M = I, and forward = -Minv inverse at qdd = aba.
        aba = lambda q_, v_, t_: pin.aba(model, data, q_, v_, t_, *extra).copy()
        rnea = lambda q_, v_, a_: pin.rnea(model, data, q_, v_, a_, *extra).copy()
        note(name, "aba dq vs finite differences", rel(dqdd_dq, central(model, lambda x: aba(x, v, tau), q, True, 1e-6)))
        note(name, "aba dv vs finite differences", rel(dqdd_dv, central(model, lambda x: aba(q, x, tau), v, False, 1e-2)))
        note(name, "Minv vs finite differences", rel(minv, central(model, lambda x: aba(q, v, x), tau, False, 1.0)))
        note(name, "rnea dq vs finite differences", rel(dtau_dq, central(model, lambda x: rnea(x, v, a), q, True, 1e-6)))
        note(name, "rnea dv vs finite differences", rel(dtau_dv, central(model, lambda x: rnea(q, x, a), v, False, 1e-2)))
        note(name, "Minv M - I", np.abs(minv @ m - np.eye(model.nv)).max())
        pin.computeRNEADerivatives(model, data, q, v, qdd, *extra)
        note(name, "dqdd_dq + Minv dtau_dq(qdd)", rel(dqdd_dq, -minv @ data.dtau_dq))
        plain = {}
        if robot.get("plain") and extra:
            # The same state without the wrenches (generated derivative functions take none).
            pin.computeABADerivatives(model, data, q, v, tau)
            plain = {"qdd": data.ddq.tolist(), "dqdd_dq": rows(data.ddq_dq), "dqdd_dv": rows(data.ddq_dv),
                     "dqdd_dtau": rows(symmetric(data.Minv))}
            pin.computeRNEADerivatives(model, data, q, v, a)
            plain.update({"tau_rnea": pin.rnea(model, data, q, v, a).tolist(), "dtau_dq": rows(data.dtau_dq),
                          "dtau_dv": rows(data.dtau_dv), "dtau_dqdd": rows(symmetric(data.M))})
            plain = {"without_f_ext": plain}
        samples.append({
            "q": q.tolist(), "v": v.tolist(), "tau": tau.tolist(), "qdd_for_rnea": a.tolist(),
            **({"f_ext": s["f_ext"]} if s["f_ext"] else {}),
            "qdd": qdd.tolist(), "dqdd_dq": rows(dqdd_dq), "dqdd_dv": rows(dqdd_dv), "dqdd_dtau": rows(minv),
            "tau_rnea": tau_a.tolist(), "dtau_dq": rows(dtau_dq), "dtau_dv": rows(dtau_dv), "dtau_dqdd": rows(m),
            **plain,
        })
    return {
        "robot": name,
        "pinocchio_version": pin.__version__,
        "urdf": robot["urdf"],
        "root": "free_flyer" if robot["floating"] else "fixed",
        "nq": model.nq,
        "nv": model.nv,
        "nq_angle": model.nq,
        "conventions": CONVENTIONS,
        "joints": joints_list(model),
        "samples": samples,
    }


docs = [reference(r) for r in ROBOTS]
for (robot, k), val in sorted(worst.items()):
    print(f"{robot:18s} {k}: {val:.3e}")
limits = {"aba dq vs finite differences": 1e-6, "aba dv vs finite differences": 1e-9,
          "Minv vs finite differences": 1e-9, "rnea dq vs finite differences": 1e-6,
          "rnea dv vs finite differences": 1e-9, "Minv M - I": 1e-9, "dqdd_dq + Minv dtau_dq(qdd)": 1e-9}
for (robot, k), val in worst.items():
    assert val <= limits[k], (robot, k, val)
for doc in docs:
    with open(f"{doc['robot']}_derivatives.json", "w") as fh:
        json.dump(doc, fh)
    print(doc["robot"], "written:", len(doc["samples"]), "samples")
