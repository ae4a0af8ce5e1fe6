"""Granular column collapse (inputs/collapse_2d.yml) against the experimental
scaling laws of two-dimensional columns.

A column H0 high and L0 wide (a = H0 / L0) stands against a free-slip wall at
x = 0 (the symmetry plane of a column 2 L0 wide) behind a gate lifted at
Walls:gate_open; it slumps and spreads over a no-slip floor. References:

  Lube, Huppert, Sparks & Freundt (2005), Phys. Rev. E 72, 041301 (quasi-2D
  channel experiments): runout (L_inf - L0) / L0 = 1.2 a for a < 2.3 and
  1.9 a^(2/3) above; final height H_inf = H0 for a < 1.15 and
  H_inf / L0 = a^(2/5) above.
  Balmforth & Kerswell (2005), J. Fluid Mech. 538, 399: the same power laws
  (runout exponent about 2/3 in narrow channels, about 0.9 in wide ones, with
  prefactors that depend on the grains' friction; final height ~ a^0.4).

The front is the foremost x of the material that is not a lone particle (its
bin of width 2 dr holds at least two); the final height is the highest
material at the wall (x < 2 dr). The flow stops within a few sqrt(H0 / g)
(Lube et al.: about 3); runs go to 0.02 + 7 sqrt(H0 / g).

The set "lagree" runs the columns of Lagree, Staron & Popinet (2011, J. Fluid
Mech. 686, 378) at their mu(I) parameters and compares the final deposits with
the contact-dynamics (CD) deposits their paper compares with. Its fronts are
grain-scale: the foremost bin of the wall-connected deposit thicker than 1.5 d
and 3 d (what a CD deposit or an experiment can see), beside the front above,
which follows a film thinner than a grain and does not converge with dr at
these parameters (docs/validation.md, "Against contact dynamics").
The glass-bead sets (lajeunesse*) report both: the front above, and where
dr <= d the foremost deposit thicker than 1.5 and 3 bead diameters (GLASS_D).

  python3 -m tools.studies.collapse_study run --sphseg build/sphseg --out out/collapse_study [--backend gpu]
  python3 -m tools.studies.collapse_study report --out out/collapse_study [--docs docs/data/collapse]
  python3 -m tools.studies.collapse_study sheet RUN_DIR [--every K]

`sheet` reads a run's snapshots (run --keep) and prints, for each, the material ahead of the deposit
thicker than 3 d (the sheet that runs ahead of it): how many particles, how far, its lowest and mean
height over dr above the floor's face y = 0 (a particle resting on the floor sits at dr/2), the share
at the tension cut-off (sigma = 0) and its mean speed (docs/validation.md, "What runs ahead").
"""
import csv
import math
import os
import re
import sys

import numpy as np

from tools import ROOT  # noqa: E402
from tools.studies import batch  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "collapse_2d.yml")
GLASS_SCENE = os.path.join(ROOT, "inputs", "collapse_2d_glass.yml")
G = 9.81
GATE = 0.02


def lube_runout(a):
    a = np.asarray(a, float)
    return np.where(a < 2.3, 1.2 * a, 1.9 * a ** (2.0 / 3.0))


def lube_height(a):
    a = np.asarray(a, float)
    return np.where(a < 1.15, a, a ** 0.4)


# The floor past the column: 3 times Lube et al.'s runout plus 2 L0. Until 2026-11-30 it was 1.5 times
# plus L0, and the runs whose deposit reached its end wall (a >= 4, and a = 2 on a Coulomb floor) read the
# wall's place as their runout: 1.5 + L0 / law times the law (1.92 at a = 2, 1.71 at 4, 1.63 at 8).
FLOOR_LAW, FLOOR_L0 = 3.0, 2.0
OLD_FLOOR_LAW, OLD_FLOOR_L0 = 1.5, 1.0  # the floor of the runs before, to mark their results (x_end)
AT_WALL = 4  # a front within 2h + dr (h 1.5 dr) of the floor's end wall, in reach of its dummies: a bound


def x_end_of(L0, dr, runout):
    """The end wall's x: the column and the floor in whole dr (src/sim/setup.c walls_box)."""
    return (round(L0 / dr) + round(runout / dr)) * dr


def case(name, a, L0=0.02, dr=0.001, scene=SCENE, **extra):
    H0 = a * L0
    run = L0 * (FLOOR_LAW * float(lube_runout(a)) + FLOOR_L0)
    t_end = GATE + 7 * math.sqrt(H0 / G)
    over = {"Geometry:dr": dr, "Geometry:height": round(H0, 9), "Geometry:width": L0,
            "Geometry:runout": round(run, 4), "Run:t_end": round(t_end, 4), "Output:dt": 0.01,
            "Output:diag_dt": 0.01, "Run:progress_s": 1e9}
    over.update(extra)
    x_end = x_end_of(L0, dr, float(over["Geometry:runout"]))
    return batch.Case(name, scene, over, a=a, L0=L0, H0=H0, dr=dr, t_end=t_end, x_end=x_end)


def at_end_wall(r, front):
    """Whether a run's final front lies at its floor's end wall (runs.csv row r; a run from before x_end
    was recorded had the old floor)."""
    L0, dr, a = float(r["L0"]), float(r["dr"]), float(r["a"])
    x_end = float(r["x_end"]) if r.get("x_end") else x_end_of(
        L0, dr, round(L0 * (OLD_FLOOR_LAW * float(lube_runout(a)) + OLD_FLOOR_L0), 4))
    return front >= x_end - AT_WALL * dr


