#!/usr/bin/env python3
"""Analysis of a rotating-drum run (inputs/drum_2d_EV.yml, drum_2d_EN.yml,
drum_3d.yml), after paper §6:

  python3 -m tools.analysis.drum_analysis OUTDIR [--times 20 30 40] [--png PREFIX] [--slab W]

prints, per snapshot time asked (nearest snapshot): the dynamic angle of the
free surface and how flat it is (rolling regime), the largest speed on the
mid-chord (the surface speed), the segregation index (below), the top grains'
speed, and writes
  PREFIX_midchord.png  speed, shear rate and C along the mid-chord (figs 19-21, 26)
  PREFIX_rates.png     the three concentration-rate contributions along the
                       mid-chord (figs 28-29): C1 = -F grad_g V,
                       C2 = -V F' grad_g C, C3 = div(D grad C)
  PREFIX_maps.png      C, speed and shear rate over the bed (figs 17, 18, 24, 25)
  PREFIX_global.png    mean C and the drift of sum C_i V_i against time (fig 27)
and with --profiles FILE the mid-chord profiles as numbers (CSV: t, d_mc/R,
speed, shear rate, C; NaN beyond the material).

3D drums (snapshot Dimension 3): the material is projected onto the x-y
plane (the drum's cross-section) and analysed as a 2D drum: all of it, or,
with --slab W (m), only the mid-length slab |z - L/2| < W/2 (L = the drum
length), away from the end walls (W = 1.5 dr keeps the middle plane, or the
middle two when the drum is an even number of dr long).
Volumes are divided by the slab width (W, or L), so Shepard weights and the
rate terms see a cross-section's area per particle. Without --slab the
PNGs of a 3D drum (midchord, rates, maps) are of the axial analysis's
mid-length slab (--endslab W): the rate terms of the whole length
projected would pair every particle with ~L/dr planes of neighbours.

Definitions.
Free surface: the highest material particle in vertical bins of width 2 dr;
a line is fitted to the bins in the middle 60 % of the bed's horizontal
extent; dynamic angle = atan |slope|; flatness = rms distance of those bins
from the line, in dr. Mid-chord: from M, the foot of the perpendicular from
the drum centre to the surface line, along the inward normal of the line
down to the drum wall; depth d_mc = distance from M, normalised by R (the
paper's normalised mid-chord depth). Fields on the mid-chord are Shepard
interpolations of the material particles within 2h. Surface speed ("max |u|
mc"): the largest interpolated speed on the mid-chord. It averages particles
below the surface over 2h, so it reads low by an amount that falls with dr
(tools/analysis/drum_fe_read.py: 3.2, 1.2, 0.5 % of the FE reference's at dr
0.5, 0.25, 0.125 mm, h = 1.5 dr). "top grains u": the mean speed of the
surface grains (the highest particle of each bin, those the line is fitted to)
within 0.1 R of M along the line; it reads the speed at the top row's depth,
dr / 2.
Segregation index: (<r> - <r>_C) / <r>, with <r> the mean distance of the
material particles from the bed's centroid and <r>_C the same mean weighted
by C: positive when small grains gather in the core (figs 24-25), 0 when
mixed.
Concentration-rate contributions: SPH gradients with a renormalised kernel
gradient (first-order consistent), grad_g = (g/|g|) . grad, and the
diffusion term in the form of eq. (3.8); V, D from eq. (2.7) with the run's
chi_V, chi_D, d^S, d^L and the snapshot's shear rate.

3D drums also get the axial analysis (class Axial; --zbins N, default 8;
--endslab W, default 3 dr; --csv FILE, one row per time: the whole-bed,
mid and end numbers, the banding, the shells, then angle_zK, seg_zK, C_zK
per z-bin K): per time, the
dynamic angle, surface speed on the mid-chord and segregation index of the
whole bed, of the slab of width W at mid-length and of the slabs next to
each end wall (z < W, z > L - W); per z-bin the angle, the segregation
index, the mean C and the x-y offset of the small grains' centroid
(weights V C) from the bed's (weights V), i.e. the first moment of the
small-grain excess, sum V (C - <C>) x / sum V C (distance, x and y); the axial banding (the share of C's
variance that lies between the z-bins: 0 for a z-uniform bed, 1 when C is
uniform within each bin); the mean C in five shells about the bed's
centroid, inner to outer (a core of small grains: falling); and with --png
PREFIX_axial.png (angle and segregation index against z, the mid-chord
speed and C at mid-length and next to the z = 0 end wall at every time
asked, C in the
mid-length slab and over (z, r)). tests/validate_drum3d_analysis.py checks
it on snapshots built with known answers.
"""
import argparse
import csv
import os

