"""Small deterministic URDF / URDF+ writer shared by gen_models.py and gen_rotor_chain.py.

Part of embedyn's test models. Original to this project. Licence: MIT OR Apache-2.0.
Standard library only.
"""

import math

HEADER_LICENCE = (
    "  Part of embedyn's closed-loop test models (models/loops). Original to this project: all\n"
    "  dimensions, masses and inertias are invented, merely realistic in magnitude.\n"
    "  Licence: MIT OR Apache-2.0, same as embedyn.\n"
)


def fmt(x):
    """Exact decimal text of a float: the short form when it round-trips in <= 10 characters
    (round design numbers such as 0.12), else 17 significant digits."""
    x = float(x)
    if x == 0.0:
        return "0"
    s = repr(x)
    if len(s) <= 10 and float(s) == x:
        if s.endswith(".0"):
            s = s[:-2]
        return s
    s = "%.17g" % x
    assert float(s) == x
    return s


def vec(v):
    return " ".join(fmt(c) for c in v)


# ---------------------------------------------------------------------------------------------
# planar helpers: mechanisms drawn in the x-z plane of a frame, joint axes along +y.
# A rotation by psi about +y maps the x axis to (cos psi, 0, -sin psi); so a link frame whose x
# axis points along the planar direction (dx, dz) has psi = atan2(-dz, dx).
# ---------------------------------------------------------------------------------------------


def ang(d):
    return math.atan2(-d[1], d[0])


def along(p, psi, length):
    return (p[0] + length * math.cos(psi), p[1] - length * math.sin(psi))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1])


def norm(d):
    return math.hypot(d[0], d[1])


def circles(c1, r1, c2, r2):
    """Both intersections of circle(c1, r1) and circle(c2, r2); first = left of c1->c2
    (positive z side when c1->c2 points along +x)."""
    d = sub(c2, c1)
    L = norm(d)
    a = (r1 * r1 - r2 * r2 + L * L) / (2.0 * L)
    h2 = r1 * r1 - a * a
    assert h2 > 0.0, "circles do not intersect"
    h = math.sqrt(h2)
    ux, uz = d[0] / L, d[1] / L
    mx, mz = c1[0] + a * ux, c1[1] + a * uz
    left = (mx - h * uz, mz + h * ux)
    right = (mx + h * uz, mz - h * ux)
    return left, right


def to_local(p, origin, psi):
    """Planar point p (x, z) in the frame at `origin` rotated by psi about +y -> (x, z) local."""
    d = sub(p, origin)
    c, s = math.cos(psi), math.sin(psi)
    # R = Ry(psi): local x axis = (c, -s) in (x, z); local z axis = (s, c).
    return (d[0] * c - d[1] * s, d[0] * s + d[1] * c)


# ---------------------------------------------------------------------------------------------


class Model:
    def __init__(self, name, comment):
        self.name = name
        self.comment = comment.rstrip("\n") + "\n"
        self.items = []

    def raw(self, text):
        self.items.append(text)

    def link(self, name, mass=None, com=(0, 0, 0), inertia=None, comment=None):
        out = []
        if comment:
            out.append("  <!-- %s -->" % comment)
        if mass is None:
            out.append('  <link name="%s"/>' % name)
        else:
            ixx, iyy, izz, ixy, ixz, iyz = inertia
            out.append('  <link name="%s">' % name)
            out.append("    <inertial>")
            out.append('      <origin xyz="%s" rpy="0 0 0"/>' % vec(com))
            out.append('      <mass value="%s"/>' % fmt(mass))
            out.append(
                '      <inertia ixx="%s" ixy="%s" ixz="%s" iyy="%s" iyz="%s" izz="%s"/>'
                % (fmt(ixx), fmt(ixy), fmt(ixz), fmt(iyy), fmt(iyz), fmt(izz))
            )
            out.append("    </inertial>")
            out.append("  </link>")
        self.items.append("\n".join(out))

    def joint(self, name, jtype, parent, child, xyz=(0, 0, 0), rpy=(0, 0, 0), axis=None,
              independent=None, mimics=(), comment=None):
        out = []
        if comment:
            out.append("  <!-- %s -->" % comment)
        attrs = 'name="%s" type="%s"' % (name, jtype)
        if independent is not None:
            attrs += ' independent="%s"' % ("true" if independent else "false")
        out.append("  <joint %s>" % attrs)
        out.append('    <origin xyz="%s" rpy="%s"/>' % (vec(xyz), vec(rpy)))
        out.append('    <parent link="%s"/>' % parent)
        out.append('    <child link="%s"/>' % child)
        if axis is not None:
            out.append('    <axis xyz="%s"/>' % vec(axis))
        if jtype == "revolute":
            out.append('    <limit lower="-6.3" upper="6.3" effort="100" velocity="30"/>')
        elif jtype == "prismatic":
            out.append('    <limit lower="-1" upper="1" effort="200" velocity="2"/>')
        for (mj, mult, off) in mimics:
            out.append('    <mimic joint="%s" multiplier="%s" offset="%s"/>' % (mj, fmt(mult), fmt(off)))
        out.append("  </joint>")
        self.items.append("\n".join(out))

    def loop(self, name, ltype, pred, pred_xyz, pred_rpy, succ, succ_xyz, succ_rpy, axis=(0, 1, 0),
             comment=None):
        out = []
        if comment:
            out.append("  <!-- %s -->" % comment)
        out.append('  <loop name="%s" type="%s">' % (name, ltype))
        out.append('    <predecessor link="%s">' % pred)
        out.append('      <origin xyz="%s" rpy="%s"/>' % (vec(pred_xyz), vec(pred_rpy)))
        out.append("    </predecessor>")
        out.append('    <successor link="%s">' % succ)
        out.append('      <origin xyz="%s" rpy="%s"/>' % (vec(succ_xyz), vec(succ_rpy)))
        out.append("    </successor>")
        out.append('    <axis xyz="%s"/>' % vec(axis))
        out.append("  </loop>")
        self.items.append("\n".join(out))

    def coupling(self, name, pred, succ, ratio, comment=None):
        out = []
        if comment:
            out.append("  <!-- %s -->" % comment)
        out.append('  <coupling name="%s">' % name)
        out.append('    <predecessor link="%s"/>' % pred)
        out.append('    <successor link="%s"/>' % succ)
        out.append('    <ratio value="%s"/>' % fmt(ratio))
        out.append("  </coupling>")
        self.items.append("\n".join(out))

    def text(self):
        s = '<?xml version="1.0" encoding="utf-8"?>\n<!--\n'
        s += self.comment
        s += HEADER_LICENCE
        s += "  Generated by models/loops/%s; do not edit by hand.\n" % self.generator
        s += "-->\n"
        s += '<robot name="%s">\n' % self.name
        s += "\n".join(self.items) + "\n"
        s += "</robot>\n"
        return s

    generator = "gen_models.py"

    def write(self, path):
        with open(path, "w", encoding="utf-8", newline="\n") as f:
            f.write(self.text())
