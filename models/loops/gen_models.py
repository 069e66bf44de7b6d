#!/usr/bin/env python3
"""Writes the hand-designed closed-loop models of models/loops (all but rotor_chain_N.urdf, which
gen_rotor_chain.py writes). Deterministic: same bytes on every run. Standard library only.

Part of embedyn's test models. Original to this project. Licence: MIT OR Apache-2.0.

Usage: python3 gen_models.py [OUTDIR]   (default: the directory of this script)

Conventions: planar mechanisms are drawn in the x-z plane (gravity -z in the plane), every joint axis
along +y. A link frame sits on its proximal joint with its x axis along the link; its orientation is the
rotation psi about +y (rpy "0 psi 0"), psi = atan2(-dz, dx) of the link direction (dx, dz). Every loop is
assembled at q = 0 exactly: both cut frames are given the same world pose (origin and orientation).
"""

import math
import os
import sys

sys.dont_write_bytecode = True  # keep models/loops free of __pycache__
from urdfgen import Model, along, ang, circles, fmt, norm, sub  # noqa: E402

Y = (0, 1, 0)


def mirror_y(com, inertia):
    """The same body mirrored through the x-z plane (left leg -> right leg)."""
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    return (com[0], -com[1], com[2]), (ixx, iyy, izz, -ixy, ixz, -iyz)


# ---------------------------------------------------------------------------------------------
# 1 + 2: the four-bar with a pendulum on the coupler, cut two ways
# ---------------------------------------------------------------------------------------------

FB_A0 = (0.0, 0.0)  # crank ground pivot (x, z) in base
FB_C0 = (0.30, 0.05)  # rocker ground pivot
FB_LA, FB_LB, FB_LC = 0.12, 0.32, 0.22  # crank, coupler, rocker lengths (Grashof crank-rocker)
FB_PSI_A = -1.1  # crank at q = 0: 63 degrees above +x


def four_bar_geometry():
    a1 = along(FB_A0, FB_PSI_A, FB_LA)
    up, _down = circles(a1, FB_LB, FB_C0, FB_LC)
    b = up  # coupler-rocker pin, upper branch
    psi_b = ang(sub(b, a1))
    psi_c = ang(sub(b, FB_C0))
    return a1, b, psi_b, psi_c


FB_CRANK = dict(mass=0.4, com=(0.06, 0, 0.003), inertia=(4.4e-5, 4.9e-4, 5.1e-4, 2e-6, -3e-6, 1e-6))
FB_COUPLER = dict(mass=0.8, com=(0.16, 0.002, -0.004),
                  inertia=(1.5e-4, 6.9e-3, 6.9e-3, 4e-6, 1.2e-5, -2e-6))
FB_ROCKER_I = (1.0e-4, 2.44e-3, 2.47e-3, -3e-6, 5e-6, 2e-6)
FB_ROCKER_COM = (0.11, 0, 0.004)  # in the rocker frame at the ground pivot C0
FB_ROCKER_COM_AT_B = (-0.11, 0, 0.004)  # the same point in a frame at the pin B (shifted by 0.22 along x)
FB_TIP = dict(mass=0.2, com=(0, 0, -0.1), inertia=(3.4e-5, 3.3e-5, 3.0e-5, 1e-6, 0, -1e-6))
FB_TIP_XYZ = (0.16, 0, -0.03)  # tip pivot in the coupler frame


