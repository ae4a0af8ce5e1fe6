"""A packed bed of DEM grains at rest under water (inputs/dem_bed.yml; issue
58, "beyond the paper"): a lattice block of free grains dropped in a box
periodic along x and z with a base settles onto the base and comes to rest.
The reference is the statics of the DEM paper's model A (Markauskas,
Kruggel-Emden, Sivanesapillai & Steeb 2016, eq. 6; the code's fluid, its
eq. 23 on the grains): at rest the drag is zero, the fluid's pressure is
hydrostatic, -eps grad p + eps rho_f g = 0, so

    p_f(base)  = rho_f g H                          (the fluid's part)
    L / A      = N V (rho_s - rho_f) g / A          (the grains' contact load)
    p_f + L/A  = rho_f g H + N V (rho_s - rho_f) g / A   (the base's pressure)

each within 2 % (the issue's), H the free surface's height, A the period's
cross-section, N the grains, V a grain's volume; and the grains at rest.
The fluid's part holds since each fluid particle's volume is the space it
represents beside the grains, phi / eps (docs/dem.md, "A packed bed at
rest"; +28 % before). Measured over the last WINDOW s of the run:

- L: the grains' normal force on the base from their overlap with it,
  sum_i max(k_n delta_i - gamma_n v_n,i, 0), delta_i = d/2 - y_i > 0
  (DEM/Coordinates, DEM/Velocities; k_n and e the run's, used_params.yml,
  gamma_n from e as dem_damping gives it; the base is y = 0);
- p_f: the mean pressure -tr(sigma)/3 of the fluid's lowest row of particles
  (those within dr/2 of the lowest) plus rho_f g times its mean height
  (the hydrostatic part below it; on water alone, one grain on the base,
  this reads the base's pressure 4.6 % low: the wall row, docs/dem.md);
- H: the mean height of the top row of fluid particles (as many as there
  are lattice columns, (width / dr)^2) plus dr / 2.

The grains are at rest: their kinetic energy (diagnostics.csv,
dem_kinetic_energy) at the end is under 1e-4 of its largest. Printed beside:
rho_f g sum V / A, the space the fluid's particles represent (Particles/Volume,
phi / eps beside the grains) in pressure units, which is rho_f g H where they
fill the column, and the drag's share of the contact
load, sum_i F_D,y / eps_i from eqs. (19, 21, 22) at the fluid velocity the run
reports at the grains (the residual fluid motion).

CI case (default): 13 x 4 x 13 grains (d 4 mm, 1200 kg/m^3, spacing 5.33
mm) dropped from 8 mm above the base in water 12 dr deep, to t = 0.5 s,
window 0.4-0.5 s (at rest from 0.35 s; the columns of grains buckle after
0.5 s); --full: the scene as it stands (13 x 10 x 13 grains in water 24 dr
deep, to 0.5 s, window 0.4-0.5 s); --analyse DIR reads a run made.

  python3 -m tests.validate_dem_bed --sphseg build/sphseg --work /tmp/vbed
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
from tests.validate_dem_settling import drag as drag_d  # noqa: E402

SCENE = os.path.join(HERE, "..", "inputs", "dem_bed.yml")
RHO_F, RHO_S, G, D, DR = 1000.0, 1200.0, 9.81, 0.004, 0.00533
WIDTH = 13 * DR
AREA = WIDTH ** 2
TOL, REST = 0.02, 1e-4
CI = {"window": 0.1, "over": ["DEM:block_n=[13, 4, 13]", "Container:regions=[{shape: fill, level: 0.06396, C: 0}]",
                              "Run:t_end=0.5", "Output:dt=0.01"]}
FULL = {"window": 0.1, "over": []}
V = math.pi / 6 * D ** 3


def contact_params(out):
    """(DEM:kn, DEM:e) of the run (OUT/used_params.yml)."""
    import yaml
    with open(os.path.join(out, "used_params.yml")) as f:
        dem = yaml.safe_load(f)["DEM"]
    return float(dem["kn"]), float(dem["e"])


def damping(kn, e):
    """gamma_n (kg/s) of dem_damping for the restitution e, m* = m / 2."""
    ms, le = 0.5 * V * RHO_S, math.log(e)
    return -2 * le * math.sqrt(ms * kn) / math.sqrt(math.pi ** 2 + le ** 2)


def snapshot(path, kn, e):
    """(time, contact load on the base (N), the drag's downward share (N),
    p_f at the base (Pa), H (m), grains, rho_f sum V / A of the fluid (kg/m^2))
    for the contacts' kn and e."""
    with h5py.File(path, "r") as f:
        t = float(f["Header"].attrs["Time"])
        x, v = f["DEM/Coordinates"][:], f["DEM/Velocities"][:]
        eps, uf = f["DEM/FluidFraction"][:], f["DEM/FluidVelocity"][:]
        k, X, s, vol = f["Particles/Kind"][:], f["Particles/Coordinates"][:], f["Particles/Stress"][:], f["Particles/Volume"][:]
    delta = 0.5 * D - x[:, 1]
    load = float(np.where(delta > 0, np.maximum(kn * delta - damping(kn, e) * v[:, 1], 0), 0).sum())
    fd = 0.0
    for u, e in zip(uf - v, eps):
        um = float(np.linalg.norm(u))
        if um > 0:
            fd += -drag_d(D, e, um) * u[1] / um / e  # downward
    mat = k == 0
    y, p = X[mat, 1], -(s[mat, 0] + s[mat, 1] + s[mat, 2]) / 3
    low = y < y.min() + 0.5 * DR
    pf = float(p[low].mean() + RHO_F * G * y[low].mean())
    ncol = int(round(WIDTH / DR)) ** 2
    H = float(np.sort(y)[-ncol:].mean() + 0.5 * DR)
    mf = float(RHO_F * vol[mat].sum() / AREA)
    return t, load, fd, pf, H, len(x), mf


