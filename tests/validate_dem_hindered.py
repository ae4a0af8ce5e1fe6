"""Hindered settling of a suspension of DEM grains (inputs/dem_hindered.yml;
issue 58, "beyond the paper"): a simple cubic lattice of free grains of
spacing s, fluid fraction eps = 1 - (pi/6) d^3 / s^3, settles through water
in a box periodic along x and z with a base; the fluid it displaces returns
up through it. Its velocity is held to Richardson & Zaki's (1954) law

    v / v_t = eps^n,   n = 4.45 Re_t^-0.1  (their correlation for 200 < Re_t
                                           < 500, without the wall term:
                                           the box is periodic)

within 10 % (the issue's), v_t the single grain's terminal velocity with the
code's drag (eq. 27 at eps = 1, Di Felice's eqs. 19, 21, 22:
terminal() of tests/validate_dem_settling.py; 0.1205 m/s for d 4 mm, 1200 kg/m^3 in
water, Re_t = 482, n = 2.399). Garside & Al-Dibouni's (1977) continuous form,
(5.1 - n) / (n - 2.7) = 0.1 Re_t^0.9, and Rowe's (1987), n = (4.7 + 0.41
Re_t^0.75) / (1 + 0.175 Re_t^0.75), are printed beside (n = 2.789 and 2.467).

v: the mean downward velocity of the interior grains over a window in
which it is steady (the means of the window's halves within 2 %: its first and
last n // 2 snapshots, the middle one of an odd count left out), before the
block nears the base. The grains of the block's top and bottom K layers
are left out: their fluid fraction (eq. 20, the kernel's smoothing over 2h,
and eq. 15's again) takes in the clear fluid beyond the block, so they see
less drag and leave the lattice (the bottom ones fall ahead, the top ones
catch up). K = ceil(2h / s) layers: 2h is the reach of eq. (15); the interior
grains' eps is then within 0.5 % of the lattice's (checked). Printed beside:
the balance of the code's own forces for a uniform suspension, eq. (23)
with zero net volume flux (the fluid returns at (1 - eps) v / eps):
V (rho_s - rho_f) g = F_D(v / eps, eps) / eps, v = eps u_slip; its
difference from eps^n is the drag closure's (Di Felice's eps^-chi is itself a
fit to settling and fluidisation data).

Numerical choices (docs/dem.md, "Hindered settling"): the period n s with n
the fewest whole spacings over 4 supports 2h at h = 1.5 dr, dr = n s / 13
(13 fluid particles across: dr 5.05-5.34 mm, the paper's 5.33; h/d 1.9-2.0);
c_s 5 m/s (over 40 times the fastest grain).

CI case (default): eps 0.8, 12 x 8 x 12 grains, 3.5 cm above the base, water
1.2 cm over the block, to t = 0.2 s, window 0.12-0.2 s; --full: eps from
--eps (default 0.8), 12 layers, 5 cm above the base, water 2 cm over it, to
0.28 s, window 0.12-0.28 s (the block's lowest grains stay over 3 cm above
the base: nearer, the interior speeds up); --analyse DIR reads a run made
(with --eps). DEM:kn is the scene's (100 N/m).

  python3 -m tests.validate_dem_hindered --sphseg build/sphseg --work /tmp/vhs
"""
import argparse
import glob
import math
import os
import sys

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
from tests.containers import run_scene  # noqa: E402
from tests.validate_dem_settling import drag, terminal  # noqa: E402

SCENE = os.path.join(HERE, "..", "inputs", "dem_hindered.yml")
RHO_F, RHO_S, NU, G, D = 1000.0, 1200.0, 1e-6, 9.81, 0.004
TOL, TOL_STEADY, TOL_EPS = 0.10, 0.02, 0.005
V = math.pi / 6 * D ** 3


def spacing(eps):
    """The simple cubic lattice's spacing for the fluid fraction eps, m."""
    return D * (math.pi / 6 / (1 - eps)) ** (1 / 3)


