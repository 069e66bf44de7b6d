#!/usr/bin/env python3
"""Link-frame poses from Pinocchio for the reference robots of this folder: `<robot>_frames.json`.

For the first five samples of `<robot>.json` (its `q`, Pinocchio's layout), the world pose (oMf) of every
BODY frame (one per URDF link) after `pin.framesForwardKinematics`. Run from this folder with the `pin`
wheel installed (`pip install pin==4.1.0`); the numbers are Pinocchio's, this script only selects them.
"""
import json

import numpy as np
import pinocchio as pin

ROBOTS = [("ur5", False), ("panda", False), ("solo12_floating", True)]

for name, floating in ROBOTS:
    ref = json.load(open(f"{name}.json"))
    path = ref["urdf_copy"]
    model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(path)
    data = model.createData()
    out = {
        "robot": name,
        "pinocchio_version": pin.__version__,
        "source": f"{name}.json samples 0-4 (q in Pinocchio's layout); pin.framesForwardKinematics; BODY frames",
        "fields": "frames[link] = {R: world rotation row-major (columns: the link axes in the world), p: origin in the world}",
        "samples": [],
    }
    for s in ref["samples"][:5]:
        q = np.array(s["q"])
        pin.framesForwardKinematics(model, data, q)
        frames = {}
        for fid, f in enumerate(model.frames):
            if f.type == pin.FrameType.BODY:
                m = data.oMf[fid]
                frames[f.name] = {"R": m.rotation.reshape(-1).tolist(), "p": m.translation.tolist()}
        out["samples"].append({"q": s["q"], "frames": frames})
    with open(f"{name}_frames.json", "w") as fh:
        json.dump(out, fh)
    print(name, len(out["samples"][0]["frames"]), "frames")