def bound(v, wall, digits=2):
    """A value, or a lower bound ("≥") where the floor's end wall stopped the front."""
    return ("≥ " if wall else "") + "%.*f" % (digits, v)


# Lagree, Staron & Popinet (2011): mu_s 0.32, delta mu 0.28, I0 0.4 (their Gerris example
# doc/examples/column/column.gfs and Basilisk sandbox/M1EMN/Exemples/granular.h), I with the
# continuum's own density (rho_s = rho), no-slip base, the column's axis a symmetry line; the grain
# size d over the half-width R0 = L0 of each aspect ratio, from the grain counts of the CD data.
LAGREE = {"Material:mu_s": 0.32, "Material:mu_d": 0.60, "Material:I0": 0.4, "Material:rho_s": 1500,
          "Material:yield": "mu_I"}
LAGREE_D = {0.5: 1 / 60, 1.42: 1.42 / 65, 6.26: 0.04623}  # d / R0
# The CD final deposits (Staron's contact dynamics of disks, as plotted by Lagree's Basilisk
# example granular_column.c: files Img/ShapeTime.A-01, A-04, A-03.dat), measured from the last
# output block: runout (L - R0)/R0 where the deposit is thicker than 1.5 d and 3 d, and the
# height at the axis over R0 (docs/data/collapse/lagree/README.md says how).
LAGREE_CD = {0.5: (0.91, 0.76, 0.48), 1.42: (3.36, 2.90, 0.73), 6.26: (12.28, 10.38, 1.20)}
LAGREE_N = (20, 40, 80, 160)  # L0 / dr


def lagree_case(a, n, L0=0.02, **extra):
    d = LAGREE_D[a] * L0
    over = dict(LAGREE)
    over.update({"Grains:d_small": "%.6g" % d, "Grains:d_large": "%.6g" % (d * 1.0001),
                 "Geometry:runout": round(L0 * (3 * float(lube_runout(a)) + 2), 4)})
    over.update(extra)
    c = case("a%g_%s_n%d" % (a, over["Material:yield"], n), a, L0=L0, dr=L0 / n, **over)
    c.meta["d"] = d
    return c


# Lajeunesse's glass beads (inputs/collapse_2d_glass.yml: d 1.15 mm, Jop, Forterre & Pouliquen's mu(I)) and
# the constant friction tan 27.4 deg (the beads' avalanche angle) that Rousseau et al. (2023) recommend as
# the cross-check; the aspect ratios and resolutions the issue asks for (docs/validation.md).
GLASS_MODELS = {"glass": {}, "const": {"Material:mu_s": 0.5184, "Material:mu_d": 0.5184}}
GLASS_A = (0.5, 2, 4, 8)
# The floor with the beads' wall friction angle, 24.8 deg (Kumar's thesis, ch. 4, from Lajeunesse et al.
# 2004), as a Coulomb wall (Walls:slip coulomb) in place of the scene's no-slip floor.
COULOMB_FLOOR = {"Walls:slip": "coulomb", "Walls:mu_w": 0.4621}
# The same floor with its friction on each particle (Walls:coulomb_force particles, set lajeunesse_contact): the
# dummies' normal force, whatever term carries it, times mu_w resists the slip of a sheet at sigma = 0 too
CONTACT_FLOOR = dict(COULOMB_FLOOR, **{"Walls:coulomb_force": "particles"})
# L0 / dr (80: a = 0.5 and 2, 160: a = 0.5, on the development machine; the rest of 80 and 160 want a GPU)
GLASS_N = (10, 20, 40, 80, 160)
# The beads' diameter, m (the scene's Grains:d_small; Kumar's table): the grain-scale fronts of the report, the
# foremost bin of the wall-connected deposit thicker than 1.5 d and 3 d (as the Lagree set's), where the spacing
# resolves a grain's thickness (dr <= d: L0/dr 20 and finer; at 10, dr = 2 mm, one particle is thicker than 1.5 d)
GLASS_D = 1.15e-3
# The quasi-2D channel (set lajeunesse_slot): the 3D column between end walls z = 0 and z = W (Walls:end_slip), free
# slip (a 2D column's equal) or the beads' Coulomb friction tan 24.8 deg on the glass; a = 2 and 0.5 at L0/dr 10
# and 20 (W of 5 to 40 particles). The back wall x = 0 (the symmetry plane) and the gate stay free slip.
SLOT_W = (0.01, 0.02, 0.04)
SLOT_A = (2, 0.5)
SLOT_N = (10, 20, 40)  # at 40 only a = 2, W 1 and 2 cm were run (--only; docs/data/collapse/glass/README.md)
SLOT_SLIPS = (("fs", "free_slip"), ("cw", "coulomb"))
# The numerical dissipation's share (sets lajeunesse_flow, lajeunesse_alpha). The scene keeps the paper's kind of
# stabilisation, Monaghan's artificial viscosity at alpha_av 1, whose viscosity alpha c h falls with dr; the drum
# scenes' flow (Riemann, bed damping, corrected gradient, Fickian shifting; docs/method.md) dissipates less; and
# Monaghan's at alpha_av 0.3 and 0.1 at a = 2. The tag names each in the run's name and the report's "flow".
FLOW_SCENES = {"Flow:stabilization": "riemann", "Flow:bed_damping": 1, "Flow:gradient_correction": "on",
               "Flow:shifting": "fickian"}
FLOW_ALPHAS = (0.3, 0.1)


def glass_case(a, n, model="glass", L0=0.02, tag="", **extra):
    over = dict(GLASS_MODELS[model])
    over.update(extra)
    c = case("a%g_%s_n%d%s" % (a, model, n, tag), a, L0=L0, dr=L0 / n, scene=GLASS_SCENE, **over)
    c.meta["model"] = model
    return c