def geometry(eps, layers, gap, above):
    """(-P overrides, n across, h) for the lattice of eps: n spacings across
    the period (the fewest over 6.4 cm: at dr = period / 13 and h = 1.5 dr,
    h is near the paper's 8 mm and the period holds 4 supports 2h = 12 dr),
    `layers` layers, the lowest `gap` m above the base, water
    `above` m over the highest (rounded up to whole dr)."""
    s = spacing(eps)
    n = math.ceil(0.064 / s - 1e-9)  # the period over 6.4 cm: h = 1.5 dr near the paper's 8 mm, 4 supports in 13 dr
    period = n * s
    dr = period / 13
    top = gap + (layers - 1) * s + above
    level = math.ceil(top / dr) * dr
    o = 0.5 * s
    over = ["Geometry:dr=%.9g" % dr, "Geometry:width=%.9g" % period, "Geometry:depth=%.9g" % period,
            "Container:walls=[{name: base, from: [0, 0], to: [%.9g, 0]}]" % period,
            "Container:regions=[{shape: fill, level: %.9g, C: 0}]" % level,
            "DEM:block_n=[%d, %d, %d]" % (n, layers, n), "DEM:block_spacing=%.9g" % s,
            "DEM:block_origin=[%.9g, %.9g, %.9g]" % (o, gap, o)]
    return over, n, 1.5 * dr


def n_rz(re):
    """Richardson & Zaki's (1954) exponent without the wall term."""
    if re < 0.2:
        return 4.65
    if re < 1:
        return 4.35 * re ** -0.03
    if re < 500:
        return 4.45 * re ** -0.1
    return 2.39


def n_ga(re):
    """Garside & Al-Dibouni (1977): (5.1 - n) / (n - 2.7) = 0.1 Re^0.9."""
    x = 0.1 * re ** 0.9
    return (5.1 + 2.7 * x) / (1 + x)


def n_rowe(re):
    """Rowe (1987)."""
    x = re ** 0.75
    return (4.7 + 0.41 * x) / (1 + 0.175 * x)


def balance(eps):
    """The code's uniform suspension: v = eps u_slip, V (rho_s - rho_f) g =
    F_D(u_slip, eps) / eps, by bisection, m/s."""
    w = V * (RHO_S - RHO_F) * G
    lo, hi = 1e-9, 10.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if drag(D, eps, mid) / eps > w else (mid, hi)
    return eps * 0.5 * (lo + hi)


