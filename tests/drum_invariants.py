"""Invariants every drum test checks (tests/validate_drum.py, 2D;
tests/validate_drum3d.py, 3D), printed as ok/FAIL lines by Checks."""
import numpy as np

import snap


class Checks:
    """check(name, good, detail) prints one line; ok is False once any failed."""

    def __init__(self):
        self.ok = True

    def __call__(self, name, good, detail):
        self.ok &= bool(good)
        print("%s %s: %s" % ("ok  " if good else "FAIL", name, detail))


def mass_bounds_conservation(check, out, unit):
    """mass: the material IDs and sum V_i equal in every snapshot of OUT (V in
    unit, "m^2" or "m^3"); bounds: C within [-0.01, 1.01]; conservation: the
    relative drift of sum C_i V_i below 1e-10 (diagnostics.csv). Returns the
    material coordinates of each snapshot (for the caller's containment
    test) and the diagnostics."""
    ids0 = vol0 = None
    coords = []
    for p in snap.list_snapshots(out):
        s = snap.read_snapshot(p)
        m = s["Kind"] == snap.MATERIAL
        ids, vol = np.sort(s["ParticleIDs"][m]), s["Volume"][m].sum()
        if ids0 is None:
            ids0, vol0 = ids, vol
        check("mass t=%g" % s["Time"], np.array_equal(ids, ids0) and vol == vol0,
              "%d material of %d particles, sum V = %.6e %s" % (len(ids), len(m), vol, unit))
        coords.append(s["Coordinates"][m])
    dg = snap.read_diagnostics(out)
    check("bounds", dg["C_min"].min() >= -0.01 and dg["C_max"].max() <= 1.01,
          "C in [%.4f, %.4f]" % (dg["C_min"].min(), dg["C_max"].max()))
    drift = np.abs(dg["small_volume_drift"]).max()
    check("conservation", drift < 1e-10, "max |drift| %.2e" % drift)
    return coords, dg
