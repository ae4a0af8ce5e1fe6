"""The CI-sized container scenes the validations share, as -P overrides of
inputs/column_2d.yml (one place, so that validate_mpi, validate_gpu,
validate_restart and the single-case validations run the same cases).

  CHUTE     a 3 cm layer on a 40-degree incline, periodic along x (dr 2.5 mm)
  CHUTE_3D  the same in 3D, periodic along x and z (dr 5 mm, 9 x 9 cm)
  FILM      a Newtonian film, 1 cm on a 30-degree incline (validate_film.py)
  SILO      a 2D silo with a 1.25 cm opening over an outlet 2 cm below the base,
            a bidisperse fill (validate_outlet.py)
  COLLAPSE  a 5 cm column held by a gate lifted at 0.01 s over a 10 cm runout
  HOPPER    inputs/hopper_2d.yml (Geometry:type container) at dr 2 mm: a bin on a
            45-degree hopper, its opening gated until 0.05 s, three layers
  HOPPER_3D the same extruded 2.4 cm along z (dr 4 mm)
  COLUMN_AS_CONTAINER, DRUM_AS_CONTAINER  inputs/column_2d.yml and
            inputs/drum_2d_EN.yml written as containers (validate_container.py)
  PLAIN     the drum scenes' flow without the corrected gradient and the
            shifting they set: for the cases that test one other option alone
  PAPER_FLOW  the paper's flow in the drum scenes: monaghan, and PLAIN
"""
PLAIN = ["Flow:gradient_correction=off", "Flow:shifting=off"]
PAPER_FLOW = ["Flow:stabilization=monaghan"] + PLAIN
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
#           periodic along x, driven by a body force of 2 m/s^2: inputs/poiseuille_2d.yml
#           (bit-identical; validate_channel.py runs the scene), kept here for
#           validate_mpi and validate_gpu
CHANNEL = ["Material:model=newtonian", "Material:eta=1.5", "Material:E=1800", "Geometry:periodic=x",
           "Geometry:lid=on", "Geometry:dr=0.0005", "Geometry:height=0.01", "Geometry:width=0.01",
           "Physics:gravity=[2,0,0]", "Flow:alpha_av=0", "Flow:damping_until=0", "Initial:stress=zero"]

HOPPER = ["Geometry:dr=0.002"]
HOPPER_3D = ["Geometry:dim=3", "Geometry:depth=0.024", "Geometry:dr=0.004"]
# column_2d.yml's box at dr = 2.5 mm as a list of walls: the base keeps its
# corners (priority 1), as the built-in column's does; side walls as high as
# the built-in ones (the material plus nl = 3 layers); C 0 below half the
# height and 1 above (Initial's defaults; mu(I)'s grain size reads C)
COLUMN_AS_CONTAINER = [
    "Geometry:type=container",
    "Container:walls=[{name: base, from: [0, 0], to: [0.05, 0], priority: 1},"
    " {name: xhi, from: [0.05, 0], to: [0.05, 0.1075], slip: free_slip},"
    " {name: xlo, from: [0, 0.1075], to: [0, 0], slip: free_slip}]",
    "Container:regions=[{lo: [0, 0], hi: [0.05, 0.05], C: 0}, {lo: [0, 0.05], hi: [0.05, 0.1], C: 1}]"]
# drum_3d.yml (R 35 mm, R_f 0.42: H = -0.0056 m, split at -R + 0.5 (H + R) = -0.0203 m, C 0.5
# both) 12 mm long, its end walls turning with the cylinder
DRUM3D_AS_CONTAINER = [
    "Geometry:type=container", "Geometry:depth=0.012",
    "Container:walls=[{name: drum, shape: cylinder, centre: [0, 0], radius: 0.035, motion: turning, rpm: 5},"
    " {name: ends, shape: ends, slip: no_slip, motion: turning, rpm: 5}]",
    "Container:regions=[{shape: fill, level: -0.0203, C: 0.5}, {shape: fill, floor: -0.0203, level: -0.0056, C: 0.5}]"]
# CHUTE as a container: the base alone, periodic along x over Geometry:width (0.05 m), C 0 below
# half the layer and 1 above (use with CHUTE)
CHUTE_AS_CONTAINER = [
    "Geometry:type=container", "Container:walls=[{name: base, from: [0, 0], to: [0.05, 0]}]",
    "Container:regions=[{lo: [0, 0], hi: [0.05, 0.015], C: 0}, {lo: [0, 0.015], hi: [0.05, 0.03], C: 1}]"]