def four_bar(terminal):
    a1, b, psi_b, psi_c = four_bar_geometry()
    if not terminal:
        name = "four_bar_internal"
        comment = (
            "  four_bar_internal: planar four-bar (x-z plane, axes +y) with a 0.2 kg pendulum on the coupler.\n"
            "  Ground = root link base; crank and rocker pivot on the ground; loop cut at the coupler-rocker\n"
            "  pin (predecessor coupler, successor rocker: a direct child of the ground). Spanning joints in\n"
            "  depth-first order: crank_joint (independent), coupler_joint (dependent), tip_joint,\n"
            "  rocker_joint (dependent). 2 independent DoF (crank_joint, tip_joint).\n"
            "  Same physical mechanism as four_bar_terminal.urdf; see README.md for the coordinate map.\n"
        )
    else:
        name = "four_bar_terminal"
        comment = (
            "  four_bar_terminal: the mechanism of four_bar_internal.urdf (same masses, inertias, geometry,\n"
            "  same tip pendulum), cut at the rocker's ground pivot instead: spanning tree base -> crank ->\n"
            "  coupler -> rocker, loop from the rocker (predecessor) back to base (successor, an ancestor).\n"
            "  Spanning joints in depth-first order: crank_joint (independent), coupler_joint (dependent),\n"
            "  tip_joint, rocker_joint (dependent; rocker relative to the coupler). 2 independent DoF.\n"
            "  q_rocker(internal) = q_crank + q_coupler + q_rocker(terminal); other coordinates are equal.\n"
        )
    m = Model(name, comment)
    m.link("base", comment="ground (fixed root); pivots at x-z (0, 0) and (0.30, 0.05)")
    m.link("crank", **FB_CRANK)
    m.link("coupler", **FB_COUPLER)
    m.link("tip", **FB_TIP)
    if not terminal:
        m.link("rocker", mass=0.6, com=FB_ROCKER_COM, inertia=FB_ROCKER_I,
               comment="rocker frame on its ground pivot, x axis towards the coupler pin")
    else:
        m.link("rocker", mass=0.6, com=FB_ROCKER_COM_AT_B, inertia=FB_ROCKER_I,
               comment="rocker frame on the coupler pin (the internal file's frame shifted 0.22 along x)")
    m.joint("crank_joint", "revolute", "base", "crank", (FB_A0[0], 0, FB_A0[1]), (0, FB_PSI_A, 0), Y,
            independent=True)
    m.joint("coupler_joint", "revolute", "crank", "coupler", (FB_LA, 0, 0), (0, psi_b - FB_PSI_A, 0), Y,
            independent=False)
    m.joint("tip_joint", "revolute", "coupler", "tip", FB_TIP_XYZ, (0, 0, 0), Y)
    if not terminal:
        m.joint("rocker_joint", "revolute", "base", "rocker", (FB_C0[0], 0, FB_C0[1]), (0, psi_c, 0), Y,
                independent=False)
        m.loop("coupler_rocker_pin", "revolute", "coupler", (FB_LB, 0, 0), (0, -psi_b, 0),
               "rocker", (FB_LC, 0, 0), (0, -psi_c, 0), Y,
               comment="cut joint: coupler end = rocker end; both cut frames aligned with base at q = 0")
    else:
        m.joint("rocker_joint", "revolute", "coupler", "rocker", (FB_LB, 0, 0), (0, psi_c - psi_b, 0), Y,
                independent=False)
        m.loop("rocker_ground_pivot", "revolute", "rocker", (-FB_LC, 0, 0), (0, -psi_c, 0),
               "base", (FB_C0[0], 0, FB_C0[1]), (0, 0, 0), Y,
               comment="cut joint: the rocker's ground pivot, closed back onto the root")
    return m


# ---------------------------------------------------------------------------------------------
# 3: slider-crank
# ---------------------------------------------------------------------------------------------


def slider_crank():
    r, l, e, psi_a = 0.08, 0.26, -0.02, -1.0
    a1 = along((0.0, 0.0), psi_a, r)
    bx = a1[0] + math.sqrt(l * l - (e - a1[1]) ** 2)
    b = (bx, e)
    psi_rod = ang(sub(b, a1))
    m = Model("slider_crank", (
        "  slider_crank: offset slider-crank in the x-z plane. Crank about +y on base; connecting rod about\n"
        "  +y on the crank; slider prismatic along x on base (rail at z = -0.02); the loop is the revolute\n"
        "  pin between the rod end (predecessor) and the slider (successor). Spanning joints in depth-first\n"
        "  order: crank_joint (independent), rod_joint (dependent), slider_joint (dependent). 1 DoF.\n"
    ))
    m.link("base", comment="ground (fixed root)")
    m.link("crank", mass=0.5, com=(0.03, 0, 0), inertia=(6e-5, 3.2e-4, 3.4e-4, 1e-6, -2e-6, 0))
    m.link("rod", mass=0.3, com=(0.12, 0, 0.002), inertia=(5e-5, 1.70e-3, 1.71e-3, 0, 3e-6, 0))
    m.link("slider", mass=1.0, com=(0, 0, 0.01), inertia=(2.7e-4, 4.3e-4, 4.4e-4, 0, 1e-5, 0))
    m.joint("crank_joint", "revolute", "base", "crank", (0, 0, 0), (0, psi_a, 0), Y, independent=True)
    m.joint("rod_joint", "revolute", "crank", "rod", (r, 0, 0), (0, psi_rod - psi_a, 0), Y, independent=False)
    m.joint("slider_joint", "prismatic", "base", "slider", (bx, 0, e), (0, 0, 0), (1, 0, 0), independent=False)
    m.loop("rod_slider_pin", "revolute", "rod", (l, 0, 0), (0, -psi_rod, 0), "slider", (0, 0, 0), (0, 0, 0), Y)
    return m


# ---------------------------------------------------------------------------------------------
# 4: two-stage geared arm
# ---------------------------------------------------------------------------------------------

ROTOR_Y = dict(mass=0.2, com=(0, 0, 0), inertia=(5.2e-5, 9e-5, 5.2e-5, 0, 0, 0))


