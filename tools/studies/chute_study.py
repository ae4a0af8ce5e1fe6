"""Steady flow down a rough incline (inputs/chute_2d.yml) against the analytic
Bagnold solution of the mu(I) rheology, and the steady segregation profile of
Gray & Chugunov (2006) on the same chute.

Reference (docs/validation.md "Chute"). For a layer of depth H on a slope
theta, periodic along the slope, the lithostatic pressure is
p = rho g cos(theta) (H - z) and the shear stress tau = p tan(theta). The
model's yield surface is sqrt(J2) = k_mu p with k_mu = 3 mu / sqrt(9 + 12 mu^2)
(paper eq. 2.12); in simple shear sqrt(J2) = tau, so the steady flow has
k_mu(mu(I)) = tan(theta), a uniform inertial number

    I = I0 (mu - mu_s) / (mu_d - mu),   mu = 3 t / sqrt(9 - 12 t^2), t = tan(theta),

the shear rate du/dz = I sqrt(p / rho_s) / d and the Bagnold profile

    u(z) = (2/3) I sqrt(rho g cos(theta) / rho_s) / d (H^1.5 - (H - z)^1.5),

depth-mean 3/5 of the surface speed. It flows steadily only for
k_mu(mu_s) < tan(theta) < k_mu(mu_d) (19.3 to 28.2 degrees with mu_s 0.382,
mu_d 0.682); below it stays at rest, above it accelerates. (Reading mu(I) =
tan(theta), as for a rheology written tau = mu p, gives a slower flow and
the window atan mu_s..atan mu_d; both are charted.)

Segregation: with constant V along gravity and D, the steady small-grain
concentration across the layer is eq. 28 of
papers/thornton-weinhart-multiscale-granular-review.txt with the Peclet
number of the flux normal to the base, Pe = V cos(theta) H / D (the flux
along the slope is uniform and drops out).

  python3 -m tools.studies.chute_study run --sphseg build/sphseg --out out/chute_study [--backend gpu] [--set full]
  python3 -m tools.studies.chute_study report --out out/chute_study [--docs docs/data/chute]

`run` reduces each run's snapshots to row profiles (profiles.csv: t, y, u, C
of each lattice row) and deletes the snapshots unless --keep.
"""
import math
import os
import shutil

import numpy as np

from tools import ROOT  # noqa: E402
from tools.analysis.inertial_range import inertial_number_of_ratio  # noqa: E402
from tools.studies import batch  # noqa: E402

SCENE = os.path.join(ROOT, "inputs", "chute_2d.yml")
G = 9.81
# inputs/chute_2d.yml's material and grains
RHO, RHO_S, D_GRAIN, MU_S, MU_D, I0 = 1500.0, 2500.0, 0.002, 0.382, 0.682, 0.279


def kmu(mu):
    return 3 * mu / math.sqrt(9 + 12 * mu * mu)


def mu_of_kmu(k):
    return 3 * k / math.sqrt(9 - 12 * k * k) if 12 * k * k < 9 else math.inf


# Material:yield -> the reading of the steady state: drucker_prager's yield
# sqrt(J2) = k_mu(mu) p gives k_mu(mu(I)) = tan(theta), mu_I's sqrt(J2) = mu p
# gives mu(I) = tan(theta)
READING = {"drucker_prager": "k_mu", "mu_I": "mu"}


def inertial_number(theta_deg, reading="k_mu", pr_alpha=None):
    """Steady I for the slope, or 0 (arrested) or inf (no steady flow). pr_alpha:
    Barker & Gray's (2017) partially regularised law (Material:mu_law partial) with
    this alpha: below I_N1, mu = sqrt(alpha / ln(A / I)), so I = A exp(-alpha / mu^2),
    and no slope is arrested."""
    P = {"mu_s": MU_S, "mu_d": MU_D, "I0": I0, "yield": "drucker_prager" if reading == "k_mu" else "mu_I",
         "mu_law": "regularized" if pr_alpha is None else "partial", "pr_alpha": pr_alpha}
    return float(inertial_number_of_ratio(math.tan(math.radians(theta_deg)), P))


