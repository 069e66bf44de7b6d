#!/usr/bin/env python3
"""Configuration-space reference data from Pinocchio: `configuration.json`.

For ur5 (fixed base) and solo12_floating (Pinocchio's free flyer `root_joint`, embedyn's `--floating`),
`pin.integrate(model, q, v)` and `pin.difference(model, q0, q1)` on random samples, including rotations of
the free flyer by tiny angles (1e-12, 1e-6, 1e-3 rad), near π (π − 1e-6, π − 1e-9) and beyond π (integrate),
and quaternions of either sign (difference). Every vector is in Pinocchio's layout (map by joint name
through `<robot>.json`'s `joints`). Run from this folder with the `pin` wheel installed
(`pip install pin==4.1.0`); the numbers are Pinocchio's, this script only chooses the inputs.
"""
import json

import numpy as np
import pinocchio as pin

ROBOTS = [("ur5", False), ("solo12_floating", True)]
RNG = np.random.default_rng(20240611)


def random_q(model):
    lower = np.where(np.abs(model.lowerPositionLimit) < 1e10, model.lowerPositionLimit, -np.pi)
    upper = np.where(np.abs(model.upperPositionLimit) < 1e10, model.upperPositionLimit, np.pi)
    return pin.randomConfiguration(model, np.maximum(lower, -np.pi), np.minimum(upper, np.pi))


def random_v(model, floating, angle=None):
    v = RNG.uniform(-2.0, 2.0, model.nv)
    if floating and angle is not None:
        axis = RNG.normal(size=3)
        v[3:6] = angle * axis / np.linalg.norm(axis)
    return v


out = {
    "pinocchio_version": pin.__version__,
    "source": "configuration.py: pin.integrate and pin.difference; q, v in Pinocchio's layout of <robot>.json",
    "fields": "integrate: {q, v, q_out = pin.integrate(q, v)}; difference: {q0, q1, v = pin.difference(q0, q1)}; "
    "angle: the free flyer's rotation angle |omega| of v (null: random)",
    "robots": {},
}
ANGLES = [None, None, None, None, 1e-12, 1e-6, 1e-3, 1.0, np.pi - 1e-6, np.pi - 1e-9]
for name, floating in ROBOTS:
    ref = json.load(open(f"{name}.json"))
    path = ref["urdf_copy"]
    model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(path)
    integrate, difference = [], []
    angles = ANGLES + ([4.0, 2 * np.pi - 1e-3] if floating else [])
    for angle in angles:
        q = random_q(model)
        v = random_v(model, floating, angle)
        q_out = pin.integrate(model, q, v)
        integrate.append({"angle": angle, "q": q.tolist(), "v": v.tolist(), "q_out": q_out.tolist()})
    for k, angle in enumerate(ANGLES):
        q0 = random_q(model)
        if angle is None:
            q1 = random_q(model)
        else:
            # A rotation of the given angle from q0 (angle ≤ π: the least rotation).
            q1 = pin.integrate(model, q0, random_v(model, floating, angle))
        if floating and k % 2 == 1:
            q1[3:7] *= -1.0  # the same configuration
        v = pin.difference(model, q0, q1)
        difference.append({"angle": angle, "q0": q0.tolist(), "q1": q1.tolist(), "v": v.tolist()})
    out["robots"][name] = {"floating": floating, "integrate": integrate, "difference": difference}
    print(name, len(integrate), "integrate,", len(difference), "difference samples")

with open("configuration.json", "w") as fh:
    json.dump(out, fh, indent=None)