import numpy as np
import yaml
from scipy.spatial import cKDTree

from tools.analysis import snap  # noqa: E402


def used_params(outdir):
    """A run's used_params.yml; a container turning one cylinder about the origin (Geometry:type container,
    e.g. a drum periodic along z) is read as a drum: its radius, rpm and direction in Geometry:radius,
    Walls:rpm and :direction, and in 3D its depth as Geometry:length (the period, when periodic in z)."""
    with open(os.path.join(outdir, "used_params.yml")) as f:
        par = yaml.safe_load(f)
    return drum_of_container(par)


def drum_of_container(par):
    g = par.get("Geometry", {})
    if g.get("type") != "container":
        return par
    cyl = [w for w in par.get("Container", {}).get("walls", []) or []
           if w.get("shape") == "cylinder" and w.get("motion") == "turning"]
    if len(cyl) != 1 or any(abs(float(c)) > 1e-12 for c in cyl[0].get("centre", [0, 0])):
        return par  # not a drum about the origin: the drum tools do not apply
    w = cyl[0]
    g["radius"] = float(w["radius"])
    par.setdefault("Walls", {})["rpm"] = float(w.get("rpm", 0))
    par["Walls"]["direction"] = w.get("direction", "clockwise")
    if int(g.get("dim", 2)) == 3:
        g["length"] = float(g["depth"])
    return par


def drum_wall(par):
    """The drum's radius R (m) and its wall's signed rate omega (rad/s about +z,
    y up: clockwise is negative) from a run's used_params.yml."""
    w = float(par["Walls"]["rpm"]) * 2 * np.pi / 60
    return float(par["Geometry"]["radius"]), (-w if par["Walls"].get("direction", "clockwise") == "clockwise" else w)


def wendland(q):
    """The Wendland C2 kernel's shape at q = r / h (support 2 h), unnormalised: (1 - q/2)^4 (2 q + 1);
    times 7 / (4 pi h^2) in 2D it is the solver's kernel."""
    return np.where(q < 2, (1 - q / 2) ** 4 * (2 * q + 1), 0.0)


