"""The single-precision build (PRECISION=single) against the double one on the
CI drum (inputs/drum_2d_EV.yml at dr = 2.5 mm, E = 0.1 MPa, Flow:stabilization
monaghan with alpha_av 1.0, 0.6 s, as tests/validate_conc_window.py: the
tolerances below were measured with monaghan).

The concentration, its start-of-step copy and its rate are double in both
builds (creal, src/core/hd.h), and the conservative scheme sums its pair
terms in double: a float C rounds at every update, which made sum C_i V_i
drift by 1.3e-5 in these 15 169 steps (and 1.5e-8 with concentration
windows), measured on the dev machine before the change. Checked:

  conservation: the drift of sum C_i V_i recomputed from the single run's
                snapshots (tools/analysis/drum_compare.py) is < 1e-13 with C in every
                step and with windows (measured 3e-16 and 0);
  accuracy:     single against double, C in every step: rms |C - C_double|
                < 2e-8 (measured 9.4e-9), the dynamic angle within 0.01
                degrees and the mid-chord speed profile within 1e-5 of the
                surface speed (measured 6e-7); with windows rms |C - C_double|
                < 1.6e-6 (measured 8.1e-7: the windows' own error, first order
                in K, tests/validate_conc_window.py).

  set-up:       every 2D container scene of inputs/ (walls as data, some
                through lattice sites: the hopper's 45-degree walls) lays out
                the same material and dummy counts in both builds (the
                single build once stopped on inputs/hopper_2d.yml: a site on a
                wall's line, a float rounding behind it).

--single is the single-precision binary (default $BUILD-single/sphseg:
make PRECISION=single GPU=0 BUILD=build-single), which tests/run.sh builds
first; a missing one fails the test.
"""
import argparse
import glob
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
from tools.analysis import drum_compare  # noqa: E402
from tests.drum_invariants import Checks  # noqa: E402  (tests/drum_invariants.py)

DRUM = os.path.join(HERE, "..", "inputs", "drum_2d_EV.yml")
OVER = ["Flow:stabilization=monaghan", "Flow:gradient_correction=off", "Flow:shifting=off", "Geometry:dr=0.0025", "Material:E=1e5", "Flow:alpha_av=1", "Run:t_end=0.6",
        "Output:dt=0.3", "Run:progress_s=1e9"]
check = Checks()  # check(name, good, detail): one ok/FAIL line; check.ok


def run(binary, out, every):
    cmd = [binary, DRUM, "-o", out, "--overwrite", "--backend", "cpu"] + sum([["-P", o] for o in OVER + ["Segregation:every=" + every]], [])
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("%s failed (%d): %s" % (binary, r.returncode, r.stderr.strip()[-300:]))


def counts(binary, scene, out):
    """The set-up's material and dummy counts of one scene (one step, no output)."""
    r = subprocess.run([binary, scene, "-o", out, "--overwrite", "--backend", "cpu", "-P", "Run:max_steps=1",
                        "-P", "Output:snapshots=off"], capture_output=True, text=True)
    m = re.search(r"(\d+) material \+ (\d+) dummy", r.stdout + r.stderr)
    return (int(m.group(1)), int(m.group(2))) if r.returncode == 0 and m else "exit %d: %s" % (
        r.returncode, (r.stderr.strip().splitlines() or [""])[-1][-160:])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", default=os.path.join(HERE, "..", "build", "sphseg"))
    ap.add_argument("--single", default=os.path.join(HERE, "..", os.environ.get("BUILD", "build") + "-single", "sphseg"))
    ap.add_argument("--work", default="/tmp/validate_single")
    a = ap.parse_args()
    if not os.access(a.single, os.X_OK):
        sys.exit("no single-precision binary at %s (make PRECISION=single GPU=0 BUILD=build-single)" % a.single)
    os.makedirs(a.work, exist_ok=True)
    d1, s1, sa = (os.path.join(a.work, n) for n in ("double_k1", "single_k1", "single_auto"))
    run(a.sphseg, d1, "1")
    run(a.single, s1, "1")
    run(a.single, sa, "auto")
    for name, out in (("C every step", s1), ("windows", sa)):
        drift = drum_compare.small_volume_drift(out)
        check("single, %s: sum C V conserved" % name, drift < 1e-13, "max |drift| %.2e (tol 1e-13)" % drift)
    r = drum_compare.compare(d1, s1, [0.6])[0]
    check("single vs double, C every step: C", r["C_rms"] < 2e-8, "rms %.2e (tol 2e-8)" % r["C_rms"])
    check("single vs double: dynamic angle", abs(r["angle"] - r["angle_ref"]) < 0.01,
          "%.4f vs %.4f deg" % (r["angle"], r["angle_ref"]))
    check("single vs double: mid-chord speed", r["speed_err"] < 1e-5, "%.2e of the surface speed" % r["speed_err"])
    r = drum_compare.compare(d1, sa, [0.6])[0]
    check("single with windows vs double: C", r["C_rms"] < 1.6e-6, "rms %.2e (tol 1.6e-6)" % r["C_rms"])
    for scene in sorted(glob.glob(os.path.join(HERE, "..", "inputs", "*_2d.yml"))):
        with open(scene) as f:
            if not re.search(r"^\s*type:\s*container", f.read(), re.M):
                continue
        cd = counts(a.sphseg, scene, os.path.join(a.work, "setup_double"))
        cs = counts(a.single, scene, os.path.join(a.work, "setup_single"))
        check("set-up of %s: single as double" % os.path.basename(scene), cd == cs and not isinstance(cd, str),
              "material, dummies: double %s, single %s" % (cd, cs))
    print("all checks passed" if check.ok else "SOME CHECKS FAILED")
    sys.exit(0 if check.ok else 1)


if __name__ == "__main__":
    main()