def geared_motor():
    m = Model("geared_motor", (
        "  geared_motor: a 2-DoF pitch-pitch arm, each joint driven through a spur gear by a motor whose\n"
        "  rotor sits on the joint's parent link (a sibling of the driven link). Couplings:\n"
        "  shoulder_rotor = 9 * shoulder, elbow_rotor = 6 * elbow. The housing is fixed to base (merged).\n"
        "  Spanning joints in depth-first order (siblings in file order): shoulder, elbow, elbow_rotor_joint,\n"
        "  shoulder_rotor_joint; the two rotor joints are dependent. 2 DoF, 4 spanning joints.\n"
    ))
    m.link("base", comment="fixed root, frame only")
    m.link("housing", mass=1.5, com=(0, 0, -0.04), inertia=(2.6e-3, 2.4e-3, 1.9e-3, 0, 1e-4, 0))
    m.joint("housing_mount", "fixed", "base", "housing", (0, 0, 0.3))
    m.link("upper_arm", mass=1.0, com=(0.15, 0.004, 0.003),
           inertia=(4.2e-4, 7.7e-3, 7.75e-3, 1.5e-5, -2e-5, 3e-6))
    m.link("shoulder_rotor", **ROTOR_Y)
    m.link("forearm", mass=0.6, com=(0.12, 0.002, 0), inertia=(1.6e-4, 3.2e-3, 3.21e-3, 4e-6, 6e-6, -1e-6))
    m.link("elbow_rotor", **ROTOR_Y)
    m.joint("shoulder", "revolute", "housing", "upper_arm", (0, 0, 0), (0, -0.3, 0), Y, independent=True)
    m.joint("shoulder_rotor_joint", "revolute", "housing", "shoulder_rotor", (-0.04, 0, -0.05), (0, 0, 0), Y,
            independent=False)
    m.coupling("shoulder_gear", "upper_arm", "shoulder_rotor", 9.0,
               comment="rotor = 9 * shoulder (nearest common ancestor: housing)")
    m.joint("elbow", "revolute", "upper_arm", "forearm", (0.3, 0, 0), (0, 0.9, 0), Y, independent=True)
    m.joint("elbow_rotor_joint", "revolute", "upper_arm", "elbow_rotor", (0.22, 0, 0.03), (0, 0, 0), Y,
            independent=False)
    m.coupling("elbow_gear", "forearm", "elbow_rotor", 6.0,
               comment="rotor = 6 * elbow (nearest common ancestor: upper_arm)")
    return m


# ---------------------------------------------------------------------------------------------
# 6: bevel-gear differential wrist
# ---------------------------------------------------------------------------------------------

ROTOR_X = dict(mass=0.1, com=(0, 0, 0), inertia=(1.1e-5, 1.3e-5, 1.3e-5, 0, 0, 0))


def differential_wrist():
    r = 4.0
    m = Model("differential_wrist", (
        "  differential_wrist: an elbow (about +y) carries the forearm, which holds two motor rotors (axes\n"
        "  along the forearm, x) driving a bevel-gear differential: wrist_pitch (about y) then wrist_roll\n"
        "  (about x). Each rotor joint mimics both wrist joints (one <mimic> per driver):\n"
        "  rotor1 = 4 pitch + 4 roll, rotor2 = 4 pitch - 4 roll (i.e. pitch = (m1 + m2) / 8,\n"
        "  roll = (m1 - m2) / 8). Spanning joints in depth-first order: elbow, rotor1_joint, rotor2_joint,\n"
        "  wrist_pitch, wrist_roll; the rotors are dependent. 3 DoF (elbow, wrist_pitch, wrist_roll).\n"
    ))
    m.link("base", comment="fixed root, frame only")
    m.link("forearm", mass=1.2, com=(0.12, 0, -0.005), inertia=(9.8e-4, 6.7e-3, 6.75e-3, 1e-5, -3e-5, 2e-6))
    m.link("rotor1", **ROTOR_X)
    m.link("rotor2", **ROTOR_X)
    m.link("pitch_link", mass=0.15, com=(0.01, 0, 0), inertia=(6e-5, 4e-5, 5e-5, 0, 1e-6, 0),
           comment="differential carrier")
    m.link("roll_link", mass=0.35, com=(0.05, 0.003, -0.004),
           inertia=(2.2e-4, 3.5e-4, 3.0e-4, 2e-6, -8e-6, 1e-6), comment="output flange")
    m.joint("elbow", "revolute", "base", "forearm", (0, 0, 0), (0, -0.4, 0), Y)
    m.joint("rotor1_joint", "revolute", "forearm", "rotor1", (0.08, 0.025, 0), (0, 0, 0), (1, 0, 0),
            independent=False, mimics=[("wrist_pitch", r, 0.0), ("wrist_roll", r, 0.0)])
    m.joint("rotor2_joint", "revolute", "forearm", "rotor2", (0.08, -0.025, 0), (0, 0, 0), (1, 0, 0),
            independent=False, mimics=[("wrist_pitch", r, 0.0), ("wrist_roll", -r, 0.0)])
    m.joint("wrist_pitch", "revolute", "forearm", "pitch_link", (0.25, 0, 0), (0, 0.5, 0), Y, independent=True)
    m.joint("wrist_roll", "revolute", "pitch_link", "roll_link", (0.03, 0, 0), (0, 0, 0), (1, 0, 0),
            independent=True)
    return m


