"""Shear-box validation study: run sphseg over resolutions, schemes and
segregation models, compare each run with the 1D finite-volume reference
(tools/analysis/seg1d.py) at t/T = 20, 40, 80 (MAE and RMSE, paper eqs. 5.3-5.4), and
collect the drift of sum C_i V_i and the wall time.

Used by tools/studies/shearbox_study.py (the full study, docs/) and by
tests/validate_shearbox.py (the CI-sized version).
"""
import os
import subprocess
import time

import numpy as np

from tools.analysis import seg1d  # noqa: E402
from tools.analysis import snap  # noqa: E402
from tools import ROOT

H = 0.087
SCENE = os.path.join(ROOT, "inputs", "shearbox_2d.yml")

# The four validation cases of paper §5: flux function x V/D model.
CASES = {
    "sym_const": {"Segregation:flux": "symmetric", "Segregation:model": "constant"},
    "asym_const": {"Segregation:flux": "asymmetric", "Segregation:model": "constant"},
    "sym_shear": {"Segregation:flux": "symmetric", "Segregation:model": "shear_rate"},
    "asym_shear": {"Segregation:flux": "asymmetric", "Segregation:model": "shear_rate"},
}


class RunFailed(RuntimeError):
    """sphseg ended with a nonzero exit status."""

    def __init__(self, cmd, returncode, stderr):
        super().__init__(f"{' '.join(cmd)} failed ({returncode}):\n{stderr}")
        self.returncode, self.stderr = returncode, stderr


def run_case(sphseg, outdir, case, scheme, dr_over_H, taus=(20, 40, 80), extra=None):
    """Run sphseg for one case; returns the wall time in seconds."""
    T = 13.0
    over = dict(CASES[case])
    over.update({"Segregation:scheme": scheme, "Geometry:dr": repr(dr_over_H * H),
                 "Run:t_end": repr(max(taus) * T), "Output:dt": repr(min(taus) * T),
                 "Output:diag_dt": repr(T), "Run:progress_s": "1e9"})
    over.update(extra or {})
    cmd = [sphseg, SCENE, "-o", outdir, "--overwrite"]
    for k, v in over.items():
        cmd += ["-P", f"{k}={v}"]
    t0 = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        raise RunFailed(cmd, res.returncode, res.stderr)
    return wall


def case_errors(outdir, taus=(20, 40, 80), n_cells=1600):
    """Errors of one run against the FV reference at the given t/T."""
    p = seg1d.params_from_yaml(outdir)
    import yaml
    with open(os.path.join(outdir, "used_params.yml")) as f:
        dr = float(yaml.safe_load(f)["Geometry"]["dr"])
    times = [tau * p.period for tau in taus]
    y_ref, C_ref = seg1d.solve(p, times, n_cells=n_cells)
    snaps = {round(snap.snapshot_time(s) / p.period, 6): s for s in snap.list_snapshots(outdir)}
    out = {}
    for k, tau in enumerate(taus):
        s = snaps.get(round(float(tau), 6))
        if s is None:
            raise RuntimeError(f"{outdir}: no snapshot at t/T = {tau}")
        y, C = snap.row_profile(snap.read_snapshot(s), dr)
        ref = seg1d.profile_at(y_ref, C_ref[k], y)
        out[tau] = {"mae": seg1d.mae(C, ref), "rmse": seg1d.rmse(C, ref),
                    "max": float(np.max(np.abs(C - ref)))}
    diag = snap.read_diagnostics(outdir)
    drift = np.asarray(diag["small_volume_drift"], dtype=float)
    return {"errors": out, "drift_max": float(np.max(np.abs(drift))),
            "drift_final": float(drift[-1]), "diag": diag}


def order(e_coarse, e_fine, ratio=2.0):
    """Observed order of convergence between two resolutions."""
    return float(np.log(e_coarse / e_fine) / np.log(ratio))