class Drum:
    """One snapshot of a drum run with the derived quantities."""

    def __init__(self, path, par, slab=None, zwin=None, snapshot=None):
        s = snapshot if snapshot is not None else snap.read_snapshot(path)
        g = par["Geometry"]
        self.t = float(s["Time"])
        m = np.asarray(s["Kind"]) == snap.MATERIAL
        width = 1.0
        if int(s.get("Dimension", 2)) == 3:  # the cross-section: a slab (mid-length, or zwin) or all, projected
            L = round(g["length"] / g["dr"]) * g["dr"]
            width = slab if slab else L
            z = np.asarray(s["Coordinates"])[:, 2]
            if zwin is not None:  # z0 <= z < z1
                width = zwin[1] - zwin[0]
                m &= (z >= zwin[0]) & (z < zwin[1])
            elif slab:
                m &= np.abs(z - 0.5 * L) < 0.5 * slab
        self.x = np.asarray(s["Coordinates"])[m, :2]
        self.z = np.asarray(s["Coordinates"])[m, 2]  # 0 in 2D
        self.v = np.asarray(s["Velocities"])[m, :2]
        self.C = np.asarray(s["Concentration"])[m]
        self.gdot = np.asarray(s["ShearRate"])[m]
        self.vol = np.asarray(s["Volume"])[m] / width
        self.speed = np.hypot(self.v[:, 0], self.v[:, 1])
        self.width = width  # the volume divisor: 1 in 2D
        self.dr, self.R = g["dr"], g["radius"]
        self.h = g["h_factor"] * self.dr
        self.par = par
        self.tree = cKDTree(self.x)
        self._surface()

    def _surface(self):
        x, dr = self.x, self.dr
        lo, hi = x[:, 0].min(), x[:, 0].max()
        edges = np.arange(lo, hi + 2 * dr, 2 * dr)
        k = np.digitize(x[:, 0], edges)
        top = []
        for b in np.unique(k):
            sel = k == b
            top.append(int(np.argmax(np.where(sel, x[:, 1], -np.inf))))
        self.top = np.array(top)  # the surface grains: the highest particle of each bin
        bx, by = x[self.top, 0], x[self.top, 1]
        mid = 0.5 * (lo + hi)
        core = np.abs(bx - mid) <= 0.3 * (hi - lo)
        a, b = np.polyfit(bx[core], by[core], 1)
        self.slope = a
        self.angle = float(np.degrees(np.arctan(abs(a))))
        # distance of the bins from the line y = a x + b
        self.flatness = float(np.sqrt(np.mean(((by[core] - (a * bx[core] + b)) / np.hypot(1, a)) ** 2)) / dr)
        # foot of the perpendicular from the centre (0, 0) onto a x - y + b = 0
        n = np.array([a, -1.0]) / np.hypot(a, 1.0)  # unit normal, points down into the bed
        self.M = -b * np.array([a, -1.0]) / (a * a + 1.0)
        self.n = n if n[1] < 0 else -n

    def interp(self, pts, field):
        """Shepard interpolation of a particle field at points pts (k x 2)."""
        out = np.full(len(pts), np.nan)
        for q, p in enumerate(pts):
            idx = self.tree.query_ball_point(p, 2 * self.h)
            if not idx:
                continue
            w = wendland(np.hypot(*(self.x[idx] - p).T) / self.h) * self.vol[idx]
            if w.sum() > 0:
                out[q] = np.dot(w, field[idx]) / w.sum()
        return out

    def midchord(self, npts=120):
        """Depth d_mc / R and sample points from the surface to the wall."""
        # |M + d n| = R: d^2 + 2 d M.n + |M|^2 - R^2 = 0
        Mn, M2 = float(np.dot(self.M, self.n)), float(np.dot(self.M, self.M))
        dmax = -Mn + np.sqrt(max(Mn * Mn - M2 + self.R ** 2, 0.0))
        d = np.linspace(0, dmax, npts)
        return d / self.R, self.M[None, :] + d[:, None] * self.n[None, :]

    def surface_speed(self):
        """The largest speed on the mid-chord, m/s."""
        _, pts = self.midchord()
        return float(np.nanmax(self.interp(pts, self.speed)))

    def surface_grain_speed(self, window=0.1):
        """The mean speed of the surface grains (the particles the surface line is fitted to) within
        window R of M along the line, m/s: what a camera tracking the top grains reads. Unlike
        surface_speed it averages no particles below the surface, so its bias is the top row's depth,
        dr / 2 times the shear rate there (tools/analysis/drum_fe_read.py)."""
        t = np.array([1.0, self.slope]) / np.hypot(1.0, self.slope)
        s = (self.x[self.top] - self.M) @ t
        near = self.top[np.abs(s) <= window * self.R]
        return float(np.mean(self.speed[near])) if len(near) else float("nan")

    def surface_grains_along(self, edges):
        """The surface grains binned along the fitted line by s / R (s from M along the line, growing
        with x): per bin of `edges` the mean s / R, their mean speed (m/s), their mean height above
        the line in dr (the surface's shape) and their number (nan where a bin is empty). In the bins
        at the wall the highest particle of an x bin may be a corner's, below the surface."""
        t = np.array([1.0, self.slope]) / np.hypot(1.0, self.slope)
        rel = self.x[self.top] - self.M
        s = rel @ t / self.R
        up = -(rel @ self.n) / self.dr
        k = np.digitize(s, edges) - 1
        out = []
        for b in range(len(edges) - 1):
            m = k == b
            n = int(m.sum())
            out.append((float(s[m].mean()) if n else np.nan, float(self.speed[self.top][m].mean()) if n else np.nan,
                        float(up[m].mean()) if n else np.nan, n))
        return out

    def segregation_index(self):
        c = np.average(self.x, axis=0, weights=self.vol)
        r = np.hypot(*(self.x - c).T)
        return float((np.average(r, weights=self.vol) - np.average(r, weights=self.vol * self.C))
                     / np.average(r, weights=self.vol))

    def rate_terms(self):
        """C1 = -F grad_g V, C2 = -V F' grad_g C, C3 = div(D grad C), 1/s."""
        seg = self.par["Segregation"]
        grains = self.par.get("Grains", seg)  # an output written before the Grains section: Segregation's
        dS, dL = grains["d_small"], grains["d_large"]
        C = self.C
        davg = dS * C + dL * (1 - C)
        V = seg["chi_V"] * self.gdot * davg
        D = seg["chi_D"] * self.gdot * davg ** 2
        F = C * (1 - C)
        dF = 1 - 2 * C
        if seg.get("flux") == "asymmetric":
            A, kap = seg["A"], seg["kappa"]
            F = A * C * (1 - C) * (1 - kap * C)
            dF = A * (3 * kap * C * C - 2 * (1 + kap) * C + 1)
        gv = np.asarray(self.par["Physics"]["gravity"][:2], float)
        ghat = gv / np.linalg.norm(gv)
        n = len(C)
        h = self.h
        alpha = 7.0 / (4 * np.pi * h * h)
        pairs = self.tree.query_pairs(2 * h, output_type="ndarray")
        i, j = np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]])
        xij = self.x[i] - self.x[j]
        r = np.hypot(xij[:, 0], xij[:, 1])
        q = r / h
        f = -5 * alpha * (1 - q / 2) ** 3 / (h * h)  # (1/r) dW/dr
        gW = f[:, None] * xij  # grad_i W_ij
        Vj = self.vol[j]
        # renormalisation L_i = (sum_j V_j (x_j - x_i) (x) grad_i W_ij)^-1
        Mm = np.zeros((n, 2, 2))
        np.add.at(Mm, i, (Vj[:, None, None] * (-xij)[:, :, None] * gW[:, None, :]))
        det = Mm[:, 0, 0] * Mm[:, 1, 1] - Mm[:, 0, 1] * Mm[:, 1, 0]
        ok = np.abs(det) > 1e-6
        Linv = np.zeros_like(Mm)
        Linv[ok, 0, 0], Linv[ok, 1, 1] = Mm[ok, 1, 1] / det[ok], Mm[ok, 0, 0] / det[ok]
        Linv[ok, 0, 1], Linv[ok, 1, 0] = -Mm[ok, 0, 1] / det[ok], -Mm[ok, 1, 0] / det[ok]
        Linv[~ok] = np.eye(2)

        def grad_g(fld):
            g = np.zeros((n, 2))
            np.add.at(g, i, (Vj * (fld[j] - fld[i]))[:, None] * gW)
            g = np.einsum("nab,nb->na", Linv.transpose(0, 2, 1), g)
            return g @ ghat

        c3 = np.zeros(n)
        xg = np.einsum("ka,ka->k", xij, gW) / (r * r + 0.01 * h * h)
        np.add.at(c3, i, Vj * (D[i] + D[j]) * (C[i] - C[j]) * xg)
        return -F * grad_g(V), -V * dF * grad_g(C), c3



