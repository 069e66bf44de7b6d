#!/usr/bin/env python3
"""Checks the closed-loop models of models/loops: every loop closes at q = 0, every coupling and mimic
holds at q = 0, the velocity-constraint Jacobian has its generic rank at q = 0 and the declared dependent
joints form a regular partition there, the groups and DoF counts, and the inertias are valid.
Also checks the coordinate map between four_bar_internal and four_bar_terminal, and the toggle angle of
singular_four_bar. Deterministic; standard library + numpy. Exit code 1 on any failure.

Part of embedyn's test models. Original to this project. Licence: MIT OR Apache-2.0.

Usage: python3 check_closure.py [FILE.urdf ...]   (default: every *.urdf next to this script)

Conventions (URDF): joint origin = xyz then rpy, R = Rz(yaw) Ry(pitch) Rx(roll); child frame =
parent frame * origin * joint motion; a loop's axis is in the predecessor's cut frame (the frame of its
<origin>). Coupling: ratio * (sum of q on the path A -> predecessor) = (sum on A -> successor), A the
nearest common ancestor. Mimic: q = sum(multiplier_i q_i) + sum(offset_i).
"""

import glob
import math
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np

TOL_CLOSE = 1e-12
FAIL = []


def fail(msg):
    FAIL.append(msg)
    print("  FAIL:", msg)


def floats(s, n=3, default=0.0):
    if s is None:
        return np.full(n, default)
    v = np.array([float(t) for t in s.split()])
    assert v.shape == (n,), s
    return v