# ---------------------------------------------------------------------------------------------
# 7: Watt-II six-bar (two four-bars in series sharing the ternary link "ternary")
# ---------------------------------------------------------------------------------------------

SB_OA, SB_OC, SB_OE = (0.0, 0.0), (0.28, 0.02), (0.55, -0.03)
SB_LA, SB_LB, SB_LCP, SB_LD, SB_LE = 0.10, 0.30, 0.20, 0.30, 0.20
SB_Q_LOCAL = (0.16, 0.09)  # third pin of the ternary link, (x, z) in its frame
SB_PSI_A = -1.2


def six_bar_geometry():
    a1 = along(SB_OA, SB_PSI_A, SB_LA)
    p, _ = circles(a1, SB_LB, SB_OC, SB_LCP)  # coupler-ternary pin, upper branch
    psi_b = ang(sub(p, a1))
    psi_c = ang(sub(p, SB_OC))
    c, s = math.cos(psi_c), math.sin(psi_c)
    qx, qz = SB_Q_LOCAL
    q = (SB_OC[0] + qx * c + qz * s, SB_OC[1] - qx * s + qz * c)  # ternary-link2 pin in base
    _, rr = circles(q, SB_LD, SB_OE, SB_LE)  # link2-output pin, the branch right of q -> OE
    psi_d = ang(sub(rr, q))
    psi_e = ang(sub(rr, SB_OE))
    return dict(a1=a1, p=p, q=q, r=rr, psi_b=psi_b, psi_c=psi_c, psi_d=psi_d, psi_e=psi_e)


def six_bar():
    g = six_bar_geometry()
    qx, qz = SB_Q_LOCAL
    m = Model("six_bar", (
        "  six_bar: planar Watt-II six-bar (x-z plane, axes +y): two four-bars in series. Ground pivots\n"
        "  (x, z) = (0, 0), (0.28, 0.02), (0.55, -0.03). Loop 1: crank, coupler, ternary link (pivoted on the\n"
        "  ground); loop 2: ternary link, link2, output rocker. 7 revolute pairs: 5 spanning joints + 2 cut\n"
        "  joints; both loops contain the ternary link's joint, so they form one group of 5 bodies with 4\n"
        "  constraints. Spanning joints in depth-first order: crank_joint (independent), coupler_joint,\n"
        "  ternary_joint, link2_joint, output_joint (the last four dependent). 1 DoF.\n"
    ))
    m.link("base", comment="ground (fixed root)")
    m.link("crank", mass=0.3, com=(0.05, 0, 0), inertia=(2.5e-5, 2.7e-4, 2.8e-4, 0, 1e-6, 0))
    m.link("coupler", mass=0.5, com=(0.15, 0, 0.003), inertia=(1.0e-4, 3.8e-3, 3.82e-3, 1e-6, 4e-6, 0))
    cx, cz = (SB_LCP + qx) / 3.0, qz / 3.0
    m.link("ternary", mass=0.8, com=(cx, 0.0, cz), inertia=(5e-4, 1.9e-3, 1.45e-3, 0, -1.5e-4, 0),
           comment="ternary link: pins at (0, 0) [ground], (0.20, 0) [coupler], (%s, %s) [link2]; com = centroid"
           % (fmt(qx), fmt(qz)))
    m.link("link2", mass=0.5, com=(0.15, 0.001, 0), inertia=(1.0e-4, 3.8e-3, 3.82e-3, 0, -2e-6, 1e-6))
    m.link("output", mass=0.4, com=(0.1, 0, -0.002), inertia=(4e-5, 1.35e-3, 1.37e-3, 0, 2e-6, 0))
    m.joint("crank_joint", "revolute", "base", "crank", (SB_OA[0], 0, SB_OA[1]), (0, SB_PSI_A, 0), Y,
            independent=True)
    m.joint("coupler_joint", "revolute", "crank", "coupler", (SB_LA, 0, 0), (0, g["psi_b"] - SB_PSI_A, 0), Y,
            independent=False)
    m.joint("ternary_joint", "revolute", "base", "ternary", (SB_OC[0], 0, SB_OC[1]), (0, g["psi_c"], 0), Y,
            independent=False)
    m.joint("link2_joint", "revolute", "ternary", "link2", (qx, 0, qz), (0, g["psi_d"] - g["psi_c"], 0), Y,
            independent=False)
    m.joint("output_joint", "revolute", "base", "output", (SB_OE[0], 0, SB_OE[1]), (0, g["psi_e"], 0), Y,
            independent=False)
    m.loop("loop1", "revolute", "coupler", (SB_LB, 0, 0), (0, -g["psi_b"], 0),
           "ternary", (SB_LCP, 0, 0), (0, -g["psi_c"], 0), Y, comment="coupler end = ternary pin")
    m.loop("loop2", "revolute", "link2", (SB_LD, 0, 0), (0, -g["psi_d"], 0),
           "output", (SB_LE, 0, 0), (0, -g["psi_e"], 0), Y, comment="link2 end = output rocker end")
    return m


