"""Steady flow down a rough incline (inputs/chute_2d.yml) at a CI size, against
the analytic Bagnold solution of the model's mu(I) rheology, its flowing and
arrested regimes, and the Gray & Chugunov steady segregation profile.

Reference (tools/studies/chute_study.py; docs/validation.md "Chute"): the yield
sqrt(J2) = k_mu(mu(I)) p gives tau / p = k_mu(mu(I)) = tan(theta) in simple
shear, a uniform I and u(z) ~ H^1.5 - (H - z)^1.5; the layer rests below
atan k_mu(mu_s) = 19.3 degrees and accelerates above atan k_mu(mu_d) = 28.2.
Segregation: eq. 28 of papers/thornton-weinhart-multiscale-granular-review.txt
with Pe = V cos(theta) H / D.

Cases (H / dr = 20 rows: 10 rows lose their lattice rows without artificial
viscosity, docs/validation.md):
  steady   25 deg, H = 5 mm, dr 0.25 mm, alpha_av 0, E 2.5e4 (c 4.8 m/s,
           Mach 0.02), to 1.2 s (the layer's relaxation time is 0.16 s).
           Measured: depth-mean 2.9 % above the analytic 0.0607 m/s; rows
           above the first within 5.3 % of u(H) of the profile (the first
           row, next to the no-slip base, slips by 14 %). Tolerances 6 % on
           the mean, 9 % on the rows above the first.
  rest     18 deg (below 19.3), the same layer to 0.4 s: measured depth-mean
           1.6e-4 m/s; tolerance 2 % of the 25-degree analytic mean (1.2e-3).
  running  30 deg (above 28.2): no steady state; the depth-mean must still
           grow between 0.3 and 0.4 s by more than 10 % of its value
           (measured +25 %; a steady layer's changes by < 1 % by then).
  riemann  the steady case with Flow:stabilization riemann (the Riemann
           solver's momentum dissipation alone, docs/granular.md
           "Stabilisation") to 0.8 s (five relaxation times), the mean of the
           snapshots of t = 0.4-0.8 s: measured 1.3 % under the analytic
           (0.65 % over it to 1.2 s with the last 0.5 s, 40 s more of a core;
           development machine, 2026-12-01); the same tolerance on the mean as
           alpha_av 0.
  segreg.  25 deg, H = 2 cm, dr 2 mm, V 0.04 m/s, D 2e-4 m^2/s, C 0.5 (Pe 3.6)
           to 3 s: measured MAE 0.0096 against eq. 28 (0.0055 at dr 1 mm,
           0.0030 at 0.5 mm on the H100); tolerance 0.02.
"""
import math
import os
import sys

import numpy as np

from tools.studies import batch  # noqa: E402
from tools.studies import chute_study as cs  # noqa: E402
from tests.containers import sphseg_work_args  # noqa: E402  (tests/containers.py)

TOL_MEAN, TOL_ROWS, TOL_REST, MIN_GROWTH, TOL_SEG = 0.06, 0.09, 0.02, 0.10, 0.02


