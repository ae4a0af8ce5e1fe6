#!/usr/bin/env python3
"""The planner of tools/studies/time_to_solution.py (plan) on a table whose answers are known.

Synthetic rows at dr 0.5 and 0.25 mm: the planner must take the cheapest row
within the tolerance on both errors at the measured spacing nearest above or at
the asked one, scale its hours as dr^-4, refuse a spacing coarser than every
measured one, and say so when no row is within the tolerance. Then the real
table (docs/data/gpu/time_to_solution_pair.csv) must give a plan at 3 % for
dr 0.5 mm whose keys are Run:preset fast's (tests/test_preset.sh holds the
planner's presets to the C table).
"""
import csv
import os
import sys
import tempfile

from tools import ROOT
from tools.studies import time_to_solution as tts

HEAD = ["label", "E_Pa", "alpha_av", "cfl_flow", "every", "gpu_hours_per_rev", "speed_err", "seg_err", "t_s", "source"]
ROWS = [("the pair, dr 0.5 mm, E 10 kPa", 1e4, 0.2, 1.0, -0.05, 0.01),
        ("the pair, dr 0.5 mm, E 30 kPa", 3e4, 0.2, 2.0, -0.02, 0.02),
        ("the pair, dr 0.5 mm, E 0.1 MPa", 1e5, 0.2, 3.0, -0.005, 0.001),
        ("the pair, dr 0.25 mm, E 0.1 MPa", 1e5, 0.2, 40.0, 0.0, 0.0),
        ("riemann alone, dr 0.5 mm, E 10 kPa", 1e4, 0.2, 0.5, 0.0, 0.0)]  # not the scenes' flow: never chosen


def main():
    fails = []
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "t.csv")
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(HEAD)
            for lab, E, chi, h, se, ge in ROWS:
                w.writerow([lab, E, "", chi, "auto", h, se, ge, "3-5", "synthetic"])
        rows = tts.plan_rows(path)
        if len(rows) != 4:
            fails.append("plan_rows kept %d rows, not the 4 of the scenes' flow" % len(rows))
        r, h = tts.plan(rows, 0.03, 0.0005)
        if r is None or r["E"] != 3e4 or abs(h - 2.0) > 1e-12:
            fails.append("3 %% at dr 0.5 mm: expected E 30 kPa at 2.0 h, got %s" % ((r or {}).get("label"), h))
        r, h = tts.plan(rows, 0.01, 0.0005)
        if r is None or r["E"] != 1e5:
            fails.append("1 %% at dr 0.5 mm: expected E 0.1 MPa, got %s" % ((r or {}).get("label"),))
        r, h = tts.plan(rows, 0.03, 0.0004)  # between the measured spacings: the coarser's accuracy, hours scaled
        if r is None or r["dr"] != 0.0005 or abs(h - 2.0 * (0.5 / 0.4) ** 4) > 1e-9:
            fails.append("3 %% at dr 0.4 mm: expected the dr 0.5 mm row scaled to %.4g h, got %s" % (
                2.0 * (0.5 / 0.4) ** 4, h))
        r, why = tts.plan(rows, 0.03, 0.001)
        if r is not None or "coarser" not in why:
            fails.append("dr 1 mm: expected a refusal (coarser than measured), got %s" % (why,))
        r, why = tts.plan(rows, 0.001, 0.0005)
        if r is not None or "within" not in why:
            fails.append("0.1 %%: expected no plan, got %s" % (why,))
    real = tts.plan_rows(os.path.join(ROOT, "docs", "data", "gpu", "time_to_solution_pair.csv"))
    r, h = tts.plan(real, 0.03, 0.0005)
    fast = tts.PRESETS["fast"]
    if r is None or (r["E"], r["chi"], r["integrator"]) != (fast["Material:E"], fast["Run:cfl_flow"],
                                                            tts.PRESET_INTEGRATOR["fast"]):
        fails.append("the real table at 3 %%, dr 0.5 mm: not the fast preset's E, chi and integrator (%s)" % (r,))
    for f in fails:
        print("FAIL", f)
    if fails:
        return 1
    print("ok: the planner picks, scales and refuses as it should; the real table's 3 % plan at dr 0.5 mm is preset fast")
    return 0


if __name__ == "__main__":
    sys.exit(main())
