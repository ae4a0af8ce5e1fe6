"""1D finite-volume reference for the shear-box segregation problem.

Solves the segregation-diffusion equation (Zhu, Peng & Wu 2024, eqs. 2.5-2.9)
reduced to the vertical coordinate y (up, gravity down), on 0 <= y <= H:

    C_t = d/dy ( V F(C) + D C_y ),    V F + D C_y = 0 at y = 0 and y = H,

with F = C(1-C) (eq. 2.8, symmetric) or F = A C(1-C)(1-kappa C) (eq. 2.9,
asymmetric).  V, D are either constants or follow eq. (2.7),
V = chi_V gdot d_avg, D = chi_D gdot d_avg^2, d_avg = d_S C + d_L (1-C), with
the oscillatory-shear rate gdot(t) = gamma0 omega |cos(omega t)|.

Usage as a CLI:
    /usr/bin/python3 -m tools.analysis.seg1d OUTDIR_or_used_params.yml \
        --times 260 520 1040 --cells 800 --csv out.csv
"""
import argparse
import dataclasses
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp
from scipy.sparse import diags
from scipy.special import expit

import yaml


@dataclasses.dataclass(frozen=True)
class Params:
    """What the 1D PDE needs (SI units)."""
    H: float                      # material height, m
    flux: str = "symmetric"       # 'symmetric' (2.8) or 'asymmetric' (2.9)
    A: float = 1.6
    kappa: float = 0.89
    model: str = "constant"       # 'constant' or 'shear_rate' (2.7)
    V: float = 0.0                # constant model, m/s
    D: float = 0.0                # constant model, m^2/s
    chi_V: float = 0.11
    chi_D: float = 0.0307
    d_small: float = 0.004
    d_large: float = 0.008
    gamma0: float = 0.57735
    period: float = 13.0
    sheared: bool = True          # False for kinematics velocity 'rest'
    C_below: float = 0.0
    C_above: float = 1.0
    split: float = 0.5            # y/H of the initial interface


def _sec(d, name):
    """Section `name` of the used_params dict; a missing one is an error."""
    if not isinstance(d.get(name), dict):
        raise KeyError(f"used_params: no section {name}")
    return d[name]


def _key(sec, name, key):
    """sec[key]; a missing key is an error naming Section:key (the solver's
    used_params.yml holds every key, defaults included: a reference built
    from a default the run did not use would compare with the wrong PDE)."""
    if key not in sec:
        raise KeyError(f"used_params: no {name}:{key}")
    return sec[key]


def params_from_dict(d):
    """Build Params from a dict shaped like the solver's used_params.yml;
    every key it reads must be there."""
    geo, kin = _sec(d, "Geometry"), _sec(d, "Kinematics")
    seg, ini = _sec(d, "Segregation"), _sec(d, "Initial")
    # the grain sizes: Grains (before that section existed, an output held them in Segregation)
    G, gra = ("Grains", d["Grains"]) if "Grains" in d else ("Segregation", seg)
    f = lambda sec, name, key: float(_key(sec, name, key))
    flux = str(_key(seg, "Segregation", "flux")).lower()
    model = str(_key(seg, "Segregation", "model")).lower()
    if flux not in ("symmetric", "asymmetric"):
        raise ValueError(f"unknown Segregation.flux {flux!r}")
    if model not in ("constant", "shear_rate"):
        raise ValueError(f"unknown Segregation.model {model!r}")
    S, K, I = "Segregation", "Kinematics", "Initial"
    return Params(
        H=f(geo, "Geometry", "height"), flux=flux,
        A=f(seg, S, "A"), kappa=f(seg, S, "kappa"), model=model,
        V=f(seg, S, "V"), D=f(seg, S, "D"),
        chi_V=f(seg, S, "chi_V"), chi_D=f(seg, S, "chi_D"),
        d_small=f(gra, G, "d_small"), d_large=f(gra, G, "d_large"),
        gamma0=f(kin, K, "gamma0"), period=f(kin, K, "period"),
        sheared=str(_key(kin, K, "velocity")).lower() != "rest",
        C_below=f(ini, I, "C_below"), C_above=f(ini, I, "C_above"),
        split=f(ini, I, "split"))


