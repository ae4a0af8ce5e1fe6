"""Granular column collapse (inputs/collapse_2d.yml) at a CI size against the
experimental laws of two-dimensional columns (Lube, Huppert, Sparks &
Freundt 2005, Phys. Rev. E 72, 041301): runout (L_inf - L0)/L0 = 1.2 a for
a < 2.3, final height H_inf = H0 for a < 1.15 and a^(2/5) L0 above
(tools/studies/collapse_study.py, docs/validation.md "Column collapse").

L0 = 2 cm at dr = 1 mm (L0/dr = 20, as the study's aspect sweep).
  a = 0.5: the model agrees with the law: measured runout 0.97 and final
           height 0.95 of Lube's (H100); tolerance 15 % on each.
  a = 2:   the model runs out farther than the experiments: measured 1.66
           times Lube's runout and 0.76 times the final height at this
           resolution (at least 1.9 times at L0/dr 80, where the front met the
           floor's end wall; the model's static friction is atan k_mu(mu_s) =
           19.3 degrees, a lower angle than the experiments' grains, and a
           friction of 30 degrees brings it to 1.37, docs/validation.md). Held
           within 12 % of those measured ratios, so that a change of the
           collapse shows.
Lajeunesse's glass beads (inputs/collapse_2d_glass.yml: d 1.15 mm, the
mu(I) of Jop, Forterre & Pouliquen 2005), a = 2 at L0/dr = 10: measured
1.14 times Lube's runout and 0.81 times the final height (development
machine); from L0/dr 10 to 20 the runout ratio moves to 1.41 (+24 %) and
the height ratio to 0.80 (docs/validation.md). Held within 12 %, half the
runout's own resolution change, of the measured ratios.
All: the front has stopped (it moves < 5 mm/s at the end) short of the
floor's end wall (collapse_study.at_end_wall: else the runout would be the
domain's), and no material is lost.
"""
import os
import sys

from tools.studies import batch  # noqa: E402
from tools.studies import collapse_study as cs  # noqa: E402
from tests.containers import sphseg_work_args  # noqa: E402  (tests/containers.py)

# name: (runout / Lube, height / Lube) expected, tolerance (relative)
EXPECT = {"a0.5": ((1.0, 1.0), 0.15), "a2": ((1.66, 0.76), 0.12), "a2_glass_n10": ((1.14, 0.81), 0.12)}
CREEP = 0.005  # m/s


def detector_check():
    """The end-wall test on two runs of the floor before (1.5 times Lube's runout plus L0, no x_end
    recorded): a = 8 at L0/dr 20, whose front stopped 0.7 dr short of the wall (runout 12.32 L0), and
    a = 2 at L0/dr 20, whose front stopped 31 dr short of it (3.98 L0)."""
    r8, r2 = {"L0": 0.02, "dr": 0.001, "a": 8}, {"L0": 0.02, "dr": 0.001, "a": 2}
    ok = cs.at_end_wall(r8, 0.02 * (1 + 12.32)) and not cs.at_end_wall(r2, 0.02 * (1 + 3.98))
    print("%s the end-wall test: a = 8 at the wall, a = 2 short of it" % ("ok  " if ok else "FAIL"))
    return ok


def grain_front_check():
    """The grain-scale front (collapse_study.thickness_fronts) on a made deposit, bins of 2 dr from the wall
    (dr 1 mm, L0 2 cm, bin centres x = dr + 2 dr k): tops 9, 8, 6, 4, 3, 2 mm to x = 11 mm, an empty bin, then a
    lone 9-mm heap beyond it. Thicker than 5 mm: bins to x = 5 mm, its right edge 6 mm; than 2.5 mm: 10 mm; than
    10 mm: none. The heap past the gap is not the wall's deposit and is not read."""
    import numpy as np
    dr, L0 = 1e-3, 0.02
    x = np.array([1, 3, 5, 7, 9, 11, 15]) * dr
    dep = {"x": x, "top": np.array([9, 8, 6, 4, 3, 2, 9]) * 1e-3}
    f5, f25, f10 = cs.thickness_fronts(dep, dr, L0, (5e-3, 2.5e-3, 10e-3))
    ok = abs(f5 - (6e-3 - L0) / L0) < 1e-12 and abs(f25 - (10e-3 - L0) / L0) < 1e-12 and np.isnan(f10)
    print("%s the grain-scale front: %.3f, %.3f L0 (expected %.3f, %.3f), none above the deposit" % (
        "ok  " if ok else "FAIL", f5, f25, (6e-3 - L0) / L0, (10e-3 - L0) / L0))
    return ok