def bagnold(z, theta_deg, H, reading="k_mu", d=D_GRAIN, pr_alpha=None):
    """Analytic velocity at heights z above the base (m/s); pr_alpha as inertial_number."""
    I = inertial_number(theta_deg, reading, pr_alpha)
    c = math.cos(math.radians(theta_deg))
    z = np.clip(np.asarray(z, float), 0, H)
    return 2.0 / 3.0 * I * math.sqrt(RHO * G * c / RHO_S) / d * (H ** 1.5 - (H - z) ** 1.5)


def gray_chugunov(zeta, phi0, Pe):
    """Eq. 28: steady small-grain fraction at zeta = z / H."""
    a = 1 - math.exp(-phi0 * Pe)
    e = np.exp((phi0 - np.asarray(zeta)) * Pe)
    return a * e / (1 - math.exp(-(1 - phi0) * Pe) + a * e)


def gravity(theta_deg):
    t = math.radians(theta_deg)
    return "[%.6f,%.6f,0]" % (G * math.sin(t), -G * math.cos(t))


def case(name, theta=25.0, H=0.02, dr=0.0005, alpha=0.1, t_end=3.0, seg=None, E=1e5, dim=2,
         yield_="drucker_prager", stab="monaghan", **extra):
    """One run of the chute. yield_ is Material:yield; the study's runs before
    Material:yield existed (docs/validation.md) are drucker_prager, which is
    why it is the default here and not the scene's mu_I."""
    over = {"Geometry:dr": dr, "Geometry:height": H, "Geometry:width": round(20 * dr, 9),
            "Physics:gravity": gravity(theta), "Flow:alpha_av": alpha, "Run:t_end": t_end,
            "Output:dt": 0.1, "Output:diag_dt": 0.05, "Run:progress_s": 1e9, "Material:E": E,
            "Material:yield": yield_, "Flow:stabilization": stab}
    if dim == 3:  # periodic along the slope (x) and across it (z), 20 dr each way
        over.update({"Geometry:dim": 3, "Geometry:depth": round(20 * dr, 9), "Geometry:periodic": "xz"})
    meta = {"theta": theta, "H": H, "dr": dr, "alpha": alpha, "t_end": t_end, "E": E, "seg": 0, "dim": dim,
            "yield": yield_, "stab": stab}
    if seg:
        V, D, phi0 = seg
        over.update({"Segregation:enabled": "on", "Segregation:flux": "symmetric", "Segregation:model": "constant",
                     "Segregation:V": V, "Segregation:D": D, "Initial:C_below": phi0, "Initial:C_above": phi0})
        meta.update({"seg": 1, "V": V, "D": D, "phi0": phi0})
    over.update(extra)
    return batch.Case(name, SCENE, over, **meta)


SEG = (0.04, 2e-4, 0.5)  # V, D, phi0: Pe = V cos(25) H / D = 3.6 at H = 2 cm

# Pouliquen's (1999) flow rule for glass beads: u / sqrt(g h) = BETA h / h_stop(theta),
# h_stop = L_STOP d (tan theta2 - tan theta) / (tan theta - tan theta1), with
# tan theta1 = mu_s and tan theta2 = mu_d of Table 1 (Jop, Forterre & Pouliquen 2005)
BETA, L_STOP = 0.136, 1.65
# the flow-rule runs (Material:yield mu_I): (theta, H) with H / h_stop from 1 to 6.6
# (and 22 degrees at H = h_stop), and the surface speed under a tenth of the sound
# speed at E = 1e5 Pa
FLOWRULE = [(22, 0.04), (22, 0.06), (22, 0.08), (24, 0.02), (24, 0.04), (26, 0.02), (26, 0.04), (28, 0.01),
            (28, 0.02)]


