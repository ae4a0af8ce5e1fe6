"""The inertial numbers a run reaches, against the window where incompressible
mu(I) is well posed (Barker, Schaeffer, Bohorquez & Gray 2015).

Window. For mu(I) = mu_s + (mu_d - mu_s) / (I0 / I + 1) and nu = I mu'(I) / mu,
short waves of the 2D incompressible equations about a uniform shear grow as
k^2 (ill-posed) unless

    C(I) = 4 nu^2 - 4 nu + mu^2 (1 - nu / 2)^2 < 0.

(Derivation, docs/granular.md "Well-posedness": principal axes of the base
strain rate D0 = diag(d, -d), a perturbation of wavevector k at angle phi,
c = cos(2 phi); the growth rate is -(mu p k^2 / (2 rho d)) G(c) / (1 - m c),
m = mu (1 - nu / 2), G(c) = nu + (1 - nu) c^2 - m c, whose minimum over c is
nu - m^2 / (4 (1 - nu)). It is the form of Barker & Gray 2017, eq. 3.9, as
alexjarosch/OpenFOAM-muI utils/calc_IN1.py writes it.) C -> mu_s^2 > 0 as
I -> 0 and mu_d^2 > 0 as I -> inf: ill-posed at both ends.

Run. Each material particle's I = gdot d_avg / sqrt(p / rho_s) (ShearRate,
Stress, Concentration of the snapshots; Grains and Material from the run's
used_params.yml), among the flowing particles: p > 0, at the yield surface
(sqrt(J2) within 1 % of k p, k from Material:yield) and sheared at least
--gdot-fraction (0.1) of the snapshot's 99th-percentile shear rate. The shear
rate is what tells: the geostatic start puts a whole bed on the yield
surface, and a drum's bed stays there as it turns, while only its surface
layer shears (2D EV drum at 8 s: gdot 1-10 1/s and 2 cm/s off the rigid
rotation in the layer; below 1 1/s and 0.3 mm/s off it elsewhere).

Conditioning. A flow whose stress the momentum balance fixes shears at the I
where k(mu(I)) equals its stress ratio r = sqrt(J2) / p, so a relative error e
in r becomes a relative error kappa e in the shear rate, kappa = d ln I / d ln
k = 1 / (nu d ln k / d ln mu), with the nu of the criterion above (d ln k / d
ln mu = 9 / (9 + 12 mu^2) for drucker_prager, 1 for mu_I). As I -> 0, nu -> 0
and kappa grows without bound: the same nu makes the law ill-posed and the
rate ill-conditioned in the stress near the static yield.

  python3 -m tools.analysis.inertial_range window [--mu-s 0.382 --mu-d 0.682 --I0 0.279] [--pr-alpha 1.9]
  python3 -m tools.analysis.inertial_range condition [--I 0.01 0.02 0.04 0.1] [--yield drucker_prager]
  python3 -m tools.analysis.inertial_range run OUTDIR [--from T] [--gdot-fraction 0.1]
"""
import argparse
import functools
import math
import os

import numpy as np

from tools.analysis import snap  # noqa: E402


def mu_of_I(I, mu_s, mu_d, I0):
    """mu(I) = mu_s + (mu_d - mu_s) / (I0 / I + 1)."""
    return mu_s + (mu_d - mu_s) * I / (I + I0)


def nu_of_I(I, mu_s, mu_d, I0):
    """(nu, mu) at I: nu = I mu'(I) / mu of the regularized law."""
    I = np.asarray(I, float)
    mu = mu_of_I(I, mu_s, mu_d, I0)
    return I * (mu_d - mu_s) * I0 / (I + I0) ** 2 / mu, mu


def criterion(I, mu_s, mu_d, I0):
    """C(I) above: < 0 well posed."""
    nu, mu = nu_of_I(I, mu_s, mu_d, I0)
    return 4 * nu * nu - 4 * nu + mu * mu * (1 - nu / 2) ** 2