def drum_length(par):
    """The 3D drum's length between its end walls, rounded to whole dr as setup.c does."""
    g = par["Geometry"]
    return round(g["length"] / g["dr"]) * g["dr"]


class Axial:
    """One snapshot of a 3D drum along its axis (z): the whole bed, nz equal
    z-bins, a slab of width W at mid-length and one next to each end wall
    (z < W and z > L - W), each analysed as a 2D cross-section (Drum)."""

    NSHELL = 5

    def __init__(self, path, par, nz=8, endslab=None, snapshot=None):
        s = snapshot if snapshot is not None else snap.read_snapshot(path)
        if int(s.get("Dimension", 2)) != 3:
            raise ValueError("%s: not a 3D drum snapshot" % path)
        dr, L = par["Geometry"]["dr"], drum_length(par)
        W = endslab if endslab else 3 * dr
        if not 0 < W <= 0.5 * L:
            raise ValueError("end slab width %g m: expected 0 < W <= L/2 = %g m" % (W, 0.5 * L))
        self.t, self.L, self.W, self.dr = float(s["Time"]), L, W, dr
        self.whole = Drum(path, par, snapshot=s)
        self.mid = Drum(path, par, zwin=(0.5 * (L - W), 0.5 * (L + W)), snapshot=s)
        self.end0 = Drum(path, par, zwin=(-0.5 * dr, W), snapshot=s)
        self.end1 = Drum(path, par, zwin=(L - W, L + 0.5 * dr), snapshot=s)
        edges = np.linspace(0.0, L, nz + 1)
        edges[0], edges[-1] = -0.5 * dr, L + 0.5 * dr
        self.zc = 0.5 * (np.linspace(0.0, L, nz + 1)[1:] + np.linspace(0.0, L, nz + 1)[:-1])
        self.bins = [Drum(path, par, zwin=(edges[k], edges[k + 1]), snapshot=s) for k in range(nz)]
        w = self.whole
        self.meanC = float(np.average(w.C, weights=w.vol))
        # axial banding: the share of C's variance that lies between the z-bins
        binC = np.array([np.average(b.C, weights=b.vol) for b in self.bins])
        binV = np.array([b.vol.sum() * b.width for b in self.bins])  # Drum divides by its slab's width
        varC = float(np.average((w.C - self.meanC) ** 2, weights=w.vol))
        self.binC = binC
        self.banding = float(np.average((binC - self.meanC) ** 2, weights=binV) / varC) if varC > 0 else 0.0
        # where the small grains gather: the small-grain centroid (weights V C) from the bed's (weights V), per bin
        self.offset = np.array([self.small_offset(b) for b in self.bins])
        self.offset_whole = self.small_offset(w)
        # mean C in shells of equal width about the bed's centroid, inner to outer
        c = np.average(w.x, axis=0, weights=w.vol)
        r = np.hypot(*(w.x - c).T)
        k = np.minimum((r / r.max() * self.NSHELL).astype(int), self.NSHELL - 1)
        self.shellC = np.array([np.average(w.C[k == q], weights=w.vol[k == q]) if np.any(k == q) else np.nan
                                for q in range(self.NSHELL)])

    @staticmethod
    def small_offset(d):
        """x-y centroid of the small grains (weights V C) less the bed's (weights V), m; equal to
        sum V (C - <C>) x / sum V C, the first moment of the small-grain excess. NaN without small grains."""
        if not np.sum(d.vol * d.C) > 0:
            return np.array([np.nan, np.nan])
        return np.average(d.x, axis=0, weights=d.vol * d.C) - np.average(d.x, axis=0, weights=d.vol)

    def row(self):
        """The numbers of one time, for the table and --csv."""
        r = {"t": self.t, "angle": self.whole.angle, "seg": self.whole.segregation_index()}
        for tag, d in (("mid", self.mid), ("end0", self.end0), ("end1", self.end1)):
            r["angle_" + tag] = d.angle
            r["speed_" + tag] = d.surface_speed()
            r["seg_" + tag] = d.segregation_index()
        r["banding"] = self.banding
        r["offset_mm"] = 1e3 * float(np.mean(np.hypot(*self.offset.T)))
        r["offset_x_mm"], r["offset_y_mm"] = (1e3 * float(v) for v in self.offset_whole)
        for q in range(self.NSHELL):
            r["C_shell%d" % q] = float(self.shellC[q])
        for k, b in enumerate(self.bins):  # per z-bin, bin k centred at zc[k]
            r["angle_z%d" % k], r["seg_z%d" % k], r["C_z%d" % k] = b.angle, b.segregation_index(), float(self.binC[k])
        return r

    def report(self):
        r = self.row()
        lines = ["t = %.3f s  (L = %.1f mm, end slabs W = %.1f mm, %d z-bins)" % (self.t, 1e3 * self.L, 1e3 * self.W,
                                                                                 len(self.bins)),
                 "  %-22s %8s %12s %10s" % ("", "angle", "surface u", "seg index"),
                 "  %-22s %7.2f° %12s %10.4f" % ("whole bed", r["angle"], "", r["seg"])]
        for tag, name in (("mid", "mid-length slab"), ("end0", "end slab z < W"), ("end1", "end slab z > L - W")):
            lines.append("  %-22s %7.2f° %7.2f cm/s %10.4f" % (name, r["angle_" + tag], 100 * r["speed_" + tag],
                                                                  r["seg_" + tag]))
        lines.append("  z (mm)        " + " ".join("%7.1f" % (1e3 * z) for z in self.zc))
        lines.append("  angle (°)     " + " ".join("%7.2f" % b.angle for b in self.bins))
        lines.append("  seg index     " + " ".join("%7.4f" % b.segregation_index() for b in self.bins))
        lines.append("  mean C        " + " ".join("%7.4f" % c for c in self.binC))
        lines.append("  small off (mm)" + " ".join("%7.2f" % (1e3 * np.hypot(*o)) for o in self.offset))
        lines.append("   its x (mm)   " + " ".join("%7.2f" % (1e3 * o[0]) for o in self.offset))
        lines.append("   its y (mm)   " + " ".join("%7.2f" % (1e3 * o[1]) for o in self.offset))
        lines.append("  axial banding (share of C's variance between z-bins) %.4f; mean C by shell about the bed's "
                     "centroid, inner to outer: %s" % (r["banding"], " ".join("%.3f" % c for c in self.shellC)))
        return "\n".join(lines)