def rpy_matrix(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def axis_angle(a, q):
    a = a / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(q) * k + (1.0 - math.cos(q)) * (k @ k)


def origin_tf(el):
    o = el.find("origin") if el is not None else None
    if o is None:
        return np.eye(3), np.zeros(3)
    return rpy_matrix(floats(o.get("rpy"))), floats(o.get("xyz"))


def perp_basis(a):
    a = a / np.linalg.norm(a)
    t = np.array([1.0, 0, 0]) if abs(a[0]) < 0.9 else np.array([0, 1.0, 0])
    u = np.cross(a, t)
    u /= np.linalg.norm(u)
    return np.array([u, np.cross(a, u)])


class Joint:
    pass


class Model:
    def __init__(self, path):
        self.path = path
        root = ET.parse(path).getroot()
        self.name = root.get("name")
        self.links = {}
        for l in root.findall("link"):
            self.links[l.get("name")] = l
        self.joints = []
        self.joint_by_name = {}
        self.joint_of_child = {}
        for j in root.findall("joint"):
            J = Joint()
            J.name, J.type = j.get("name"), j.get("type")
            J.parent, J.child = j.find("parent").get("link"), j.find("child").get("link")
            J.R, J.p = origin_tf(j)
            ax = j.find("axis")
            J.axis = floats(ax.get("xyz")) if ax is not None else np.array([1.0, 0, 0])
            J.axis = J.axis / np.linalg.norm(J.axis)
            J.independent = j.get("independent")
            J.mimics = [(m.get("joint"), float(m.get("multiplier", "1")), float(m.get("offset", "0")))
                        for m in j.findall("mimic")]
            J.nv = {"revolute": 1, "continuous": 1, "prismatic": 1, "fixed": 0, "floating": 6}[J.type]
            self.joints.append(J)
            self.joint_by_name[J.name] = J
            self.joint_of_child[J.child] = J
        roots = [n for n in self.links if n not in self.joint_of_child]
        assert len(roots) == 1, roots
        self.root = roots[0]
        # depth-first order, siblings in file order
        children = {n: [] for n in self.links}
        for J in self.joints:
            children[J.parent].append(J)
        self.dfs = []

        def visit(link):
            for J in children[link]:
                self.dfs.append(J)
                visit(J.child)

        sys.setrecursionlimit(10000)
        visit(self.root)
        self.moving = [J for J in self.dfs if J.nv > 0]
        col = 0
        for J in self.moving:
            J.col = col
            col += J.nv
        self.nv = col
        self.loops = []
        for l in root.findall("loop"):
            pr, su = l.find("predecessor"), l.find("successor")
            L = dict(name=l.get("name"), type=l.get("type"), pred=pr.get("link"), succ=su.get("link"),
                     pred_tf=origin_tf(pr), succ_tf=origin_tf(su), axis=floats(l.find("axis").get("xyz")))
            L["axis"] = L["axis"] / np.linalg.norm(L["axis"])
            self.loops.append(L)
        self.couplings = []
        for c in root.findall("coupling"):
            r = c.find("ratio")
            self.couplings.append(dict(name=c.get("name"), pred=c.find("predecessor").get("link"),
                                       succ=c.find("successor").get("link"),
                                       ratio=float(r.get("value")) if r is not None else 1.0))

    # ---------- kinematics ----------
    def path_from_root(self, link):
        out = []
        while link in self.joint_of_child:
            J = self.joint_of_child[link]
            out.append(J)
            link = J.parent
        return out[::-1]

    def nca_paths(self, a, b):
        pa, pb = self.path_from_root(a), self.path_from_root(b)
        k = 0
        while k < len(pa) and k < len(pb) and pa[k] is pb[k]:
            k += 1
        return ([J for J in pa[k:] if J.nv > 0], [J for J in pb[k:] if J.nv > 0])

    def fk(self, q):
        """q: dict joint name -> value (missing = 0). Returns link -> (R, p) and joint -> (axis_w, origin_w)."""
        T = {self.root: (np.eye(3), np.zeros(3))}
        JW = {}
        for J in self.dfs:
            R0, p0 = T[J.parent]
            R = R0 @ J.R
            p = p0 + R0 @ J.p
            JW[J.name] = (R @ J.axis, p.copy(), R.copy())
            v = q.get(J.name, 0.0)
            if J.type in ("revolute", "continuous"):
                R = R @ axis_angle(J.axis, v)
            elif J.type == "prismatic":
                p = p + R @ J.axis * v
            elif J.type == "floating":
                assert np.all(np.asarray(v) == 0.0), "floating base only at identity here"
            T[J.child] = (R, p)
        return T, JW

    def cut_frames(self, L, T):
        Rp, pp = T[L["pred"]]
        Rs, ps = T[L["succ"]]
        Ro, po = L["pred_tf"]
        Rpc, ppc = Rp @ Ro, pp + Rp @ po
        Ro, po = L["succ_tf"]
        Rsc, psc = Rs @ Ro, ps + Rs @ po
        return Rpc, ppc, Rsc, psc

    def loop_residual(self, L, q):
        """Position-level residual, zero iff the cut joint is assembled (type-specific)."""
        T, _ = self.fk(q)
        Rpc, ppc, Rsc, psc = self.cut_frames(L, T)
        a = L["axis"]
        dp = Rpc.T @ (psc - ppc)
        Rrel = Rpc.T @ Rsc
        t = L["type"]
        if t in ("revolute", "continuous"):
            return np.concatenate([dp, np.cross(a, Rrel @ a)])
        if t == "prismatic":
            return np.concatenate([dp - a * (a @ dp), (Rrel - Rrel.T)[[2, 0, 1], [1, 2, 0]] / 2, [Rrel.trace() - 3]])
        if t == "spherical":
            return dp
        if t == "fixed":
            return np.concatenate([dp, (Rrel - Rrel.T)[[2, 0, 1], [1, 2, 0]] / 2, [Rrel.trace() - 3]])
        raise ValueError(t)

    def twist_columns(self, J, JW, T, point):
        """Spatial velocity (omega, v at `point`) of J's child per unit velocity of each of J's dofs."""
        a, o, R = JW[J.name]
        if J.type in ("revolute", "continuous"):
            return [(a, np.cross(a, point - o))]
        if J.type == "prismatic":
            return [(np.zeros(3), a)]
        if J.type == "floating":
            Rb, pb = T[J.child]
            cols = [(np.zeros(3), Rb[:, k]) for k in range(3)]
            cols += [(Rb[:, k], np.cross(Rb[:, k], point - pb)) for k in range(3)]
            return cols
        return []

    def loop_jacobian(self, L, q):
        """Velocity-constraint rows of a loop over all nv spanning velocities: the relative twist of the
        successor cut frame w.r.t. the predecessor cut frame, in the predecessor cut frame, restricted
        to the directions the cut joint locks."""
        T, JW = self.fk(q)
        Rpc, ppc, _, _ = self.cut_frames(L, T)
        W = np.zeros((6, self.nv))  # rows: omega (3), v (3), world frame
        for sign, link in ((+1.0, L["succ"]), (-1.0, L["pred"])):
            for J in self.path_from_root(link):
                for k, (w, v) in enumerate(self.twist_columns(J, JW, T, ppc)):
                    W[:3, J.col + k] += sign * w
                    W[3:, J.col + k] += sign * v
        Wl = np.vstack([Rpc.T @ W[:3], Rpc.T @ W[3:]])
        a = L["axis"]
        P = perp_basis(a)
        t = L["type"]
        if t in ("revolute", "continuous"):
            return np.vstack([Wl[3:], P @ Wl[:3]])  # 3 + 2 rows
        if t == "prismatic":
            return np.vstack([P @ Wl[3:], Wl[:3]])  # 2 + 3 rows
        if t == "spherical":
            return Wl[3:]
        if t == "fixed":
            return Wl
        raise ValueError(t)

    def coupling_row(self, C):
        pa, pb = self.nca_paths(C["pred"], C["succ"])
        row = np.zeros((1, self.nv))
        for J in pa:
            row[0, J.col] += C["ratio"]
        for J in pb:
            row[0, J.col] -= 1.0
        return row, pa + pb

    def mimic_rows(self):
        out = []
        for J in self.moving:
            if not J.mimics:
                continue
            row = np.zeros((1, self.nv))
            row[0, J.col] += 1.0
            js = [J]
            for (mj, mult, off) in J.mimics:
                D = self.joint_by_name[mj]
                row[0, D.col] -= mult
                js.append(D)
            out.append((J, row, js))
        return out

    def constraints(self, q):
        """List of (kind, name, rows, joints, residual) for every loop, coupling and mimic joint."""
        out = []
        for L in self.loops:
            pa, pb = self.nca_paths(L["pred"], L["succ"])
            out.append(("loop", L["name"], self.loop_jacobian(L, q), pa + pb, self.loop_residual(L, q), L))
        for C in self.couplings:
            row, js = self.coupling_row(C)
            pa, pb = self.nca_paths(C["pred"], C["succ"])
            res = C["ratio"] * sum(q.get(J.name, 0.0) for J in pa) - sum(q.get(J.name, 0.0) for J in pb)
            out.append(("coupling", C["name"], row, js, np.array([res]), C))
        for (J, row, js) in self.mimic_rows():
            res = q.get(J.name, 0.0) - sum(m * q.get(n, 0.0) + o for (n, m, o) in J.mimics)
            out.append(("mimic", J.name, row, js, np.array([res]), J))
        return out

    def dependent(self, J):
        return J.independent == "false" or bool(J.mimics)

    def solve(self, q, dep_names, iters=60):
        """Gauss-Newton on the dependent coordinates (loops only), starting from q; returns q."""
        q = dict(q)
        for _ in range(iters):
            r = np.concatenate([self.loop_residual(L, q) for L in self.loops])
            if np.max(np.abs(r)) < 1e-15:
                break
            Jm = np.zeros((len(r), len(dep_names)))
            h = 1e-7
            for k, n in enumerate(dep_names):
                qp, qm = dict(q), dict(q)
                qp[n] = q.get(n, 0.0) + h
                qm[n] = q.get(n, 0.0) - h
                Jm[:, k] = (np.concatenate([self.loop_residual(L, qp) for L in self.loops])
                            - np.concatenate([self.loop_residual(L, qm) for L in self.loops])) / (2 * h)
            dx = np.linalg.lstsq(Jm, -r, rcond=None)[0]
            for k, n in enumerate(dep_names):
                q[n] = q.get(n, 0.0) + dx[k]
        return q


def rank(M, tol=1e-9):
    if M.size == 0:
        return 0
    s = np.linalg.svd(M, compute_uv=False)
    return int(np.sum(s > tol * max(1.0, s[0])))


def check_inertias(m):
    worst = None
    total = 0.0
    for name, l in m.links.items():
        inert = l.find("inertial")
        if inert is None:
            continue
        mass = float(inert.find("mass").get("value"))
        total += mass
        i = inert.find("inertia")
        g = {k: float(i.get(k, "0")) for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
        I = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]], [g["ixz"], g["iyz"], g["izz"]]])
        ev = np.linalg.eigvalsh(I)
        if mass <= 0 or ev[0] <= 0:
            fail("%s: mass %g, inertia eigenvalues %s" % (name, mass, ev))
        margin = min(ev[0] + ev[1] - ev[2], ev[0] + ev[2] - ev[1], ev[1] + ev[2] - ev[0]) / ev[2]
        if margin < 0.01:
            fail("%s: triangle inequality margin %.4f < 1%%" % (name, margin))
        if worst is None or margin < worst[0]:
            worst = (margin, name)
    return total, worst