# ---------------------------------------------------------------------------------------------
# 8: parallel gripper
# ---------------------------------------------------------------------------------------------


def parallel_gripper():
    m = Model("parallel_gripper", (
        "  parallel_gripper: a hand on a wrist joint (about x) with two prismatic fingers. The finger axes\n"
        "  are mirrored (+y and -y), so finger2_joint mimics finger1_joint with multiplier 1 (offset 0): both\n"
        "  fingers open together. Spanning joints in depth-first order: wrist, finger1_joint,\n"
        "  finger2_joint (dependent). 2 DoF.\n"
    ))
    m.link("base", comment="fixed root, frame only")
    m.link("hand", mass=0.4, com=(0, 0, -0.05), inertia=(6e-4, 3e-4, 4.5e-4, 0, 0, 1e-5))
    m.link("finger1", mass=0.05, com=(0, -0.003, -0.02), inertia=(8.3e-6, 7.1e-6, 2.1e-6, 0, 0, 0))
    m.link("finger2", mass=0.05, com=(0, 0.003, -0.02), inertia=(8.3e-6, 7.1e-6, 2.1e-6, 0, 0, 0))
    m.joint("wrist", "revolute", "base", "hand", (0, 0, 0), (0.2, 0, 0), (1, 0, 0))
    m.joint("finger1_joint", "prismatic", "hand", "finger1", (0, 0.02, -0.1), (0, 0, 0), (0, 1, 0), independent=True)
    m.joint("finger2_joint", "prismatic", "hand", "finger2", (0, -0.02, -0.1), (0, 0, 0), (0, -1, 0),
            independent=False, mimics=[("finger1_joint", 1.0, 0.0)])
    return m


# ---------------------------------------------------------------------------------------------
# 9: floating-base biped with four-bar knees and geared hip-pitch rotors
# ---------------------------------------------------------------------------------------------

KN_THIGH = 0.35
KN_C0 = (-0.02, -0.07)  # knee crank pivot (x, z) in the thigh frame
KN_LCRANK = 0.05
KN_PSI_CRANK = 2.8  # crank points backwards and slightly down at q = 0
KN_LEVER = (-0.045, 0.02)  # rod pin on the shank, (x, z) in the shank frame (at the knee)


def knee_geometry():
    p = along(KN_C0, KN_PSI_CRANK, KN_LCRANK)  # crank tip in thigh frame
    qpt = (KN_LEVER[0], -KN_THIGH + KN_LEVER[1])  # lever tip in thigh frame (shank frame = thigh - 0.35 z)
    d = sub(qpt, p)
    return p, qpt, norm(d), ang(d)


