#!/usr/bin/env python3
"""tools/analysis/drum_mixing.py against particles whose wandering is known (no sphseg run; a few
seconds): 7 200 particles on a disordered lattice of dr 0.5 mm move with a curved shear flow,
u_x = kappa (y - yc)^2 (kappa 1000 1/(m s), |y - yc| <= 7.5 mm: a local shear rate of 0 to 15 1/s,
the drum layer's range), plus a Brownian motion of diffusivity D0 = 5e-9 m^2/s (Euler steps of a
fiftieth of the snapshots' spacing), and each snapshot records the positions with an independent
jitter of 0.02 dr (a rattle that mixes nothing) and ShearRate = |du_x/dy| at the particle. Snapshots
every 2.5 ms, 14 of them, written as sphseg writes them (Header Time, Dimension; Particles
Coordinates, Kind, ParticleIDs, ShearRate, Concentration), with a used_params.yml.

- D_num recovers D0 within 10 % in each class of shear rate holding at least 4e4 samples (the
  reference is the Brownian motion put in; with the class's shear dispersion in the fitted line,
  M = D_num (4 tau + (2/3) gdot^2 tau^3) + M0), and so does D_perp, across the streamline (no shear
  dispersion there); the same in 3D (six layers of the same flow, a Brownian motion in x, y, z);
- the same motion without the Brownian part (jitter alone) gives |D_num| < 5 % of D0: the jitter's
  constant offset M0 is not read as diffusion, and the fit follows the flow's gradient and curvature;
- the affine fit (--order 1) on that flow reads the curvature as departure: its D_num is well off
  D0 (more than 30 %), which shows the second-order terms are what the first check rests on;
- D_phys = chi_D gdot d_avg^2 with d_avg = d_small C + d_large (1 - C), from used_params.yml, to
  1e-12 relative;
- unevenly spaced snapshots are refused;
- with --sphseg (the runner passes it), tools/studies/drum_mixing.sh TINY=1 runs end to end on the CPU (the EV
  drum at dr 2 mm developed to 0.3 s, two windows restarted from its checkpoint, one with the shifting off) and
  each window's measurement has classes with samples (about 10 s).

    /usr/bin/python3 -m tests.test_drum_mixing [--work DIR]
"""
import os
import shutil
import sys
import tempfile

import h5py
import numpy as np

from tests.checks import check, parse_args, summary  # noqa: E402
from tools.analysis import drum_mixing as dm  # noqa: E402

DR, KAPPA, D0, STEP, NSNAP = 5e-4, 1000.0, 5e-9, 2.5e-3, 14
CHI_D, DS, DL, C0 = 0.0307, 2.5e-4, 5e-4, 0.3


def write_snapshots(path, D, jitter, times=None, seed=1, dim=2):
    """The run folder: used_params.yml and the snapshots (dim 3: 120 x 30 x 6 particles, the same flow in x, y)."""
    os.makedirs(path, exist_ok=True)
    with open(os.path.join(path, "used_params.yml"), "w") as f:
        f.write("Geometry:\n  dr: %r\n  h_factor: 1.5\nGrains:\n  d_small: %r\n  d_large: %r\n"
                "Segregation:\n  chi_D: %r\nFlow:\n  shifting: off\n" % (DR, DS, DL, CHI_D))
    rng = np.random.default_rng(seed)
    nx, ny = 240, 30
    if dim == 2:
        gx, gy = np.meshgrid((np.arange(nx) + 0.5) * DR, (np.arange(ny) + 0.5) * DR)
        x = np.stack([gx.ravel(), gy.ravel()], 1)
    else:
        nx = 120
        gx, gy, gz = np.meshgrid(*((np.arange(m) + 0.5) * DR for m in (nx, ny, 6)))
        x = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], 1)
    x = x + rng.normal(0, 0.05 * DR, x.shape)
    n = len(x)
    yc = 0.5 * ny * DR
    times = np.arange(NSNAP) * STEP if times is None else np.asarray(times, float)
    for k, tk in enumerate(times):
        if k > 0:
            sub = 50
            h = (tk - times[k - 1]) / sub
            for _ in range(sub):
                y = x[:, 1] - yc
                x[:, 0] += KAPPA * y * y * h
                if D > 0:
                    x += rng.normal(0, np.sqrt(2 * D * h), x.shape)
        obs = x + rng.normal(0, jitter * DR, x.shape)
        perm = rng.permutation(n)  # rows in any order: the tool matches particles by ParticleIDs
        with h5py.File(os.path.join(path, "snapshot_%05d.h5" % k), "w") as f:
            hd = f.create_group("Header")
            hd.attrs["Time"] = float(tk)
            hd.attrs["Dimension"] = dim
            p = f.create_group("Particles")
            p["Coordinates"] = (np.column_stack([obs, np.zeros(n)]) if dim == 2 else obs)[perm]
            p["Kind"] = np.zeros(n, np.uint8)
            p["ParticleIDs"] = np.arange(n, dtype=np.int64)[perm]
            p["ShearRate"] = (2 * KAPPA * np.abs(obs[:, 1] - yc))[perm]
            p["Concentration"] = np.full(n, C0)


