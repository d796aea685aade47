"""An estimator of a planar arm's contact force and point, independent of the one under test.

``processes/contact/src/identify.rs`` (the estimator under test) fits an extended wrench
(F_x, F_y, τ_z) at the loaded joints' centroid, intersects its line of action with the
links' contours (Cyrus–Beck) and picks a link with the depth sensor. This module shares none of
that. It searches the surface instead: for every link k and every point p of a fine sampling of
k's contour it takes the least-squares force

    F(p) = argmin_F |τ − J_p(q)ᵀ·F|²,   row i of J_pᵀ: (−(p_y − y_i), p_x − x_i) for joints
                                          i ≤ k, 0 for the joints beyond k,

over *all* the arm's joints (a push on link k leaves the joints beyond it unloaded, so they
count against it), keeps the points whose F lies inside the friction cone about the inward
normal and which no other link covers, and takes the least residual |τ − J_pᵀ·F|. The best
sample of each link is then refined along its contour by repeated finer grids, and the link
with the least refined residual wins. Only links with at least three joints are candidates (a
force and its point are three unknowns). It uses neither the depth sensor nor any noise
threshold.

The geometry comes from the arm's URDF (the chain of revolute joints about +z, each joint's
origin in its parent link, the fixed tip joint giving the last link's length) and the stadium
radius beside it: each link's surface is the outline of a capsule of that radius around the
segment from its joint to the next, with each half circle drawn as 7 chords (16 segments in
all, the reference's Ω_k, on which the scripted person also places its pushes).

Everything is batched with numpy over M estimates at once: ``q`` and ``tau`` are (M, n).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

ARC_CHORDS = 7  # chords per half circle: 2 sides + 2·7 chords = 16 segments


class Arm:
    """The planar chain of a URDF: joint names, link names, each joint's origin in its parent
    link (x, y), and each link's length (to the next joint or the tip)."""

    def __init__(self, urdf_path: str, radius: float, base=(0.0, 0.0, 0.0)):
        root = ET.parse(urdf_path).getroot()
        joints = {}
        for j in root.findall("joint"):
            origin = j.find("origin")
            xyz = [float(v) for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()]
            rpy = origin.get("rpy") if origin is not None else None
            if rpy and any(abs(float(v)) > 0 for v in rpy.split()):
                raise ValueError(f"{urdf_path}: joint {j.get('name')} turns its origin; not a planar chain")
            axis = j.find("axis")
            joints[j.find("parent").get("link")] = {
                "name": j.get("name"),
                "type": j.get("type"),
                "child": j.find("child").get("link"),
                "xy": (xyz[0], xyz[1]),
                "axis": axis.get("xyz") if axis is not None else None,
            }
        children = {j["child"] for j in joints.values()}
        roots = [p for p in joints if p not in children]
        if len(roots) != 1:
            raise ValueError(f"{urdf_path}: not a single chain")
        self.joints, self.links, self.origins, self.lengths = [], [], [], []
        link = roots[0]
        while link in joints:
            j = joints[link]
            if j["type"] in ("revolute", "continuous"):
                if [float(v) for v in j["axis"].split()] != [0.0, 0.0, 1.0]:
                    raise ValueError(f"{urdf_path}: joint {j['name']} does not turn about +z")
                if self.joints:
                    self.lengths.append(math.hypot(*j["xy"]))
                self.joints.append(j["name"])
                self.links.append(j["child"])
                self.origins.append(j["xy"])
            elif j["type"] == "fixed" and self.joints:
                self.lengths.append(math.hypot(*j["xy"]))  # the tip frame
                break
            link = j["child"]
        if len(self.lengths) != len(self.joints):
            raise ValueError(f"{urdf_path}: the last link has no tip frame giving its length")
        for (x, y), _ in zip(self.origins[1:], self.lengths):
            if abs(y) > 1e-12 or x <= 0:
                raise ValueError(f"{urdf_path}: a joint is not on its parent's x axis")
        self.n = len(self.joints)
        self.radius = radius
        self.base = base
        self.contours = [Contour(length, radius) for length in self.lengths]

    def frames(self, q: np.ndarray):
        """Each link's frame in the world for joint angles ``q`` (M, n): origins (M, n, 2) (the
        joint axes) and headings (M, n)."""
        bx, by, byaw = self.base
        heading = byaw + np.cumsum(q, axis=1)
        origin = np.empty(q.shape + (2,))
        x = np.full(q.shape[0], bx)
        y = np.full(q.shape[0], by)
        h_parent = np.full(q.shape[0], byaw)
        for i, (ox, oy) in enumerate(self.origins):
            x = x + ox * np.cos(h_parent) - oy * np.sin(h_parent)
            y = y + ox * np.sin(h_parent) + oy * np.cos(h_parent)
            origin[:, i, 0], origin[:, i, 1] = x, y
            h_parent = heading[:, i]
        return origin, heading


