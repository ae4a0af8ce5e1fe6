"""The CI-sized container scenes the validations share, as -P overrides of
inputs/column_2d.yml (one place, so that validate_mpi, validate_gpu,
validate_restart and the single-case validations run the same cases).

  CHUTE     a 3 cm layer on a 40-degree incline, periodic along x (dr 2.5 mm)
  CHUTE_3D  the same in 3D, periodic along x and z (dr 5 mm, 9 x 9 cm)
  FILM      a Newtonian film, 1 cm on a 30-degree incline (validate_film.py)
  SILO      a 2D silo with a 1.25 cm opening over an outlet 2 cm below the base,
            a bidisperse fill (validate_outlet.py)
  COLLAPSE  a 5 cm column held by a gate lifted at 0.01 s over a 10 cm runout
"""
CHUTE = ["Geometry:dr=0.0025", "Geometry:height=0.03", "Geometry:periodic=x", "Material:E=1e5",
         "Flow:damping_until=0", "Physics:gravity=[6.306,-7.515,0]"]
CHUTE_3D = ["Geometry:dim=3", "Geometry:dr=0.005", "Geometry:width=0.09", "Geometry:depth=0.09",
            "Geometry:height=0.03", "Geometry:periodic=xz", "Material:E=1e5", "Flow:damping_until=0",
            "Physics:gravity=[6.306,-7.515,0]"]
FILM = ["Material:model=newtonian", "Material:eta=1.5", "Material:E=11250", "Geometry:periodic=x",
        "Geometry:dr=0.0005", "Geometry:height=0.01", "Geometry:width=0.01", "Physics:gravity=[4.905,-8.496,0]",
        "Flow:alpha_av=0", "Flow:damping_until=0", "Initial:stress=geostatic"]
SILO = ["Geometry:dr=0.0025", "Geometry:height=0.05", "Geometry:outlet_width=0.0125", "Outlet:enabled=on",
        "Outlet:below=-0.02", "Material:E=1e5", "Flow:damping_until=0", "Segregation:enabled=on",
        "Segregation:V=0.01", "Segregation:D=1e-5", "Initial:C_below=0.3"]
COLLAPSE = ["Geometry:dr=0.0025", "Geometry:height=0.05", "Geometry:runout=0.1", "Walls:gate_open=0.01",
            "Material:E=1e5", "Flow:damping_until=0.01"]
# CHANNEL   plane Poiseuille flow of the Newtonian fluid between the base and a lid,
#           periodic along x, driven by a body force of 2 m/s^2 (validate_channel.py)
CHANNEL = ["Material:model=newtonian", "Material:eta=1.5", "Material:E=1800", "Geometry:periodic=x",
           "Geometry:lid=on", "Geometry:dr=0.0005", "Geometry:height=0.01", "Geometry:width=0.01",
           "Physics:gravity=[2,0,0]", "Flow:alpha_av=0", "Flow:damping_until=0", "Initial:stress=zero"]


def row_profile(s, dr):
    """The material of snapshot s by lattice row (y = (j + 1/2) dr): each row's
    mean height, mean x velocity, and the largest spread of the x velocity
    within a row (a layer periodic along x is uniform along it)."""
    import numpy as np
    mat = np.asarray(s["Kind"]) == 0
    y, u = np.asarray(s["Coordinates"])[mat, 1], np.asarray(s["Velocities"])[mat, 0]
    row = np.round(y / dr - 0.5).astype(int)
    rows = np.unique(row)
    return (np.array([y[row == k].mean() for k in rows]), np.array([u[row == k].mean() for k in rows]),
            max(np.ptp(u[row == k]) for k in rows))


def run_column(sphseg, out, over, extra=(), backend=None):
    """sphseg inputs/column_2d.yml -o out with the overrides over (and
    extra arguments, --backend when given); exits the script with FAIL and
    the run's last output when sphseg fails. Returns its stdout."""
    import os
    import subprocess
    import sys
    scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "inputs", "column_2d.yml")
    cmd = [sphseg, scene, "-o", out] + (["--backend", backend] if backend else [])
    r = subprocess.run(cmd + sum([["-P", o] for o in over], []) + list(extra), capture_output=True, text=True)
    if r.returncode != 0:
        print(r.stdout[-2000:], r.stderr[-2000:])
        sys.exit("FAIL: sphseg exited with %d" % r.returncode)
    return r.stdout
