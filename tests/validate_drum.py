"""A CI-sized rotating drum (inputs/drum_2d_EV.yml at dr = 2.5 mm = R/14,
E = 0.1 MPa, 2 s = 1/6 revolution; 228 material particles), run twice: with
the paper's scheme (-P Flow:stabilization=monaghan -P
Flow:gradient_correction=off -P Flow:shifting=off; the measurements below
are its) and with the scene's own flow (riemann, bed damping, the corrected
gradient and fickian shifting). Each must keep the physical invariants of
paper §6 with tolerances, the same for both: they are bounds of the physics,
not of a scheme.

  mass:          the material particle IDs are the same in every snapshot
                 (no particle lost, none created), every Volume dr^2;
  containment:   every material particle stays inside the drum, r < R;
  bounds:        C stays in [-1e-3, 1 + 1e-3] (diagnostics.csv C_min, C_max;
                 Segregation:limiter donor, the default);
  rolling:       at t = 2 s the bed has avalanched: the free surface is flat
                 (rms deviation < 1 dr) at a dynamic angle between 15 and 35
                 degrees (atan mu_s = 20.9, atan mu_d = 34.3 degrees bound it
                 for a bed that flows; measured 22-23 degrees at dr = 1 mm,
                 docs/granular.md), and the surface moves at 1-20 cm/s (the
                 paper's DEM: 6-7 cm/s);
  direction:     the bed turns with the drum (its mean angular velocity has
                 the drum's sign) and its surface rises on the side the wall
                 carries up (slope of the drum's sign: down to the right for
                 a clockwise drum);
  friction:      the stress ratio sqrt(J2)/p of the material particles at
                 t = 1 .. 2 s stays inside the mu_d cone (k_mu of eq. 2.12,
                 written out in drum_invariants.py) and, mu(I) (2.14) being
                 above mu_s where the bed flows, more than FRICTION_FRAC of
                 them lie beyond the mu_s cone by 0.1 % (measured 0.56,
                 0.28, 0.65 at t = 1, 1.5, 2 s); a constant friction mu_s
                 keeps every one within it;
  segregation:   small grains move toward the core: the segregation index of
                 tools/analysis/drum_analysis.py (C-weighted versus plain mean distance
                 from the bed's centroid) is positive at 2 s and larger than
                 at 1.5 s;
  conservation:  the relative drift of sum C_i V_i, recomputed from the
                 snapshots, stays below 1e-10 (the conservative scheme
                 conserves it to round-off), and diagnostics.csv agrees with
                 the snapshots (drum_invariants.py);
  diagnostics:   the kinetic energy, largest speed, C range and material count of
                 diagnostics.csv equal those of the snapshots.
"""
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
from tools.analysis import drum_analysis  # noqa: E402
from tools.analysis import snap  # noqa: E402
from tests.drum_invariants import (Checks, diagnostics_columns, drum_omega, kmu, mass_bounds_conservation,  # noqa: E402
                             omega_of, stress_ratio)
from tests.containers import PAPER_FLOW, sphseg_work_args  # noqa: E402  (tests/containers.py)

SCENE = os.path.join(HERE, "..", "inputs", "drum_2d_EV.yml")
FRICTION_FRAC = 0.1


BASE = ["Geometry:dr=0.0025", "Material:E=1e5", "Run:t_end=2", "Output:dt=0.5", "Output:diag_dt=0.05",
        "Run:progress_s=1e9"]
# the paper's scheme, and the scene as it ships (its own Flow keys)
FLOWS = (("paper", PAPER_FLOW),
         ("scene", []))


def main():
    a = sphseg_work_args()
    # the two runs side by side, one core each (228 particles: a second thread adds little)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    runs = []
    for name, keys in FLOWS:
        out = os.path.join(a.work, "drum_" + name)
        cmd = [a.sphseg, SCENE, "-o", out] + sum([["-P", o] for o in BASE + keys], [])
        runs.append((name, out, subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                                 text=True)))
    ok = True
    for name, out, p in runs:
        _, err = p.communicate()
        print("== %s" % name)
        if p.returncode != 0:
            print(err)
            print("FAIL sphseg exited with %d" % p.returncode)
            ok = False
            continue
        ok &= drum_checks(out)
    sys.exit(0 if ok else 1)


def drum_checks(out):
    """The checks of the run in out; True if every one passed."""
    par = drum_analysis.used_params(out)
    R = par["Geometry"]["radius"]
    check = Checks()
    coords, _ = mass_bounds_conservation(check, out, "m^2", par["Geometry"]["dr"], 2)
    diagnostics_columns(check, out, par["Physics"]["rho"])
    rmax = max(np.hypot(*x[:, :2].T).max() for x in coords)
    check("containment", rmax < R, "max r = %.5f m, R = %.5f m" % (rmax, R))
    paths = snap.list_snapshots(out)
    d15, d2 = [drum_analysis.Drum(p, par) for p in drum_analysis.pick(paths, [1.5, 2.0])]
    us = d2.surface_speed()
    check("rolling", 15 <= d2.angle <= 35 and d2.flatness < 1 and 0.01 <= us <= 0.2,
          "angle %.1f deg, flatness %.2f dr, surface speed %.1f cm/s" % (d2.angle, d2.flatness, 100 * us))
    w = drum_omega(par)
    s = snap.read_snapshot(paths[-1])
    m = s["Kind"] == snap.MATERIAL
    om = omega_of(s["Coordinates"][m], s["Velocities"][m], s["Volume"][m])
    check("direction", om * w > 0 and d2.slope * w > 0,
          "bed Omega = %.3f rad/s, drum omega = %.3f rad/s, surface slope %.3f" % (om, w, d2.slope))
    mat = par["Material"]
    frac, worst = [], 0.0
    for p in drum_analysis.pick(paths, [1.0, 1.5, 2.0]):
        r = stress_ratio(snap.read_snapshot(p))
        frac.append(np.mean(r > 1.001 * kmu(mat["mu_s"])))
        worst = max(worst, r.max() / kmu(mat["mu_d"]))
    check("friction", worst <= 1 + 1e-9 and min(frac) > FRICTION_FRAC,
          "sqrt(J2)/p at most %.4f of the mu_d cone; beyond the mu_s cone: %s of the particles" % (
              worst, ", ".join("%.3f" % f for f in frac)))
    s15, s2 = d15.segregation_index(), d2.segregation_index()
    check("segregation", s2 > 0 and s2 > s15, "index %.2e at 1.5 s, %.2e at 2 s" % (s15, s2))
    return check.ok


if __name__ == "__main__":
    main()
