"""Invariants every drum test checks (tests/validate_drum.py, 2D;
tests/validate_drum3d.py, 3D), printed as ok/FAIL lines by Checks."""
import numpy as np

from tools.analysis import drum_analysis, snap


class Checks:
    """check(name, good, detail) prints one line; ok is False once any failed."""

    def __init__(self):
        self.ok = True

    def __call__(self, name, good, detail):
        self.ok &= bool(good)
        print("%s %s: %s" % ("ok  " if good else "FAIL", name, detail))


def diagnostics_columns(check, out, rho):
    """The diagnostics' n_material, kinetic_energy, max_speed, C_min and
    C_max columns at every snapshot time against the snapshot: the count of
    material particles, 1/2 rho sum V_i |u_i|^2, max |u_i|, min and max C_i
    over them (rho the bulk density), to 1e-12 (summation order)."""
    dg = snap.read_diagnostics(out)
    worst, n_bad = 0.0, 0
    for p in snap.list_snapshots(out):
        s = snap.read_snapshot(p)
        k = np.nonzero(np.abs(dg["time"] - float(s["Time"])) <= 1e-9 * max(1.0, float(s["Time"])))[0]
        if len(k) == 0:
            check("diagnostics t=%g" % s["Time"], False, "no diagnostics row at this snapshot's time")
            continue
        m = s["Kind"] == snap.MATERIAL
        v2 = np.sum(np.asarray(s["Velocities"], dtype=float)[m] ** 2, axis=1)
        ke = 0.5 * rho * np.sum(np.asarray(s["Volume"], dtype=float)[m] * v2)
        row = {c: float(dg[c][k[0]]) for c in ("n_material", "kinetic_energy", "max_speed", "C_min", "C_max")}
        n_bad += row["n_material"] != m.sum()
        C = np.asarray(s["Concentration"], dtype=float)[m]
        for got, ref in ((row["kinetic_energy"], ke), (row["max_speed"], np.sqrt(v2.max())),
                         (row["C_min"], C.min()), (row["C_max"], C.max())):
            worst = max(worst, abs(got - ref) / max(abs(ref), 1e-300) if ref != 0 or got != 0 else 0.0)
    check("diagnostics", n_bad == 0 and worst <= 1e-12,
          "n_material, kinetic_energy, max_speed, C_min, C_max against the snapshots: %d count mismatches, largest "
          "relative difference %.1e" % (n_bad, worst))


def mass_bounds_conservation(check, out, unit, dr, dim):
    """mass: the same material IDs in every snapshot of OUT, and every
    material Volume the lattice's dr^dim (unit "m^2" or "m^3"; the scene's
    value, not the code's first snapshot); bounds: C within [-1e-3, 1 + 1e-3]
    (the donor limiter's, Segregation:limiter, docs/numerics.md);
    conservation, recomputed from the snapshots (snap.conservation): the
    relative drift of sum C_i V_i below 1e-10 (the conservative scheme
    conserves it to round-off), the diagnostics' small_volume column equal to
    the snapshots' correctly rounded sums to 1e-15 (the code sums compensated,
    src/core/ksum.h), and its drift column the
    drift of that column exactly. Returns the material coordinates of each
    snapshot (for the caller's containment test) and the diagnostics."""
    ids0 = None
    coords = []
    vol_ref = dr ** dim
    for p in snap.list_snapshots(out):
        s = snap.read_snapshot(p)
        m = s["Kind"] == snap.MATERIAL
        ids, vol = np.sort(s["ParticleIDs"][m]), np.asarray(s["Volume"][m], dtype=float)
        if ids0 is None:
            ids0 = ids
        verr = np.abs(vol / vol_ref - 1).max()
        check("mass t=%g" % s["Time"], np.array_equal(ids, ids0) and verr < 1e-6,
              "%d material of %d particles, V_i / dr^%d - 1 within %.1e, sum V = %.6e %s" % (
                  len(ids), len(m), dim, verr, vol.sum(), unit))
        coords.append(s["Coordinates"][m])
    dg = snap.read_diagnostics(out)
    check("bounds", dg["C_min"].min() >= -1e-3 and dg["C_max"].max() <= 1 + 1e-3,
          "C in [%.6f, %.6f]" % (dg["C_min"].min(), dg["C_max"].max()))
    c = snap.conservation(out)
    check("conservation", c["drift"] < 1e-10 and c["column"] <= 1e-15 and c["reported"] == 0,
          "max |drift| %.2e from %d snapshots; small_volume column within %.1e of them; drift column %s" % (
              c["drift"], c["snapshots"], c["column"],
              "its definition" if c["reported"] == 0 else "off its definition by %.2e" % c["reported"]))
    return coords, dg


def omega_of(x, v, vol):
    """Mean angular velocity about the z axis, rad/s (counter-clockwise > 0)."""
    lz = np.sum(vol * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]))
    return lz / np.sum(vol * (x[:, 0] ** 2 + x[:, 1] ** 2))


def drum_omega(par):
    """The drum's angular velocity from the used parameters, rad/s
    (counter-clockwise > 0)."""
    return drum_analysis.drum_wall(par)[1]


def kmu(mu):
    """k_mu = 3 mu / sqrt(9 + 12 mu^2), the Drucker-Prager cone of mu (eq.
    2.12), written out here as the independent reference."""
    return 3 * mu / np.sqrt(9 + 12 * mu * mu)


def stress_ratio(s):
    """sqrt(J2) / p of the material particles of snapshot s with p > 0
    (Stress tension positive, xx yy zz xy xz yz)."""
    m = s["Kind"] == snap.MATERIAL
    S = np.asarray(s["Stress"], dtype=float)[m]
    p = -(S[:, 0] + S[:, 1] + S[:, 2]) / 3
    dev = S[:, :3] + p[:, None]
    J2 = 0.5 * np.sum(dev ** 2, axis=1) + np.sum(S[:, 3:] ** 2, axis=1)
    ok = p > 0
    return np.sqrt(J2[ok]) / p[ok]