def cases(which):
    c = []
    if which == "lagree":  # not in "full": the L0/dr = 160 runs want a GPU
        for a in sorted(LAGREE_D):
            for n in LAGREE_N:
                c.append(lagree_case(a, n))
    if which == "lajeunesse":  # not in "full": the L0/dr = 40 runs want a GPU
        c += [glass_case(a, n) for n in GLASS_N for a in GLASS_A]
    if which == "lajeunesse_const":
        c += [glass_case(a, n, "const") for n in GLASS_N for a in GLASS_A]
    if which == "lajeunesse_coulomb":  # the floor with the beads' wall friction, tan 24.8 deg (Kumar's table)
        c += [glass_case(a, n, m, tag="_cw", **COULOMB_FLOOR) for m in ("glass", "const") for n in GLASS_N
              for a in GLASS_A]
    if which == "lajeunesse_contact":  # that floor's friction on the particles (Walls:coulomb_force particles)
        c += [glass_case(a, n, m, tag="_ct", **CONTACT_FLOOR) for m in ("glass", "const") for n in GLASS_N
              for a in GLASS_A]
    if which == "lajeunesse_slot":
        c += [glass_case(a, n, tag="_slot%g_%s" % (W * 1e3, t), **{"Geometry:dim": 3, "Geometry:depth": W,
                                                                  "Walls:end_slip": slip, "Walls:mu_w": 0.4621})
              for n in SLOT_N for a in SLOT_A for W in SLOT_W for t, slip in SLOT_SLIPS]
    if which == "lajeunesse_flow":  # the drum scenes' flow in place of Monaghan's alpha_av 1
        c += [glass_case(a, n, tag="_flow", **FLOW_SCENES) for n in GLASS_N for a in GLASS_A]
    if which == "lajeunesse_alpha":  # Monaghan's viscosity weaker, at a = 2
        c += [glass_case(2, n, tag="_av%g" % al, **{"Flow:alpha_av": al}) for al in FLOW_ALPHAS for n in GLASS_N]
    if which == "lajeunesse_E":  # the stiffness is numerical: E x 10 at the fastest column
        c += [glass_case(a, n, tag="_E1e6", **{"Material:E": 1e6}) for a, n in ((2, 10), (2, 20), (2, 40), (8, 20))]
    if which in ("full", "aspect"):
        for a in (0.5, 1, 2, 3, 5, 7, 10):
            c.append(case("a%g" % a, a))
    if which in ("full", "yield"):
        # Material:yield mu_I (onset at atan mu_s = 20.9 degrees) against the scene's drucker_prager (19.3)
        for a in (1, 2, 5):
            c.append(case("a%g_muI" % a, a, **{"Material:yield": "mu_I"}))
    if which in ("full", "resolution"):
        for dr in (0.002, 0.0005, 0.00025):  # dr 1 mm is a2 above
            c.append(case("a2_dr%g" % (dr * 1e3), 2, dr=dr))
    return c


def reduce_run(outdir, dr, keep=False):
    from tools.analysis import snap
    rows, last = [], None
    for p in snap.list_snapshots(outdir):
        s = snap.read_snapshot(p)
        mat = np.asarray(s["Kind"]) == snap.MATERIAL
        xy = np.asarray(s["Coordinates"])[mat, :2]
        v = np.asarray(s["Velocities"])[mat, :2]
        b = np.floor(xy[:, 0] / (2 * dr)).astype(int)
        cnt = np.bincount(b - b.min())
        ok = cnt[b - b.min()] >= 2
        front = xy[ok, 0].max()
        wall = xy[xy[:, 0] < 2 * dr, 1]
        rows.append((float(s["Time"]), front, wall.max() if wall.size else 0.0,
                     float(np.sqrt((v ** 2).sum(1)).max()), int(mat.sum())))
        last = xy
        if not keep:
            os.remove(p)
    batch.write_csv(os.path.join(outdir, "front.csv"), ["t", "front", "height_at_wall", "max_speed", "n"], rows)
    if last is not None:  # the final deposit's surface
        x, top = deposit_top(last, dr)
        batch.write_csv(os.path.join(outdir, "deposit.csv"), ["x", "top"], [[a, b] for a, b in zip(x, top)])
    return len(rows)


def deposit_top(xy, dr):
    """A deposit's surface: per occupied bin of 2 dr along x, its centre and the top of its highest material
    particle (y + dr/2); deposit.csv's columns x and top, which thickness_fronts reads."""
    b = np.floor(xy[:, 0] / (2 * dr)).astype(int)
    ks = np.unique(b)
    return [(k + 0.5) * 2 * dr for k in ks], [xy[b == k, 1].max() + 0.5 * dr for k in ks]


def thickness_fronts(deposit, dr, L0, thresholds):
    """Runout (L - L0)/L0 of the deposit connected to the wall (deposit.csv: bins of 2 dr, top of the
    highest particle + dr/2), at the right edge of its foremost bin whose top exceeds each threshold."""
    x, top = np.atleast_1d(deposit["x"]), np.atleast_1d(deposit["top"])
    k = np.round((x - dr) / (2 * dr)).astype(int)  # bin index (x is the bin's centre)
    o = np.argsort(k)
    k, x, top = k[o], x[o], top[o]
    gap = np.nonzero(np.diff(k) > 1)[0]
    end = gap[0] + 1 if len(gap) else len(k)  # the first empty bin ends the wall-connected deposit
    out = []
    for thr in thresholds:
        hit = np.nonzero(top[:end] > thr)[0]
        out.append((x[hit[-1]] + dr - L0) / L0 if len(hit) else float("nan"))
    return out


