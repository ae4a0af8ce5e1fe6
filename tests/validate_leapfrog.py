"""Run:integrator leapfrog (src/sim/integrate.c step_lf), one flow
evaluation a step, against the predictor-corrector and against itself:

  convergence: the column of inputs/column_2d.yml at dr = 5 mm falling from
      zero stress without damping or filter (elastic waves), 0.02 s at fixed
      dt = 2e-5, 1e-5, 5e-6 s against a reference at 2.5e-6 s (the same
      integrator: the scheme's own time error). Second order halves dt and
      quarters the error: the ratios of successive velocity and stress
      errors must be >= 3 (first order gives 2; measured 3.21, 3.39, 3.60 in
      velocity and 3.89, 4.02, 4.08 in stress, with 4e-5 first).
  shearbox: inputs/shearbox_2d.yml at dr/H = 0.04, one period (prescribed
      kinematics, C alone): leapfrog's C within 1e-4 of the
      predictor-corrector's at the same dr, every particle (reference: the
      PC; measured 1.9e-5; the scheme's own error against the analytic
      one-dimensional solution is tests/validate_shearbox.py's).
  drum: inputs/drum_2d_EV.yml at dr = 2.5 mm, E = 0.1 MPa, 0.1 s of spin-up:
      kinetic energy and largest speed of every diagnostics row within 1e-3
      (relative) of the predictor-corrector's (measured 5.1e-4 and 3.3e-4
      over the rows, with the shift fused into the midpoint flow pass), and the run as fast or faster in steps (the same dt bounds).
  restart: the drum (riemann, shifting) stopped at step 73 (rates carried in
      the checkpoint) and at step 90 (a Shepard filter step: fresh rates) and
      restarted to 160; the shear box stopped at step 30 and restarted: bit-identical
      to the straight runs (tests/validate_restart.py's stop_restart).
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
from tools.analysis import snap  # noqa: E402
from tests import validate_restart as vr  # noqa: E402
from tests.containers import run_scene, sphseg_work_args  # noqa: E402

COLUMN = os.path.join(HERE, "..", "inputs", "column_2d.yml")
LF = ["Run:integrator=leapfrog"]
OK = True


def check(name, good, how):
    global OK
    OK &= bool(good)
    print("%s %s: %s" % ("ok  " if good else "FAIL", name, how))


def material(out):
    s = snap.read_snapshot(snap.list_snapshots(out)[-1])
    m = s["Kind"] == 0
    o = np.argsort(s["ParticleIDs"][m])
    return {k: s[k][m][o] for k in ("Velocities", "Stress", "Concentration")}


def rows(out):
    return np.genfromtxt(os.path.join(out, "diagnostics.csv"), delimiter=",", names=True)


def test_convergence(a):
    runs = {}
    for dt in ("2e-5", "1e-5", "5e-6", "2.5e-6"):
        out = os.path.join(a.work, "conv_" + dt)
        run_scene(a.sphseg, COLUMN, out, LF + ["Run:progress_s=1e9", "Geometry:dr=0.005", "Run:cfl_flow=10",
                                                "Run:dt_max=" + dt, "Flow:shepard_every=0", "Flow:damping_until=0",
                                                "Run:t_end=0.02", "Output:dt=0.02"])
        runs[dt] = material(out)
    ref = runs.pop("2.5e-6")
    err = [{k: np.abs(r[k] - ref[k]).max() / np.abs(ref[k]).max() for k in ("Velocities", "Stress")}
           for r in runs.values()]
    for k in ("Velocities", "Stress"):
        ratios = [err[i][k] / err[i + 1][k] for i in range(len(err) - 1)]
        check("column %s error ratios" % k, min(ratios) >= 3.0,
              "errors %s, ratios %s (>= 3)" % (" ".join("%.2e" % e[k] for e in err), " ".join("%.2f" % x for x in ratios)))


def test_shearbox(a):
    c = {}
    for name, over in (("pc", []), ("lf", LF)):
        out = os.path.join(a.work, "box_" + name)
        run_scene(a.sphseg, vr.BOX, out, vr.BOX_P + over)
        c[name] = material(out)["Concentration"]
    d = np.abs(c["lf"] - c["pc"]).max()
    check("shear box C, leapfrog against predictor-corrector", d <= 1e-4, "max |dC| = %.2e (<= 1e-4)" % d)


def test_drum(a):
    r = {}
    for name, over in (("pc", []), ("lf", LF)):
        out = os.path.join(a.work, "drum_" + name)
        run_scene(a.sphseg, vr.DRUM, out, ["Geometry:dr=0.0025", "Material:E=1e5", "Run:t_end=0.1", "Output:dt=0.05",
                                           "Output:diag_dt=0.01", "Run:progress_s=1e9"] + over)
        r[name] = rows(out)
    for k in ("kinetic_energy", "max_speed"):
        rel = np.abs(r["lf"][k][1:] - r["pc"][k][1:]) / np.abs(r["pc"][k][1:])
        check("drum %s, leapfrog against predictor-corrector" % k, rel.max() <= 1e-3,
              "max relative difference %.2e over %d rows (<= 1e-3)" % (rel.max(), len(rel)))
    check("drum steps", r["lf"]["step"][-1] <= r["pc"]["step"][-1],
          "%d against %d" % (r["lf"]["step"][-1], r["pc"]["step"][-1]))


def test_restart(a):
    a.backend = getattr(a, "backend", "cpu")
    keys = vr.DRUM_P + LF + ["Flow:stabilization=riemann", "Flow:shifting=fickian"]
    vr.stop_restart(a, "lf_drum_73", vr.DRUM, keys, 73, 160)
    vr.stop_restart(a, "lf_drum_90", vr.DRUM, keys, 90, 160)
    vr.stop_restart(a, "lf_box_30", vr.BOX, vr.BOX_P + LF, 30, 60)
    check("leapfrog restarts bit-identical", vr.OK, "tests/validate_restart.py checks above")


def main():
    a = sphseg_work_args()
    a.backend = "cpu"
    test_convergence(a)
    test_shearbox(a)
    test_drum(a)
    test_restart(a)
    print("validate_leapfrog:", "PASS" if OK else "FAIL")
    sys.exit(0 if OK else 1)


if __name__ == "__main__":
    main()