class Contour:
    """A link's surface in its own frame (joint at the origin, the next joint at (L, 0)): a
    closed convex 16-gon, counter-clockwise, sampled by arc length."""

    def __init__(self, length: float, radius: float):
        self.length, self.radius = length, radius
        t = -math.pi / 2 + math.pi * np.arange(ARC_CHORDS + 1) / ARC_CHORDS
        far = np.stack([length + radius * np.cos(t), radius * np.sin(t)], axis=1)
        near = np.stack([radius * np.cos(t + math.pi), radius * np.sin(t + math.pi)], axis=1)
        self.vertices = np.concatenate([far, near])
        edges = np.roll(self.vertices, -1, axis=0) - self.vertices
        self.seg_len = np.hypot(edges[:, 0], edges[:, 1])
        self.unit = edges / self.seg_len[:, None]
        # Counter-clockwise: the inward normal is the edge direction turned left.
        self.inward = np.stack([-self.unit[:, 1], self.unit[:, 0]], axis=1)
        self.start = np.concatenate([[0.0], np.cumsum(self.seg_len)[:-1]])
        self.perimeter = float(self.seg_len.sum())

    def at(self, s: np.ndarray):
        """Points and inward normals at arc lengths ``s`` (any shape, wrapped)."""
        s = np.mod(s, self.perimeter)
        j = np.clip(np.searchsorted(self.start, s, side="right") - 1, 0, len(self.start) - 1)
        along = s - self.start[j]
        return self.vertices[j] + along[..., None] * self.unit[j], self.inward[j]

    def samples(self, spacing: float) -> np.ndarray:
        """Arc lengths every ``spacing`` m or closer, each vertex included."""
        s = [self.start]
        for j, length in enumerate(self.seg_len):
            k = max(1, math.ceil(length / spacing))
            s.append(self.start[j] + length * np.arange(1, k) / k)
        return np.sort(np.concatenate(s))

    def strictly_inside(self, u: np.ndarray) -> np.ndarray:
        """Whether local points ``u`` (..., 2) lie strictly inside the polygon."""
        x, y = u[..., 0], u[..., 1]
        inner = self.radius * math.cos(math.pi / (2 * ARC_CHORDS))  # a chord's distance

        def in_cap(cx, cy):
            # The half 16-gon about (0, 0) opening towards +x: the chord of the sector holding
            # the point's angle bounds it.
            phi = np.arctan2(cy, cx)
            k = np.clip(np.floor((phi + math.pi / 2) / (math.pi / ARC_CHORDS)), 0, ARC_CHORDS - 1)
            mid = -math.pi / 2 + (k + 0.5) * math.pi / ARC_CHORDS
            return (cx > 0) & (cx * np.cos(mid) + cy * np.sin(mid) < inner)

        body = (x >= 0) & (x <= self.length) & (np.abs(y) < self.radius)
        # Only points within the radius of an end can lie in its cap: test those alone.
        inside = body.copy()
        for cx, cy in ((x - self.length, y), (-x, -y)):
            near = (cx > 0) & (cx * cx + cy * cy < self.radius * self.radius)
            inside[near] |= in_cap(cx[near], cy[near])
        return inside


