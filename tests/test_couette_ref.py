#!/usr/bin/env python3
"""The plane Couette reference of tools/analysis/couette.py, checked against
answers known without it (no sphseg run; a few seconds):

- without gravity the stress ratio is the same at every depth, so the shear
  rate is too and the profile is linear: u(0) = gdot H with gdot = I(mu) sqrt(p
  / rho_s) / d, I = I0 (mu - mu_s) / (mu_d - mu), mu the friction whose yield
  ratio (drucker_prager k_mu(mu) = 3 mu / sqrt(9 + 12 mu^2), or mu_I's mu) is
  tau / p (1e-12);
- inertial_range.mu_of_yield_ratio inverts k_of_mu on both yield surfaces
  (1e-12);
- under gravity the shear stops at the yield depth z_y = (tau / k(mu_s) -
  sigma_top) / (rho g): the profile's shear rate is 0 below it and positive
  above (within one grid step);
- tau_for_lid returns the tau whose lid moves at U (1e-6 of U);
- the partial law (Barker & Gray 2017): where the ratio is the yield ratio of
  Material:mu_law partial at I (inertial_range.yield_ratio in tools/analysis,
  above and below I_N1), the shear rate is that I's, sqrt(gdot^2 + lambda^2)
  d / sqrt(p / rho_s) = I (1e-9), and tau_for_lid finds a tau below the static
  yield stress, where that law's bed still creeps (1e-6);
- measure on a laid lattice: rows of spacing dr carrying the reference's own
  profile and stresses (sigma_xy = -tau, sigma_yy = -(sigma_top + rho g z))
  give back tau and sigma_top to round-off and tau / tau_ref = 1 (1e-4: the
  bisection), and the same lattice with tau 1 % high reads 1.01.

    /usr/bin/python3 -m tests.test_couette_ref [--sphseg IGNORED --work IGNORED]
"""
import math
import sys

import numpy as np

from tests.checks import check, parse_args, summary  # noqa: E402
from tools.analysis import couette as cu  # noqa: E402
from tools.analysis import inertial_range as ir  # noqa: E402

BASE = {"mu_s": 0.382, "mu_d": 0.682, "I0": 0.279, "rho_s": 2500.0, "yield": "drucker_prager", "mu_law": "regularized",
        "pr_alpha": 1.9, "lambda": 1e-3, "d": 0.000375, "H": 0.016, "dr": 0.0005, "U": 0.085, "rho": 1500.0,
        "g": 0.981}


def scene(**kw):
    return dict(BASE, **kw)


def lattice(P, tau, s_top, per_row=20):
    """A snapshot dict whose rows (spacing dr, the lid's row first at z = dr / 2) carry the reference's
    profile at tau and s_top, with that stress."""
    z_rows = (np.arange(round(P["H"] / P["dr"])) + 0.5) * P["dr"]
    zr, ur, gr, _ = cu.profile(tau, s_top, P)
    z = np.repeat(z_rows, per_row)
    n = z.size
    x = np.c_[np.tile(np.arange(per_row) * P["dr"], len(z_rows)), P["H"] - z, np.zeros(n)]
    v = np.c_[np.interp(z, zr, ur), np.zeros(n), np.zeros(n)]
    S = np.zeros((n, 6))
    S[:, 1] = -(s_top + P["rho"] * P["g"] * z)
    S[:, 0] = S[:, 2] = S[:, 1]
    S[:, 3] = -tau
    return {"Time": 0.5, "Kind": np.zeros(n, int), "Coordinates": x, "Velocities": v, "Stress": S,
            "ShearRate": np.interp(z, zr, gr)}


