"""Water driven by gravity through a fixed porous block of DEM grains
(inputs/dem_porous_flow.yml; Markauskas, Kruggel-Emden, Sivanesapillai &
Steeb 2016, §7), in a box periodic along all three axes. The steady
superficial velocity U_s (the mean fluid velocity on the horizontal slab at
the period's seam, a support 2h and more from the block, where eps = 1: the
paper's "average velocity on a cross plane") against the analytic balance
of the code's equations:

    sum_i F_D(U_s / eps_i, eps_i) / eps_i = rho_f g V_box,

F_D Di Felice's drag (eqs. 19, 21, 22) at the interstitial speed U_s / eps_i
(continuity), V_box the box (the fluid's weight plus the pressure share of
eq. 23's -V rho_f g: in a periodic box the pressure has no mean gradient,
so the drag alone carries rho_f g V_box). This is the paper's eq. (27) with
m its fluid's total mass (the analytic 0.856 m/s of its §7). Two analytic
values are printed:
  - eps_i the fluid fraction the run reports at each grain (DEM/FluidFraction,
    eq. 20: the kernel-smoothed one, larger in the block's outer layers): the
    reference of the tolerance (the code's own balance, as the paper's §8
    took its eps from its run);
  - eps_i = 1 - (pi/6) d^3 / s^3 = 0.779 everywhere, the block's true
    fraction, the paper's analytic curve: the run is faster than it by what
    the smoothed eps of the outer layers takes off the drag.

CI case (default): 13 x 13 x 13 dr, a block of 13 x 4 x 13 grains, nu =
1e-4 m^2/s (eta 0.1 Pa s, Re about 10: steady in 0.15 s), c_s 5 m/s and the
leapfrog integrator (one coupling a step), so
that it runs in about a minute; tolerance 3 % on U_s (the mean over the last
0.04 s; the full case 0.1 s: the fluid's pressure waves move it by a few
per cent between snapshots) against the smoothed-eps analytic, and steady
(the window's two halves within 1.5 %: the flow wobbles by +-1 % about its
steady value, the halves 0.86 % apart on the leapfrog and 0.39 % on the
predictor-corrector, where the approach before 0.1 s rises 1.5 % in 0.02 s;
the full case's water, Re 2500, keeps its +-4 % waves: 2 % there, over
0.15 s). --full runs the
scene as it stands (water, 13 x 13 x 24 dr, the paper's 10 layers; minutes)
and prints the same lines; --analyse DIR reads a run already made.

  python3 -m tests.validate_dem_porous --sphseg build/sphseg --work /tmp/vdp
"""
import glob
import math
import os
import sys

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
from tests.containers import case_main  # noqa: E402

SCENE = os.path.join(HERE, "..", "inputs", "dem_porous_flow.yml")
RHO_F, G, D, S, DR = 1000.0, 9.81, 0.004, 0.00533, 0.00533
TOL = 0.03
CI = {"nu": 1e-4, "ny": 13, "layers": 4, "window": 0.04, "steady": 0.015,
      "over": ["Material:eta=0.1", "Material:E=30000", "Geometry:height=0.06929",
               "Container:regions=[{shape: fill, level: 0.06929, C: 0}]", "DEM:block_n=[13, 4, 13]",
               "DEM:block_origin=[0.002665, 0.026650, 0.002665]", "Initial:pressure=2000",
               "Run:t_end=0.16", "Output:dt=0.01", "Run:integrator=leapfrog"]}
FULL = {"nu": 1e-6, "ny": 24, "layers": 10, "window": 0.15, "steady": 0.02, "over": []}


def drag(eps, u, nu):
    """Di Felice's drag, eqs. (19), (21), (22), N, at the relative speed u > 0."""
    re = eps * u * D / nu
    cd = (0.63 + 4.8 / math.sqrt(re)) ** 2
    chi = 3.7 - 0.65 * math.exp(-(1.5 - math.log10(re)) ** 2 / 2)
    return 0.125 * cd * RHO_F * math.pi * D * D * u * u * eps ** (2 - chi)


def analytic(eps, vbox, nu):
    """U_s with sum_i F_D(U_s / eps_i, eps_i) / eps_i = rho_f g V_box, by bisection."""
    w = RHO_F * G * vbox
    lo, hi = 1e-9, 20.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        f = sum(drag(e, mid / e, nu) / e for e in eps)
        lo, hi = (lo, mid) if f > w else (mid, hi)
    return 0.5 * (lo + hi)


def rows(out, height):
    """(time, U_s, grains' eps) of each snapshot: U_s the mean downward
    velocity of the fluid within 1.5 dr of the period's seam y = 0."""
    res = []
    for p in sorted(glob.glob(os.path.join(out, "snapshot_*.h5"))):
        with h5py.File(p, "r") as f:
            t = float(f["Header"].attrs["Time"])
            x = f["Particles/Coordinates"][:, 1]
            v = f["Particles/Velocities"][:, 1]
            k = f["Particles/Kind"][:]
            eps = f["DEM/FluidFraction"][:]
        y = np.mod(x, height)
        seam = (k == 0) & ((y < 1.5 * DR) | (y > height - 1.5 * DR))
        res.append((t, -float(np.mean(v[seam])), eps))
    return res


def check(out, case):
    height = case["ny"] * DR
    vbox = (13 * DR) ** 2 * height
    r = rows(out, height)
    t = r[-1][0]
    win = [x for x in r if x[0] >= t - case["window"] - 1e-9]
    half = len(win) // 2
    u = float(np.mean([x[1] for x in win]))
    u_first, u_last = np.mean([x[1] for x in win[:half]]), np.mean([x[1] for x in win[half:]])
    eps = np.mean([x[2] for x in win], axis=0)
    ua = analytic(eps, vbox, case["nu"])
    ut = analytic(np.full(len(eps), 1 - math.pi / 6 * D ** 3 / S ** 3), vbox, case["nu"])
    err, steady = (u - ua) / ua, abs(u_last - u_first) / u
    ok = abs(err) <= TOL and steady <= case["steady"]
    print("%s porous block %d layers, nu %g: U_s = %.4f m/s over t = %.3f-%.3f s; analytic with the run's eps at the "
          "grains (%.4f to %.4f, mean %.4f) %.4f m/s: %+.2f %% (tolerance %.0f %%); with the block's eps 0.779 %.4f m/s: "
          "%+.2f %%; the window's halves differ by %.2f %% (tolerance %.1f %%)"
          % ("ok  " if ok else "FAIL", case["layers"], case["nu"], u, win[0][0], t, eps.min(), eps.max(), eps.mean(), ua,
             100 * err, 100 * TOL, ut, 100 * (u - ut) / ut, 100 * steady, 100 * case["steady"]))
    return ok


def main():
    case_main(SCENE, CI, FULL, check, "the scene as it stands (water, 10 layers; minutes)")


if __name__ == "__main__":
    main()
