"""Bounded C (issue 30): the conservative scheme with Segregation:limiter
donor keeps the small-grain concentration within [-1e-3, 1 + 1e-3] and
sum C_i V_i conserved to round-off, in runs where the unlimited scheme
(limiter none) leaves those bounds:

  - a column at rest (the shear box's geometry, Kinematics:velocity rest),
    dr/H = 0.04, small grains on top of large ones (Initial: C = 0 below
    H/2, 1 above), constant V and D at Pe = V H / D = 200 (particle Peclet
    V h / D = 12), to t = H / V: the fronts sink and rise through pure
    layers of each kind. Measured C in [-0.103, 1.103] (symmetric flux) and
    [-0.048, 1.156] (asymmetric) without the limiter, [0, 1] with it;
  - the same column from a uniform C = 1/2 at Pe = 1000 (symmetric flux):
    |dQ/dC| = 0 at every particle, so the segregation bound on the time
    step is void at the start; without the limiter the first step (0.76 s,
    the diagnostics interval) takes C to [-0.273, 1.273]; with it the wave speed of
    the bound is at least A V (src/physics/step.h) and C stays in [0, 1]
    (without that, C reached [-0.061, 1.061] with the limiter on);
  - the shear box of paper §5 (inputs/shearbox_2d.yml), shear-rate model,
    symmetric flux, dr/H = 0.04, 80 periods: C up to 1.039 without the
    limiter (t/T ~ 60), within [0, 1] with it; the limiter's MAE against the
    1D reference (tools/analysis/seg1d.py) <= 0.03 at t/T = 20, 40, 80 (the
    tolerance of tests/validate_shearbox.py) and at t/T = 80 no more than
    10 % above the unlimited scheme's (measured 0.0200 against 0.0241).

Bounds: C_min and C_max of every diagnostics row (one per 1/200 of the
column's run, per T/20 in the shear box), checked against the snapshots
(drum_invariants.diagnostics_columns). Conservation: the relative drift of
sum C_i V_i recomputed from the snapshots (snap.conservation) <= 1e-12 in
the double build, 1e-5 in the single one (docs/shearbox.md: 2e-15 and
< 1e-6 measured), the diagnostics' column equal to the snapshots' sums.
"""
import os
import subprocess
import sys

import numpy as np

from tools.analysis import snap  # noqa: E402
from tools.studies import study  # noqa: E402
from tests.drum_invariants import Checks, diagnostics_columns  # noqa: E402
from tests.containers import sphseg_work_args  # noqa: E402  (tests/containers.py)

LO, HI = -1e-3, 1 + 1e-3
DRIFT = {"double": 1e-12, "single": 1e-5}
MAE_TOL, MAE_RATIO = 0.03, 1.1


def c_range(out):
    dg = snap.read_diagnostics(out)
    return float(np.min(dg["C_min"])), float(np.max(dg["C_max"]))


def conserved(check, out, name, rho):
    prec = snap.read_snapshot(snap.list_snapshots(out)[0]).get("Precision", "double")
    c = snap.conservation(out)
    check(name + " conservation", c["drift"] <= DRIFT[prec] and c["column"] <= 1e-15 and c["reported"] == 0,
          "drift of sum C_i V_i %.1e from %d snapshots (%s, tolerance %.0e), small_volume column within %.1e"
          % (c["drift"], c["snapshots"], prec, DRIFT[prec], c["column"]))
    diagnostics_columns(check, out, rho)


def column(sphseg, out, flux, limiter, Pe=200.0, C0=(0.0, 1.0), rows=200, D=1e-6, dr_over_H=0.04):
    """The column at rest to t = H / V, C0 = (below, above) H/2, a
    diagnostics row every t / rows; the exit status."""
    H = study.H
    V = Pe * D / H
    t_end = H / V
    over = {"Kinematics:velocity": "rest", "Segregation:flux": flux, "Segregation:model": "constant",
            "Segregation:V": repr(V), "Segregation:D": repr(D), "Segregation:scheme": "conservative",
            "Segregation:limiter": limiter, "Initial:C_below": repr(C0[0]), "Initial:C_above": repr(C0[1]),
            "Geometry:dr": repr(dr_over_H * H), "Geometry:width": repr(H / 4), "Run:t_end": repr(t_end),
            "Output:dt": repr(t_end / 4), "Output:diag_dt": repr(t_end / rows), "Run:progress_s": "1e9"}
    cmd = [sphseg, study.SCENE, "-o", out, "--overwrite"] + sum([["-P", f"{k}={v}"] for k, v in over.items()], [])
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode not in (0, 3):
        raise RuntimeError(f"{' '.join(cmd)}: exit {r.returncode}\n{r.stderr}")
    return r.returncode