def condition(I, mu_s, mu_d, I0, yield_="drucker_prager"):
    """(nu, kappa) at inertial number I (module doc, "Conditioning"): nu = I mu'(I) / mu and
    kappa = d ln I / d ln k(mu(I)) for the regularized law on Material:yield's surface."""
    nu, mu = nu_of_I(I, mu_s, mu_d, I0)
    dk = 1.0 if yield_ == "mu_I" else 9 / (9 + 12 * mu * mu)
    return nu, 1 / (nu * dk)


def window(mu_s, mu_d, I0):
    """(I_low, I_high) of the well-posed window, or None; bisection on C."""
    I = np.logspace(-8, 4, 4001)
    ok = np.where(criterion(I, mu_s, mu_d, I0) < 0)[0]
    if len(ok) == 0:
        return None

    def edge(a, b):  # C changes sign between a and b
        sa = criterion(a, mu_s, mu_d, I0) < 0
        for _ in range(200):
            m = math.sqrt(a * b)
            if (criterion(m, mu_s, mu_d, I0) < 0) == sa:
                a = m
            else:
                b = m
        return math.sqrt(a * b)

    return edge(I[ok[0] - 1], I[ok[0]]), edge(I[ok[-1]], I[ok[-1] + 1])


def params(outdir):
    import yaml
    with open(os.path.join(outdir, "used_params.yml")) as f:
        u = yaml.safe_load(f)
    m, g = u["Material"], u["Grains"]
    return {"mu_s": float(m["mu_s"]), "mu_d": float(m["mu_d"]), "I0": float(m["I0"]), "rho_s": float(m["rho_s"]),
            "yield": str(m.get("yield", "drucker_prager")), "d_small": float(g["d_small"]),
            "d_large": float(g["d_large"]), "mu_law": str(m.get("mu_law", "regularized")),
            "pr_alpha": float(m.get("pr_alpha", 1.9))}


def kmu(mu):
    return 3 * mu / np.sqrt(9 + 12 * mu * mu)


def pressure_tau(S):
    """p = -tr(sigma) / 3 and sqrt(J2) of snapshot stresses S (N x 6: xx, yy, zz, xy, xz, yz)."""
    S = np.asarray(S)
    p = -(S[:, 0] + S[:, 1] + S[:, 2]) / 3
    dev = S[:, :3] + p[:, None]
    return p, np.sqrt(0.5 * (dev ** 2).sum(1) + (S[:, 3:] ** 2).sum(1))


def inertial_number(gdot, d, p, rho_s):
    """I = gdot d / sqrt(p / rho_s), for p > 0."""
    return gdot * d / np.sqrt(p / rho_s)