def plot_axial(axs, png):
    """Angle and segregation index against z per time; the mid-chord speed and C
    at mid-length and next to the z = 0 end wall; C over (z, r) at the last time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(2, 3, figsize=(15, 8))
    for a in axs:
        ax[0, 0].plot(1e3 * a.zc, [b.angle for b in a.bins], "o-", label="t = %.0f s" % a.t)
        ax[0, 1].plot(1e3 * a.zc, [b.segregation_index() for b in a.bins], "o-", label="t = %.0f s" % a.t)
    ax[0, 0].set_xlabel("z (mm)"), ax[0, 0].set_ylabel("dynamic angle (°)"), ax[0, 0].legend(fontsize=7)
    ax[0, 1].set_xlabel("z (mm)"), ax[0, 1].set_ylabel("segregation index"), ax[0, 1].legend(fontsize=7)
    last = axs[-1]
    for q, a in enumerate(axs):  # mid-length solid, next to the z = 0 end wall dashed, one colour per time
        for d, ls, lab in ((a.mid, "-", "mid-length"), (a.end0, "--", "end wall z = 0")):
            dm, pts = d.midchord()
            kw = dict(color="C%d" % q, ls=ls, label="%s, t = %.0f s" % (lab, a.t))
            ax[1, 0].plot(100 * d.interp(pts, d.speed), dm, **kw)
            ax[1, 1].plot(d.interp(pts, d.C), dm, **kw)
    for k, xl in ((0, "speed (cm/s)"), (1, "C")):
        ax[1, k].invert_yaxis(), ax[1, k].set_xlabel(xl), ax[1, k].set_ylabel("depth along the mid-chord / R")
        ax[1, k].legend(fontsize=6), ax[1, k].set_title("mid-chord: mid-length slab and end slab", fontsize=9)
    w = last.whole
    m = last.mid
    sc = ax[0, 2].scatter(1e3 * m.x[:, 0], 1e3 * m.x[:, 1], c=m.C, s=2, cmap="coolwarm", vmin=0, vmax=1)
    ax[0, 2].set_aspect("equal"), ax[0, 2].set_title("C, mid-length slab, t = %.0f s" % last.t, fontsize=9)
    fig.colorbar(sc, ax=ax[0, 2])
    c = np.average(w.x, axis=0, weights=w.vol)
    zs, rs = w.z, np.hypot(*(w.x - c).T)
    H, xe, ye = np.histogram2d(zs, rs, bins=(len(last.bins) * 3, 12), weights=w.vol * w.C)
    V, _, _ = np.histogram2d(zs, rs, bins=(xe, ye), weights=w.vol)
    im = ax[1, 2].pcolormesh(1e3 * xe, 1e3 * ye, np.where(V > 0, H / np.maximum(V, 1e-300), np.nan).T, cmap="coolwarm",
                             vmin=0, vmax=1)
    ax[1, 2].set_xlabel("z (mm)"), ax[1, 2].set_ylabel("distance from the bed's centroid (mm)")
    ax[1, 2].set_title("mean C over (z, r), t = %.0f s" % last.t, fontsize=9)
    fig.colorbar(im, ax=ax[1, 2])
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)

def pick(paths, times):
    ts = np.array([snap.snapshot_time(p) for p in paths])
    return [paths[int(np.argmin(np.abs(ts - t)))] for t in times]


def write_profiles(drums, path):
    """The mid-chord profiles of figures 19-21 and 26 as numbers, one row per point."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "d_mc", "speed", "gdot", "C"])
        for d in drums:
            dm, pts = d.midchord()
            for row in zip(dm, d.interp(pts, d.speed), d.interp(pts, d.gdot), d.interp(pts, d.C)):
                w.writerow(["%.6g" % d.t] + ["%.6g" % v for v in row])


