"""An outlet (Outlet:enabled, Outlet:below) under a silo's opening
(Geometry:outlet_width): material that falls below the plane leaves the run.

The scene is inputs/column_2d.yml at dr = 2.5 mm, 5 cm wide and 5 cm high,
with a 1.25 cm opening centred in its base and the outlet plane 2 cm below
the base; the grains are bidisperse (C = 0.3 in the lower half, 1 above,
segregation on, so that C varies along what drains) and the material soft (E = 0.1 MPa). Over
0.15 s of discharge:

  - material leaves: the last diagnostics row counts n_outflow > 0, and the
    last snapshot holds that many fewer material particles (the store
    shrinks), none of them below the plane;
  - every diagnostics row has n_material + n_outflow = the initial count;
  - conservation counts the outflow: the drift of sum C_i V_i inside plus
    small_volume_outflow stays at round-off (|drift| <= 1e-12; measured a
    few 1e-15), while the sum inside alone falls by the outflow once C > 0
    reaches the opening (the check would fail without the outflow term);
  - the snapshots' own sum C_i V_i plus the outflow of the same row equals
    the t = 0 sum to round-off (the diagnostics are not trusted alone).
"""
import csv
import os
import sys

import numpy as np

from tools.analysis import snap  # noqa: E402

from tests.containers import SILO as SILO_CASE, run_column, sphseg_work_args  # noqa: E402  (tests/containers.py)
SILO = SILO_CASE + ["Run:t_end=0.15", "Output:dt=0.05", "Output:diag_dt=0.005", "Run:progress_s=1e9"]
TOL = 1e-12


def main():
    a = sphseg_work_args()
    out = os.path.join(a.work, "silo")
    run_column(a.sphseg, out, SILO)
    with open(os.path.join(out, "diagnostics.csv")) as f:
        rows = list(csv.DictReader(f))
    ok = True

    def check(name, good, detail):
        nonlocal ok
        ok &= bool(good)
        print("%s %s: %s" % ("ok  " if good else "FAIL", name, detail))

    n0 = int(rows[0]["n_material"])
    total = [int(x["n_material"]) + int(x["n_outflow"]) for x in rows]
    check("particles inside plus outflow", all(t == n0 for t in total),
          "%d rows, initial %d, range %d..%d" % (len(rows), n0, min(total), max(total)))
    drift = max(abs(float(x["small_volume_drift"])) for x in rows)
    out_cv = float(rows[-1]["small_volume_outflow"])
    small0 = float(rows[0]["small_volume"])
    check("sum C V inside plus outflow conserved", drift <= TOL,
          "largest |drift| %.2e (tolerance %.0e); outflow %.3e = %.2f %% of the initial sum" % (
              drift, TOL, out_cv, 100 * out_cv / small0))
    check("small grains left through the outlet", out_cv > 1e-3 * small0, "outflow %.3e" % out_cv)
    paths = snap.list_snapshots(out)
    first, last = snap.read_snapshot(paths[0]), snap.read_snapshot(paths[-1])
    m0, m1 = np.asarray(first["Kind"]) == 0, np.asarray(last["Kind"]) == 0
    nout = int(rows[-1]["n_outflow"])
    check("the store shrank by the outflow", m0.sum() - m1.sum() == nout and nout > 0,
          "%d material particles at t = 0, %d at t = %.3g s, %d counted out" % (
              m0.sum(), m1.sum(), float(last["Time"]), nout))
    y = np.asarray(last["Coordinates"])[m1, 1]
    check("nothing left below the plane", y.min() >= -0.02, "lowest material y = %.4f m" % y.min())
    row = next(x for x in rows if abs(float(x["time"]) - float(last["Time"])) < 1e-9)
    cv = lambda s, m: float(np.sum(np.asarray(s["Concentration"])[m] * np.asarray(s["Volume"])[m]))
    rel = abs(cv(last, m1) + float(row["small_volume_outflow"]) - cv(first, m0)) / cv(first, m0)
    check("snapshots: sum C V inside plus outflow", rel <= TOL, "relative difference %.2e" % rel)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