def params_from_yaml(path):
    """Read Params from used_params.yml (or from a directory holding it)."""
    if os.path.isdir(path):
        path = os.path.join(path, "used_params.yml")
    with open(path) as fh:
        return params_from_dict(yaml.safe_load(fh))


def flux_function(p, C):
    """Segregation function F(C): eq. (2.8) or eq. (2.9)."""
    if p.flux == "symmetric":
        return C * (1.0 - C)
    return p.A * C * (1.0 - C) * (1.0 - p.kappa * C)


def accumulated_strain(p, t):
    """Gamma(t) = int_0^t gdot ds with gdot = gamma0 omega |cos(omega s)|.

    Per half period the integral of |cos| is 2; within one, sin r for
    r <= pi/2 and 2 - sin r beyond (r = omega t mod pi).
    """
    t = np.asarray(t, dtype=float)
    if not p.sheared:
        return np.zeros_like(t)
    theta = 2.0 * np.pi * t / p.period
    n, r = np.divmod(theta, np.pi)
    part = np.where(r <= 0.5 * np.pi, np.sin(r), 2.0 - np.sin(r))
    return p.gamma0 * (2.0 * n + part)


def _clock(p, times):
    """Map physical times to the solver's autonomous clock s.

    Constant model: s = t.  Shear-rate model: V and D in eq. (2.7) share the
    factor gdot(t), so with s = Gamma(t) the PDE becomes autonomous,
    dC/ds = d/dy(chi_V d_avg F + chi_D d_avg^2 C_y): the |cos| kinks of gdot
    are integrated exactly instead of being stepped over.
    """
    if p.model == "constant":
        return np.asarray(times, dtype=float)
    return accumulated_strain(p, times)


def _coefficients(p, Cf):
    """Face V and D per unit clock s (eq. 2.7 per unit strain, or constants)."""
    if p.model == "constant":
        return p.V, p.D
    d = p.d_small * Cf + p.d_large * (1.0 - Cf)
    return p.chi_V * d, p.chi_D * d * d


def rhs(C, p, h):
    """FV semi-discretisation dC_i/ds = (G_{i+1/2} - G_{i-1/2}) / h.

    Interior face flux G = V_f F(C_f) + D_f (C_{i+1} - C_i)/h with the
    second-order central face value C_f = (C_i + C_{i+1})/2; G = 0 at both
    walls (no-flux condition).
    """
    Cf = 0.5 * (C[1:] + C[:-1])
    Vf, Df = _coefficients(p, Cf)
    G = np.zeros(C.size + 1)
    G[1:-1] = Vf * flux_function(p, Cf) + Df * np.diff(C) / h
    return np.diff(G) / h


def grid(p, n_cells):
    """Cell width and cell-centre heights of the uniform grid on [0, H]."""
    h = p.H / n_cells
    return h, (np.arange(n_cells) + 0.5) * h


def initial_condition(p, n_cells):
    """Exact cell averages of the step C_below (y/H <= split), C_above above."""
    h, _ = grid(p, n_cells)
    edges = np.arange(n_cells + 1) * h
    below = np.clip(p.split * p.H - edges[:-1], 0.0, h) / h
    return p.C_below * below + p.C_above * (1.0 - below)


def shear_rate(p, t):
    """Oscillatory-shear rate gdot(t) = gamma0 omega |cos(omega t)| (0 at rest)."""
    if not p.sheared:
        return 0.0 * np.asarray(t, dtype=float)
    omega = 2.0 * np.pi / p.period
    return p.gamma0 * omega * np.abs(np.cos(omega * np.asarray(t, dtype=float)))