def biped_floating():
    _p, _q, lrod, psi_rod = knee_geometry()
    m = Model("biped_floating", (
        "  biped_floating: a floating-base biped. A floating joint from the massless link world to pelvis;\n"
        "  per leg (left, then right; the right leg mirrors the left through the x-z plane): hip_yaw (z),\n"
        "  hip_roll (x), hip_pitch (y) driven by a geared rotor on the hip-roll link (coupling ratio 6),\n"
        "  a knee driven by a four-bar (thigh = ground, knee crank, rod, shank; loop between the rod end and\n"
        "  a lever on the shank), and an ankle pitch (y). Independent per leg: hip_yaw, hip_roll, hip_pitch,\n"
        "  knee_crank_joint, ankle; dependent: hip_pitch_rotor_joint, knee_rod_joint, knee.\n"
        "  Spanning joints in depth-first order: floating_base, then per leg (l_, then r_) hip_yaw,\n"
        "  hip_roll, hip_pitch_rotor_joint, hip_pitch, knee_crank_joint, knee_rod_joint, knee, ankle.\n"
        "  nq = 7 + 16, nv = 6 + 16, independent nv = 6 + 10. Total mass 19.9 kg.\n"
    ))
    m.link("world", comment="world frame: no inertial")
    m.link("pelvis", mass=8.0, com=(0, 0, 0.05), inertia=(0.075, 0.042, 0.087, 2e-4, 1e-3, -1e-4))
    m.joint("floating_base", "floating", "world", "pelvis")
    bodies = [
        ("hip_yaw_link", 0.8, (0, 0, -0.04), (1.2e-3, 1.0e-3, 6e-4, 0, 5e-5, 0)),
        ("hip_roll_link", 1.0, (0, 0.01, -0.03), (1.5e-3, 1.3e-3, 1.1e-3, 1e-5, 4e-5, 2e-5)),
        ("hip_pitch_rotor", 0.2, (0, 0, 0), (5.2e-5, 9e-5, 5.2e-5, 0, 0, 0)),
        ("thigh", 2.0, (0.005, 0.01, -0.15), (0.0215, 0.0212, 2.2e-3, 5e-5, 4e-4, 3e-4)),
        ("knee_crank", 0.15, (0.025, 0, 0), (1.2e-5, 4.2e-5, 4.0e-5, 0, 0, 0)),
        ("knee_rod", 0.1, (lrod / 2.0, 0, 0), (1.2e-5, 5.0e-4, 5.0e-4, 0, 0, 0)),
        ("shank", 1.2, (0.005, 0, -0.16), (0.0125, 0.0124, 9e-4, 0, 2e-4, 1e-5)),
        ("foot", 0.5, (0.03, 0, -0.03), (3.3e-4, 1.73e-3, 1.93e-3, 0, 1e-4, 0)),
    ]
    for side, sy in (("l", 1.0), ("r", -1.0)):
        for (n, mass, com, inertia) in bodies:
            if sy < 0:
                com, inertia = mirror_y(com, inertia)
            m.link("%s_%s" % (side, n), mass=mass, com=com, inertia=inertia)
        s = side + "_"
        m.joint(s + "hip_yaw", "revolute", "pelvis", s + "hip_yaw_link", (0, sy * 0.1, -0.05), (0, 0, 0), (0, 0, 1))
        m.joint(s + "hip_roll", "revolute", s + "hip_yaw_link", s + "hip_roll_link", (0, 0, -0.08), (0, 0, 0),
                (1, 0, 0))
        m.joint(s + "hip_pitch_rotor_joint", "revolute", s + "hip_roll_link", s + "hip_pitch_rotor",
                (-0.03, sy * 0.05, 0), (0, 0, 0), Y, independent=False)
        m.joint(s + "hip_pitch", "revolute", s + "hip_roll_link", s + "thigh", (0, 0, -0.05), (0, 0, 0), Y,
                independent=True)
        m.coupling(s + "hip_pitch_gear", s + "thigh", s + "hip_pitch_rotor", 6.0,
                   comment="rotor = 6 * hip_pitch (nearest common ancestor: hip_roll_link)")
        m.joint(s + "knee_crank_joint", "revolute", s + "thigh", s + "knee_crank", (KN_C0[0], 0, KN_C0[1]),
                (0, KN_PSI_CRANK, 0), Y, independent=True)
        m.joint(s + "knee_rod_joint", "revolute", s + "knee_crank", s + "knee_rod", (KN_LCRANK, 0, 0),
                (0, psi_rod - KN_PSI_CRANK, 0), Y, independent=False)
        m.joint(s + "knee", "revolute", s + "thigh", s + "shank", (0, 0, -KN_THIGH), (0, 0, 0), Y,
                independent=False)
        m.joint(s + "ankle", "revolute", s + "shank", s + "foot", (0, 0, -0.35), (0, 0, 0), Y)
        m.loop(s + "knee_linkage", "revolute", s + "knee_rod", (lrod, 0, 0), (0, -psi_rod, 0),
               s + "shank", (KN_LEVER[0], 0, KN_LEVER[1]), (0, 0, 0), Y,
               comment="rod end = shank lever pin; cut frames aligned with the thigh at q = 0")
    return m


# ---------------------------------------------------------------------------------------------
# 10: parallelogram four-bar (passes through toggle configurations)
# ---------------------------------------------------------------------------------------------

PG_GROUND, PG_CRANK = 0.30, 0.15
PG_PSI = -math.pi / 3.0  # crank and rocker 60 degrees above +x at q = 0