def merge_check(work):
    """report --merge (collapse_study.glass_kept): of an earlier glass.csv with rows x and y, a rerun of y keeps x
    as written (its numbers read back as numbers, for the chart) and drops the old y."""
    import csv
    os.makedirs(work, exist_ok=True)
    path = os.path.join(work, "glass.csv")
    row = dict(model="glass", floor="no_slip", a=4.0, n=40, E="1e5", runout=8.13, lube_runout=4.79, height=1.38,
               lube_height=1.74, runout_1_5d=float("nan"), runout_3d=7.0, creep_mm_s=0.1, wall_s="93.5", steps="41213",
               backend="gpu", end_wall=1)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, ["name"] + list(row))
        w.writeheader()
        w.writerow(dict(row, name="x")), w.writerow(dict(row, name="y"))
    kept = cs.glass_kept(path, [dict(row, name="y", runout=8.55, end_wall=0)])
    ok = ([q["name"] for q in kept] == ["x"] and kept[0]["runout"] == 8.13 and kept[0]["n"] == 40
          and kept[0]["end_wall"] == 1 and kept[0]["runout_1_5d"] != kept[0]["runout_1_5d"])
    print("%s report --merge: the row not rerun kept as written, the rerun's old row dropped" % ("ok  " if ok else "FAIL"))
    good = kept and kept[0]["flow"] == "monaghan_1"
    print("%s report --merge: a glass.csv from before the flow column reads as the scene's flow (alpha_av 1)"
          % ("ok  " if good else "FAIL"))
    return ok and good


def names_check():
    """Every case of the glass-bead sets is read back (collapse_study.glass_name) with the flow, floor, E and
    L0/dr its set gave it; the slot's cases are not glass rows."""
    want = {"lajeunesse": "monaghan_1", "lajeunesse_flow": "riemann", "lajeunesse_alpha": None}
    ok, count = True, 0
    for which, flow in want.items():
        for c in cs.cases(which):
            q = cs.glass_name(c.name)
            fl = flow or "monaghan_%g" % c.over["Flow:alpha_av"]
            ok &= q is not None and q["flow"] == fl and q["n"] == round(c.meta["L0"] / c.meta["dr"]) and (
                q["floor"] == "no_slip" and q["E"] == "1e5")
            ok &= fl == "monaghan_1" or ("Flow:alpha_av" in c.over) == fl.startswith("monaghan_")
            count += 1
    cw = cs.glass_name(cs.cases("lajeunesse_coulomb")[0].name)
    ok &= cw is not None and cw["floor"] == "coulomb" and all(cs.glass_name(c.name) is None
                                                             for c in cs.cases("lajeunesse_slot"))
    print("%s the glass sets' %d case names read back with their flow, floor, E and L0/dr" % ("ok  " if ok else "FAIL",
                                                                                           count))
    return ok


def main():
    a = sphseg_work_args()
    if not detector_check() or not grain_front_check() or not merge_check(os.path.join(a.work, "merge")) or (
            not names_check()):
        sys.exit(1)
    cases = [cs.case("a0.5", 0.5), cs.case("a2", 2), cs.glass_case(2, 10)]
    batch.run_cases_or_exit(cases, a.sphseg, a.work, limit_s=600)
    ok = True
    for c in cases:
        cs.reduce_run(os.path.join(a.work, c.name), c.meta["dr"])
        f = cs.load(a.work, c.name)
        av, L0 = c.meta["a"], c.meta["L0"]
        run, hf = (f["front"][-1] - L0) / L0, f["height_at_wall"][-1] / L0
        (want_r, want_h), tol = EXPECT[c.name]
        rr, rh = run / float(cs.lube_runout(av)), hf / float(cs.lube_height(av))
        creep = abs(f["front"][-1] - f["front"][-2]) / (f["t"][-1] - f["t"][-2])
        wall = cs.at_end_wall(dict(c.meta, L0=L0, dr=c.meta["dr"], a=av), f["front"][-1])
        good = (abs(rr / want_r - 1) <= tol and abs(rh / want_h - 1) <= tol and creep < CREEP
                and f["n"][-1] == f["n"][0] and not wall)
        if wall:
            print("FAIL %s: the front stopped at the floor's end wall (x = %.4f m): the runout is the domain's"
                  % (c.name, c.meta["x_end"]))
        ok &= good
        print("%s %s a = %g: runout %.2f L0 (Lube %.2f: ratio %.2f, expected %.2f +- %.0f %%), final height %.2f L0 "
              "(Lube %.2f: ratio %.2f, expected %.2f), front moving %.1f mm/s at t = %.2f s, %d particles" % (
                  "ok  " if good else "FAIL", c.name, av, run, cs.lube_runout(av), rr, want_r, 100 * tol, hf,
                  cs.lube_height(av), rh, want_h, 1e3 * creep, f["t"][-1], f["n"][-1]))
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