def lagree_table(runs, where, P):
    names = [n for n in runs if re.fullmatch(r"a[0-9.]+_(mu_I|drucker_prager)_n[0-9]+", n)]
    if not names:
        return
    P("")
    P("| a | yield | L0/dr | runout (front above) | runout, h > 1.5 d | CD | ratio | runout, h > 3 d | CD | ratio | "
      "H_inf/R0 (top) | CD | ratio | wall (s) | backend |")
    P("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    key = lambda n: (float(runs[n]["a"]), n.split("_n")[0], float(runs[n]["L0"]) / float(runs[n]["dr"]))
    for n in sorted(names, key=key):
        r, f = runs[n], load(where[n], n)
        av, L0, dr = float(r["a"]), float(r["L0"]), float(r["dr"])
        if av not in LAGREE_CD:
            continue
        d = LAGREE_D[av] * L0
        dep = np.genfromtxt(os.path.join(where[n], n, "deposit.csv"), delimiter=",", names=True)
        f15, f3 = thickness_fronts(dep, dr, L0, (1.5 * d, 3 * d))
        x, top = np.atleast_1d(dep["x"]), np.atleast_1d(dep["top"])
        h = top[x < 2 * dr].max() / L0 if np.any(x < 2 * dr) else float("nan")
        cd = LAGREE_CD[av]
        P("| %g | %s | %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.3f | %.2f | %.2f | %s | %s |" % (
            av, n.split("_n")[0].split("_", 1)[1], round(L0 / dr), (f["front"][-1] - L0) / L0, f15, cd[0], f15 / cd[0],
            f3, cd[1], f3 / cd[1], h, cd[2], h / cd[2], r["wall_s"], r.get("backend", "")))


def glass_name(n):
    """What a glass-bead run's name (glass_case) says: its friction model, floor, L0/dr, E and flow; None for
    another run's (the slot's: slot_report)."""
    m = re.fullmatch(r"a([0-9.]+)_(glass|const)_n([0-9]+)(_E1e6)?(_cw|_ct)?(_flow|_av[0-9.]+)?", n)
    if not m:
        return None
    floor = {"_cw": "coulomb", "_ct": "contact"}.get(m.group(5), "no_slip")
    return dict(model=m.group(2), floor=floor, n=int(m.group(3)),
                E="1e6" if m.group(4) else "1e5",
                flow="riemann" if m.group(6) == "_flow" else "monaghan_" + (m.group(6)[3:] if m.group(6) else "1"))


def glass_rows(runs, where):
    """One row per glass-bead run: its final runout and height against Lube et al.'s laws."""
    rows = []
    for n in runs:
        m = glass_name(n)
        if not m:
            continue
        r, f = runs[n], load(where[n], n)
        if runs[n]["rc"] != "0" or f["t"][-1] < float(r["t_end"]) - 0.011:  # stopped early (limit, signal): partial
            continue
        av, L0, dr = float(r["a"]), float(r["L0"]), float(r["dr"])
        run, hf = (f["front"][-1] - L0) / L0, f["height_at_wall"][-1] / L0
        creep = (f["front"][-1] - f["front"][-2]) / (f["t"][-1] - f["t"][-2]) * 1e3
        g15 = g3 = float("nan")  # grain-scale fronts (GLASS_D), where dr resolves a grain
        if dr <= GLASS_D:
            dep = np.genfromtxt(os.path.join(where[n], n, "deposit.csv"), delimiter=",", names=True)
            g15, g3 = thickness_fronts(dep, dr, L0, (1.5 * GLASS_D, 3 * GLASS_D))
        rows.append(dict(name=n, model=m["model"], floor=m["floor"], flow=m["flow"], a=av, n=m["n"], E=m["E"],
                         runout=run, lube_runout=float(lube_runout(av)), height=hf, lube_height=float(lube_height(av)),
                         runout_1_5d=g15, runout_3d=g3,
                         creep_mm_s=creep, wall_s=r["wall_s"], steps=r["steps"], backend=r.get("backend", ""),
                         end_wall=int(at_end_wall(r, f["front"][-1]))))
    return sorted(rows, key=glass_order)


def glass_order(q):
    return q["floor"], q["model"] != "glass", q["E"], q["flow"] != "monaghan_1", q["flow"], q["n"], q["a"]


def glass_label(model, floor, flow="monaghan_1"):
    return ("mu(I)" if model == "glass" else "tan 27.4") + {"coulomb": ", Coulomb floor", "contact": ", Coulomb floor "
                                                            "on the particles"}.get(floor, "") + (
        "" if flow == "monaghan_1" else ", the scenes' flow" if flow == "riemann" else
        ", alpha_av " + flow.split("_")[1])


GLASS_FLOATS = ("a", "runout", "lube_runout", "height", "lube_height", "runout_1_5d", "runout_3d", "creep_mm_s")


def glass_kept(path, rows):
    """The rows of an earlier glass.csv whose runs are not among rows (report --merge: some cases rerun)."""
    if not os.path.exists(path):
        return []
    have, kept = {q["name"] for q in rows}, []
    with open(path) as f:
        for q in csv.DictReader(f):
            if q["name"] not in have:
                q.update({k: float(q[k]) for k in GLASS_FLOATS})
                q.update(n=int(q["n"]), end_wall=int(q["end_wall"]))
                q.setdefault("flow", "monaghan_1")  # a glass.csv from before the flow column
                kept.append(q)
    return kept


def glass_report(runs, where, P, docs, merge=False):
    """The glass-bead sets: a table, glass.csv (in the --docs folder) and the chart of runout and height against a;
    with merge, glass.csv's rows of runs not given stay."""
    rows = glass_rows(runs, where)
    if merge:
        rows = sorted(rows + glass_kept(os.path.join(docs, "glass.csv"), rows), key=glass_order)
    if not rows:
        return
    import matplotlib.pyplot as plt
    os.makedirs(docs, exist_ok=True)
    head = list(rows[0])
    batch.write_csv(os.path.join(docs, "glass.csv"), head, [[q[k] for k in head] for q in rows])
    P("")
    P("| friction (floor: no slip unless Coulomb, tan 24.8) | E (Pa) | a | L0/dr | runout (L_inf - L0)/L0 | Lube 2005 | ratio | "
      "runout, h > 1.5 d | ratio | runout, h > 3 d | ratio | H_inf/L0 | Lube 2005 | ratio | "
      "front moving at t_end (mm/s) | wall (s) | backend |")
    P("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")

    def grain(v, q):  # a grain-scale front and its ratio to the law ("-" where dr > d)
        if math.isnan(v):
            return "- | -"
        return "%s | %s" % (bound(v, q["end_wall"]), bound(v / q["lube_runout"], q["end_wall"]))
    for q in rows:  # "≥": the front stopped at the floor's end wall
        P("| %s | %s | %g | %d | %s | %.2f | %s | %s | %s | %.2f | %.2f | %.2f | %.1f | %s | %s |" % (
            glass_label(q["model"], q["floor"], q["flow"]), q["E"], q["a"], q["n"], bound(q["runout"], q["end_wall"]),
            q["lube_runout"], bound(q["runout"] / q["lube_runout"], q["end_wall"]), grain(q["runout_1_5d"], q),
            grain(q["runout_3d"], q), q["height"], q["lube_height"],
            q["height"] / q["lube_height"], q["creep_mm_s"], q["wall_s"], q["backend"]))
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.3))
    ax = [ax[0], ax[2], ax[1]]  # runout, height, grain-scale runout (drawn between them)
    aa = np.linspace(0.4, 10, 200)
    ax[0].loglog(aa, lube_runout(aa), "k-", label="Lube et al. 2005")
    ax[1].loglog(aa, lube_height(aa), "k-", label="Lube et al. 2005")
    bounds = False
    for k, (model, floor) in enumerate((("glass", "no_slip"), ("const", "no_slip"), ("glass", "coulomb"),
                                        ("const", "coulomb"))):
        for j, nn in enumerate(GLASS_N):
            sel = [q for q in rows if q["model"] == model and q["floor"] == floor and q["n"] == nn and q["E"] == "1e5"
                   and q["flow"] == "monaghan_1"]
            if not sel:
                continue
            st = dict(marker="os^v"[k], ls="none", color="C%d" % j, mfc="none" if k % 2 else "C%d" % j,
                      label="%s, L0/dr %d" % (glass_label(model, floor), nn))
            ax[0].loglog([q["a"] for q in sel], [q["runout"] for q in sel], **st)
            ax[1].loglog([q["a"] for q in sel], [q["height"] for q in sel], **st)
            g = [q for q in sel if not math.isnan(q["runout_1_5d"]) and not q["end_wall"]]
            if g:
                ax[2].loglog([q["a"] for q in g], [q["runout_1_5d"] for q in g], **st)
            b = [q for q in sel if q["end_wall"]]  # a lower bound: the front stopped at the floor's end wall
            if b:
                ax[0].loglog([q["a"] for q in b], [q["runout"] for q in b], ls="none", color="k", ms=10,
                             marker="$\\uparrow$", label=None if bounds else "a bound (the floor's end wall)")
                bounds = True
    ax[2].loglog(aa, lube_runout(aa), "k-", label="Lube et al. 2005")
    for x in ax:
        law = lube_height(aa) if x is ax[1] else lube_runout(aa)
        x.fill_between(aa, 0.85 * law, 1.15 * law, color="0.85", label="law +- 15 %")
        x.set_xlabel("a = H0 / L0"), x.legend(fontsize=7)
    ax[0].set_ylabel("(L$_\\infty$ - L0) / L0"), ax[1].set_ylabel("H$_\\infty$ / L0")
    ax[2].set_ylabel("(L$_\\infty$ - L0) / L0, deposit thicker than 1.5 d")
    ax[0].set_title("glass beads, d 1.15 mm, L0 2 cm: runout (last particle)")
    ax[1].set_title("final height at the wall")
    ax[2].set_title("runout where the deposit is thicker than 1.5 d\n"
                    "(L0/dr 20 and finer, where dr <= d; runs at the end wall left out)")
    fig.tight_layout()
    fig.savefig(os.path.join(docs, "validation_collapse_glass.png"), dpi=110)
    plt.close(fig)
    dissipation_chart(rows, docs)
    floor_chart(rows, docs)