def h_stop(theta_deg, d=D_GRAIN):
    """Pouliquen's h_stop, m (inf at or below theta1 = atan mu_s)."""
    t = math.tan(math.radians(theta_deg))
    return L_STOP * d * (MU_D - t) / (t - MU_S) if MU_S < t < MU_D else (math.inf if t <= MU_S else 0.0)


def relax_time(theta_deg, H, reading="mu"):
    """The time a layer starting from rest needs to come within about 2 % of
    its steady mean (an estimate): the acceleration time ubar / (g (sin - mu_s
    cos)) plus 4 relaxation times H^2 / (2.5 nu) of the mu(I) viscosity
    linearised at the base, nu = mu'(I) d sqrt(p rho_s) / rho (k_mu' mu' with
    drucker_prager's reading)."""
    th = math.radians(theta_deg)
    I = inertial_number(theta_deg, reading)
    p = RHO * G * math.cos(th) * H
    dmu = (MU_D - MU_S) * I0 / (I + I0) ** 2
    if reading == "k_mu":
        mu = mu_of_kmu(math.tan(th))
        dmu *= 3 * 9 / (9 + 12 * mu * mu) ** 1.5
    nu = dmu * D_GRAIN * math.sqrt(p * RHO_S) / RHO
    ubar = 0.6 * float(bagnold(H, theta_deg, H, reading))
    return ubar / (G * (math.sin(th) - MU_S * math.cos(th))) + 4 * H * H / (2.5 * nu)


def cases(which):
    """The study's runs. The layer relaxes to its steady state with the time
    constant of the linearised mu(I) viscosity, about H^2 / (2.5 nu) with
    nu = k_mu'(mu) mu'(I) d sqrt(p rho_s) / rho at the base: 0.45 s
    for H = 1 cm at 25 degrees (1.25 s for 2 cm, growing as H^1.5), so the
    velocity runs are 1 cm deep and 4 s long (9 time constants)."""
    c = []
    if which in ("full", "resolution"):
        for dr in (0.002, 0.001, 0.0005, 0.00025):
            for alpha in (1.0, 0.1, 0.0):
                c.append(case("res_dr%g_a%g" % (dr * 1e3, alpha), H=0.01, dr=dr, alpha=alpha, t_end=4.0))
        for alpha in (0.1, 0.0):  # steady by 2.5 s (within 0.5 % at dr 0.25 mm)
            c.append(case("res_dr0.125_a%g" % alpha, H=0.01, dr=0.000125, alpha=alpha, t_end=2.5))
    if which in ("full", "stabilization"):
        # Flow:stabilization riemann and delta on the resolution runs' layer (alpha_av unused)
        for dr in (0.001, 0.0005, 0.00025):
            for stab in ("riemann", "delta"):
                c.append(case("stab_%s_dr%g" % (stab, dr * 1e3), H=0.01, dr=dr, alpha=0.0, t_end=4.0, stab=stab))
    if which in ("full", "regimes"):
        for theta in (15, 18, 20, 22, 24, 25, 26, 28, 30):
            c.append(case("theta%g" % theta, theta=theta, H=0.01, dr=0.0005, t_end=4.0, alpha=0.0))
        # 20 rows or more across the layer (H / dr = 10 loses its lattice rows)
        c.append(case("H5", H=0.005, dr=0.00025, t_end=4.0, alpha=0.0))
        c.append(case("H15", H=0.015, dr=0.0005, t_end=5.0, alpha=0.0))
    if which in ("full", "3d"):
        # the 3D layer at 20, 30 and 40 rows (8 000 to 64 000 particles) and its 2D
        # twins, E 1e4 for a 3x longer step; dim3_H5 / dim2_H5 are the 20-row pair
        for dim in (3, 2):
            c.append(case("dim%d_H5" % dim, H=0.005, dr=0.00025, alpha=0.0, E=1e4, t_end=0.6, dim=dim))
            for rows in (30, 40):
                c.append(case("dim%d_H5_rows%d" % (dim, rows), H=0.005, dr=round(0.005 / rows, 9), alpha=0.0,
                              E=1e4, t_end=0.6, dim=dim))
    if which in ("full", "seg"):
        for dr in (0.002, 0.001, 0.0005):
            c.append(case("seg_dr%g" % (dr * 1e3), dr=dr, seg=SEG))
    if which in ("full", "flowrule"):
        # mu_I, 20 rows, alpha_av 0 (the study's means within 2.8 % at 20-26 degrees)
        for theta, H in FLOWRULE:
            t_end = max(1.0, math.ceil(2 * relax_time(theta, H)) / 2)
            c.append(case("fr_t%g_H%g" % (theta, H * 100), theta=theta, H=H, dr=round(H / 20, 9), alpha=0.0,
                          t_end=t_end, yield_="mu_I"))
    return c


