"""Reference joint limits (issue 11, item 5), read by Pinocchio (PyPI `pin`) from the URDF files of this folder:
`model.lowerPositionLimit`, `upperPositionLimit`, `velocityLimit` and `effortLimit` at each joint's coordinates,
written to limits.json for tests/limits.rs.

Per robot, per joint in Pinocchio's order: `name`, `urdf_type`, and `lower`, `upper`, `velocity`, `effort` as
Pinocchio holds them — `null` where Pinocchio's number is not a limit in embedyn's sense: the position limits of a
continuous joint (Pinocchio stores bounds on its (cos, sin) pair, ±1.01) and every limit of the free-flyer root
(±f64::MAX). Each joint also lists `attributes`, the `<limit>` attributes its URDF element carries (read here with
ElementTree), so that a test can tell a number the file gives from a default urdfdom fills in.

Run from the repository root: python3 tests/data/pinocchio/limits.py
"""
import json
import xml.etree.ElementTree as ET

import pinocchio as pin

HERE = "tests/data/pinocchio"
ROBOTS = [
    ("double_pendulum", "double_pendulum.urdf", False),
    ("double_pendulum_continuous", "double_pendulum_continuous.urdf", False),
    ("panda", "panda.urdf", False),
    ("ur5", "ur5.urdf", False),
    ("solo12_floating", "solo12.urdf", True),
    ("armature_arm", "armature_arm.urdf", False),
]


def number(x):
    return float(x)


def reference(urdf, floating):
    path = f"{HERE}/{urdf}"
    model = (
        pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
        if floating
        else pin.buildModelFromUrdf(path)
    )
    tag = lambda e: e.tag.rsplit("}", 1)[-1]  # noqa: E731 (ur5.urdf declares a namespace)
    elements = {e.get("name"): e for e in ET.parse(path).getroot() if tag(e) == "joint"}
    joints = []
    for jid in range(1, model.njoints):
        name = model.names[jid]
        j = model.joints[jid]
        element = elements.get(name)
        urdf_type = element.get("type") if element is not None else None
        limit = next((c for c in element if tag(c) == "limit"), None) if element is not None else None
        entry = {
            "name": name,
            "urdf_type": urdf_type,
            "attributes": sorted(limit.attrib) if limit is not None else [],
        }
        if floating and jid == 1:  # the free-flyer root
            assert element is None, name
            entry.update(lower=None, upper=None, velocity=None, effort=None)
        else:
            assert urdf_type is not None, name
            positioned = urdf_type in ("revolute", "prismatic")
            entry.update(
                lower=number(model.lowerPositionLimit[j.idx_q]) if positioned else None,
                upper=number(model.upperPositionLimit[j.idx_q]) if positioned else None,
                velocity=number(model.velocityLimit[j.idx_v]),
                effort=number(model.effortLimit[j.idx_v]),
            )
        joints.append(entry)
    return {"urdf": urdf, "floating": floating, "joints": joints}


out = {
    "pinocchio_version": pin.__version__,
    "robots": {name: reference(urdf, floating) for name, urdf, floating in ROBOTS},
}
with open(f"{HERE}/limits.json", "w") as f:
    json.dump(out, f, indent=1)
    f.write("\n")