class Estimator:
    """The search over the contours (module doc). ``spacing``: the coarse sampling (m);
    ``rounds``: grid refinements, each 8 times finer."""

    def __init__(self, arm: Arm, mu: float, spacing: float = 0.004, rounds: int = 10, grid: int = 21,
                 min_joints: int = 3):
        self.arm, self.spacing, self.rounds, self.grid = arm, spacing, rounds, grid
        # A force and its point on a contour are three unknowns: the torques of fewer than three
        # joints do not fix them (every point of link 1 or 2 explains them exactly, with any
        # force along a line, however large), so those links are no candidates.
        self.first_link = min_joints - 1
        self.cone_cos = 1.0 / math.sqrt(1.0 + mu * mu)
        self.samples = [c.samples(spacing) for c in arm.contours]

    def _local(self, link: np.ndarray, s: np.ndarray):
        """Local points and inward normals on link ``link[m]`` at arc lengths ``s[m, :]``."""
        pts = np.empty(s.shape + (2,))
        nin = np.empty(s.shape + (2,))
        for k, c in enumerate(self.arm.contours):
            rows = link == k
            if rows.any():
                pts[rows], nin[rows] = c.at(s[rows])
        return pts, nin

    def evaluate(self, origin, heading, tau, link, s):
        """For M estimates and K points each (link ``link[m]``, arc lengths ``s[m, k]``): the
        residual (∞ where the force leaves the cone or another link covers the point), the
        least-squares force (M, K, 2) and the world point (M, K, 2)."""
        m = np.arange(len(link))
        loc, nin_loc = self._local(link, s)
        c, sn = np.cos(heading[m, link])[:, None], np.sin(heading[m, link])[:, None]
        o = origin[m, link][:, None, :]
        p = np.stack([o[..., 0] + c * loc[..., 0] - sn * loc[..., 1],
                      o[..., 1] + sn * loc[..., 0] + c * loc[..., 1]], axis=-1)
        nin = np.stack([c * nin_loc[..., 0] - sn * nin_loc[..., 1],
                        sn * nin_loc[..., 0] + c * nin_loc[..., 1]], axis=-1)
        active = (np.arange(self.arm.n)[None, :] <= link[:, None])[:, None, :]
        d = p[:, :, None, :] - origin[:, None, :, :]  # (M, K, n, 2)
        ax = np.where(active, -d[..., 1], 0.0)
        ay = np.where(active, d[..., 0], 0.0)
        t = tau[:, None, :]
        g00, g01, g11 = (ax * ax).sum(-1), (ax * ay).sum(-1), (ay * ay).sum(-1)
        b0, b1 = (ax * t).sum(-1), (ay * t).sum(-1)
        det = g00 * g11 - g01 * g01
        tr = g00 + g11
        ok = det > 1e-12 * tr * tr
        safe = np.where(ok, det, 1.0)
        # One joint only (link 1): the torque fixes one component; the least-norm force.
        fx = np.where(ok, (g11 * b0 - g01 * b1) / safe, b0 / tr)
        fy = np.where(ok, (g00 * b1 - g01 * b0) / safe, b1 / tr)
        r = t - (ax * fx[..., None] + ay * fy[..., None])
        residual = np.sqrt((r * r).sum(-1))
        fn = np.hypot(fx, fy)
        valid = (fx * nin[..., 0] + fy * nin[..., 1] >= self.cone_cos * fn) & (fn > 0)
        for j, cj in enumerate(self.arm.contours):
            cj_, sj = np.cos(heading[:, j])[:, None], np.sin(heading[:, j])[:, None]
            rel = p - origin[:, j][:, None, :]
            u = np.stack([cj_ * rel[..., 0] + sj * rel[..., 1], -sj * rel[..., 0] + cj_ * rel[..., 1]], -1)
            valid &= ~((link[:, None] != j) & cj.strictly_inside(u))
        return np.where(valid, residual, np.inf), np.stack([fx, fy], -1), p

    def estimate(self, q: np.ndarray, tau: np.ndarray) -> dict:
        """Estimates for joint angles ``q`` and external torques ``tau`` (both (M, n), N·m):
        ``force`` (M, 2), ``point`` (M, 2), ``link`` (M,), ``residual`` (M,) (∞: no point of any
        link fits inside the cone; force and point are then NaN)."""
        origin, heading = self.arm.frames(q)
        M = len(q)
        best_res = np.full(M, np.inf)
        best_f = np.full((M, 2), np.nan)
        best_p = np.full((M, 2), np.nan)
        best_link = np.full(M, -1)
        rows = np.arange(M)
        for k, coarse in enumerate(self.samples):
            if k < self.first_link:
                continue
            link = np.full(M, k)
            res, f, p = self.evaluate(origin, heading, tau, link, np.broadcast_to(coarse, (M, len(coarse))))
            i = np.argmin(res, axis=1)
            s0 = coarse[i]
            r0 = res[rows, i]
            width = self.spacing
            for _ in range(self.rounds):
                s = s0[:, None] + np.linspace(-width, width, self.grid)[None, :]
                res, f, p = self.evaluate(origin, heading, tau, link, s)
                i = np.argmin(res, axis=1)
                better = res[rows, i] <= r0
                s0 = np.where(better, s[rows, i], s0)
                r0 = np.where(better, res[rows, i], r0)
                width /= 8.0
            res, f, p = self.evaluate(origin, heading, tau, link, s0[:, None])
            win = res[:, 0] < best_res
            best_res = np.where(win, res[:, 0], best_res)
            best_f[win], best_p[win], best_link[win] = f[win, 0], p[win, 0], k
        return {"force": best_f, "point": best_p, "link": best_link, "residual": best_res}
