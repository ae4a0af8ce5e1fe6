"""A container described as data (Geometry:type container: Container:walls and
Container:regions, src/sim/setup_container.c):

  - the built-in drum written as a container (a turning cylinder and two
    fill layers, tests/containers.py DRUM_AS_CONTAINER) is the built-in
    drum: the same particles in the same order, and every snapshot field
    bit for bit equal after 300 steps (the Wall field names the same wall);
  - the built-in column written as a container (three segments, the base
    with priority 1, COLUMN_AS_CONTAINER) has the same particles and the
    same wall for every dummy, but its dummies in another order: the sums
    over neighbours add in another order, so the fields agree to round-off,
    1e-10 of their scale after 30 steps (the tolerance of validate_mpi
    across rank counts; a column falling from zero stress amplifies
    round-off by about 1e4 every 30 steps after that, so longer runs are not
    compared);
  - the shear box written as a container (SHEARBOX_AS_CONTAINER) under the
    same prescribed shear: the same particles, positions bit for bit, C to
    round-off (1e-10) after 200 steps;
  - the 3D drum written as a container (a turning cylinder and turning ends,
    DRUM3D_AS_CONTAINER; its end walls the drum's polar discs) has the same
    particles and walls; its material is numbered row by row rather than
    plane by plane, so particles are matched by their initial position, and
    the fields agree to round-off (1e-10) after 30 steps;
  - the chute (CHUTE: a layer on a 40-degree incline, periodic along x)
    written as a container (its base alone, Geometry:periodic x,
    CHUTE_AS_CONTAINER) has the same particles and walls; matched by initial
    position, the fields agree to round-off (1e-10) after 30 steps;
  - inputs/hopper_2d.yml at dr = 2 mm: the walls listed (header Walls), each
    region's C at the start (0, 1, 0 by layer), the material held by the
    gate until 0.05 s and flowing out of the opening after, the sum C V of
    the inside plus the outflow conserved to 1e-12, nothing beyond a wall;
  - its 3D extrusion sets up and runs 20 steps, with end walls end_lo, end_hi.

  python3 -m tests.validate_container --sphseg build/sphseg --work /tmp/v
"""
import csv
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
from tools.analysis import snap  # noqa: E402
from tests.drum_invariants import Checks  # noqa: E402  (tests/drum_invariants.py)
from tests.containers import (sphseg_work_args, CHUTE, CHUTE_AS_CONTAINER, COLUMN_AS_CONTAINER, DRUM3D_AS_CONTAINER,  # noqa: E402
                        DRUM_AS_CONTAINER, HOPPER, HOPPER_3D, SHEARBOX_AS_CONTAINER)

INPUTS = os.path.join(HERE, "..", "inputs")
TOL = 1e-10

check = Checks()  # check(name, good, detail): one ok/FAIL line; check.ok


def run(sphseg, scene, out, over):
    cmd = [sphseg, os.path.join(INPUTS, scene), "-o", out, "--backend", "cpu", "-P", "Run:progress_s=1e9"]
    r = subprocess.run(cmd + sum([["-P", o] for o in over], []), capture_output=True, text=True,
                       env=dict(os.environ, OMP_NUM_THREADS="1"))
    if r.returncode != 0:
        print(r.stdout[-2000:], r.stderr[-2000:])
        sys.exit("FAIL: %s exited with %d" % (scene, r.returncode))
    return r.stdout


def snaps(out):
    return [snap.read_snapshot(p) for p in snap.list_snapshots(out)]


def by_id(s):
    o = np.argsort(s["ParticleIDs"])
    return {k: np.asarray(v)[o] for k, v in s.items() if isinstance(v, np.ndarray) and len(v) == len(o)}


def wall_of_dummies(s):
    """{position in nm: wall name} of the dummies of snapshot s."""
    names = {v: k for k, v in snap.wall_ids(s).items()}
    d = np.asarray(s["Kind"]) == 1
    pos = np.round(np.asarray(s["Coordinates"])[d] / 1e-9).astype(np.int64)
    return {tuple(p): names[int(w)] for p, w in zip(pos, np.asarray(s["Wall"])[d])}