def singular_four_bar():
    m = Model("singular_four_bar", (
        "  singular_four_bar: a parallelogram four-bar (crank = rocker = 0.15 m, coupler = ground = 0.30 m)\n"
        "  in the x-z plane, axes +y; loop cut at the coupler-rocker pin (successor rocker). At q = 0 the\n"
        "  crank stands 60 degrees above +x (a regular configuration). On the parallelogram branch\n"
        "  (q_coupler = -q_crank, q_rocker = q_crank) all four links become collinear - a toggle where\n"
        "  the dependent columns of the constraint Jacobian lose rank - at q_crank = pi/3 and -2 pi/3.\n"
        "  Spanning joints in depth-first order: crank_joint (independent), coupler_joint, rocker_joint\n"
        "  (dependent). 1 DoF.\n"
    ))
    m.link("base", comment="ground (fixed root); pivots at x-z (0, 0) and (0.30, 0)")
    m.link("crank", mass=0.3, com=(0.075, 0, 0), inertia=(3e-5, 5.7e-4, 5.8e-4, 1e-6, 0, 0))
    m.link("coupler", mass=0.6, com=(0.15, 0, 0.002), inertia=(1.2e-4, 4.52e-3, 4.53e-3, 0, 2e-6, 0))
    m.link("rocker", mass=0.35, com=(0.075, 0, 0), inertia=(3.5e-5, 6.7e-4, 6.8e-4, 0, 0, 1e-6))
    m.joint("crank_joint", "revolute", "base", "crank", (0, 0, 0), (0, PG_PSI, 0), Y, independent=True)
    m.joint("coupler_joint", "revolute", "crank", "coupler", (PG_CRANK, 0, 0), (0, -PG_PSI, 0), Y,
            independent=False)
    m.joint("rocker_joint", "revolute", "base", "rocker", (PG_GROUND, 0, 0), (0, PG_PSI, 0), Y,
            independent=False)
    m.loop("coupler_rocker_pin", "revolute", "coupler", (PG_GROUND, 0, 0), (0, 0, 0),
           "rocker", (PG_CRANK, 0, 0), (0, -PG_PSI, 0), Y)
    return m


# ---------------------------------------------------------------------------------------------
# 11: floating-base quadruped whose knees are driven through four-bar linkages
# ---------------------------------------------------------------------------------------------
# Each leg is drawn in the x-z plane of its thigh frame: the thigh frame sits on the hip-flexion axis
# with x along the thigh (towards the knee); at q = 0 the thigh points down and back (psi 2.4, 0.83 rad
# behind the vertical) and the shank down and forward (knee at -1.6 relative to the thigh, shank psi
# 0.8), so the foot is 8.5 mm behind the hip and 0.292 m below it. The knee four-bar has the thigh as
# ground: a crank pivoting near the hip, a rod along the back of the thigh, and a lever on the shank
# behind the knee. Crank 0.035 m and lever 0.04 m are nearly parallel at q = 0 (close to, but not, a
# parallelogram), so the knee follows the crank with a ratio near 0.9 and both transmission angles are
# near 90 degrees.

QK_HIP_X, QK_HIP_Y = 0.19, 0.05  # hip-abduction axes on the trunk at (+-0.19, +-0.05, 0)
QK_HIP_LINK_Y = 0.08  # hip-flexion axis offset (outwards) on the hip link
QK_THIGH, QK_SHANK = 0.21, 0.21
QK_PSI_THIGH = 2.4  # thigh x axis in the hip-link frame at q = 0: down and back
QK_KNEE0 = -1.6  # shank frame relative to the thigh frame at q = 0 (a bent knee)
QK_C0 = (0.03, -0.005)  # knee crank pivot (x, z) in the thigh frame
QK_LCRANK = 0.035
QK_PSI_CRANK = 1.5  # crank direction in the thigh frame at q = 0: towards the back of the thigh
QK_LEVER = (-0.04, 0.004)  # rod pin on the shank, (x, z) in the shank frame (behind the knee)


def quadruped_knee_geometry():
    p = along(QK_C0, QK_PSI_CRANK, QK_LCRANK)  # crank tip in the thigh frame
    c, s = math.cos(QK_KNEE0), math.sin(QK_KNEE0)
    lx, lz = QK_LEVER
    qpt = (QK_THIGH + lx * c + lz * s, -lx * s + lz * c)  # lever pin in the thigh frame
    d = sub(qpt, p)
    return p, qpt, norm(d), ang(d)