def big(res):
    """The classes of shear rate with at least 4e4 samples."""
    return [c for c in res["classes"] if c["n"] >= 40000]


def main():
    a = parse_args(__doc__, "a folder for the made runs (default: a temporary one, removed)")
    work = a.work or tempfile.mkdtemp(prefix="drum_mixing_")
    try:
        brown, still = os.path.join(work, "brownian"), os.path.join(work, "jitter")
        write_snapshots(brown, D0, 0.02)
        write_snapshots(still, 0.0, 0.02, seed=2)
        r = dm.measure(brown)
        check("classes of >= 4e4 samples", len(big(r)), ">= 3", len(big(r)) >= 3, "shear rates 0-15 1/s")
        dexp = DS * C0 + DL * (1 - C0)
        for c in big(r):
            name = "gdot %g-%s" % (c["gdot_lo"], c["gdot_hi"] or "")
            check("D_num of a Brownian motion, " + name, c["D_num"] / D0 - 1, "|x| < 0.10",
                  abs(c["D_num"] / D0 - 1) < 0.10, "the diffusivity put in, D0 = 5e-9 m^2/s")
            want = CHI_D * c["gdot_mean"] * dexp ** 2
            check("D_phys, " + name, c["D_phys"] / want - 1, "|x| < 1e-12", abs(c["D_phys"] / want - 1) < 1e-12,
                  "chi_D gdot d_avg^2, eq. 2.7")
        for c in big(r):
            name = "gdot %g-%s" % (c["gdot_lo"], c["gdot_hi"] or "")
            check("D_perp of a Brownian motion, " + name, c["D_perp"] / D0 - 1, "|x| < 0.10",
                  abs(c["D_perp"] / D0 - 1) < 0.10, "the diffusivity put in; across the streamline no shear dispersion")
        b3 = os.path.join(work, "brownian3d")
        write_snapshots(b3, D0, 0.02, seed=3, dim=3)
        r3 = dm.measure(b3)
        for c in big(r3):
            name = "3D, gdot %g-%s" % (c["gdot_lo"], c["gdot_hi"] or "")
            for key in ("D_num", "D_perp"):
                check("%s of a Brownian motion, %s" % (key, name), c[key] / D0 - 1, "|x| < 0.10",
                      abs(c[key] / D0 - 1) < 0.10, "the diffusivity put in (120 x 30 x 6 particles, 2 dim = 6)")
        worst = max(abs(c["D_num"]) for c in big(dm.measure(still))) / D0
        check("D_num of jitter alone, worst class", worst, "< 0.05", worst < 0.05,
              "no diffusion put in; the jitter's M0 = 8e-4 dr^2 does not grow with the lag")
        least = min(abs(c["D_num"] / D0 - 1) for c in big(dm.measure(brown, order=1)))
        check("D_num, affine fit, curved flow, least error", least, "> 0.30", least > 0.30,
              "kappa (y - yc)^2 over the lags is not affine")
        uneven = os.path.join(work, "uneven")
        write_snapshots(uneven, D0, 0.02, times=[0, 2.5e-3, 5e-3, 9e-3])
        try:
            dm.measure(uneven)
            refused = False
        except SystemExit:
            refused = True
        check("uneven snapshots refused", float(refused), "1", refused, "the slope needs even lags")
        if a.sphseg and os.path.exists(a.sphseg):
            import subprocess
            out = os.path.join(work, "study")
            env = dict(os.environ, OUT=out, SPHSEG=os.path.abspath(a.sphseg), TINY="1", DRUMS="EV", RADII="2",
                       PY=sys.executable)
            root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
            rc = subprocess.run(["bash", "tools/studies/drum_mixing.sh"], cwd=root, env=env).returncode
            subprocess.run(["tar", "xzf", os.path.join(out, "drum_mixing_res.tgz"), "-C", out])
            got = []
            for var in ("shift", "noshift"):
                f = os.path.join(out, "res", "EV_%s_dr2.json" % var)
                if os.path.exists(f):
                    import json
                    with open(f) as fh:
                        got.append(sum(c["n"] for c in json.load(fh)["classes"]))
            ok = rc == 0 and len(got) == 2 and min(got) > 0
            check("the study script, TINY", float(ok), "1", ok, "rc %d, samples %s" % (rc, got))
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)
    return summary("test_drum_mixing")


if __name__ == "__main__":
    sys.exit(main())
