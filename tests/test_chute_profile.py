#!/usr/bin/env python3
"""How tools/analysis/chute_profile.py reads a chute layer, checked on a layer
whose answer is known without it (no sphseg run; under a second):

A lattice of N = 13 rows of spacing dr = 0.5 mm (H = 6.5 mm, the 2D drum's
flowing layer), 20 particles a row jittered by up to 0.3 dr in height, each with
the Bagnold speed of chute_study.bagnold at its own height (drucker_prager's
reading, 21.3 deg, d = 0.375 mm) and the stress of a steady uniform layer in
simple shear: sigma_xx = sigma_yy = sigma_zz = -p, p = rho g cos(theta) (H - y),
sigma_xy = -tan(theta) p. So:

- rows_of finds the N rows, each at its particles' mean height;
- compare gives the depth mean and the top row at 1 (2e-3: a row's mean speed is
  the profile's mean over its particles' jitter, not its value at their mean
  height; the curvature leaves 2e-4);
- the rows' p is the lithostatic pressure and sqrt(J2) / p = tan(theta) (1e-12);
- mean_rows keeps the rows present in every snapshot (a second snapshot without
  the top row drops it) and averages them;
- a layer 5 % slow reads 0.95 in both ratios.

    /usr/bin/python3 -m tests.test_chute_profile [--sphseg IGNORED --work IGNORED]
"""
import math
import sys

import numpy as np

from tests.checks import check, parse_args, summary  # noqa: E402
from tools.analysis import chute_profile as cp  # noqa: E402
from tools.studies.chute_study import RHO, G, bagnold  # noqa: E402

N, DR, THETA, D = 13, 0.0005, 21.3, 0.000375
H = N * DR


def layer(rng, slow=1.0, rows=N):
    k = np.repeat(np.arange(rows), 20)
    y = (k + 0.5) * DR + rng.uniform(-0.3, 0.3, k.size) * DR
    u = slow * np.asarray(bagnold(y, THETA, H, "k_mu", d=D), float)
    p = RHO * G * math.cos(math.radians(THETA)) * (H - y)
    sig = np.zeros((k.size, 6))
    sig[:, 0] = sig[:, 1] = sig[:, 2] = -p
    sig[:, 3] = -math.tan(math.radians(THETA)) * p
    return y, u, sig


def main():
    parse_args(__doc__)
    rng = np.random.default_rng(7)
    y, u, sig = layer(rng)
    r = cp.rows_of(y, u, sig, DR)
    check("rows found", len(r), N, len(r) == N, "the lattice's rows")
    ey = max(abs(r[k][0] - y[np.rint(y / DR - 0.5) == k].mean()) for k in r) / DR
    check("row height - its particles' mean, in dr", ey, 1e-12, ey < 1e-12, "the jittered lattice")
    yy, uu, pp, sj = cp.mean_rows([r])
    rm, rt = cp.compare(yy, uu, THETA, H, "k_mu", D)
    # the row means of u are means of the profile at the particles' heights, not the profile at
    # the rows' mean heights: equal to round-off only where u is linear over a row; the Bagnold
    # profile's curvature over 0.6 dr leaves a few 1e-4 (the base row, where u is smallest, most)
    check("depth mean / Bagnold's at the rows' heights - 1", abs(rm - 1), 2e-3, abs(rm - 1) < 2e-3,
          "the laid profile, averaged over each row's jitter")
    check("top row / Bagnold's - 1", abs(rt - 1), 2e-3, abs(rt - 1) < 2e-3, "the laid profile")
    pl = RHO * G * math.cos(math.radians(THETA)) * (H - yy)
    ep = np.max(np.abs(pp / pl - 1))
    check("p / lithostatic - 1", ep, 1e-12, ep < 1e-12, "the laid stress (linear in y: the row mean is exact)")
    et = np.max(np.abs(sj / pp - math.tan(math.radians(THETA))))
    check("sqrt(J2) / p - tan(theta)", et, 1e-12, et < 1e-12, "simple shear at the slope's stress ratio")
    y2, u2, s2 = layer(rng, rows=N - 1)
    both = cp.mean_rows([r, cp.rows_of(y2, u2, s2, DR)])
    check("rows kept over two snapshots, one without the top row", len(both[0]), N - 1, len(both[0]) == N - 1,
          "the rows present in every snapshot")
    ys, us, ss = layer(rng, slow=0.95)
    s = cp.mean_rows([cp.rows_of(ys, us, ss, DR)])
    rm5, rt5 = cp.compare(s[0], s[1], THETA, H, "k_mu", D)
    e5 = max(abs(rm5 - 0.95), abs(rt5 - 0.95))
    check("a layer 5 % slow: both ratios - 0.95", e5, 2e-3, e5 < 2e-3, "the laid profile times 0.95")
    sys.exit(summary("test_chute_profile"))


if __name__ == "__main__":
    main()
