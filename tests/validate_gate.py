"""A gate (Geometry:runout, Walls:gate_open): a column held by a wall of
dummies that leaves the run at a given time, the start of a column collapse.

The scene is inputs/column_2d.yml at dr = 2.5 mm: a column 5 cm wide and
5 cm high (aspect ratio 1) at x in [0, 5 cm], a floor running on to x = 15
cm (Geometry:runout = 0.1) closed by a side wall, and the gate, nl = 3
layers of dummies standing on the floor just past the column, removed at
t = 0.03 s (the column settles under damping until then). Checks:

  - the gate's dummies carry the gate's wall id (snapshot field Wall, named
    by the header attribute Walls) and stand in
    x in (W, W + 3 dr), nl (ny + nl) of them, and the other dummies carry
    the ids of the base and the two side walls;
  - while the gate stands the column stays behind it (no material past
    x = W);
  - after t = 0.03 s the gate is gone from the store, the front runs out
    past W + 10 dr by t = 0.2 s, and no material passes the end wall;
  - a run stopped before the gate opens (a checkpoint at step 400) and
    restarted ends bit-identical to the straight run (the store the
    checkpoint holds still has its gate, and the restart lifts it at the
    same time); with --backend gpu equal to round-off (1e-8 of each field's
    scale, as tests/validate_restart.py: the restart builds its Verlet list
    afresh).
Every run uses --backend (default cpu).
"""
import argparse
import os
import sys

import numpy as np

from tools.analysis import snap  # noqa: E402
from tests.containers import run_column  # noqa: E402  (tests/containers.py)

BACKEND = "cpu"
DR, W, H, RUN, T_OPEN = 0.0025, 0.05, 0.05, 0.1, 0.03
GATE = ["Geometry:dr=%g" % DR, "Geometry:width=%g" % W, "Geometry:height=%g" % H, "Geometry:runout=%g" % RUN,
        "Walls:gate_open=%g" % T_OPEN, "Flow:damping_until=%g" % T_OPEN, "Material:E=1e5", "Run:t_end=0.2",
        "Output:dt=0.01", "Run:progress_s=1e9"]


def run(sphseg, out, over, extra=()):
    return run_column(sphseg, out, over, extra, BACKEND)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--backend", choices=("cpu", "gpu"), default="cpu")
    a = ap.parse_args()
    global BACKEND
    BACKEND = a.backend
    ok = True

    def check(name, good, detail):
        nonlocal ok
        ok &= bool(good)
        print("%s %s: %s" % ("ok  " if good else "FAIL", name, detail))

    out = os.path.join(a.work, "straight")
    log = run(a.sphseg, out, GATE)
    snaps = [snap.read_snapshot(p) for p in snap.list_snapshots(out)]
    s0 = snaps[0]
    wall, kind, x = np.asarray(s0["Wall"]), np.asarray(s0["Kind"]), np.asarray(s0["Coordinates"])
    nl, ny = 3, round(H / DR)
    wid = snap.wall_ids(s0)
    check("the container's walls", wid == {"base": 1, "xlo": 2, "xhi": 3, "gate": 4}, "Walls header: %s" % s0.get("Walls"))
    gid = wid.get("gate", -1)
    gate = wall == gid
    check("gate dummies at t = 0", gate.sum() == nl * (ny + nl) and np.all(kind[gate] == 1) and
          np.all((x[gate, 0] > W) & (x[gate, 0] < W + nl * DR)),
          "%d with the gate's wall id (expected %d), x in [%.4f, %.4f]" % (gate.sum(), nl * (ny + nl), x[gate, 0].min(),
                                                                 x[gate, 0].max()))
    ids = sorted(set(wall[kind == 1].tolist()))
    check("dummy wall ids", ids == [1, 2, 3, 4] and np.all(wall[kind == 0] == 0),
          "ids %s (1 base, 2 x = 0, 3 x = end, 4 gate); material 0" % ids)
    held = [s for s in snaps if float(s["Time"]) < T_OPEN - 1e-9]
    front_held = max(np.asarray(s["Coordinates"])[np.asarray(s["Kind"]) == 0, 0].max() for s in held)
    check("the column stays behind the gate", front_held < W, "front %.4f m < W = %.3f m over %d snapshots" % (
        front_held, W, len(held)))
    last = snaps[-1]
    m = np.asarray(last["Kind"]) == 0
    front = np.asarray(last["Coordinates"])[m, 0].max()
    check("the gate is lifted", "the gate is open" in log and not np.any(np.asarray(last["Wall"]) == gid),
          "%d gate dummies left at t = %.2f s" % (int(np.sum(np.asarray(last["Wall"]) == gid)), float(last["Time"])))
    check("the column runs out", W + 10 * DR < front <= W + RUN,
          "front %.4f m at t = %.2f s (W + 10 dr = %.4f, end wall %.3f)" % (front, float(last["Time"]), W + 10 * DR,
                                                                           W + RUN))

    out_b = os.path.join(a.work, "restarted")
    run(a.sphseg, out_b, GATE + ["Run:max_steps=400", "Run:max_wall_time=1e6"])
    hb = snap.read_snapshot(snap.list_snapshots(out_b)[-1])
    run(a.sphseg, out_b, GATE, ["--restart", os.path.join(out_b, "checkpoint.h5")])
    sa, sb = snap.read_snapshot(snap.list_snapshots(out)[-1]), snap.read_snapshot(snap.list_snapshots(out_b)[-1])
    same = all(np.array_equal(np.asarray(sa[k]), np.asarray(sb[k])) for k in
               ("ParticleIDs", "Coordinates", "Velocities", "Stress", "Wall"))
    worst = snap.max_field_difference(sa, sb) if np.array_equal(sa["ParticleIDs"], sb["ParticleIDs"]) else np.inf
    good = same if BACKEND == "cpu" else worst <= 1e-8
    check("stopped before the gate opened, restarted: %s" % ("bit-identical" if BACKEND == "cpu" else
                                                            "equal to round-off"), good and float(hb["Time"]) < T_OPEN,
          "checkpoint at t = %.4f s; final snapshots %s (max field difference %.2e of its scale)" % (
              float(hb["Time"]), "equal" if same else "differ", worst))
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