def mu_partial(I, IN1, A, alpha, mu):
    """Barker & Gray's (2017) law below IN1, sqrt(alpha / ln(A / I)), and mu (the law above) elsewhere."""
    I = np.asarray(I, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(I < IN1, np.sqrt(alpha / np.log(A / np.maximum(I, 1e-300))), mu)


def partial_inverse(mu, A, alpha):
    """The I at which the partial law gives mu: A exp(-alpha / mu^2) (0 at mu = 0)."""
    return A * math.exp(-alpha / (mu * mu)) if mu > 0 else 0.0


def yield_ratio(P, I):
    """k(mu(I)): the ratio sqrt(J2) / p on the yield surface of P's Material:yield at inertial number I,
    with P's Material:mu_law (partial: Barker & Gray's law below I_N1; the solver's lambda floor on
    the shear rate, which matters only where gdot < lambda = 1e-3 1/s, is left out)."""
    I = np.asarray(I, float)
    mu = mu_of_I(I, P["mu_s"], P["mu_d"], P["I0"])
    if P.get("mu_law") == "partial":
        lo, A, _ = partial_regularisation(P["mu_s"], P["mu_d"], P["I0"], P["pr_alpha"])
        mu = mu_partial(I, lo, A, P["pr_alpha"], mu)
    return mu if P["yield"] == "mu_I" else kmu(mu)


def mu_of_yield_ratio(r, yield_):
    """The friction mu at which Material:yield's surface has sqrt(J2) / p = r: mu_I r itself,
    drucker_prager the inverse of kmu, 3 r / sqrt(9 - 12 r^2) (inf where 12 r^2 >= 9)."""
    r = np.asarray(r, float)
    if yield_ == "mu_I":
        return r
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(12 * r * r < 9, 3 * r / np.sqrt(np.maximum(9 - 12 * r * r, 1e-300)), np.inf)


def inertial_number_of_ratio(r, P):
    """The inverse of yield_ratio: the I at which P's Material:yield and Material:mu_law hold
    sqrt(J2) / p = r; inf at or above mu_d (no steady state). Regularized: 0 at or below mu_s
    (arrested). Partial: below mu(I_N1), A exp(-alpha / mu^2) (partial_inverse), so no ratio arrests."""
    mu = mu_of_yield_ratio(r, P["yield"])
    with np.errstate(divide="ignore", invalid="ignore"):
        I = np.where(mu >= P["mu_d"], np.inf,
                     np.where(mu <= P["mu_s"], 0.0, P["I0"] * (mu - P["mu_s"]) / (P["mu_d"] - mu)))
        if P.get("mu_law") == "partial":
            _, A, mu_N1 = partial_regularisation(P["mu_s"], P["mu_d"], P["I0"], P["pr_alpha"])
            I = np.where(mu < mu_N1, A * np.exp(-P["pr_alpha"] / np.maximum(mu, 1e-300) ** 2), I)
    return I


def inertial_numbers(s, P, gdot_fraction=0.1):
    """I of the flowing material particles of snapshot s (and the count of
    the material with p > 0)."""
    mat = np.asarray(s["Kind"]) == snap.MATERIAL
    p, tau = pressure_tau(np.asarray(s["Stress"])[mat])
    g = np.asarray(s["ShearRate"])[mat]
    C = np.asarray(s["Concentration"])[mat]
    d = P["d_small"] * C + P["d_large"] * (1 - C)
    pos = p > 0
    I = np.zeros_like(p)
    I[pos] = inertial_number(g[pos], d[pos], p[pos], P["rho_s"])
    k = yield_ratio(P, I)
    flowing = pos & (tau >= 0.99 * k * p) & (g >= gdot_fraction * np.percentile(g, 99))
    return I[flowing], int(pos.sum())


@functools.lru_cache(maxsize=None)  # a window scan per call; the references call it per profile
def partial_regularisation(mu_s, mu_d, I0, alpha):
    """Barker & Gray's (2017) partially regularised law below the window's lower edge I_N1:
    mu(I) = sqrt(alpha / ln(A / I)) with A = I_N1 exp(alpha / mu(I_N1)^2), continuous at I_N1 (as
    alexjarosch/OpenFOAM-muI muIreg writes it). Returns (I_N1, A, mu(I_N1))."""
    lo = window(mu_s, mu_d, I0)[0]
    mu_lo = mu_of_I(lo, mu_s, mu_d, I0)
    return lo, lo * math.exp(alpha / (mu_lo * mu_lo)), mu_lo


def cmd_window(a):
    w = window(a.mu_s, a.mu_d, a.I0)
    print("mu_s %g, mu_d %g, I0 %g: well posed for %.4g < I < %.4g" % (a.mu_s, a.mu_d, a.I0, w[0], w[1]))
    if a.pr_alpha:
        lo, A, mu_lo = partial_regularisation(a.mu_s, a.mu_d, a.I0, a.pr_alpha)
        print("partial regularisation (Barker & Gray 2017), alpha %g: mu = sqrt(alpha / ln(A / I)) below "
              "I_N1 = %.4g, A = %.4g; mu(1e-4) = %.4f, mu(1e-6) = %.4f (mu_s %g)" % (
                  a.pr_alpha, lo, A, float(mu_partial(1e-4, lo, A, a.pr_alpha, mu_lo)),
                  float(mu_partial(1e-6, lo, A, a.pr_alpha, mu_lo)), a.mu_s))
        print("  a steady uniform layer whose shear stress ratio is mu = tan(theta) (the mu_I yield surface) "
              "flows at I = A exp(-alpha / mu^2):")
        for th in a.angles:
            m = math.tan(math.radians(th))
            if m < mu_lo:
                print("    %5.2f deg: I = %.3g" % (th, partial_inverse(m, A, a.pr_alpha)))


def cmd_run(a):
    P = params(a.outdir)
    lo, hi = window(P["mu_s"], P["mu_d"], P["I0"])
    Is, npos, nsnap = [], 0, 0
    for path in snap.list_snapshots(a.outdir):
        s = snap.read_snapshot(path)
        if float(s["Time"]) < a.t_from - 1e-9:
            continue
        I, n = inertial_numbers(s, P, a.gdot_fraction)
        Is.append(I)
        npos += n
        nsnap += 1
    I = np.concatenate(Is) if Is else np.zeros(0)
    if not len(I):
        print("%s: no flowing particles in %d snapshots from t = %g s" % (a.outdir, nsnap, a.t_from))
        return
    q = np.percentile(I, [1, 5, 25, 50, 75, 95, 99])
    print("%s (%s, %d snapshots from t = %g s): %d flowing of %d material particle-snapshots with p > 0 (%.1f %%)" % (
        a.outdir, P["yield"], nsnap, a.t_from, len(I), npos, 100.0 * len(I) / max(npos, 1)))
    print("  well-posed window %.4g < I < %.4g (mu_s %g, mu_d %g, I0 %g)" % (lo, hi, P["mu_s"], P["mu_d"], P["I0"]))
    print("  I percentiles 1/5/25/50/75/95/99: " + " ".join("%.3g" % v for v in q))
    print("  below the window: %.1f %%, inside: %.1f %%, above: %.1f %%" % (
        100.0 * np.mean(I <= lo), 100.0 * np.mean((I > lo) & (I < hi)), 100.0 * np.mean(I >= hi)))


def cmd_condition(a):
    print("mu_s %g, mu_d %g, I0 %g, %s: a relative error e in the stress ratio sqrt(J2) / p makes kappa e "
          "in the shear rate" % (a.mu_s, a.mu_d, a.I0, a.yld))
    print("       I       nu    kappa   stress-ratio error for 3 % in the rate")
    for I in a.I:
        nu, kap = condition(I, a.mu_s, a.mu_d, a.I0, a.yld)
        print("  %6.3g  %7.4f  %7.2f   %.3f %%" % (I, nu, kap, 3.0 / kap))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    w = sub.add_parser("window")
    w.add_argument("--mu-s", type=float, default=0.382)
    w.add_argument("--mu-d", type=float, default=0.682)
    w.add_argument("--I0", type=float, default=0.279)
    w.add_argument("--pr-alpha", type=float, default=None, help="also Barker & Gray's (2017) partially "
                   "regularised law with this alpha (theirs: 1.9)")
    w.add_argument("--angles", type=float, nargs="+", default=[19.0, 20.0, 20.5, 20.9],
                   help="slopes (deg) at which --pr-alpha reports the layer's I")
    c = sub.add_parser("condition")
    c.add_argument("--mu-s", type=float, default=0.382)
    c.add_argument("--mu-d", type=float, default=0.682)
    c.add_argument("--I0", type=float, default=0.279)
    c.add_argument("--I", type=float, nargs="+", default=[0.01, 0.02, 0.04, 0.06, 0.1, 0.3])
    c.add_argument("--yield", dest="yld", choices=("drucker_prager", "mu_I"), default="drucker_prager")
    r = sub.add_parser("run")
    r.add_argument("outdir")
    r.add_argument("--from", dest="t_from", type=float, default=0.0)
    r.add_argument("--gdot-fraction", type=float, default=0.1)
    a = ap.parse_args(argv)
    {"window": cmd_window, "condition": cmd_condition, "run": cmd_run}[a.cmd](a)


if __name__ == "__main__":
    main()