def reduce_run(outdir, dr, keep=False):
    """Row profiles of every snapshot of a run -> outdir/profiles.csv."""
    from tools.analysis import snap
    rows = []
    for p in snap.list_snapshots(outdir):
        s = snap.read_snapshot(p)
        mat = np.asarray(s["Kind"]) == snap.MATERIAL
        y = np.asarray(s["Coordinates"])[mat, 1]
        u = np.asarray(s["Velocities"])[mat, 0]
        C = np.asarray(s["Concentration"])[mat]
        j = np.rint(y / dr - 0.5).astype(int)
        for k in np.unique(j):
            m = j == k
            rows.append((float(s["Time"]), y[m].mean(), u[m].mean(), C[m].mean(), int(m.sum())))
        if not keep:
            os.remove(p)
    batch.write_csv(os.path.join(outdir, "profiles.csv"), ["t", "y", "u", "C", "n"], rows)
    return len(rows)


def load_profiles(outdir):
    a = np.genfromtxt(os.path.join(outdir, "profiles.csv"), delimiter=",", names=True)
    return {t: a[a["t"] == t] for t in np.unique(a["t"])}


def reduce_done(a, c, rec):
    """After each run: its snapshots to profiles.csv; restart files dropped."""
    d = os.path.join(a.out, c.name)
    if os.path.isdir(d):
        n = reduce_run(d, float(c.over["Geometry:dr"]), a.keep)
        for extra in ("checkpoint", "restart"):
            shutil.rmtree(os.path.join(d, extra), ignore_errors=True)
        print("%s: %d row records" % (c.name, n), flush=True)


def summarise(out, name, row, window=0.0):
    """Surface and depth-mean speed of a run at its last snapshot and 0.5 s
    before, and its error against the analytic profile. With window > 0 (s)
    the profile is the row-by-row mean of the snapshots of the last `window`
    seconds (a steady layer's profile is a time average: one snapshot of a
    layer without artificial viscosity carries its realisation's noise)."""
    theta, H = float(row["theta"]), float(row["H"])
    reading = READING[row.get("yield") or "drucker_prager"]  # runs.csv before Material:yield: drucker_prager
    prof = load_profiles(os.path.join(out, name))
    times = sorted(prof)
    last = prof[times[-1]]
    if window > 0:  # rows of fewer than half the median count are stray grains between rows, not rows
        full = {t: prof[t][prof[t]["n"] >= 0.5 * np.median(prof[t]["n"])] for t in times}
        last = full[times[-1]]
        span = [full[t] for t in times if t >= times[-1] - window - 1e-9 and len(full[t]["u"]) == len(last["u"])]
        last = last.copy()  # a structured array: its rows' u and n the window's means
        last["u"] = np.mean([p["u"] for p in span], axis=0)
        last["n"] = np.mean([p["n"] for p in span], axis=0)
    before = prof[min(times, key=lambda t: abs(t - (times[-1] - 0.5)))]
    steady = np.isfinite(inertial_number(theta, reading))
    ref = bagnold(last["y"], theta, H, reading) if steady else np.full(len(last["y"]), np.nan)
    uref_top = float(bagnold(H, theta, H, reading)) if steady else math.inf
    mean = float(np.average(last["u"], weights=last["n"]))
    mean_before = float(np.average(before["u"], weights=before["n"]))
    res = {"t": times[-1], "u_top": float(last["u"].max()), "u_mean": mean, "u_mean_before": mean_before,
           "u_ref_top": uref_top, "u_ref_mean": 0.6 * uref_top,
           # the rows above the first (the first, next to the no-slip base, slips: err_base)
           "err_profile": float(np.abs(last["u"] - ref)[1:].max() / uref_top) if 0 < uref_top < math.inf else math.nan,
           "err_base": float((last["u"][0] - ref[0]) / uref_top) if 0 < uref_top < math.inf else math.nan,
           "err_mean": abs(mean / (0.6 * uref_top) - 1) if 0 < uref_top < math.inf else math.nan,
           "series": [(t, float(np.average(prof[t]["u"], weights=prof[t]["n"]))) for t in times],
           "y": last["y"], "u": last["u"], "C": last["C"]}
    return res