def report(path):
    m = Model(path)
    fname = os.path.basename(path)
    print("== %s (robot %s)" % (fname, m.name))
    total, worst = check_inertias(m)
    print("  total mass %.4g kg; inertias positive definite, smallest triangle-inequality margin %.1f%% (%s)"
          % (total, 100 * worst[0], worst[1]))
    names = []
    for J in m.moving:
        tag = "dep" if m.dependent(J) else "ind"
        names.append("%s[%s%s]" % (J.name, tag, "" if J.nv == 1 else ",nv=%d" % J.nv))
    if len(names) <= 40:
        print("  spanning joints (depth-first): " + ", ".join(names))
    else:
        print("  spanning joints (depth-first): " + ", ".join(names[:6]) + ", ... , " + ", ".join(names[-2:])
              + "  (%d joints)" % len(names))
    q0 = {}
    cons = m.constraints(q0)
    # groups: constraints sharing a joint merge
    parent = {}

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for c in cons:
        for J in c[3]:
            parent.setdefault(J.name, J.name)
        for J in c[3][1:]:
            parent[find(J.name)] = find(c[3][0].name)
    groups = {}
    for c in cons:
        groups.setdefault(find(c[3][0].name), []).append(c)
    # long listings (the rotor chains) print the first MAXLINES items and a summary of the rest
    MAXLINES = 4
    quiet_n, quiet_res = 0, 0.0
    for ci, c in enumerate(cons):
        kind, name, rows, js, res, obj = c
        quiet = len(cons) > 2 * MAXLINES and ci >= MAXLINES
        if kind == "loop":
            T, _ = m.fk(q0)
            Rpc, ppc, Rsc, psc = m.cut_frames(obj, T)
            dpos = np.linalg.norm(psc - ppc)
            drot = np.max(np.abs(Rpc - Rsc))
            tres = np.max(np.abs(res))
            line = ("  loop %-22s %-9s pred %-14s succ %-14s |p_s - p_p| = %.1e, max|R_p - R_s| = %.1e, "
                    "residual %.1e; velocity Jacobian %d rows x %d, rank %d"
                    % (name, obj["type"], obj["pred"], obj["succ"], dpos, drot, tres, rows.shape[0],
                       rows.shape[1], rank(rows)))
            if tres > TOL_CLOSE or dpos > TOL_CLOSE:
                fail("loop %s does not close at q = 0" % name)
            # cross-check the analytic velocity Jacobian against central differences of the position
            # residual over the 1-dof joints: both must span the same row space
            fd = np.zeros((len(res), m.nv))
            for J in js:
                if J.nv != 1:
                    continue
                qp, qm = {J.name: 1e-6}, {J.name: -1e-6}
                fd[:, J.col] = (m.loop_residual(obj, qp) - m.loop_residual(obj, qm)) / 2e-6
            if rank(np.vstack([rows, fd]), 1e-7) != rank(rows) or rank(fd, 1e-7) != rank(rows):
                fail("loop %s: analytic Jacobian disagrees with finite differences" % name)
        else:
            tres = abs(res[0])
            line = ("  %-8s %-22s joints {%s}: residual at q = 0 %.1e, rank %d"
                    % (kind, name, ", ".join(J.name for J in js), tres, rank(rows)))
            if tres > TOL_CLOSE:
                fail("%s %s violated at q = 0" % (kind, name))
        if quiet:
            quiet_n += 1
            quiet_res = max(quiet_res, tres)
        else:
            print(line)
    if quiet_n:
        print("  ... %d more constraints of the same kind, max residual at q = 0 %.1e" % (quiet_n, quiet_res))
    sum_rank = 0
    glist = sorted(groups.items(), key=lambda kv: min(J.col for c in kv[1] for J in c[3]))
    quiet_n = 0
    for gi, (key, cs) in enumerate(glist):
        js = sorted({J.name: J for c in cs for J in c[3]}.values(), key=lambda J: J.col)
        K = np.vstack([c[2] for c in cs])
        cols = [J.col for J in js]
        r = rank(K)
        r_group_cols = rank(K[:, cols])
        dep = [J for J in js if m.dependent(J)]
        Kd = K[:, [J.col for J in dep]]
        rd = rank(Kd)
        s = np.linalg.svd(Kd, compute_uv=False) if Kd.size else np.array([0.0])
        smin = s[min(len(s), Kd.shape[1]) - 1] if Kd.size else 0.0
        sum_rank += r
        line = ("  group %d: bodies {%s}; %d constraint%s (%s), %d rows, rank %d; dependent {%s}: rank %d, "
                "sigma_min %.3g, cond %.3g"
                % (gi + 1, ", ".join(J.child for J in js), len(cs), "" if len(cs) == 1 else "s",
                   ", ".join(c[1] for c in cs), K.shape[0], r, ", ".join(J.name for J in dep), rd, smin,
                   s[0] / smin if smin > 0 else float("inf")))
        if len(glist) > 2 * MAXLINES and gi >= MAXLINES:
            quiet_n += 1
        else:
            print(line)
        assert r == r_group_cols
        if len(dep) != r or rd != r:
            fail("group %d: %d dependent joints, constraint rank %d, rank of dependent columns %d"
                 % (gi + 1, len(dep), r, rd))
    if quiet_n:
        print("  ... %d more groups of the same kind (all checked)" % quiet_n)
    n_dep = sum(1 for J in m.moving if m.dependent(J) and any(J in c[3] for c in cons))
    print("  nv (spanning) = %d, constraint rank = %d, declared dependent = %d -> independent DoF = %d"
          % (m.nv, sum_rank, n_dep, m.nv - sum_rank))
    if n_dep != sum_rank:
        fail("declared dependent %d != rank %d" % (n_dep, sum_rank))
    return m


