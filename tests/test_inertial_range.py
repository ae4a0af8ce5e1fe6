#!/usr/bin/env python3
"""The well-posedness window and Barker & Gray's partial regularisation of
tools/analysis/inertial_range.py, against what they must satisfy (no sphseg
run; under a second):

- the window's edges for Table 1's mu(I) (mu_s 0.382, mu_d 0.682, I0 0.279)
  are where the criterion C(I) changes sign: C > 0 just outside, < 0 just
  inside (relative step 1e-6), and C -> mu_s^2 > 0 as I -> 0 (ill-posed, as
  Barker et al. 2015 state for any mu(I) of this form);
- the edges as docs/granular.md "Well-posedness" quotes them: 0.01656 and 0.841
  (1e-3 relative);
- the partially regularised law sqrt(alpha / ln(A / I)) equals mu(I) at the
  window's lower edge I_N1 (continuity, which fixes A; 1e-12), lies below mu_s
  at I = 1e-4, and the I the tool reports for a slope theta inverts it:
  mu_PR(I) = tan theta (1e-12);
- inertial_number_of_ratio inverts yield_ratio on both yield surfaces under both
  laws (1e-9), and under the regularized law gives 0 below the static ratio
  k(mu_s) and inf above the dynamic one k(mu_d);
- the conditioning kappa = d ln I / d ln k is the centred difference of ln I
  against ln yield_ratio (1e-6) on both yield surfaces, and it grows as I -> 0.

    /usr/bin/python3 -m tests.test_inertial_range [--sphseg IGNORED --work IGNORED]
"""
import math
import sys

from tests.checks import check, parse_args, summary  # noqa: E402
from tools.analysis import inertial_range as ir  # noqa: E402

MU_S, MU_D, I0, ALPHA = 0.382, 0.682, 0.279, 1.9


def main():
    parse_args(__doc__)
    lo, hi = ir.window(MU_S, MU_D, I0)
    C = lambda I: float(ir.criterion(I, MU_S, MU_D, I0))
    for name, I, inside in (("below I_low", lo * (1 - 1e-6), False), ("above I_low", lo * (1 + 1e-6), True),
                            ("below I_high", hi * (1 - 1e-6), True), ("above I_high", hi * (1 + 1e-6), False)):
        c = C(I)
        check("C(I) " + name, c, "< 0" if inside else "> 0", (c < 0) == inside, "the window's edge")
    c0 = C(1e-12)
    check("C(1e-12) - mu_s^2", abs(c0 - MU_S ** 2), 1e-9, abs(c0 - MU_S ** 2) < 1e-9, "I -> 0: nu -> 0")
    check("I_low / 0.01656 - 1", abs(lo / 0.01656 - 1), 1e-3, abs(lo / 0.01656 - 1) < 1e-3, "docs/granular.md")
    check("I_high / 0.841 - 1", abs(hi / 0.841 - 1), 1e-3, abs(hi / 0.841 - 1) < 1e-3, "docs/granular.md")
    IN1, A, mu_lo = ir.partial_regularisation(MU_S, MU_D, I0, ALPHA)
    mu_pr = lambda I: math.sqrt(ALPHA / math.log(A / I))
    e = abs(mu_pr(IN1) - ir.mu_of_I(IN1, MU_S, MU_D, I0))
    check("mu_PR(I_N1) - mu(I_N1)", e, 1e-12, e < 1e-12 and IN1 == lo and mu_lo == ir.mu_of_I(lo, MU_S, MU_D, I0),
          "continuity at the window's edge")
    check("mu_PR(1e-4)", mu_pr(1e-4), "< mu_s", mu_pr(1e-4) < MU_S, "no static yield below the edge")
    for th in (19.0, 20.0):
        m = math.tan(math.radians(th))
        I = A * math.exp(-ALPHA / (m * m))
        check("mu_PR(I(%g deg)) - tan" % th, abs(mu_pr(I) - m), 1e-12, abs(mu_pr(I) - m) < 1e-12, "the inverse")
    for y in ("drucker_prager", "mu_I"):
        for law in ("regularized", "partial"):
            P = {"mu_s": MU_S, "mu_d": MU_D, "I0": I0, "yield": y, "mu_law": law, "pr_alpha": ALPHA}
            for I in (1e-4, 5e-3, 0.05, 0.5):
                if law == "regularized" and I < 1e-3:
                    continue  # its yield ratio at I -> 0 is the static one, which arrests: I = 0 (below)
                e = abs(float(ir.inertial_number_of_ratio(ir.yield_ratio(P, I), P)) / I - 1)
                check("%s, %s: inertial_number_of_ratio(yield_ratio(I = %g)) / I - 1" % (y, law, I), e, 1e-9,
                      e < 1e-9, "the inverse")
        P = {"mu_s": MU_S, "mu_d": MU_D, "I0": I0, "yield": y, "mu_law": "regularized"}
        k_s, k_d = ir.yield_ratio(P, 0.0), ir.yield_ratio(P, 1e12)
        ok = ir.inertial_number_of_ratio(0.99 * k_s, P) == 0 and ir.inertial_number_of_ratio(1.001 * k_d, P) == math.inf
        check("%s, regularized: I below the static ratio, above the dynamic" % y, 0, "0 and inf", ok,
              "arrested, no steady state")
    for y in ("drucker_prager", "mu_I"):
        P = {"mu_s": MU_S, "mu_d": MU_D, "I0": I0, "yield": y, "mu_law": "regularized"}
        kaps = []
        for I in (0.01, 0.04, 0.3):
            h = 1e-5
            fd = 2 * h / (math.log(float(ir.yield_ratio(P, I * math.exp(h)))) - math.log(float(ir.yield_ratio(P, I * math.exp(-h)))))
            kap = float(ir.condition(I, MU_S, MU_D, I0, y)[1])
            kaps.append(kap)
            check("%s: kappa(I = %g) / centred difference - 1" % (y, I), abs(kap / fd - 1), 1e-6,
                  abs(kap / fd - 1) < 1e-6, "d ln I / d ln k")
        check("%s: kappa falls as I rises (0.01, 0.04, 0.3)" % y, kaps[0], "> kappa(0.04) > kappa(0.3)",
              kaps[0] > kaps[1] > kaps[2], "nu -> 0 as I -> 0")
    sys.exit(summary("test_inertial_range"))


if __name__ == "__main__":
    main()