def plot_midchord(drums, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(11, 3.6), sharey=True)
    for d in drums:
        dm, pts = d.midchord()
        lab = "t = %g s" % d.t
        ax[0].plot(100 * d.interp(pts, d.speed), dm, label=lab)
        ax[1].plot(d.interp(pts, d.gdot), dm, label=lab)
        ax[2].plot(d.interp(pts, d.C), dm, label=lab)
    ax[0].set_xlabel("speed |u| (cm/s)")
    ax[1].set_xlabel(r"shear rate $\dot\gamma$ (1/s)")
    ax[2].set_xlabel("small-grain concentration C")
    ax[0].set_ylabel(r"mid-chord depth $d_{mc}/R$")
    ax[0].invert_yaxis()
    for a in ax:
        a.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def plot_rates(drums, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, len(drums), figsize=(3.6 * len(drums), 3.6), sharey=True, squeeze=False)
    for a, d in zip(ax[0], drums):
        dm, pts = d.midchord()
        names = [r"$\dot C_1 = -F\nabla_g V$", r"$\dot C_2 = -V F'\nabla_g C$", r"$\dot C_3 = \nabla\cdot(D\nabla C)$"]
        for name, term in zip(names, d.rate_terms()):
            a.plot(d.interp(pts, term), dm, label=name)
        a.set_title("t = %g s" % d.t, fontsize=9)
        a.set_xlabel("rate (1/s)")
        a.grid(alpha=0.3)
    ax[0][0].set_ylabel(r"mid-chord depth $d_{mc}/R$")
    ax[0][0].invert_yaxis()
    ax[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def plot_maps(d, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 3, figsize=(12, 4))
    ms = (d.dr / (2.2 * d.R) * 3.0 * 72) ** 2  # markers about one spacing wide (points^2)
    for a, (fld, lab, cmap) in zip(ax, [(d.C, "C", "coolwarm"), (100 * d.speed, "|u| (cm/s)", "viridis"),
                                        (d.gdot, r"$\dot\gamma$ (1/s)", "magma")]):
        sc = a.scatter(d.x[:, 0] * 1e3, d.x[:, 1] * 1e3, c=fld, s=ms, cmap=cmap, linewidths=0)
        th = np.linspace(0, 2 * np.pi, 200)
        a.plot(d.R * 1e3 * np.cos(th), d.R * 1e3 * np.sin(th), "k-", lw=0.8)
        dm, pts = d.midchord()
        a.plot(pts[:, 0] * 1e3, pts[:, 1] * 1e3, "w--", lw=0.8)
        a.set_aspect("equal")
        a.set_title("%s, t = %g s" % (lab, d.t), fontsize=9)
        a.set_xlabel("x (mm)")
        fig.colorbar(sc, ax=a, shrink=0.7)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def plot_global(outdir, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    dg = snap.read_diagnostics(outdir, partial=True)
    d0 = Drum(snap.list_snapshots(outdir)[0], used_params(outdir))
    total = d0.vol.sum() * d0.width  # all the material, m^2 per unit depth in 2D, m^3 in 3D
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.4))
    ax[0].plot(dg["time"], dg["small_volume"] / total)
    ax[0].set_xlabel("t (s)")
    ax[0].set_ylabel(r"global concentration $\sum C_i V_i / \sum V_i$")
    ax[1].semilogy(dg["time"], np.maximum(np.abs(dg["small_volume_drift"]), 1e-17))
    ax[1].set_xlabel("t (s)")
    ax[1].set_ylabel(r"|relative drift of $\sum C_i V_i$|")
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