def floor_chart(rows, docs):
    """The floor's friction (sets lajeunesse, lajeunesse_coulomb, lajeunesse_contact): the runout over Lube's law
    against L0/dr for each a, under mu(I) (E 1e5, Monaghan's alpha 1), on the no-slip floor, the Coulomb floor
    through its dummies and the Coulomb floor on the particles (Walls:coulomb_force particles); the last
    particle's and the deposit's thicker than 1.5 d; floors.png in the --docs folder."""
    sel = [q for q in rows if q["model"] == "glass" and q["E"] == "1e5" and q["flow"] == "monaghan_1"]
    if not any(q["floor"] == "contact" for q in sel):
        return
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.2), sharey=True)
    styles = {"no_slip": ("-", "o", "no-slip floor"), "coulomb": (":", "s", "Coulomb floor, dummies"),
              "contact": ("--", "^", "Coulomb floor, on the particles")}
    for j, av in enumerate(GLASS_A):
        for floor, (ls, mk, name) in styles.items():
            q = sorted((q for q in sel if q["a"] == av and q["floor"] == floor and not q["end_wall"]),
                       key=lambda q: q["n"])
            if not q:
                continue
            lab = "a = %g, %s" % (av, name)
            ax[0].semilogx([r["n"] for r in q], [r["runout"] / r["lube_runout"] for r in q], ls=ls, marker=mk,
                           color="C%d" % j, label=lab)
            g = [r for r in q if not math.isnan(r["runout_1_5d"])]
            ax[1].semilogx([r["n"] for r in g], [r["runout_1_5d"] / r["lube_runout"] for r in g], ls=ls, marker=mk,
                           color="C%d" % j, label=lab)
    for x in ax:
        x.axhspan(0.85, 1.15, color="0.88"), x.axhline(1, color="k", lw=0.6)
        x.set_xlabel("L0 / dr")
    ax[0].set_ylabel("runout / Lube et al. 2005")
    ax[0].set_title("last particle"), ax[1].set_title("deposit thicker than 1.5 d")
    ax[1].legend(fontsize=6, ncol=2)
    fig.suptitle("glass beads, mu(I): the floor's friction (Coulomb tan 24.8 deg)", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(docs, "floors.png"), dpi=110)
    plt.close(fig)


