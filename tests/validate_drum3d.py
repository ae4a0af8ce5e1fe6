"""A CI-sized 3D rotating drum (inputs/drum_3d.yml at dr = 2.5 mm, a drum of
radius R = 20 mm = 8 dr and length L = 25 mm = 10 dr, E = 0.1 MPa as
tests/validate_drum.py, 15 rpm clockwise (Froude number 5e-3, still the
rolling regime), 0.05 s, Run:cfl_flow 0.2 (1 % off the paper's 0.1 in
speed, docs/granular.md); 4 790 particles, of which 720 material), then
the same bed with the drum at rest for 0.03 s, both with the paper's
scheme, -P Flow:stabilization=monaghan (the scene sets riemann; the
measurements below, the rest case's damping included, are monaghan's).
Checked:

  mass:          the material particle IDs and sum V_i are the same in every
                 snapshot (no particle lost, none created);
  containment:   every material particle stays inside the cylinder (r < R)
                 and between the end walls (0 < z < L);
  bounds:        C stays in [-1e-3, 1 + 1e-3] (diagnostics.csv C_min, C_max;
                 Segregation:limiter donor, the default);
  conservation:  the relative drift of sum C_i V_i stays below 1e-10 (the
                 conservative scheme conserves it to round-off, in 3D too);
  rotation:      the material turns with the drum: its mean angular
                 velocity about the axis, Omega = sum V (x v_y - y v_x) /
                 sum V r^2, has the drum's sign at the end and is at least
                 a fifth of the drum's omega (the no-slip walls drag the bed
                 into rotation within a few hundredths of a second);
  uniformity:    away from the end walls the flow does not depend on z: the
                 material planes whose centres lie more than 2h from both
                 end walls (their supports reach no end-wall dummy) have
                 the same Omega within 5 % of omega (the bed is mirror
                 symmetric about z = L/2, so only the end walls' reach
                 along the bed can make the planes differ; measured 1.2 %
                 over the inner planes, 6.7 % over all planes, the end
                 planes included), and their mean
                 |u_z| is below 5 % of their mean speed (no axial flow in
                 the middle of the drum);
  rest:          with Walls:rpm 0 the geostatic bed stays at rest: after
                 0.03 s its Omega is below 1 % of the turning drum's omega,
                 its kinetic energy below 5 % of the turning drum's, and
                 its largest speed below half the turning wall's omega R.
                 The geostatic start is not the SPH equilibrium near the
                 curved wall: the bed rings elastically (peak speed ~8 cm/s
                 at 0.01 s) and the artificial viscosity damps it (kinetic
                 energy down 70x by 0.03 s); a bed that flowed or turned
                 would keep the turning drum's kinetic energy.

The dynamic angle of repose is not checked here: the bed needs about 1/6 of
a turn to avalanche (tests/validate_drum.py, 2 s at 5 rpm), about
2.5e4 steps of this 3D drum, half an hour on 2 cores.
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
from tools.analysis import drum_analysis  # noqa: E402
from tools.analysis import snap  # noqa: E402
from tests.drum_invariants import Checks, diagnostics_columns, mass_bounds_conservation, omega_of  # noqa: E402
from tests.containers import PAPER_FLOW, run_scene, sphseg_work_args  # noqa: E402  (tests/containers.py)

SCENE = os.path.join(HERE, "..", "inputs", "drum_3d.yml")
BASE = PAPER_FLOW + ["Geometry:dr=0.0025", "Geometry:radius=0.02", "Geometry:length=0.025", "Material:E=1e5",
                     "Run:cfl_flow=0.2", "Run:progress_s=1e9"]


def run(sphseg, out, over):
    run_scene(sphseg, SCENE, out, BASE + over)


def main():
    a = sphseg_work_args()
    out, rest = os.path.join(a.work, "drum3d"), os.path.join(a.work, "drum3d_rest")
    run(a.sphseg, out, ["Walls:rpm=15", "Run:t_end=0.05", "Output:dt=0.025", "Output:diag_dt=0.005"])
    run(a.sphseg, rest, ["Walls:rpm=0", "Run:t_end=0.03", "Output:dt=0.03", "Output:diag_dt=0.005"])
    par = drum_analysis.used_params(out)
    g = par["Geometry"]
    R, dr, h = g["radius"], g["dr"], g["h_factor"] * g["dr"]
    L = round(g["length"] / dr) * dr
    w = -15 * 2 * np.pi / 60  # clockwise
    check = Checks()
    coords, dg = mass_bounds_conservation(check, out, "m^3", dr, 3)
    diagnostics_columns(check, out, par["Physics"]["rho"])
    rmax = max(np.hypot(x[:, 0], x[:, 1]).max() for x in coords)
    zlo, zhi = min(x[:, 2].min() for x in coords), max(x[:, 2].max() for x in coords)
    check("containment", rmax < R and zlo > 0 and zhi < L,
          "max r = %.5f m (R = %.5f), z in [%.5f, %.5f] m (L = %.5f)" % (rmax, R, zlo, zhi, L))

    s = snap.read_snapshot(snap.list_snapshots(out)[-1])
    m = s["Kind"] == snap.MATERIAL
    x, v, vol = s["Coordinates"][m], s["Velocities"][m], s["Volume"][m]
    om = omega_of(x, v, vol)
    check("rotation", om * w > 0 and abs(om) >= 0.2 * abs(w),
          "Omega = %.3f rad/s at t = %g s, drum omega = %.3f rad/s" % (om, s["Time"], w))
    plane = np.floor(x[:, 2] / dr).astype(int)  # material planes z = (q + 1/2) dr
    zc = (plane + 0.5) * dr
    inner = (zc > 2 * h) & (zc < L - 2 * h)
    oms = np.array([omega_of(x[sel], v[sel], vol[sel]) for q in np.unique(plane[inner]) for sel in [plane == q]])
    spread = (oms.max() - oms.min()) / abs(w)
    speed = np.linalg.norm(v[inner], axis=1).mean()
    axial = np.abs(v[inner, 2]).mean() / speed
    allq = np.array([omega_of(x[sel], v[sel], vol[sel]) for q in np.unique(plane) for sel in [plane == q]])
    check("uniformity", spread < 0.05 and axial < 0.05,
          "%d inner planes: Omega %.4f..%.4f rad/s (spread %.2f %% of omega), mean |u_z| / |u| = %.3f; "
          "all planes %.4f..%.4f" % (len(oms), oms.min(), oms.max(), 100 * spread, axial, allq.min(), allq.max()))

    s = snap.read_snapshot(snap.list_snapshots(rest)[-1])
    m = s["Kind"] == snap.MATERIAL
    x, v, vol = s["Coordinates"][m], s["Velocities"][m], s["Volume"][m]
    umax, om = np.linalg.norm(v, axis=1).max(), omega_of(x, v, vol)
    ke_rest, ke_turn = snap.read_diagnostics(rest)["kinetic_energy"], dg["kinetic_energy"]
    check("rest", umax < 0.5 * abs(w) * R and abs(om) < 0.01 * abs(w) and ke_rest[-1] < 0.05 * ke_turn[-1],
          "at t = %g s: max speed %.2e m/s (turning drum's wall %.2e), Omega = %.1e rad/s, kinetic energy "
          "%.2e J (peak %.2e; turning drum %.2e)" % (s["Time"], umax, abs(w) * R, om, ke_rest[-1], ke_rest.max(),
                                                    ke_turn[-1]))
    sys.exit(0 if check.ok else 1)


if __name__ == "__main__":
    main()
