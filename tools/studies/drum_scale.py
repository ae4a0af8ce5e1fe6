#!/usr/bin/env python3
"""The 2D drum's surface at two spacings, run by run, against a continuum
reference (docs/granular.md "Nearer the onset: the drum scaled at a fixed flux").

  /usr/bin/python3 -m tools.studies.drum_scale \
      --case "LABEL;COARSE.ana;FINE.ana;TMIN;TMAX[;FE_U0_CM_S]" [--case ...]

Each --case is a pair of `drum_analysis` outputs (their tables of snapshots),
the coarser spacing first, and the time window of the steady state. Prints,
per run, the means over the window of the dynamic angle and of the top grains'
speed (with its standard error, the snapshots' spread over sqrt(n)), the fine
run's change against the coarse one, and, where the FE's surface speed u(0) is
given (`drum_mui_ref`, cm/s), each run's ratio to it. The top grains read the
FE's u(dr/2), 0.99-1.0 of u(0) at these spacings ("The layer point by point").
"""
import argparse
import math

import numpy as np

from tools.analysis.drum_analysis import read_window  # noqa: E402


def window_means(path, tmin, tmax):
    """(n, mean angle deg, mean top grains u cm/s, its standard error) over the snapshots in [tmin, tmax]."""
    rows = np.array([(r[1], r[4]) for r in read_window(path, tmin, tmax)])
    if len(rows) < 2:
        raise SystemExit(f"{path}: fewer than two snapshots in [{tmin}, {tmax}] s")
    u = rows[:, 1]
    return len(rows), rows[:, 0].mean(), u.mean(), u.std(ddof=1) / math.sqrt(len(u))


def parse_case(spec):
    p = spec.split(";")
    if len(p) not in (5, 6):
        raise SystemExit(f"--case {spec!r}: expected LABEL;COARSE.ana;FINE.ana;TMIN;TMAX[;FE_U0_CM_S]")
    return p[0], p[1], p[2], float(p[3]), float(p[4]), (float(p[5]) if len(p) == 6 else None)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", action="append", required=True, help="LABEL;COARSE.ana;FINE.ana;TMIN;TMAX[;FE_U0]")
    a = ap.parse_args(argv)
    print(f"{'case':36s} {'window s':>9s} {'n':>3s} {'angle coarse':>12s} {'fine':>7s} "
          f"{'top grains coarse':>17s} {'fine':>13s} {'change':>7s} {'FE u(0)':>7s} {'/FE':>11s}")
    for label, coarse, fine, t0, t1, fe in map(parse_case, a.case):
        n, a0, u0, e0 = window_means(coarse, t0, t1)
        _, a1, u1, e1 = window_means(fine, t0, t1)
        ratio = f"{u0 / fe:5.3f} {u1 / fe:5.3f}" if fe else "-"
        print(f"{label[:36]:36s} {t0:4g}-{t1:<4g} {n:3d} {a0:11.2f}° {a1:6.2f}° "
              f"{u0:9.2f} ± {e0:4.2f} {u1:6.2f} ± {e1:4.2f} {100 * (u1 / u0 - 1):+6.1f}% "
              f"{(f'{fe:.2f}' if fe else '-'):>7s} {ratio:>11s}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