def cmd_report(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    runs, where = batch.load_runs(a.out, "profiles.csv")
    S = {n: summarise(where[n], n, r) for n, r in runs.items()}
    lines = []
    P = lines.append
    # resolution x artificial viscosity
    res = sorted((n for n in S if n.startswith("res_")), key=lambda n: (-float(runs[n]["alpha"]), -float(runs[n]["dr"])))
    if res:
        P("| dr (mm) | H/dr | alpha_av | t (s) | surface u (m/s) | depth-mean u | analytic mean | error of the mean | "
          "profile error above the first row (max, of u(H)) | first row's slip (of u(H)) | wall (s) | backend | steps |")
        P("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for n in res:
            r, s = runs[n], S[n]
            P("| %g | %d | %g | %.1f | %.4f | %.4f | %.4f | %.1f %% | %.1f %% | %+.1f %% | %s | %s | %s |" % (
                float(r["dr"]) * 1e3, round(float(r["H"]) / float(r["dr"])), float(r["alpha"]), s["t"], s["u_top"],
                s["u_mean"], s["u_ref_mean"], 100 * s["err_mean"], 100 * s["err_profile"], 100 * s["err_base"],
                r["wall_s"], r.get("backend", ""), r["steps"]))
        for alpha in sorted({float(runs[n]["alpha"]) for n in res}, reverse=True):
            ns = [n for n in res if float(runs[n]["alpha"]) == alpha]
            ns = [n for n in ns if float(runs[n]["H"]) / float(runs[n]["dr"]) >= 19.5]  # H/dr = 5, 10: no lattice rows left
            hs = [float(runs[n]["dr"]) for n in ns]
            P("")
            P("alpha_av = %g, H/dr >= 20: observed order of the profile error %.2f, of the depth-mean's error %.2f "
              "(dr = %s mm)" % (alpha, batch.observed_order(hs, [S[n]["err_profile"] for n in ns]),
                                batch.observed_order(hs, [S[n]["err_mean"] for n in ns]),
                                ", ".join("%g" % (h * 1e3) for h in hs)))
        fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
        H = float(runs[res[0]]["H"])
        z = np.linspace(0, H, 100)
        ax[0].plot(bagnold(z, 25, H), z / H, "k-", lw=2, label="Bagnold, $k_\\mu(\\mu(I))=\\tan\\theta$")
        ax[0].plot(bagnold(z, 25, H, "mu"), z / H, "k--", lw=1, label="Bagnold, $\\mu(I)=\\tan\\theta$")
        for n in res:
            r = runs[n]
            if float(r["dr"]) in (0.0005, 0.00025) or (float(r["dr"]) == 0.001 and float(r["alpha"]) == 1.0):
                ax[0].plot(S[n]["u"], S[n]["y"] / H, ".-", ms=3, lw=0.8,
                           label="dr %g mm, $\\alpha$ %g" % (float(r["dr"]) * 1e3, float(r["alpha"])))
        ax[0].set_xlabel("u (m/s)"), ax[0].set_ylabel("z / H"), ax[0].legend(fontsize=7)
        ax[0].set_title("25$^\\circ$, H = %g cm, t = %.1f s" % (H * 100, S[res[0]]["t"]))
        ax[0].set_xlim(0, 0.35)
        for alpha in sorted({float(runs[n]["alpha"]) for n in res}, reverse=True):
            ns = [n for n in res if float(runs[n]["alpha"]) == alpha]
            l, = ax[1].loglog([float(runs[n]["dr"]) * 1e3 for n in ns], [S[n]["err_mean"] for n in ns], "o-",
                              label="$\\alpha_{av}$ = %g, depth mean" % alpha)
            ax[1].loglog([float(runs[n]["dr"]) * 1e3 for n in ns], [S[n]["err_profile"] for n in ns], "s--",
                         color=l.get_color(), label="$\\alpha_{av}$ = %g, profile (rows above the first)" % alpha)
        ax[1].set_xlabel("dr (mm)  [H/dr = 5, 10, 20, 40]"), ax[1].set_ylabel("error, fraction of u(H) / of the mean")
        ax[1].legend(fontsize=7)
        ax[1].set_title("error against the Bagnold solution")
        fig.tight_layout()
        fig.savefig(os.path.join(a.docs, "validation_chute_profiles.png"), dpi=110)
    # regimes: depth-mean speed against theta, and time series
    reg = sorted((n for n in S if n.startswith("theta")), key=lambda n: float(runs[n]["theta"]))
    if reg:
        P("")
        P("| theta (deg) | regime (analytic) | depth-mean u at t_end (m/s) | 0.5 s before | analytic | error |")
        P("|---|---|---|---|---|---|")
        for n in reg + [m for m in S if m.startswith("H")]:
            th = float(runs[n]["theta"])
            I = inertial_number(th, READING[runs[n].get("yield") or "drucker_prager"])
            regime = "rest" if I == 0 else ("accelerating" if I == math.inf else "steady, I = %.3f" % I)
            s = S[n]
            err = (s["u_mean"] / s["u_ref_mean"] - 1) if 0 < s["u_ref_mean"] < math.inf else math.nan
            P("| %g (H %g cm) | %s | %.4f | %.4f | %s | %s |" % (
                th, float(runs[n]["H"]) * 100, regime, s["u_mean"], s["u_mean_before"],
                "%.4f" % s["u_ref_mean"] if s["u_ref_mean"] < math.inf else "-",
                "%+.1f %%" % (100 * err) if err == err else "-"))
        fig, ax = plt.subplots(1, 3, figsize=(14, 4.2))
        th = np.linspace(14, 31, 300)
        Hr = float(runs[reg[0]]["H"])
        for reading, style, lab in (("k_mu", "k-", "$k_\\mu(\\mu(I)) = \\tan\\theta$"),
                                    ("mu", "k--", "$\\mu(I) = \\tan\\theta$")):
            ax[0].plot(th, [0.6 * float(bagnold(Hr, t, Hr, reading)) if np.isfinite(inertial_number(t, reading))
                            else np.nan for t in th], style, label="Bagnold, " + lab)
        ax[0].plot([float(runs[n]["theta"]) for n in reg], [S[n]["u_mean"] for n in reg], "o", label="SPH, t_end")
        for x in (math.degrees(math.atan(kmu(MU_S))), math.degrees(math.atan(kmu(MU_D)))):
            ax[0].axvline(x, color="grey", lw=0.6)
        ax[0].set_ylim(0, 1.2), ax[0].legend(fontsize=7)
        ax[0].set_xlabel("$\\theta$ (deg)"), ax[0].set_ylabel("depth-mean u (m/s), H = %g cm" % (Hr * 100))
        ax[0].set_title("flowing window atan $k_\\mu(\\mu_s)$..atan $k_\\mu(\\mu_d)$")
        for n in reg:
            t, u = zip(*S[n]["series"])
            ax[1].plot(t, u, label="%g$^\\circ$" % float(runs[n]["theta"]))
        ax[1].set_xlabel("t (s)"), ax[1].set_ylabel("depth-mean u (m/s)"), ax[1].legend(fontsize=7, ncol=2)
        ax[1].set_ylim(0, 2.5)
        Hs = sorted((n for n in S if n.startswith("H") or n == "theta25"), key=lambda n: float(runs[n]["H"]))
        Hx = np.linspace(0.005, 0.035, 50)
        ax[2].plot(Hx * 100, [0.6 * float(bagnold(h, 25, h)) for h in Hx], "k-", label="Bagnold, $\\propto H^{3/2}$")
        ax[2].plot([float(runs[n]["H"]) * 100 for n in Hs], [S[n]["u_mean"] for n in Hs], "o", label="SPH")
        ax[2].set_xlabel("H (cm)"), ax[2].set_ylabel("depth-mean u (m/s), 25$^\\circ$"), ax[2].legend()
        fig.tight_layout()
        fig.savefig(os.path.join(a.docs, "validation_chute_regimes.png"), dpi=110)
    dims = sorted((n for n in S if n.startswith("dim")), key=lambda n: (-int(runs[n]["dim"]), -float(runs[n]["dr"])))
    if dims:
        P("")
        P("| dim | rows | particles | t (s) | depth-mean u (m/s) | analytic | error of the mean | profile error above "
          "the first row | first row's slip | wall (s) | backend | steps |")
        P("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for n in dims:
            r, s = runs[n], S[n]
            P("| %s | %.0f | %s | %.1f | %.4f | %.4f | %+.1f %% | %.1f %% | %+.1f %% | %s | %s | %s |" % (
                r["dim"], float(r["H"]) / float(r["dr"]), r["material"], s["t"], s["u_mean"], s["u_ref_mean"],
                100 * (s["u_mean"] / s["u_ref_mean"] - 1), 100 * s["err_profile"], 100 * s["err_base"], r["wall_s"],
                r.get("backend", ""), r["steps"]))
        for dim in ("3", "2"):
            ns = [n for n in dims if runs[n]["dim"] == dim]
            if len(ns) >= 3:
                h = [float(runs[n]["dr"]) for n in ns]
                P("")
                P("dim %s: observed order of the profile error %.2f, of the depth-mean's error %.2f (%d resolutions)" % (
                    dim, batch.observed_order(h, [S[n]["err_profile"] for n in ns]),
                    batch.observed_order(h, [S[n]["err_mean"] for n in ns]), len(ns)))
        if any(runs[n]["dim"] == "3" for n in dims):
            fig, ax = plt.subplots(figsize=(5, 4.2))
            for n in dims:
                r, s = runs[n], S[n]
                H = float(r["H"])
                ax.plot(s["u"] / s["u_ref_top"], s["y"] / H, "o-" if r["dim"] == "3" else "x:", ms=3,
                        label="%sD, %.0f rows, %s" % (r["dim"], H / float(r["dr"]), r.get("backend", "")))
            zeta = np.linspace(0, 1, 100)
            ax.plot(1 - (1 - zeta) ** 1.5, zeta, "k-", label="Bagnold")
            ax.set_xlabel("u / u_surface (analytic)"), ax.set_ylabel("z / H"), ax.legend(fontsize=7)
            ax.set_title("3D chute, 25$^\\circ$, H = 5 mm")
            fig.tight_layout()
            fig.savefig(os.path.join(a.docs, "validation_chute_3d.png"), dpi=110)
    fr = sorted((n for n in S if n.startswith("fr_")), key=lambda n: (float(runs[n]["theta"]), float(runs[n]["H"])))
    if fr:
        P("")
        P("| theta (deg) | H (cm) | H / h_stop | t (s) | depth-mean u (m/s) | 0.5 s before | u / sqrt(g H) | "
          "flow rule beta H / h_stop | error | Bagnold, mu(I) = tan theta | error | wall (s) | backend |")
        P("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        fig, ax = plt.subplots(figsize=(5.5, 4.2))
        for n in fr:
            r, s = runs[n], S[n]
            th, H = float(r["theta"]), float(r["H"])
            x = H / h_stop(th)
            fr_u = s["u_mean"] / math.sqrt(G * H)
            P("| %g | %g | %.2f | %.1f | %.4f | %.4f | %.4f | %.4f | %+.1f %% | %.4f | %+.1f %% | %s | %s |" % (
                th, H * 100, x, s["t"], s["u_mean"], s["u_mean_before"], fr_u, BETA * x, 100 * (fr_u / (BETA * x) - 1),
                s["u_ref_mean"], 100 * (s["u_mean"] / s["u_ref_mean"] - 1), r["wall_s"], r.get("backend", "")))
            ax.plot(x, fr_u, "o", color="C%d" % ((int(th) - 22) // 2), label="%g$^\\circ$" % th)
        xs = np.linspace(0, max(float(runs[n]["H"]) / h_stop(float(runs[n]["theta"])) for n in fr) * 1.05, 10)
        ax.plot(xs, BETA * xs, "k-", label="Pouliquen (1999), $\\beta$ = %g" % BETA)
        ax.axvline(1, color="grey", lw=0.6)
        h, l = ax.get_legend_handles_labels()
        keep = [i for i in range(len(l)) if l[i] not in l[:i]]
        ax.legend([h[i] for i in keep], [l[i] for i in keep], fontsize=8)
        ax.set_xlabel("H / h$_{stop}(\\theta)$"), ax.set_ylabel("$\\bar u / \\sqrt{g H}$")
        ax.set_title("chute, Material:yield mu_I")
        fig.tight_layout()
        fig.savefig(os.path.join(a.docs, "validation_chute_flowrule.png"), dpi=110)
    seg = sorted((n for n in S if n.startswith("seg")), key=lambda n: -float(runs[n]["dr"]))
    if seg:
        P("")
        P("| dr (mm) | Pe | t (s) | MAE of C against eq. 28 | max error | wall (s) |")
        P("|---|---|---|---|---|---|")
        fig, ax = plt.subplots(figsize=(5, 4.2))
        errs = []
        for n in seg:
            r, s = runs[n], S[n]
            H, th = float(r["H"]), float(r["theta"])
            Pe = float(r["V"]) * math.cos(math.radians(th)) * H / float(r["D"])
            ref = gray_chugunov(s["y"] / H, float(r["phi0"]), Pe)
            e = np.abs(s["C"] - ref)
            errs.append(e.mean())
            P("| %g | %.2f | %.1f | %.4f | %.4f | %s |" % (float(r["dr"]) * 1e3, Pe, s["t"], e.mean(), e.max(), r["wall_s"]))
            ax.plot(s["C"], s["y"] / H, "o", ms=3, label="SPH dr %g mm" % (float(r["dr"]) * 1e3))
        zeta = np.linspace(0, 1, 100)
        ax.plot(gray_chugunov(zeta, float(runs[seg[0]]["phi0"]), Pe), zeta, "k-", label="Gray & Chugunov eq. 28")
        ax.set_xlabel("C (small-grain fraction)"), ax.set_ylabel("z / H"), ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(a.docs, "validation_chute_segregation.png"), dpi=110)
        P("")
        P("observed order of the MAE: %.2f" % batch.observed_order([float(runs[n]["dr"]) for n in seg], errs))
    batch.report_tables(a, lines)


def main(argv=None):
    batch.study_main(__doc__, ("resolution", "stabilization", "regimes", "3d", "seg", "flowrule"), cases, reduce_done, cmd_report, "chute", jobs=4,
                     argv=argv)


if __name__ == "__main__":
    main()