ALONG_EDGES = np.linspace(-1.0, 1.0, 21)  # --along: bins of s / R, 0.1 R wide


def write_along(drums, path):
    """--along: the surface grains along the surface line (Drum.surface_grains_along), one row a
    non-empty bin a snapshot: t, s/R, speed (m/s), height above the fitted line (dr), count."""
    with open(path, "w") as f:
        f.write("t,s_over_R,speed,height_dr,n\n")
        for d in drums:
            for sm, u, up, n in d.surface_grains_along(ALONG_EDGES):
                if n:
                    f.write("%.6g,%.6g,%.6g,%.6g,%d\n" % (d.t, sm, u, up, n))


def read_along(path, tmin=-np.inf, tmax=np.inf):
    """write_along's file back, the snapshots in [tmin, tmax] averaged per bin of ALONG_EDGES (a
    row's mean s / R lies in its bin): {bin: (s/R, speed m/s, its standard error over the
    snapshots, height dr, snapshots)}."""
    a = np.genfromtxt(path, delimiter=",", names=True, ndmin=1)
    a = a[(a["t"] >= tmin - 1e-9) & (a["t"] <= tmax + 1e-9)]
    k = np.digitize(a["s_over_R"], ALONG_EDGES) - 1
    out = {}
    for b in np.unique(k):
        m = k == b
        u = a["speed"][m]
        se = float(u.std(ddof=1) / np.sqrt(u.size)) if u.size > 1 else float("nan")
        out[int(b)] = (float(a["s_over_R"][m].mean()), float(u.mean()), se, float(a["height_dr"][m].mean()), int(u.size))
    return out


TABLE_HEAD = "%8s %9s %10s %12s %12s %10s %13s" % ("t (s)", "angle", "flatness", "max |u| mc", "seg index",
                                                     "C range", "top grains u")