def matched(sphseg, w, name, scene, base, inst):
    """A built-in scene and its container version: the same particles (by
    initial position) and the same wall for each dummy; the fields after the
    run within TOL of their scale."""
    tag = name.split()[0].lower()
    run(sphseg, scene, os.path.join(w, tag), base)
    run(sphseg, scene, os.path.join(w, tag + "_c"), base + inst)
    A, B = snaps(os.path.join(w, tag)), snaps(os.path.join(w, tag + "_c"))
    wa, wb = wall_of_dummies(A[0]), wall_of_dummies(B[0])
    same_walls = wa == wb
    key = lambda s: {tuple(np.round(p / 1e-9).astype(np.int64)): i for p, i in zip(
        np.asarray(s["Coordinates"]), np.asarray(s["ParticleIDs"]))}
    ka, kb = key(A[0]), key(B[0])
    worst = np.inf
    if set(ka) == set(kb):
        ia = {i: n for n, i in enumerate(np.asarray(A[-1]["ParticleIDs"]))}
        ib = {i: n for n, i in enumerate(np.asarray(B[-1]["ParticleIDs"]))}
        ra = np.array([ia[ka[p]] for p in ka])
        rb = np.array([ib[kb[p]] for p in ka])
        worst = max(np.abs(np.asarray(A[-1][f])[ra] - np.asarray(B[-1][f])[rb]).max() /
                    max(np.abs(np.asarray(A[-1][f])[ra]).max(), 1e-300)
                    for f in ("Coordinates", "Velocities", "Stress", "Concentration"))
    check("%s as a container" % name, same_walls and set(ka) == set(kb) and worst <= TOL,
          "the same %d particles: %s, the same wall for each of %d dummies: %s; largest field difference after 30 "
          "steps %.1e of its scale (tolerance %.0e)" % (len(ka), set(ka) == set(kb), len(wb), same_walls, worst, TOL))