def main():
    a = sphseg_work_args()
    layer = dict(H=0.005, dr=0.00025, alpha=0.0, E=2.5e4)
    # the two long runs first: side by side on two cores the short three then fill in after them
    cases = [cs.case("steady", theta=25, t_end=1.2, **layer),
             cs.case("steady_riemann", theta=25, t_end=0.8, stab="riemann", **layer),
             cs.case("rest", theta=18, t_end=0.4, **layer), cs.case("running", theta=30, t_end=0.4, **layer),
             cs.case("seg", dr=0.002, seg=cs.SEG)]
    for c in cases:
        c.over["Output:dt"] = 0.1
    batch.run_cases_or_exit(cases, a.sphseg, a.work, limit_s=900, side_by_side=True)
    ok = True
    for c in cases:
        cs.reduce_run(os.path.join(a.work, c.name), float(c.over["Geometry:dr"]))
    # the steady layers' profiles: the mean of the snapshots of the last 0.5 s (t = 0.7-1.2 s, six of them),
    # rows of fewer than half the median count (a stray grain between two rows) left out. One snapshot of the
    # layer without artificial viscosity (alpha 0) is one realisation: at t = 1.2 s one grain had slipped
    # below the first row, so that the rows read one off and "the rows above the first" lay within 18.3 % of
    # u(H); with E moved by 4e-14 of itself, 4.8 % (2026-11-29, after the reordered sums of issue 55)
    S = {c.name: cs.summarise(a.work, c.name, {"theta": c.meta["theta"], "H": c.meta["H"]},
                              window={"steady": 0.5, "steady_riemann": 0.4}.get(c.name, 0.0)) for c in cases}

    s = S["steady"]
    good = s["err_mean"] <= TOL_MEAN and s["err_profile"] <= TOL_ROWS
    ok &= good
    print("%s 25 deg steady: depth-mean %.4f m/s against the analytic %.4f (%.1f %%, tolerance %.0f %%); rows above "
          "the first within %.1f %% of u(H) (tolerance %.0f %%); the first row %+.1f %%" % (
              "ok  " if good else "FAIL", s["u_mean"], s["u_ref_mean"], 100 * s["err_mean"], 100 * TOL_MEAN,
              100 * s["err_profile"], 100 * TOL_ROWS, 100 * s["err_base"]))
    s = S["steady_riemann"]  # Flow:stabilization riemann: the Riemann solver's momentum dissipation alone
    good = s["err_mean"] <= TOL_MEAN
    ok &= good
    print("%s 25 deg steady, Flow:stabilization riemann: depth-mean %.4f m/s against the analytic %.4f (%.1f %%, "
          "tolerance %.0f %%); rows above the first within %.1f %% of u(H)" % (
              "ok  " if good else "FAIL", s["u_mean"], s["u_ref_mean"], 100 * s["err_mean"], 100 * TOL_MEAN,
              100 * s["err_profile"]))
    ref25 = S["steady"]["u_ref_mean"]
    r = S["rest"]
    good = abs(r["u_mean"]) <= TOL_REST * ref25 and math.isclose(cs.inertial_number(18), 0.0)
    ok &= good
    print("%s 18 deg (below atan k_mu(mu_s) = %.1f): depth-mean %.2e m/s (tolerance %.1e)" % (
        "ok  " if good else "FAIL", math.degrees(math.atan(cs.kmu(cs.MU_S))), r["u_mean"], TOL_REST * ref25))
    g = dict(S["running"]["series"])
    t1, t2 = 0.3, 0.4
    u1 = g[min(g, key=lambda t: abs(t - t1))]
    u2 = g[min(g, key=lambda t: abs(t - t2))]
    good = u2 > u1 * (1 + MIN_GROWTH) and cs.inertial_number(30) == math.inf
    ok &= good
    print("%s 30 deg (above atan k_mu(mu_d) = %.1f): depth-mean %.4f -> %.4f m/s from %.1f to %.1f s (+%.0f %%, at "
          "least +%.0f %%)" % ("ok  " if good else "FAIL", math.degrees(math.atan(cs.kmu(cs.MU_D))), u1, u2, t1, t2,
                               100 * (u2 / u1 - 1), 100 * MIN_GROWTH))
    q = S["seg"]
    V, D, phi0 = cs.SEG
    Pe = V * math.cos(math.radians(25)) * 0.02 / D
    e = np.abs(q["C"] - cs.gray_chugunov(q["y"] / 0.02, phi0, Pe)).mean()
    good = e <= TOL_SEG
    ok &= good
    print("%s segregation on the chute, Pe = %.2f: MAE %.4f against Gray & Chugunov eq. 28 (tolerance %.3f)" % (
        "ok  " if good else "FAIL", Pe, e, TOL_SEG))
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