def dissipation_chart(rows, docs):
    """The numerical dissipation's share (sets lajeunesse_flow, lajeunesse_alpha): the runout over Lube's law
    against L0/dr for each a and flow (mu(I), no-slip floor, E 1e5), the last particle's and the deposit's thicker
    than 3 d; dissipation.png in the --docs folder."""
    sel = [q for q in rows if q["model"] == "glass" and q["floor"] == "no_slip" and q["E"] == "1e5"]
    if not any(q["flow"] != "monaghan_1" for q in sel):
        return
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    flows = sorted({q["flow"] for q in sel}, key=lambda f: (f != "monaghan_1", f))
    for j, av in enumerate(sorted({q["a"] for q in sel})):
        for k, fl in enumerate(flows):
            s = sorted((q for q in sel if q["a"] == av and q["flow"] == fl), key=lambda q: q["n"])
            if len(s) < 2:
                continue
            st = dict(marker="os^v"[k % 4], ls="-:--"[0 if fl == "riemann" else 1 if fl == "monaghan_1" else 2],
                      color="C%d" % j, label="a = %g, %s" % (av, glass_label("glass", "no_slip", fl)[7:] or "alpha_av 1"))
            ax[0].semilogx([q["n"] for q in s], [q["runout"] / q["lube_runout"] for q in s], **st)
            g = [q for q in s if not math.isnan(q["runout_3d"])]
            ax[1].semilogx([q["n"] for q in g], [q["runout_3d"] / q["lube_runout"] for q in g], **st)
    from matplotlib.ticker import NullFormatter, ScalarFormatter
    for x in ax:
        x.set_xticks(GLASS_N)
        x.xaxis.set_major_formatter(ScalarFormatter())
        x.xaxis.set_minor_formatter(NullFormatter())
        x.axhline(1, color="k", lw=0.6)
        x.axhspan(0.85, 1.15, color="0.9")
        x.set_xlabel("L0 / dr"), x.legend(fontsize=6)
    ax[0].set_ylabel("runout / Lube et al. (2005), last particle")
    ax[1].set_ylabel("runout / Lube et al. (2005), deposit thicker than 3 d")
    ax[0].set_title("glass beads, mu(I), no-slip floor: the stabilisation's share", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(docs, "dissipation.png"), dpi=110)
    plt.close(fig)


