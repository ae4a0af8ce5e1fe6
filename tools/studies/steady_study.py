"""Steady segregation profiles against Gray & Chugunov (2006), eq. (28) of
papers/thornton-weinhart-multiscale-granular-review.txt, for several mean
concentrations phi0 and Peclet numbers Pe = V H / D, two resolutions and two
schemes. A column at rest starts uniform at phi0 and runs to t = 4 H^2/D
(tests/validate_steady.py holds the run set-up; this is its full version).

  python3 -m tools.studies.steady_study [--sphseg build/sphseg] [--work DIR] [--md docs/data/steady/steady_table.md]
"""
import argparse
import os
import sys

import numpy as np

from tools import ROOT  # noqa: E402
from tools.analysis import seg1d  # noqa: E402
from tests import validate_steady  # noqa: E402

CASES = [(0.5, 5.0), (0.3, 20.0), (0.7, 40.0), (0.5, 100.0)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", default=os.path.join(ROOT, "build", "sphseg"))
    ap.add_argument("--work", default="/tmp/sphseg_steady")
    ap.add_argument("--md", default=os.path.join(ROOT, "docs", "data", "steady", "steady_table.md"))
    a = ap.parse_args()
    lines = ["| dr/H | phi0 | Pe | V h / D | scheme | MAE | max error | mean C |", "|---|---|---|---|---|---|---|---|"]
    for res in (0.04, 0.02):
        for phi0, Pe in CASES:
            for scheme in ("conservative", "paper"):
                out = os.path.join(a.work, f"{scheme}_{res}_{phi0}_{Pe}")
                rc, z, C = validate_steady.run(a.sphseg, out, phi0, Pe, scheme, dr_over_H=res)
                peh = Pe * 1.5 * res
                if rc:
                    row = f"| {res} | {phi0} | {Pe:g} | {peh:.2f} | {scheme} | blew up (exit {rc}) | | |"
                else:
                    ref = seg1d.steady_analytic(z, phi0, Pe)
                    row = (f"| {res} | {phi0} | {Pe:g} | {peh:.2f} | {scheme} | {seg1d.mae(C, ref):.4f} | "
                           f"{np.max(np.abs(C - ref)):.4f} | {np.mean(C):.4f} |")
                print(row, flush=True)
                lines.append(row)
    with open(a.md, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