def main():
    parse_args(__doc__)
    for y in ("drucker_prager", "mu_I"):
        P = scene(g=0.0, **{"yield": y})
        mu = 0.45
        k = cu.k_of_mu(mu, P)
        back = float(ir.mu_of_yield_ratio(k, P["yield"]))
        check("%s: mu_of_yield_ratio(k_of_mu(0.45)) - 0.45" % y, abs(back - mu), 1e-12, abs(back - mu) < 1e-12,
              "the inverse of the yield ratio")
        p, tau = 100.0, k * 100.0
        I = P["I0"] * (mu - P["mu_s"]) / (P["mu_d"] - mu)
        g_exact = I * math.sqrt(p / P["rho_s"]) / P["d"]
        z, u, gd, _ = cu.profile(tau, p, P)
        e = abs(u[0] / (g_exact * P["H"]) - 1)
        check("%s, no gravity: u(lid) / (gdot H) - 1" % y, e, 1e-12, e < 1e-12, "uniform shear, closed form")
    P = scene()
    s_top, tau = 100.0, 38.0
    zy = cu.yield_depth(tau, s_top, P)
    z, u, gd, _ = cu.profile(tau, s_top, P)
    step = z[1] - z[0]
    below, above = gd[z > zy + step], gd[z < zy - step]
    ok = np.all(below == 0) and np.all(above > 0)
    check("the shear stops at z_y = (tau / k(mu_s) - s_top) / (rho g) = %.3f mm" % (1e3 * zy), zy, step, ok,
          "gdot 0 below z_y, > 0 above (one grid step)")
    tr = cu.tau_for_lid(P["U"], s_top, P)
    e = abs(cu.profile(tr, s_top, P, 4001)[1][0] / P["U"] - 1)
    check("tau_for_lid: u(lid) / U - 1", e, 1e-6, e < 1e-6, "the bisection's own target")
    Pp = scene(mu_law="partial")
    for I in (1e-4, 3e-3, 0.05):  # below and above I_N1 = 0.0166
        p = 100.0
        k = float(ir.yield_ratio(Pp, I))
        g = float(cu.shear_rate(k * p, p, Pp))
        I_N1 = ir.partial_regularisation(Pp["mu_s"], Pp["mu_d"], Pp["I0"], Pp["pr_alpha"])[0]
        I_back = math.sqrt(g * g + Pp["lambda"] ** 2) * Pp["d"] / math.sqrt(p / Pp["rho_s"]) if I < I_N1 \
            else g * Pp["d"] / math.sqrt(p / Pp["rho_s"])
        e = abs(I_back / I - 1)
        check("partial law at I = %g: I of the shear rate / I - 1" % I, e, 1e-9, e < 1e-9,
              "inertial_range.yield_ratio, Barker & Gray 2017")
    t0 = 0.9 * cu.k_of_mu(Pp["mu_s"], Pp) * s_top  # under the partial law the bed creeps below the static yield
    U0 = cu.profile(t0, s_top, Pp, 4001)[1][0]
    e = abs(cu.tau_for_lid(U0, s_top, Pp) / t0 - 1)
    check("partial law: tau_for_lid below the static yield stress, relative", e, 1e-6, e < 1e-6,
          "the lid speed of tau = 0.9 k(mu_s) sigma_top")
    tau = cu.tau_for_lid(P["U"], s_top, P)
    r = cu.measure(lattice(P, tau, s_top), P)
    e = max(abs(r["tau"] / tau - 1), abs(r["s_top"] / s_top - 1))
    check("measure: tau and sigma_top read back, relative", e, 1e-12, e < 1e-12, "the laid stresses")
    check("measure: tau / tau_ref(U) - 1 on the reference's own layer", abs(r["ratio"] - 1), 1e-4,
          abs(r["ratio"] - 1) < 1e-4, "tau_for_lid's bisection")
    r = cu.measure(lattice(P, 1.01 * tau, s_top), P)
    check("measure: a layer with tau 1 % high reads tau / tau_ref", r["ratio"], "1.01 +- 1e-4",
          abs(r["ratio"] - 1.01) < 1e-4, "the planted error")
    return summary("test_couette_ref")


if __name__ == "__main__":
    sys.exit(main())