def slot_report(runs, where, P, docs):
    """The quasi-2D channel (set lajeunesse_slot): per a, L0/dr and W, the runout and height between free-slip and
    Coulomb end walls, their ratios to Lube et al.'s laws, and the side walls' share (Coulomb over free slip - 1);
    slot.csv in the --docs folder."""
    rows = {}
    for n in runs:
        m = re.fullmatch(r"a([0-9.]+)_glass_n([0-9]+)_slot([0-9.]+)_(fs|cw)", n)
        if not m or runs[n]["rc"] != "0":
            continue
        r, f = runs[n], load(where[n], n)
        if f["t"][-1] < float(r["t_end"]) - 0.011:
            continue
        L0 = float(r["L0"])
        rows.setdefault((float(m.group(1)), int(m.group(2)), float(m.group(3))), {})[m.group(4)] = (
            (f["front"][-1] - L0) / L0, f["height_at_wall"][-1] / L0, int(at_end_wall(r, f["front"][-1])),
            r.get("backend", ""), float(r["H0"]))
    out = []
    for (av, nn, wmm), v in sorted(rows.items()):
        if "fs" not in v or "cw" not in v:
            continue
        (rf, hf, ef, be, H0), (rc, hc, ec, _, _) = v["fs"], v["cw"]
        out.append(dict(a=av, n=nn, W_mm=wmm, W_over_H0=wmm * 1e-3 / H0, runout_free=rf, runout_coulomb=rc,
                        lube_runout=float(lube_runout(av)), share_runout_pct=100 * (rc / rf - 1), height_free=hf,
                        height_coulomb=hc, lube_height=float(lube_height(av)), share_height_pct=100 * (hc / hf - 1),
                        end_wall=ef | ec, backend=be))
    if not out:
        return
    os.makedirs(docs, exist_ok=True)
    batch.write_csv(os.path.join(docs, "slot.csv"), list(out[0]), [list(q.values()) for q in out])
    P("")
    P("| a | L0/dr | W (mm) | W/H0 | runout / law, free-slip ends | Coulomb ends | Coulomb / free - 1 | "
      "H_inf / law, free | Coulomb | Coulomb / free - 1 | backend |")
    P("|---|---|---|---|---|---|---|---|---|---|---|")
    for q in out:
        P("| %g | %d | %g | %.2f | %s | %s | %+.1f %% | %.2f | %.2f | %+.1f %% | %s |" % (
            q["a"], q["n"], q["W_mm"], q["W_over_H0"], bound(q["runout_free"] / q["lube_runout"], q["end_wall"]),
            bound(q["runout_coulomb"] / q["lube_runout"], q["end_wall"]), q["share_runout_pct"],
            q["height_free"] / q["lube_height"], q["height_coulomb"] / q["lube_height"], q["share_height_pct"],
            q["backend"]))
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
    for j, av in enumerate(sorted({q["a"] for q in out})):
        for k, nn in enumerate(sorted({q["n"] for q in out})):
            sel = sorted((q for q in out if q["a"] == av and q["n"] == nn), key=lambda q: q["W_over_H0"])
            if not sel:
                continue
            st = dict(marker="os^"[k % 3], color="C%d" % j, label="a = %g, L0/dr %d" % (av, nn))
            ax[0].plot([q["W_over_H0"] for q in sel], [q["share_runout_pct"] for q in sel], **st)
            ax[1].plot([q["W_over_H0"] for q in sel], [q["share_height_pct"] for q in sel], **st)
    for x, what in zip(ax, ("runout", "final height")):
        x.set_xscale("log")
        x.axhline(0, color="k", lw=0.5)
        x.set_xlabel("W / H0 (W: the channel's width)")
        x.set_ylabel("%s, Coulomb / free-slip end walls - 1, %%" % what)
        x.legend(fontsize=7)
    ax[0].set_title("the side walls' share: runout (glass beads, mu_w = tan 24.8 deg)", fontsize=9)
    ax[1].set_title("final height at the back wall", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(docs, "slot.png"), dpi=110)
    plt.close(fig)


def reduce_done(a, c, rec):
    d = os.path.join(a.out, c.name)
    if os.path.isdir(d):
        print("%s: %d snapshots reduced" % (c.name, reduce_run(d, float(c.over["Geometry:dr"]), a.keep)), flush=True)


def load(out, name):
    return np.genfromtxt(os.path.join(out, name, "front.csv"), delimiter=",", names=True)


def cmd_report(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs, where = batch.load_runs(a.out, "front.csv")
    lines = []
    P = lines.append
    asp = sorted((n for n in runs if re.fullmatch(r"a[0-9.]+", n)), key=lambda n: float(runs[n]["a"]))
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.3))
    if asp:
        P("| a | L0/dr | runout (L_inf - L0)/L0 | Lube 2005 | ratio | H_inf/L0 | Lube 2005 | ratio | "
          "front still moving at t_end (mm/s) | wall (s) | backend |")
        P("|---|---|---|---|---|---|---|---|---|---|---|")
        A, R, Hf = [], [], []
        for n in asp:
            r, f = runs[n], load(where[n], n)
            av, L0 = float(r["a"]), float(r["L0"])
            run, hf = (f["front"][-1] - L0) / L0, f["height_at_wall"][-1] / L0
            creep = (f["front"][-1] - f["front"][-2]) / (f["t"][-1] - f["t"][-2]) * 1e3
            A.append(av), R.append(run), Hf.append(hf)
            wall = at_end_wall(r, f["front"][-1])  # "≥": the front stopped at the floor's end wall
            P("| %g | %d | %s | %.2f | %s | %.2f | %.2f | %.2f | %.1f | %s | %s |" % (
                av, round(L0 / float(r["dr"])), bound(run, wall), lube_runout(av), bound(run / lube_runout(av), wall),
                hf, lube_height(av), hf / lube_height(av), creep, r["wall_s"], r.get("backend", "")))
        aa = np.linspace(0.4, 11, 200)
        ax[0].loglog(aa, lube_runout(aa), "k-", label="Lube et al. 2005")
        ax[0].loglog(A, R, "o", label="SPH, L0/dr = 20")
        ax[0].set_xlabel("a = H0 / L0"), ax[0].set_ylabel("(L$_\\infty$ - L0) / L0"), ax[0].legend()
        ax[1].loglog(aa, lube_height(aa), "k-", label="Lube et al. 2005")
        ax[1].loglog(A, Hf, "o", label="SPH")
        ax[1].set_xlabel("a"), ax[1].set_ylabel("H$_\\infty$ / L0"), ax[1].legend()
        for n in asp:
            r, f = runs[n], load(where[n], n)
            L0, H0 = float(r["L0"]), float(r["H0"])
            ax[2].plot((f["t"] - GATE) / math.sqrt(H0 / G), (f["front"] - L0) / L0 / lube_runout(float(r["a"])),
                       label="a = %g" % float(r["a"]))
        ax[2].set_xlim(0, 7), ax[2].axhline(1, color="k", lw=0.6)
        ax[2].set_xlabel("(t - t_gate) / sqrt(H0/g)"), ax[2].set_ylabel("front (L - L0)/L0 over Lube's final runout")
        ax[2].legend(fontsize=7)
    if asp:
        fig.tight_layout()
        fig.savefig(os.path.join(a.docs, "validation_collapse.png"), dpi=110)
    plt.close(fig)
    res = [n for n in runs if re.fullmatch(r"a2(_dr[0-9.]+)?", n)]
    res = sorted(res, key=lambda n: -float(runs[n]["dr"]))
    if res:
        P("")
        P("| a = 2, dr (mm) | L0/dr | particles | runout | H_inf/L0 | change of the runout from the next coarser | "
          "wall (s) | steps | backend |")
        P("|---|---|---|---|---|---|---|---|---|")
        prev, dh, de = None, [], []
        for n in res:
            r, f = runs[n], load(where[n], n)
            L0 = float(r["L0"])
            run = (f["front"][-1] - L0) / L0
            P("| %g | %d | %s | %s | %.3f | %s | %s | %s | %s |" % (
                float(r["dr"]) * 1e3, round(L0 / float(r["dr"])), r["material"],
                ("≥ %.3f" if at_end_wall(r, f["front"][-1]) else "%.3f") % run, f["height_at_wall"][-1] / L0,
                "%+.3f" % (run - prev) if prev is not None else "-", r["wall_s"], r["steps"], r.get("backend", "")))
            if prev is not None:
                dh.append(float(r["dr"])), de.append(abs(run - prev))
            prev = run
        P("")
        P("observed order of the runout's change between resolutions: %.2f" % batch.observed_order(dh, de))
        fig, ax = plt.subplots(figsize=(6, 3.5))
        for n in res:
            r = runs[n]
            d = np.genfromtxt(os.path.join(where[n], n, "deposit.csv"), delimiter=",", names=True)
            ax.plot(d["x"] / float(r["L0"]), d["top"] / float(r["L0"]), label="dr %g mm" % (float(r["dr"]) * 1e3))
        ax.set_xlabel("x / L0"), ax.set_ylabel("deposit surface / L0"), ax.set_title("a = 2, final deposit")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(a.docs, "validation_collapse_deposit.png"), dpi=110)
    lagree_table(runs, where, P)
    glass_report(runs, where, P, a.docs, getattr(a, "merge", False))
    slot_report(runs, where, P, a.docs)
    batch.report_tables(a, lines)


