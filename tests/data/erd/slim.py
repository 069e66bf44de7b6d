#!/usr/bin/env python3
"""Writes the slimmed copies of example-robot-data URDFs kept in this folder (see README.md).

Keeps everything the dynamics reads - <link> with <inertial>, <joint> with <origin>, <axis>, <limit>,
<dynamics>, <mimic> - with every number exactly as written, and removes what it does not: <visual>,
<collision>, <gazebo>, top-level <material>, <transmission> without a rotor inertia, <sensor>,
<calibration>, <safety_controller>, and comments. Needs the PyPI package example-robot-data (6.0.0).

    python3 slim.py            # rewrites the copies listed in COPIES

Original to this project. Licence: MIT OR Apache-2.0 (the copies keep their own licences, see README.md).
"""

import importlib.metadata
import os
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))

# copy name -> (path inside example-robot-data's robots/, upstream, licence)
COPIES = {
    "icub": ("icub_description/robots/icub.urdf", "robotology/icub-models", "CC-BY-SA-4.0"),
    "romeo": ("romeo_description/urdf/romeo.urdf", "laas/romeo", "BSD"),
    "romeo_laas_small": ("romeo_description/urdf/romeo_laas_small.urdf", "laas/romeo", "BSD"),
    "talos_reduced": ("talos_data/robots/talos_reduced.urdf", "pal-robotics/talos_robot", "Apache-2.0"),
}

DROPPED_ANYWHERE = {"visual", "collision", "gazebo", "sensor", "calibration", "safety_controller"}


def robots_dir():
    dist = importlib.metadata.distribution("example-robot-data")
    for f in dist.files:
        path = str(dist.locate_file(f))
        if "/robots/" in path and path.endswith(".urdf"):
            return path[: path.rindex("/robots/") + len("/robots")], dist.version
    raise SystemExit("example-robot-data is not installed")


def prune(element):
    for child in list(element):
        tag = child.tag if isinstance(child.tag, str) else ""
        if tag in DROPPED_ANYWHERE:
            element.remove(child)
        else:
            prune(child)


def slim(source, header):
    tree = ET.parse(source)  # comments are not kept by ElementTree's default parser
    robot = tree.getroot()
    for child in list(robot):
        if child.tag == "material":
            robot.remove(child)
        elif child.tag == "transmission" and "rotor_inertia" not in ET.tostring(child, "unicode"):
            robot.remove(child)
    prune(robot)
    ET.indent(tree, "  ")
    body = ET.tostring(robot, "unicode")
    return f'<?xml version="1.0"?>\n<!-- {header} -->\n{body}\n'


def main():
    robots, version = robots_dir()
    for name, (rel, upstream, licence) in COPIES.items():
        header = (f"Slimmed copy of {rel} from example-robot-data {version} (upstream {upstream}, licence "
                  f"{licence}, which also covers this copy): visuals, collisions, gazebo and other "
                  f"non-dynamics elements and comments removed by slim.py; inertias, joints and limits "
                  f"unchanged.")
        text = slim(os.path.join(robots, rel), header)
        with open(os.path.join(HERE, f"{name}.urdf"), "w") as f:
            f.write(text)
        print(f"{name}.urdf: {len(text)} bytes")


if __name__ == "__main__":
    main()