# shearbox_2d.yml's box (21 x 50 sites of dr = 1.74 mm, side walls 53 rows high), C 0 below half
# its height and 1 above, under the same prescribed oscillatory shear
SHEARBOX_AS_CONTAINER = [
    "Geometry:type=container",
    "Container:walls=[{name: base, from: [0, 0], to: [0.03654, 0], priority: 1},"
    " {name: xhi, from: [0.03654, 0], to: [0.03654, 0.09222], slip: free_slip},"
    " {name: xlo, from: [0, 0.09222], to: [0, 0], slip: free_slip}]",
    "Container:regions=[{lo: [0, 0], hi: [0.03654, 0.0435], C: 0}, {lo: [0, 0.0435], hi: [0.03654, 0.087], C: 1}]"]
# drum_2d_EN.yml as a turning cylinder filled to H = (2 R_f - 1) R =
# 0.00637 m, in two layers split at -R + 0.5 (H + R) = -0.014315 m (both
# C = 0.11, as the scene's Initial section)
DRUM_AS_CONTAINER = [
    "Geometry:type=container",
    "Container:walls=[{name: drum, shape: cylinder, centre: [0, 0], radius: 0.035, motion: turning, rpm: 5}]",
    "Container:regions=[{shape: fill, level: -0.014315, C: 0.11}, {shape: fill, floor: -0.014315, level: 0.00637, C: 0.11}]"]

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


def sphseg_work_args():
    """The command line every validation takes: --sphseg BIN (the binary
    under test) and --work DIR (where its runs write)."""
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", required=True)
    ap.add_argument("--work", required=True)
    return ap.parse_args()


def run_scene(sphseg, scene, out, over, extra=()):
    """sphseg SCENE -o out with the -P overrides over (and extra arguments);
    exits the script with FAIL and the run's last output when sphseg fails.
    Returns its stdout."""
    import subprocess
    import sys
    cmd = [sphseg, scene, "-o", out] + sum([["-P", o] for o in over], []) + list(extra)
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        print(r.stdout[-2000:], r.stderr[-2000:])
        sys.exit("FAIL: sphseg exited with %d" % r.returncode)
    return r.stdout


def case_main(scene, ci, full, check, full_help):
    """The command line of a validation with a CI size and a full size (the
    DEM block cases): --sphseg and --work run the scene at the CI size (or
    the full one with --full) and check it; --analyse DIR checks a run
    already made. check(out, case) returns True when the case passes; the
    script exits 0 or 1 by it."""
    import argparse
    import os
    import sys
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg")
    ap.add_argument("--work")
    ap.add_argument("--full", action="store_true", help=full_help)
    ap.add_argument("--analyse", help="a run's output folder, read only (with --full: checked as the full case)")
    a = ap.parse_args()
    case = full if a.full else ci
    out = a.analyse
    if not out:
        if not (a.sphseg and a.work):
            sys.exit("--sphseg and --work, or --analyse DIR")
        out = os.path.join(a.work, "full" if a.full else "ci")
        run_scene(a.sphseg, scene, out, case["over"] + ["Run:progress_s=1e9"], extra=["--overwrite"])
    sys.exit(0 if check(out, case) else 1)


def run_column(sphseg, out, over, extra=(), backend=None):
    """sphseg inputs/column_2d.yml -o out with the overrides over (and
    extra arguments, --backend when given); exits the script with FAIL and
    the run's last output when sphseg fails. Returns its stdout."""
    import os
    scene = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "inputs", "column_2d.yml")
    return run_scene(sphseg, scene, out, over, (["--backend", backend] if backend else []) + list(extra))


def pick_cases(ap, cases, names):
    """The entries of cases (tuples, name first) named in names ("a,b", as
    --cases takes them), in the list's order; all when names is empty; an
    unknown name is the parser's error."""
    if not names:
        return cases
    want = [n.strip() for n in names.split(",") if n.strip()]
    unknown = [n for n in want if n not in [c[0] for c in cases]]
    if unknown:
        ap.error("unknown case(s) %s; known: %s" % (", ".join(unknown), ", ".join(c[0] for c in cases)))
    return [c for c in cases if c[0] in want]