def table_row(d):
    """One snapshot's line of the printed table (under TABLE_HEAD)."""
    return ("%8.3f %8.2f° %8.2f dr %9.2f cm/s %12.4f %5.3f-%5.3f %8.2f cm/s"
            % (d.t, d.angle, d.flatness, 100 * d.surface_speed(), d.segregation_index(),
               d.C.min(), d.C.max(), 100 * d.surface_grain_speed()))


def read_table(path):
    """The printed table back from a saved output: [(t s, angle deg, max |u| mc cm/s, seg index,
    top grains u cm/s)], one per snapshot line under TABLE_HEAD."""
    rows, head = [], False
    with open(path) as f:
        for line in f:
            if line.rstrip("\n") == TABLE_HEAD:
                head = True
                continue
            tok = line.split()
            if not head or len(tok) != 10 or tok[3] != "dr" or tok[-1] != "cm/s":
                if head and rows:
                    break
                continue
            rows.append((float(tok[0]), float(tok[1].rstrip("°")), float(tok[4]), float(tok[6]), float(tok[8])))
    return rows


def read_window(path, tmin, tmax):
    """The rows of read_table whose snapshot time lies in [tmin, tmax] (to 1e-9 s); exits naming the
    file where there is none."""
    rows = [r for r in read_table(path) if tmin - 1e-9 <= r[0] <= tmax + 1e-9]
    if not rows:
        raise SystemExit(f"{path}: no snapshots in [{tmin}, {tmax}] s")
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir")
    ap.add_argument("--times", type=float, nargs="+", help="snapshot times (default: all)")
    ap.add_argument("--png", help="plot file prefix")
    ap.add_argument("--slab", type=float, help="3D drum: analyse only |z - L/2| < SLAB/2 (m); default: "
                    "the whole length projected onto x-y")
    ap.add_argument("--zbins", type=int, default=8, help="3D drum: z-bins of the axial analysis (default 8)")
    ap.add_argument("--endslab", type=float, help="3D drum: width W (m) of the slabs next to the end walls and at "
                    "mid-length in the axial analysis (default 3 dr)")
    ap.add_argument("--csv", help="3D drum: write the axial analysis, one row per time, to this CSV file")
    ap.add_argument("--along", help="write the surface grains along the surface line (t, s/R, speed m/s, height "
                    "above the fitted line in dr, count; bins 0.1 R wide) to this CSV file")
    ap.add_argument("--profiles", help="write the mid-chord profiles (t, d_mc/R, speed m/s, shear rate 1/s, C; "
                    "120 points from the surface to the wall per time) to this CSV file")
    a = ap.parse_args()
    par = used_params(a.outdir)
    paths = snap.list_snapshots(a.outdir)
    if a.times:
        paths = list(dict.fromkeys(pick(paths, a.times)))  # a time past the last snapshot picks it once
    drums = [Drum(p, par, a.slab) for p in paths]
    print(TABLE_HEAD)
    for d in drums:
        print(table_row(d))
    axs = []
    if paths and int(snap.read_snapshot(paths[0]).get("Dimension", 2)) == 3:
        axs = [Axial(p, par, a.zbins, a.endslab) for p in paths]
        print("\naxial analysis (3D drum):")
        for x in axs:
            print(x.report())
        if a.csv:
            rows = [x.row() for x in axs]
            with open(a.csv, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
                w.writeheader()
                w.writerows(rows)
            print("wrote %s" % a.csv)
    if a.along:
        write_along(drums, a.along)
        print("wrote %s" % a.along)
    if a.profiles:
        write_profiles(drums, a.profiles)
        print("wrote %s" % a.profiles)
    dg = snap.read_diagnostics(a.outdir, partial=True)
    print("max |relative drift of sum C_i V_i|: %.3e" % np.abs(dg["small_volume_drift"]).max())
    if a.png:
        if axs and not a.slab:  # the rate terms of all planes projected need O(planes^2) pairs: plot the mid slab
            drums = [x.mid for x in axs]
            print("3D drum without --slab: the plots below are of the mid-length slab, W = %.1f mm" % (1e3 * axs[0].W))
        sel = drums[1:] if len(drums) > 3 and not a.times else drums
        sel = sel[-3:] if not a.times else sel
        plot_midchord(sel, a.png + "_midchord.png")
        plot_rates(sel, a.png + "_rates.png")
        plot_maps(drums[-1], a.png + "_maps.png")
        plot_global(a.outdir, a.png + "_global.png")
        print("wrote %s_{midchord,rates,maps,global}.png" % a.png)
        if axs:
            plot_axial(axs, a.png + "_axial.png")
            print("wrote %s_axial.png" % a.png)


if __name__ == "__main__":
    main()