def columns(check, sphseg, work):
    for flux in ("symmetric", "asymmetric"):
        rng = {}
        for lim in ("none", "donor"):
            out = os.path.join(work, f"column_{flux}_{lim}")
            rc = column(sphseg, out, flux, lim)
            rng[lim] = c_range(out) if rc == 0 else (float("nan"), float("nan"))
        lo, hi = rng["none"]
        check(f"column {flux} none leaves the bounds", lo < LO and hi > HI,
              f"C in [{lo:.4f}, {hi:.4f}] without the limiter (measured [-0.103, 1.103] symmetric, "
              f"[-0.048, 1.156] asymmetric)")
        lo, hi = rng["donor"]
        check(f"column {flux} donor bounded", lo >= LO and hi <= HI, f"C in [{lo:.3g}, 1 {hi - 1:+.3g}]")
        conserved(check, os.path.join(work, f"column_{flux}_donor"), f"column {flux} donor", 1500.0)
    # uniform C = 1/2, Pe = 1000, a diagnostics row every t/10: |dQ/dC| = 0 everywhere at the start
    # (symmetric flux), so only the donor limiter's wave speed A V (step.h) keeps the first step short
    out = os.path.join(work, "column_uniform_none")
    rc = column(sphseg, out, "symmetric", "none", 1000.0, (0.5, 0.5), 10)
    lo, hi = c_range(out) if rc == 0 else (float("nan"), float("nan"))
    check("column uniform none fails", rc == 3 or lo < LO or hi > HI,
          f"exit {rc}, C in [{lo:.4f}, {hi:.4f}] without the limiter (measured: exit 0, [-0.273, 1.273]; a first "
          f"step of 0.76 s)")
    out = os.path.join(work, "column_uniform_donor")
    rc = column(sphseg, out, "symmetric", "donor", 1000.0, (0.5, 0.5), 10)
    lo, hi = c_range(out) if rc == 0 else (float("nan"), float("nan"))
    check("column uniform donor bounded", rc == 0 and lo >= LO and hi <= HI,
          f"exit {rc}, C in [{lo:.3g}, 1 {hi - 1:+.3g}] (measured [-0.061, 1.061] with the limiter and the "
          f"wave speed |dQ/dC| alone)")


def shearbox(check, sphseg, work):
    case, res, mae = "sym_shear", 0.04, {}
    for lim in ("none", "donor"):
        out = os.path.join(work, f"{case}_{lim}")
        study.run_case(sphseg, out, case, "conservative", res,
                       extra={"Segregation:limiter": lim, "Output:diag_dt": repr(13.0 / 20)})
        e = study.case_errors(out)["errors"]
        mae[lim] = {t: e[t]["mae"] for t in e}
        lo, hi = c_range(out)
        if lim == "none":
            check("shear box none leaves the bounds", lo < LO or hi > HI,
                  f"C in [{lo:.4f}, {hi:.4f}] without the limiter (measured [-0.0007, 1.039])")
        else:
            check("shear box donor bounded", lo >= LO and hi <= HI, f"C in [{lo:.3g}, 1 {hi - 1:+.3g}]")
            conserved(check, out, "shear box donor", 1500.0)
    d, n = mae["donor"], mae["none"]
    check("shear box donor MAE", all(v <= MAE_TOL for v in d.values()) and d[80] <= MAE_RATIO * n[80],
          "MAE at t/T = 20, 40, 80: %s with the limiter, %s without (tolerance %.2f; at 80 at most %.1f x "
          "the unlimited)" % (", ".join("%.4f" % d[t] for t in sorted(d)), ", ".join("%.4f" % n[t] for t in sorted(n)),
                              MAE_TOL, MAE_RATIO))


def main():
    a = sphseg_work_args()
    os.makedirs(a.work, exist_ok=True)
    check = Checks()
    columns(check, a.sphseg, a.work)
    shearbox(check, a.sphseg, a.work)
    return 0 if check.ok else 1


if __name__ == "__main__":
    sys.exit(main())