def check_four_bar_map(dirname):
    """Same physical motion in both four-bar files: solve the internal file for several crank angles,
    map with q_rocker(int) = q_rocker(term) - q_crank - q_coupler, compare body poses."""
    t = Model(os.path.join(dirname, "four_bar_internal.urdf"))
    i = Model(os.path.join(dirname, "four_bar_terminal.urdf"))
    print("== four_bar_internal <-> four_bar_terminal coordinate map")
    worst_res, worst_pose, worst_vel = 0.0, 0.0, 0.0
    q = {"crank_joint": 0.0, "coupler_joint": 0.0, "tip_joint": 0.4, "rocker_joint": 0.0}
    for qc in (0.0, 0.3, 0.9, 1.7, 2.6, 3.1, 0.0, -0.5, -1.4, -2.5, -3.1):
        # continuation in steps of at most 0.05 rad keeps the assembly branch of q = 0
        steps = max(1, int(math.ceil(abs(qc - q["crank_joint"]) / 0.05)))
        start = q["crank_joint"]
        for k in range(1, steps + 1):
            q["crank_joint"] = start + (qc - start) * k / steps
            q = t.solve(q, ["coupler_joint", "rocker_joint"])
        rt = np.max(np.abs(t.loop_residual(t.loops[0], q)))
        qi = {"crank_joint": q["crank_joint"], "coupler_joint": q["coupler_joint"], "tip_joint": q["tip_joint"],
              "rocker_joint": q["rocker_joint"] - q["crank_joint"] - q["coupler_joint"]}
        ri = np.max(np.abs(i.loop_residual(i.loops[0], qi)))
        Tt, _ = t.fk(q)
        Ti, _ = i.fk(qi)
        for link in ("crank", "coupler", "tip", "rocker"):
            ct = Tt[link][1] + Tt[link][0] @ floats(t.links[link].find("inertial/origin").get("xyz"))
            ci = Ti[link][1] + Ti[link][0] @ floats(i.links[link].find("inertial/origin").get("xyz"))
            worst_pose = max(worst_pose, np.max(np.abs(ct - ci)), np.max(np.abs(Tt[link][0] - Ti[link][0])))
        # velocities: v(int) = T v(term) maps the internal file's admissible velocities onto the
        # terminal file's (K_int T v = 0 for every v with K_term v = 0)
        Tm = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [-1, -1, 0, 1.0]])
        assert [J.name for J in t.moving] == [J.name for J in i.moving] == \
            ["crank_joint", "coupler_joint", "tip_joint", "rocker_joint"]
        Kt, Ki = t.loop_jacobian(t.loops[0], q), i.loop_jacobian(i.loops[0], qi)
        N = np.linalg.svd(Kt)[2][rank(Kt):].T  # null space of K_term
        worst_vel = max(worst_vel, np.max(np.abs(Ki @ Tm @ N)))
        worst_res = max(worst_res, rt, ri)
        print("  crank %+.2f: coupler %+.6f, rocker(term) %+.6f -> rocker(int) %+.6f; residuals %.1e / %.1e"
              % (qc, q["coupler_joint"], q["rocker_joint"], qi["rocker_joint"], rt, ri))
    print("  max loop residual %.1e, max difference of body orientations and centres of mass %.1e, "
          "max |K_int T null(K_term)| %.1e" % (worst_res, worst_pose, worst_vel))
    if worst_res > 1e-12 or worst_pose > 1e-12 or worst_vel > 1e-12:
        fail("four-bar coordinate map")


