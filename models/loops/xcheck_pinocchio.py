#!/usr/bin/env python3
"""Optional cross-check of models/loops against Pinocchio (skipped, exit 0, when `pinocchio` is not
importable). Pinocchio reads the spanning tree only (it ignores <loop> and <coupling>; mimic joints are
read as ordinary joints), which is what is checked here:

1. forward kinematics: every link pose from check_closure.py's own URDF kinematics equals Pinocchio's
   at a pseudo-random configuration (fixed seed) - so both scripts follow the same URDF conventions;
2. four_bar_internal and four_bar_terminal are the same physical system: along the assembly branch of
   q = 0, with the coordinate map of README.md, the mass matrix and the gravity vector reduced to the
   independent coordinates (crank_joint, tip_joint), X^T M X and X^T g, agree.

Part of embedyn's test models. Original to this project. Licence: MIT OR Apache-2.0.
Usage: python3 xcheck_pinocchio.py
"""

import glob
import os
import sys

sys.dont_write_bytecode = True
import numpy as np  # noqa: E402

try:
    import pinocchio as pin  # noqa: E402
except ImportError:
    print("pinocchio not importable: cross-check skipped")
    sys.exit(0)

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import check_closure as cc  # noqa: E402


def pin_q(pm, m, qd):
    q = pin.neutral(pm)
    for J in m.moving:
        if J.nv == 1:
            q[pm.joints[pm.getJointId(J.name)].idx_q] = qd.get(J.name, 0.0)
    return q


def fk_check():
    rng = np.random.default_rng(20240607)
    worst_all = 0.0
    for f in sorted(glob.glob(os.path.join(HERE, "*.urdf"))):
        m = cc.Model(f)
        pm = pin.buildModelFromUrdf(f)
        data = pm.createData()
        qd = {J.name: float(rng.uniform(-1.5, 1.5)) for J in m.moving if J.nv == 1}
        pin.forwardKinematics(pm, data, pin_q(pm, m, qd))
        pin.updateFramePlacements(pm, data)
        T, _ = m.fk(qd)
        worst = 0.0
        for link, (R, p) in T.items():
            M = data.oMf[pm.getFrameId(link, pin.FrameType.BODY)]
            worst = max(worst, np.max(np.abs(M.rotation - R)), np.max(np.abs(M.translation - p)))
        worst_all = max(worst_all, worst)
        print("  %-26s pinocchio nq %3d nv %3d; max link pose difference %.1e" % (os.path.basename(f), pm.nq,
                                                                                pm.nv, worst))
    return worst_all


def reduced(fname, qd):
    m = cc.Model(os.path.join(HERE, fname))
    pm = pin.buildModelFromUrdf(os.path.join(HERE, fname))
    data = pm.createData()
    names = [J.name for J in m.moving]
    K = m.loop_jacobian(m.loops[0], qd)
    ind = [names.index("crank_joint"), names.index("tip_joint")]
    dep = [names.index("coupler_joint"), names.index("rocker_joint")]
    X = np.zeros((len(names), 2))
    X[ind, [0, 1]] = 1.0
    X[dep, :] = -np.linalg.pinv(K[:, dep]) @ K[:, ind]
    P = np.zeros((pm.nv, len(names)))
    for k, n in enumerate(names):
        P[pm.joints[pm.getJointId(n)].idx_v, k] = 1.0
    q = pin_q(pm, m, qd)
    M = pin.crba(pm, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    g = pin.computeGeneralizedGravity(pm, data, q)
    return X.T @ (P.T @ M @ P) @ X, X.T @ (P.T @ g)


def four_bar_check():
    t = cc.Model(os.path.join(HERE, "four_bar_internal.urdf"))
    q = {"crank_joint": 0.0, "coupler_joint": 0.0, "tip_joint": 0.4, "rocker_joint": 0.0}
    worst = 0.0
    for qc in (0.0, 0.7, 1.9, 3.0, 0.0, -1.2, -2.8):
        start, steps = q["crank_joint"], 60
        for k in range(1, steps + 1):
            q["crank_joint"] = start + (qc - start) * k / steps
            q = t.solve(q, ["coupler_joint", "rocker_joint"])
        qi = dict(q)
        qi["rocker_joint"] = q["rocker_joint"] - q["crank_joint"] - q["coupler_joint"]
        Mt, gt = reduced("four_bar_internal.urdf", q)
        Mi, gi = reduced("four_bar_terminal.urdf", qi)
        d = max(np.max(np.abs(Mt - Mi)), np.max(np.abs(gt - gi)))
        worst = max(worst, d)
        print("  crank %+.2f: X^T M X = [%.9f %.9f; %.9f %.9f], X^T g = [%.9f %.9f], difference %.1e"
              % (qc, Mt[0, 0], Mt[0, 1], Mt[1, 0], Mt[1, 1], gt[0], gt[1], d))
    return worst


def main():
    print("== forward kinematics vs pinocchio %s" % pin.__version__)
    w1 = fk_check()
    print("== four_bar_internal vs four_bar_terminal: reduced mass matrix and gravity (pinocchio)")
    w2 = four_bar_check()
    ok = w1 < 1e-12 and w2 < 1e-12
    print("max differences: kinematics %.1e, reduced dynamics %.1e -> %s" % (w1, w2, "OK" if ok else "FAIL"))
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