def interior(out, n, layers, k):
    """Per snapshot: (time, the interior grains' mean downward velocity, their
    mean eps, the fluid's upward velocity at them, the lowest grain's height).
    Grain i of the block is in layer (i // n) % layers (dem_create's order)."""
    res = []
    for p in sorted(glob.glob(os.path.join(out, "snapshot_*.h5"))):
        with h5py.File(p, "r") as f:
            t = float(f["Header"].attrs["Time"])
            x, v = f["DEM/Coordinates"][:], f["DEM/Velocities"][:]
            e, uf = f["DEM/FluidFraction"][:], f["DEM/FluidVelocity"][:]
        lay = (np.arange(len(x)) // n) % layers
        m = (lay >= k) & (lay < layers - k)
        res.append((t, -float(v[m, 1].mean()), float(e[m].mean()), float(uf[m, 1].mean()), float(x[:, 1].min())))
    return np.array(res)


def check(out, eps, n, layers, h, t0, t1):
    k = math.ceil(2 * h / spacing(eps))
    r = interior(out, n, layers, k)
    w = r[(r[:, 0] >= t0 - 1e-9) & (r[:, 0] <= t1 + 1e-9)]
    v, e_in, uf = w[:, 1].mean(), w[:, 2].mean(), w[:, 3].mean()
    half = len(w) // 2  # halves of equal length: an odd count's middle snapshot in neither
    steady = abs(w[:half, 1].mean() - w[len(w) - half:, 1].mean()) / v
    amp = (w[:, 1].max() - w[:, 1].min()) / (2 * v)  # the oscillation with the water column's (printed)
    vt = terminal(D, 1.0)
    re = vt * D / NU
    nz = n_rz(re)
    ref = vt * eps ** nz
    err = v / ref - 1
    ok = abs(err) <= TOL and steady <= TOL_STEADY and abs(e_in / eps - 1) <= TOL_EPS
    print("%s eps %.2f (s %.4f mm, %d x %d x %d grains, %d face layers out): v = %.5f m/s over t = %.3f-%.3f s "
          "(halves differ %.2f %%, tolerance %.0f %%; snapshots within +-%.1f %%), eps at the interior grains %.4f, fluid up at them %.5f m/s; "
          "v_t %.5f m/s (Re_t %.0f); Richardson-Zaki n %.3f: v_t eps^n = %.5f m/s: %+.2f %% (tolerance %.0f %%); "
          "Garside-Al-Dibouni (n %.3f) %+.2f %%, Rowe (n %.3f) %+.2f %%; the code's balance eps u_slip %.5f m/s: %+.2f %%"
          % ("ok  " if ok else "FAIL", eps, 1e3 * spacing(eps), n, layers, n, k, v, w[0, 0], w[-1, 0], 100 * steady,
             100 * TOL_STEADY, 100 * amp, e_in, uf, vt, re, nz, ref, 100 * err, 100 * TOL, n_ga(re),
             100 * (v / (vt * eps ** n_ga(re)) - 1), n_rowe(re), 100 * (v / (vt * eps ** n_rowe(re)) - 1),
             balance(eps), 100 * (v / balance(eps) - 1)))
    return ok, {"eps": eps, "v": v, "eps_in": e_in, "uf": uf, "vt": vt, "re": re, "t0": w[0, 0], "t1": w[-1, 0],
                "steady": steady, "amp": amp, "bal": balance(eps)}


CI = {"layers": 8, "gap": 0.035, "above": 0.012, "t_end": 0.2, "t0": 0.12, "t1": 0.2, "out_dt": 0.01}
FULL = {"layers": 12, "gap": 0.05, "above": 0.02, "t_end": 0.28, "t0": 0.12, "t1": 0.28, "out_dt": 0.01}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sphseg")
    ap.add_argument("--work")
    ap.add_argument("--eps", type=float, default=0.8)
    ap.add_argument("--full", action="store_true", help="12 layers, 5 cm above the base, to 0.28 s (minutes)")
    ap.add_argument("--analyse", help="a run's output folder, read only (with --full and --eps as it was run)")
    ap.add_argument("--extra", action="append", default=[], help="Section:key=value, a further -P (a study's variant)")
    ap.add_argument("--tag", default="", help="appended to the run's folder name (a study's variant)")
    a = ap.parse_args()
    case = FULL if a.full else CI
    over, n, h = geometry(a.eps, case["layers"], case["gap"], case["above"])
    out = a.analyse
    if not out:
        if not (a.sphseg and a.work):
            sys.exit("--sphseg and --work, or --analyse DIR")
        out = os.path.join(a.work, "eps%g%s%s" % (a.eps, "_full" if a.full else "", a.tag))
        run_scene(a.sphseg, SCENE, out, over + ["Run:t_end=%g" % case["t_end"], "Output:dt=%g" % case["out_dt"],
                                                "Run:progress_s=1e9"] + a.extra, extra=["--overwrite"])
    kv = dict(e.split("=", 1) for e in a.extra)  # a variant's own smoothing length h = h_factor dr
    h = float(kv.get("Geometry:h_factor", 1.5)) * float(kv.get("Geometry:dr", h / 1.5))
    ok, _ = check(out, a.eps, n, case["layers"], h, case["t0"], case["t1"])
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