def solve(p, times, n_cells=800, rtol=1e-8, atol=1e-10, method="BDF",
          C0=None, strain_clock=True):
    """Integrate the FV system; return (y_centres, C[len(times), n_cells]).

    Implicit BDF/Radau via solve_ivp with a tridiagonal jac_sparsity.  For the
    shear-rate model the default integrates in accumulated strain (see
    _clock), so the |cos| kinks of gdot are exact; strain_clock=False
    integrates in physical time with gdot(t) and max_step = period/40
    instead (kept as an independent cross-check).
    """
    h, y = grid(p, n_cells)
    C0 = initial_condition(p, n_cells) if C0 is None else np.asarray(C0, float)
    direct = p.model == "shear_rate" and not strain_clock
    s_eval = np.asarray(times, float) if direct else _clock(p, times)
    out = np.empty((s_eval.size, n_cells))
    s_unique, inverse = np.unique(s_eval, return_inverse=True)
    if s_unique[-1] <= 0.0:
        out[:] = C0
        return y, out
    if direct:
        fun = lambda t, C: shear_rate(p, t) * rhs(C, p, h)
        extra = {"max_step": p.period / 40.0}
    else:
        fun, extra = (lambda s, C: rhs(C, p, h)), {}
    sparsity = diags([1, 1, 1], [-1, 0, 1], shape=(n_cells, n_cells))
    sol = solve_ivp(fun, (0.0, s_unique[-1]), C0, method=method,
                    t_eval=s_unique, rtol=rtol, atol=atol,
                    jac_sparsity=sparsity, **extra)
    if not sol.success:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    out[:] = sol.y.T[inverse.ravel()]
    return y, out


def profile_at(y_ref, C_ref, y):
    """Linear interpolation of a reference profile at heights y."""
    return np.interp(y, y_ref, C_ref)


def steady_analytic(z, phi0, Pe):
    """Gray & Chugunov (2006) steady state, review eq. (28).

    phi = (1 - e^{-phi0 Pe}) e^{(phi0-z)Pe}
          / [1 - e^{-(1-phi0)Pe} + (1 - e^{-phi0 Pe}) e^{(phi0-z)Pe}]
        = expit((phi0 - z) Pe - ln a),
    a = (1 - e^{-(1-phi0)Pe}) / (1 - e^{-phi0 Pe}),
    z = y/H, Pe = V H / D (symmetric flux, constant V, D); small grains
    (phi -> 1) collect at the bottom for large Pe.
    """
    z = np.asarray(z, dtype=float)
    if phi0 <= 0.0 or phi0 >= 1.0:
        return np.full_like(z, float(np.clip(phi0, 0.0, 1.0)))
    if Pe == 0.0:
        return np.full_like(z, phi0)
    log_a = np.log(-np.expm1(-(1.0 - phi0) * Pe)) - np.log(-np.expm1(-phi0 * Pe))
    return expit((phi0 - z) * Pe - log_a)


def mae(a, b):
    """Mean absolute error, paper eq. (5.3)."""
    return float(np.mean(np.abs(np.asarray(a) - np.asarray(b))))


def rmse(a, b):
    """Root-mean-square error, paper eq. (5.4)."""
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def write_csv(path, y, H, times, C):
    """Write profiles: columns y, z=y/H, then one C column per time."""
    header = ",".join(["y", "z"] + [f"C_t{t:g}" for t in times])
    np.savetxt(path, np.column_stack([y, y / H, C.T]), delimiter=",",
               header=header, comments="", fmt="%.10g")


def main(argv=None):
    """CLI: solve the reference for a run's parameters at given times."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("params", help="OUTDIR or path to used_params.yml")
    ap.add_argument("--times", type=float, nargs="+", required=True,
                    help="output times in seconds")
    ap.add_argument("--cells", type=int, default=800)
    ap.add_argument("--csv", help="write profiles to this CSV file")
    args = ap.parse_args(argv)
    p = params_from_yaml(args.params)
    y, C = solve(p, args.times, args.cells)
    print(p)
    for t, c in zip(args.times, C):
        print(f"t = {t:g} s (t/T = {t / p.period:g}): mean C = {c.mean():.8f}, "
              f"C(bottom) = {c[0]:.6f}, C(top) = {c[-1]:.6f}")
    if args.csv:
        write_csv(args.csv, y, p.H, args.times, C)
        print(f"wrote {args.csv}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