def sheet_rows(snapshot, dr, L0, d=GLASS_D):
    """The sheet ahead of the deposit thicker than 3 d (thickness_fronts, as the table's h > 3 d) in one
    snapshot (snap.read_snapshot's dict): None when under 3 particles lie ahead, else (t, the 3-d deposit's
    front x in m, the sheet's particle count, its foremost x in m, its lowest and mean y over dr, its share at
    sigma = 0, its mean speed along x in m/s)."""
    from tools.analysis import snap
    mat = np.asarray(snapshot["Kind"]) == snap.MATERIAL
    x = np.asarray(snapshot["Coordinates"])[mat]
    sig = np.asarray(snapshot["Stress"])[mat]
    u = np.asarray(snapshot["Velocities"])[mat, 0]
    bx, top = deposit_top(x, dr)
    f3 = thickness_fronts({"x": np.array(bx), "top": np.array(top)}, dr, L0, (3 * d,))[0]
    xf = L0 * (1 + f3) if not math.isnan(f3) else 0.0
    ahead = x[:, 0] > xf
    if ahead.sum() < 3:
        return None
    apex = np.all(sig[ahead] == 0, axis=1)
    y = x[ahead, 1] / dr
    return (float(snapshot["Time"]), xf, int(ahead.sum()), float(x[ahead, 0].max()), float(y.min()),
            float(y.mean()), float(apex.mean()), float(u[ahead].mean()))


def cmd_sheet(argv):
    import argparse
    import yaml
    from tools.analysis import snap
    ap = argparse.ArgumentParser(prog="collapse_study sheet", description="the sheet ahead of the deposit thicker "
                                 "than 3 d, snapshot by snapshot (a run kept with run --keep)")
    ap.add_argument("run", help="a run's folder (its snapshots and used_params.yml)")
    ap.add_argument("--every", type=int, default=4, help="every K-th snapshot (default 4)")
    ap.add_argument("--d", type=float, default=GLASS_D, help="grain diameter, m (default the glass beads')")
    a = ap.parse_args(argv)
    with open(os.path.join(a.run, "used_params.yml")) as f:
        par = yaml.safe_load(f)
    dr, L0 = float(par["Geometry"]["dr"]), float(par["Geometry"]["width"])
    print("t (s) | deposit > 3 d to (L0) | sheet: particles | to (L0) | lowest y/dr | mean y/dr | at sigma = 0 | u (m/s)")
    for p in snap.list_snapshots(a.run)[::a.every]:
        r = sheet_rows(snap.read_snapshot(p), dr, L0, a.d)
        if r:
            t, xf, n, xs, ylo, ym, apex, u = r
            print("%.3f | %.2f | %d | %.2f | %.2f | %.2f | %.2f | %.3f" % (
                t, (xf - L0) / L0, n, (xs - L0) / L0, ylo, ym, apex, u))


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["sheet"]:
        return cmd_sheet(argv[1:])
    batch.study_main(__doc__, ("aspect", "yield", "resolution", "lagree", "lajeunesse", "lajeunesse_const", "lajeunesse_E",
                                  "lajeunesse_flow", "lajeunesse_alpha",
                                  "lajeunesse_coulomb", "lajeunesse_contact", "lajeunesse_slot"), cases, reduce_done, cmd_report, "collapse", argv=argv,
                     merge="keep glass.csv's rows (in --docs) of the glass-bead runs not in --out: a rerun of some cases")


if __name__ == "__main__":
    main()
