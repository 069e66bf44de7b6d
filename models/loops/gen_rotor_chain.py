#!/usr/bin/env python3
"""Writes rotor_chain_N.urdf for N = 10, 50, 200 (or the N given on the command line): a serial chain of
N links, each driven through a gear by a rotor that sits on the link's parent (a sibling of the link).
Deterministic: same bytes on every run. Standard library only.

Part of embedyn's test models. Original to this project. Licence: MIT OR Apache-2.0.

Usage: python3 gen_rotor_chain.py [N ...]   (files are written next to this script)

Link i (i = 0 .. N-1): 0.5 kg, 0.1 m long along its x axis, joint_i about z (i even) or y (i odd).
Rotor i: 0.1 kg, on link i-1 (on base for i = 0), 0.03 m behind joint_i, same axis as joint_i.
coupling gear_i: predecessor link_i, successor rotor_i, ratio 6 (i even) or 9 (i odd): rotor_i = ratio *
joint_i. The rotor joint is written before the link joint, so the depth-first order (siblings in file
order) is rotor_joint_0, joint_0, rotor_joint_1, joint_1, ... ; the rotor joints are dependent.
"""

import os
import sys

sys.dont_write_bytecode = True  # keep models/loops free of __pycache__
from urdfgen import Model  # noqa: E402

LINK = dict(mass=0.5, com=(0.05, 0, 0), inertia=(3.4e-5, 4.4e-4, 4.4e-4, 2e-6, -1e-6, 5e-7))
ROTOR_Z = dict(mass=0.1, com=(0, 0, 0), inertia=(1.3e-5, 1.3e-5, 2e-5, 0, 0, 0))
ROTOR_Y = dict(mass=0.1, com=(0, 0, 0), inertia=(1.3e-5, 2e-5, 1.3e-5, 0, 0, 0))


def rotor_chain(n):
    m = Model("rotor_chain_%d" % n, (
        "  rotor_chain_%d: a serial chain of %d links (0.5 kg, 0.1 m), joint axes alternating z, y, each link\n"
        "  driven by a geared rotor (0.1 kg) on its parent link: rotor_i = ratio_i * joint_i, ratio_i = 6\n"
        "  (i even) or 9 (i odd). %d spanning joints in depth-first order rotor_joint_0, joint_0,\n"
        "  rotor_joint_1, joint_1, ...; the rotor joints are dependent. %d independent DoF (joint_i).\n"
        % (n, n, 2 * n, n)
    ))
    m.generator = "gen_rotor_chain.py"
    m.link("base", comment="fixed root, frame only")
    for i in range(n):
        parent = "base" if i == 0 else "link_%d" % (i - 1)
        x = 0.0 if i == 0 else 0.1
        xr = -0.03 if i == 0 else 0.07  # rotor 0.03 m behind the joint
        axis = (0, 0, 1) if i % 2 == 0 else (0, 1, 0)
        ratio = 6.0 if i % 2 == 0 else 9.0
        m.link("rotor_%d" % i, **(ROTOR_Z if i % 2 == 0 else ROTOR_Y))
        m.link("link_%d" % i, **LINK)
        m.joint("rotor_joint_%d" % i, "revolute", parent, "rotor_%d" % i, (xr, 0, 0), (0, 0, 0), axis,
                independent=False)
        m.joint("joint_%d" % i, "revolute", parent, "link_%d" % i, (x, 0, 0), (0, 0, 0), axis, independent=True)
        m.coupling("gear_%d" % i, "link_%d" % i, "rotor_%d" % i, ratio)
    return m


def main():
    ns = [int(a) for a in sys.argv[1:]] or [10, 50, 200]
    out = os.path.dirname(os.path.abspath(__file__))
    for n in ns:
        fname = "rotor_chain_%d.urdf" % n
        rotor_chain(n).write(os.path.join(out, fname))
        print("wrote", fname)


if __name__ == "__main__":
    main()