def check_singular(dirname):
    m = Model(os.path.join(dirname, "singular_four_bar.urdf"))
    print("== singular_four_bar toggle configurations (parallelogram branch q_coupler = -q_crank, "
          "q_rocker = q_crank)")
    L = m.loops[0]
    dep = [m.joint_by_name["coupler_joint"].col, m.joint_by_name["rocker_joint"].col]
    for qs in (math.pi / 3, -2 * math.pi / 3):
        for d in (0.0, -1e-3, 1e-3):
            qc = qs + d
            q = {"crank_joint": qc, "coupler_joint": -qc, "rocker_joint": qc}
            res = np.max(np.abs(m.loop_residual(L, q)))
            K = m.loop_jacobian(L, q)
            s = np.linalg.svd(K[:, dep], compute_uv=False)
            print("  q_crank = %-22s residual %.1e, full Jacobian rank %d, dependent block sigma = [%.3g, %.3g], "
                  "cond %.3g" % (repr(qc), res, rank(K), s[0], s[1], s[0] / s[1] if s[1] > 0 else float("inf")))
            if res > 1e-12:
                fail("singular four-bar branch does not close at %r" % qc)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    files = sys.argv[1:] or sorted(glob.glob(os.path.join(here, "*.urdf")))
    for f in files:
        report(f)
    if not sys.argv[1:]:
        check_four_bar_map(here)
        check_singular(here)
    print("FAILURES: %d" % len(FAIL))
    for f in FAIL:
        print("  " + f)
    sys.exit(1 if FAIL else 0)


if __name__ == "__main__":
    main()