def quadruped_loop_knees():
    _p, _q, lrod, psi_rod = quadruped_knee_geometry()
    psi_shank = QK_PSI_THIGH + QK_KNEE0
    m = Model("quadruped_loop_knees", (
        "  quadruped_loop_knees: a floating-base quadruped whose knees are driven through four-bar\n"
        "  linkages. A floating joint from the massless link world to trunk; legs FL, FR, HL, HR (the right\n"
        "  legs mirror the left ones through the x-z plane), each: hip_abduction (x), hip_flexion (y), and a\n"
        "  knee four-bar with the thigh as ground: knee_crank_joint (y, on the thigh near the hip; the\n"
        "  actuated input), knee_rod_joint, and the shank's knee joint, closed by the loop knee_linkage\n"
        "  between the rod end and a lever on the shank behind the knee. The foot (the contact point) is\n"
        "  fixed to the shank tip, its frame aligned with the trunk at q = 0. At q = 0 the legs stand with\n"
        "  bent knees: each foot is 0.292 m below its hip. Independent per leg: hip_abduction, hip_flexion,\n"
        "  knee_crank_joint; dependent: knee_rod_joint, knee.\n"
        "  Spanning joints in depth-first order: floating_base, then per leg (FL_, FR_, HL_, HR_)\n"
        "  hip_abduction, hip_flexion, knee_crank_joint, knee_rod_joint, knee.\n"
        "  nq = 7 + 20, nv = 6 + 20, independent nv = 6 + 12. Total mass 12 kg.\n"
    ))
    m.link("world", comment="world frame: no inertial")
    m.link("trunk", mass=6.0, com=(0.01, 0.001, -0.005), inertia=(0.0215, 0.07, 0.081, 1e-4, 8e-4, -5e-5))
    m.joint("floating_base", "floating", "world", "trunk")
    bodies = [
        ("hip", 0.45, (0.004, 0.045, 0), (2.9e-4, 4.1e-4, 3.3e-4, -5e-6, 2e-6, 3e-6)),
        ("thigh", 0.6, (0.055, -0.015, 0.004), (4.1e-4, 2.3e-3, 2.24e-3, 1e-5, 6e-5, -8e-6)),
        ("knee_crank", 0.05, (0.012, 0, 0), (3e-6, 9e-6, 8e-6, 0, 1e-7, 0)),
        ("knee_rod", 0.04, (lrod / 2.0, 0, 0), (6e-6, 1.5e-4, 1.5e-4, 0, 0, 0)),
        ("shank", 0.3, (0.08, 0, 0.002), (1.2e-4, 1.3e-3, 1.28e-3, 2e-6, -3e-5, 1e-6)),
        ("foot", 0.06, (0, 0, 0), (9.6e-6, 9.5e-6, 9.7e-6, 0, 0, 0)),
    ]
    for leg, sx, sy in (("FL", 1.0, 1.0), ("FR", 1.0, -1.0), ("HL", -1.0, 1.0), ("HR", -1.0, -1.0)):
        s = leg + "_"
        for (n, mass, com, inertia) in bodies:
            if sy < 0:
                com, inertia = mirror_y(com, inertia)
            m.link(s + n, mass=mass, com=com, inertia=inertia)
        m.joint(s + "hip_abduction", "revolute", "trunk", s + "hip", (sx * QK_HIP_X, sy * QK_HIP_Y, 0), (0, 0, 0),
                (1, 0, 0))
        m.joint(s + "hip_flexion", "revolute", s + "hip", s + "thigh", (0, sy * QK_HIP_LINK_Y, 0),
                (0, QK_PSI_THIGH, 0), Y)
        m.joint(s + "knee_crank_joint", "revolute", s + "thigh", s + "knee_crank", (QK_C0[0], 0, QK_C0[1]),
                (0, QK_PSI_CRANK, 0), Y, independent=True)
        m.joint(s + "knee_rod_joint", "revolute", s + "knee_crank", s + "knee_rod", (QK_LCRANK, 0, 0),
                (0, psi_rod - QK_PSI_CRANK, 0), Y, independent=False)
        m.joint(s + "knee", "revolute", s + "thigh", s + "shank", (QK_THIGH, 0, 0), (0, QK_KNEE0, 0), Y,
                independent=False)
        m.joint(s + "foot_joint", "fixed", s + "shank", s + "foot", (QK_SHANK, 0, 0), (0, -psi_shank, 0),
                comment="contact point at the shank tip; foot frame aligned with the trunk at q = 0")
        m.loop(s + "knee_linkage", "revolute", s + "knee_rod", (lrod, 0, 0), (0, -psi_rod, 0),
               s + "shank", (QK_LEVER[0], 0, QK_LEVER[1]), (0, -QK_KNEE0, 0), Y,
               comment="rod end = shank lever pin; cut frames aligned with the thigh at q = 0")
    return m


MODELS = [
    ("four_bar_internal.urdf", lambda: four_bar(False)),
    ("four_bar_terminal.urdf", lambda: four_bar(True)),
    ("slider_crank.urdf", slider_crank),
    ("geared_motor.urdf", geared_motor),
    ("differential_wrist.urdf", differential_wrist),
    ("six_bar.urdf", six_bar),
    ("parallel_gripper.urdf", parallel_gripper),
    ("biped_floating.urdf", biped_floating),
    ("singular_four_bar.urdf", singular_four_bar),
    ("quadruped_loop_knees.urdf", quadruped_loop_knees),
]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    for fname, make in MODELS:
        make().write(os.path.join(out, fname))
        print("wrote", fname)


if __name__ == "__main__":
    main()