def main():
    a = sphseg_work_args()
    w = a.work

    # 1. the drum as a container: bit for bit
    base = ["Geometry:dr=0.002", "Run:max_steps=300", "Output:dt=1e3"]
    run(a.sphseg, "drum_2d_EN.yml", os.path.join(w, "drum"), base)
    run(a.sphseg, "drum_2d_EN.yml", os.path.join(w, "drum_c"), base + DRUM_AS_CONTAINER)
    A, B = snaps(os.path.join(w, "drum")), snaps(os.path.join(w, "drum_c"))
    same = len(A) == len(B) == 2 and all(
        np.array_equal(np.asarray(x[k]), np.asarray(y[k])) for x, y in zip(A, B) for k in x
        if isinstance(x[k], np.ndarray))
    differ = [k for k in A[-1] if isinstance(A[-1][k], np.ndarray) and not np.array_equal(A[-1][k], B[-1][k])]
    check("drum as a container", same and A[-1]["Walls"] == B[-1]["Walls"] == "1 drum",
          "%d snapshots, fields that differ: %s; walls %r and %r" % (len(B), differ or "none", A[-1]["Walls"],
                                                                      B[-1]["Walls"]))

    # 2. the column as a container: the same particles and walls, the fields to round-off
    base = ["Geometry:dr=0.0025", "Run:max_steps=30", "Output:dt=1e3"]
    run(a.sphseg, "column_2d.yml", os.path.join(w, "column"), base)
    run(a.sphseg, "column_2d.yml", os.path.join(w, "column_c"), base + COLUMN_AS_CONTAINER)
    A, B = snaps(os.path.join(w, "column")), snaps(os.path.join(w, "column_c"))
    wa, wb = wall_of_dummies(A[0]), wall_of_dummies(B[0])
    check("column as a container: dummies", wa == wb and len(wa) > 0,
          "%d and %d dummies, %d with another wall or place" % (len(wa), len(wb), sum(wa.get(p) != wb.get(p) for p in
                                                                                       set(wa) | set(wb))))
    x, y = by_id(A[-1]), by_id(B[-1])
    m = x["Kind"] == 0
    same_ids = np.array_equal(x["ParticleIDs"][m], y["ParticleIDs"][y["Kind"] == 0])
    worst = max(np.abs(x[f][m] - y[f][y["Kind"] == 0]).max() / max(np.abs(x[f][m]).max(), 1e-300)
                for f in ("Coordinates", "Velocities", "Stress", "Concentration"))
    check("column as a container: material after 30 steps", same_ids and worst <= TOL,
          "the same material IDs: %s; largest field difference %.1e of its scale (tolerance %.0e)" % (
              same_ids, worst, TOL))

    # 2b. the shear box as a container: prescribed positions, C from sums in another order
    base = ["Run:max_steps=200", "Output:dt=1e3"]
    run(a.sphseg, "shearbox_2d.yml", os.path.join(w, "shear"), base)
    run(a.sphseg, "shearbox_2d.yml", os.path.join(w, "shear_c"), base + SHEARBOX_AS_CONTAINER)
    A, B = snaps(os.path.join(w, "shear")), snaps(os.path.join(w, "shear_c"))
    wa, wb = wall_of_dummies(A[0]), wall_of_dummies(B[0])
    x, y = by_id(A[-1]), by_id(B[-1])
    m, mb = x["Kind"] == 0, y["Kind"] == 0
    same_ids = np.array_equal(x["ParticleIDs"][m], y["ParticleIDs"][mb])
    same_x = same_ids and np.array_equal(x["Coordinates"][m], y["Coordinates"][mb])
    dc = np.abs(x["Concentration"][m] - y["Concentration"][mb]).max() if same_ids else np.inf
    check("shear box as a container", wa == wb and same_x and dc <= TOL and A[-1]["Step"] == B[-1]["Step"] == 200,
          "%d dummies, the same walls: %s; material positions equal: %s; largest C difference %.1e (tolerance %.0e)"
          % (len(wb), wa == wb, same_x, dc, TOL))

    # 2c, 2d. the 3D drum and the periodic chute as containers: matched by initial position
    for name, scene, base, inst in [
            ("3D drum", "drum_3d.yml", ["Geometry:dr=0.002", "Geometry:length=0.012"], DRUM3D_AS_CONTAINER),
            ("chute (periodic x)", "column_2d.yml", CHUTE, CHUTE_AS_CONTAINER)]:
        matched(a.sphseg, w, name, scene, base + ["Run:max_steps=30", "Output:dt=1e3"], inst)


    # 3. the hopper
    out = os.path.join(w, "hopper")
    log = run(a.sphseg, "hopper_2d.yml", out, HOPPER + ["Run:t_end=0.25"])
    S = snaps(out)
    s0 = S[0]
    ids = snap.wall_ids(s0)
    check("hopper walls", ids == {"left": 1, "hopper_left": 2, "gate": 3, "hopper_right": 4, "right": 5},
          "header Walls %r" % s0["Walls"])
    kind, xy, C = np.asarray(s0["Kind"]), np.asarray(s0["Coordinates"]), np.asarray(s0["Concentration"])
    m = kind == 0
    layer = np.where(xy[m, 1] < 0.06, 0, np.where(xy[m, 1] < 0.09, 1, 2))
    want = np.array([0.0, 1.0, 0.0])[layer]
    counts = [int(np.sum(layer == k)) for k in range(3)]
    check("hopper regions", np.array_equal(C[m], want) and min(counts) > 0 and xy[m, 1].max() < 0.12,
          "C by layer y < 0.06, < 0.09, < 0.12: %s particles, C as given: %s" % (counts, np.array_equal(C[m], want)))
    dw = np.asarray(s0["Wall"])[~m]
    per_wall = {n: int(np.sum(dw == k)) for n, k in ids.items()}
    check("hopper dummies", all(v > 0 for v in per_wall.values()), "per wall %s" % per_wall)
    held = [s for s in S if float(s["Time"]) <= 0.05 + 1e-9]
    low = min(np.asarray(s["Coordinates"])[np.asarray(s["Kind"]) == 0, 1].min() for s in held)
    check("held by the gate", low > 0 and "the gate is open (wall gate)" in log,
          "lowest material y until t = 0.05 s: %.4f m; the log says the gate opened: %s" % (
              low, "the gate is open (wall gate)" in log))
    rows = list(csv.DictReader(open(os.path.join(out, "diagnostics.csv"))))
    n0, n1 = int(rows[0]["n_material"]), int(rows[-1]["n_material"])
    nout = int(rows[-1]["n_outflow"])
    drift = max(abs(float(r["small_volume_drift"])) for r in rows)
    check("discharge", nout > 0 and n1 + nout == n0 and drift < 1e-12,
          "%d of %d particles out by t = %.2f s, inside + out = %d, largest drift of sum C V (inside plus out) %.1e"
          % (nout, n0, float(rows[-1]["time"]), n1 + nout, drift))
    last = S[-1]
    xm = np.asarray(last["Coordinates"])[np.asarray(last["Kind"]) == 0]
    inside = bool(np.all((xm[:, 0] > -0.003) & (xm[:, 0] < 0.103)))
    check("nothing beyond a wall", inside, "material x in [%.4f, %.4f] m" % (xm[:, 0].min(), xm[:, 0].max()))

    # 4. the 3D extrusion
    out = os.path.join(w, "hopper3d")
    run(a.sphseg, "hopper_2d.yml", out, HOPPER_3D + ["Run:max_steps=20", "Output:dt=1e3"])
    S = snaps(out)
    ids = snap.wall_ids(S[0])
    dw = np.asarray(S[0]["Wall"])[np.asarray(S[0]["Kind"]) == 1]
    per_wall = {n: int(np.sum(dw == k)) for n, k in ids.items()}
    check("3D hopper", "end_lo" in ids and "end_hi" in ids and all(v > 0 for v in per_wall.values()) and len(S) == 2,
          "dummies per wall %s; %d snapshots" % (per_wall, len(S)))
    sys.exit(0 if check.ok else 1)


if __name__ == "__main__":
    main()