def kinetic(out):
    """(times, dem_kinetic_energy) of diagnostics.csv (of its .part while the run goes on)."""
    path = os.path.join(out, "diagnostics.csv")
    a = np.genfromtxt(path if os.path.exists(path) else path + ".part", delimiter=",", names=True)
    return a["time"], a["dem_kinetic_energy"]


def check(out, case):
    kn, e = contact_params(out)
    rows = [snapshot(p, kn, e) for p in sorted(glob.glob(os.path.join(out, "snapshot_*.h5")))]
    t_end = rows[-1][0]
    win = np.array([r for r in rows if r[0] >= t_end - case["window"] - 1e-9])
    n = int(win[0, 5])
    load, fd, pf, H, mf = (float(win[:, q].mean()) for q in (1, 2, 3, 4, 6))
    ref_load = n * V * (RHO_S - RHO_F) * G
    ref_pf = RHO_F * G * H
    e_load, e_pf = load / ref_load - 1, pf / ref_pf - 1
    e_tot = (pf + load / AREA) / (ref_pf + ref_load / AREA) - 1
    tk, ke = kinetic(out)
    rest = ke[-1] / ke.max()
    ok = {"rest": rest <= REST, "load": abs(e_load) <= TOL, "pf": abs(e_pf) <= TOL, "tot": abs(e_tot) <= TOL}
    tag = lambda b: "ok  " if b else "FAIL"  # noqa: E731
    # Every part decides the exit status: the reference is model A's statics (Markauskas et al. 2016,
    # eq. 6 with eq. 23 on the grains), p_f = rho_f g H and L = N V (rho_s - rho_f) g, each within 2 %.
    print("%s at rest: the grains' kinetic energy at t = %.2f s is %.2e of its largest (%.3e J at t = %.3f s; "
          "tolerance %.0e)" % (tag(ok["rest"]), tk[-1], rest, ke.max(), tk[np.argmax(ke)], REST))
    print("%s contact load on the base (%d grains, t = %.2f-%.2f s): %.5e N = %.3f Pa; N V (rho_s - rho_f) g = %.5e N "
          "= %.3f Pa: %+.2f %% (tolerance %.0f %%); the drag's share sum F_D,y / eps %.2e N (%+.2f %%)"
          % (tag(ok["load"]), n, win[0, 0], t_end, load, load / AREA, ref_load, ref_load / AREA, 100 * e_load,
             100 * TOL, fd, 100 * fd / ref_load))
    print("%s fluid pressure at the base %.1f Pa; rho_f g H = %.1f Pa (H %.5f m): %+.2f %% (tolerance %.0f %%); "
          "rho_f g sum V / A = %.1f Pa" % (tag(ok["pf"]), pf, ref_pf, H, 100 * e_pf, 100 * TOL, mf * G))
    print("%s pressure on the base p_f + L / A = %.1f Pa; rho_f g H + N V (rho_s - rho_f) g / A = %.1f Pa: %+.2f %% "
          "(tolerance %.0f %%)" % (tag(ok["tot"]), pf + load / AREA, ref_pf + ref_load / AREA, 100 * e_tot, 100 * TOL))
    return all(ok.values())


def main():
    case_main(SCENE, CI, FULL, check, "the scene as it stands (13 x 10 x 13 grains, water 24 dr, to 0.5 s; minutes)")


if __name__ == "__main__":
    main()
