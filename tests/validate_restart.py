"""Checkpoints and restarts (src/output/checkpoint.c, README "Checkpoints and
restarts"): a run stopped midway and restarted from its checkpoint must end
bit-identical to the same run done straight through (DESIGN.md: checkpoints
"restart bit-for-bit on the same rank count").

  shearbox:  the CI shear box (inputs/shearbox_2d.yml at dr/H = 0.04, one
             period, prescribed kinematics, conservative scheme). Run A
             straight to t_end; run B with checkpoints every 2 s and
             Run:max_steps = half of A's steps, then --restart to t_end. Every
             field of every snapshot after the restart equals A's
             (np.array_equal), every diagnostics row after the restart equals
             A's (all columns but wall_s), the rows before it are A's rows
             (plus the row max_steps forces), one header, the XDMF index
             lists every snapshot, checkpoint_prev.h5 is the checkpoint
             before; a run with checkpoints equals one without; the restart
             lists Run:max_steps among the run-control keys that differ.
  drum:      a CI drum (inputs/drum_2d_EV.yml at dr = 2.5 mm, E = 0.1 MPa as
             tests/validate_drum.py, computed flow with the Shepard filter,
             the paper's Flow:stabilization monaghan; the scene's riemann in
             the ranks case below and with the options of OPTION_CASES):
             A to 160 steps; B to 73 steps with a checkpoint, restarted to
             160 (Shepard filter at 90, 120, 150); the final snapshot and
             the rows after step 73 are equal.
  stopfile:  OUTDIR/STOP present: the run writes a checkpoint after its
             first step, removes STOP, exits 0 saying how to continue; the
             restart ends equal to A.
  walltime:  Run:max_wall_time = 1 s on a run that needs far longer: exit 0
             (within 10 s: the machine may be loaded), a checkpoint at t < t_end;
             the restart to the next output time ends equal to a straight run.
  ranks:     the drum on 3 ranks (slabs, and METIS parts), stopped at step 73
             and restarted on 3 ranks, ends bit-identical to the straight
             3-rank run (the checkpoint carries the decomposition); restarted
             on 2 ranks from the same checkpoint it ends equal to the straight
             run to round-off (every field within 1e-8 of its scale, classes
             equal: tests/validate_mpi.py's tolerance). METIS: the checkpoint
             records the coarse-cell width (3, the ghost depth); set to 2 (a
             checkpoint of a run with DEM grains, or of the CPU before it kept
             its ghosts) the restart partitions again and ends equal to
             round-off, and so does one without it (older checkpoints, read
             as 2). (Checkpoints edited with h5py are sealed again,
             tests/ckpt_seal.py, else their checksum refuses them.)
  chute:     a layer sliding down a 40-degree incline, periodic along x
             (inputs/column_2d.yml, Geometry:periodic x): stopped at step
             450 and restarted to 900 on one rank, bit-identical; on 3 ranks
             (slabs across the period) stopped, restarted on 1 rank, equal to
             the straight 3-rank run and to the 1-rank run to round-off.
  silo:      an outlet under a silo's opening (Outlet, Geometry:outlet_width):
             stopped at step 1800 and restarted to 3000, material leaving
             before and after; the final snapshot and the rows after the
             restart (n_outflow, small_volume_outflow included) equal the
             straight run's.
  badfile:   --restart with a snapshot, a truncated file (damaged: its seal
             names another size), a checkpoint of the other precision and one
             of another dimension: exit 2, one line naming the file and the
             problem (tests/test_restart_guard.py has many more).
  dem_*:     DEM grains (issue 58) in the settling box (inputs/dem_settling.yml,
             8000 fluid particles), stopped at step 7 with a checkpoint and
             restarted to step 12 (the Shepard filter every 5 steps: at 10,
             after the restart), against the straight run: the final
             snapshot's fluid and /DEM group and the rows after step 7 (the
             grains' kinetic energy and exchanged momentum among them)
             bit-identical. dem_settling: one grain, two
             way. dem_pile: 108 free grains in contact with each other and the
             base, gravity tilted (DEM_TILT) so that they slide and roll and
             the tangential springs carry load (the checkpoint must hold
             grain and wall contacts and springs that are not zero).
             dem_rigid: a rigid body of 12 grains (DEM:motion rigid) sliding
             on the base, turning, the gravity ramp (DEM:t_damp) running
             across the checkpoint, the leapfrog integrator (fresh rates at
             the filter's step 10). dem_ranks (CPU: the GPU runs grains on one
             rank): the pile on 2 ranks (slabs across it), restarted on 2
             ranks bit-identical to the straight 2-rank run, and on 1 rank
             equal to it to round-off (fluid within TOL of each field's
             scale, grains within TOL_DEM, contact counts equal). dem_bad: a
             checkpoint of the pile whose contact count is out of range, one
             without /DEM, and the scene with DEM:mu changed: exit 2, one
             line naming the problem.

--backend gpu (default cpu) runs every case with sphseg --backend gpu (ranks
share the visible GPUs by local rank). A GPU restart builds its Verlet list
again from the loaded positions, while the straight run keeps the list it
built some steps before, so the neighbour sums may be taken in another order:
the restarted GPU runs must end equal to the straight ones to round-off (the
3-rank to 2-rank tolerance above, TOL = 1e-8 of each field's scale, classes
exact; diagnostics rows to a relative 1e-8, or 1e-12 absolute for the drift
column), and each check says whether they came out bit-identical. A run with
checkpoints must still equal the run without, bit for bit (writing one only
copies the state to the host), and so must the rows a restart keeps from
before its checkpoint. The GPU's METIS coarse cells are 3 lattice
cells wide: the edited width is then 2, and a checkpoint without the width
(read as 2) is cut again. Exits 77 (skipped) where the build has no CUDA
backend or no GPU is visible. The /DEM group of a restarted GPU run must
equal the straight run's to round-off (validate_gpu's dem_difference within
TOL); dem_ranks is skipped there.

--cases NAME,NAME runs only those cases (default all; the names above).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
from tools.analysis import snap  # noqa: E402
from tests.ckpt_seal import reseal  # noqa: E402  (a checkpoint changed on purpose is sealed again)

BOX = os.path.join(HERE, "..", "inputs", "shearbox_2d.yml")
DRUM = os.path.join(HERE, "..", "inputs", "drum_2d_EV.yml")
BOX_P = ["Geometry:dr=0.00348", "Run:t_end=13", "Output:dt=3.25", "Run:progress_s=1e9"]
DRUM_P = ["Geometry:dr=0.0025", "Material:E=1e5", "Run:t_end=100", "Output:dt=1e3", "Output:diag_dt=0.001",
          "Run:progress_s=1e9"]
COLUMN = os.path.join(HERE, "..", "inputs", "column_2d.yml")
from tests.containers import CHUTE, PAPER_FLOW, SILO, pick_cases  # noqa: E402  (tests/containers.py)
CHUTE_P = CHUTE + ["Parallel:axis=x", "Run:t_end=100", "Output:dt=1e3", "Output:diag_dt=0.001", "Run:progress_s=1e9"]
SILO_P = SILO + ["Run:t_end=100", "Output:dt=1e3", "Output:diag_dt=0.002", "Run:progress_s=1e9"]
from tests.validate_gpu import DEM_PILE, dem_difference, last_dem  # noqa: E402
DEM_SCENE = os.path.join(HERE, "..", "inputs", "dem_settling.yml")
DEM_P = ["Output:dt=1e3", "Output:diag_dt=0.001", "Run:progress_s=1e9", "Flow:shepard_every=5"]
DEM_TILT = "Physics:gravity=[3, -9.81, 1]"  # grains on the base slide and roll: their springs carry load
DEM_RIGID = ["DEM:coupling=two_way", "DEM:motion=rigid", "DEM:placement=block", "DEM:block_n=[3, 2, 2]",
             "DEM:block_spacing=0.008", "DEM:block_origin=[0.02, 0.004, 0.024]", DEM_TILT, "DEM:t_damp=0.03",
             "Run:integrator=leapfrog"]
DEM_CASES = [("dem_settling", ["DEM:coupling=two_way"]), ("dem_pile", DEM_PILE + [DEM_TILT]),
             ("dem_rigid", DEM_RIGID)]
DEM_STOP, DEM_END = 7, 12
TOL_DEM = 1e-10  # the grains across rank counts (tests/validate_mpi.py's)
OK = True
TOL = 1e-8
AGREE = {"cpu": "bit-identical", "gpu": "equal to round-off"}  # what a restart must reach
DEPTH = {"cpu": 3, "gpu": 3}  # ghost depth in lattice cells = METIS coarse-cell width (the CPU's: 2 with DEM grains)


def check(name, good, detail=""):
    global OK
    OK &= bool(good)
    print("%s %s%s" % ("ok  " if good else "FAIL", name, ": " + detail if detail else ""))
    return bool(good)


def sphseg(args, scene, out, over, extra=(), want=0):
    cmd = [args.sphseg, scene, "-o", out, "--backend", args.backend] + sum([["-P", o] for o in over], []) + list(
        extra)
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != want:
        print(r.stdout[-2000:], r.stderr[-2000:])
        sys.exit("FAIL: %s exited with %d, want %d" % (" ".join(cmd), r.returncode, want))
    return r


def rows(out):
    """diagnostics.csv as {step: row without wall_s}, and the header count."""
    with open(os.path.join(out, "diagnostics.csv")) as f:
        lines = f.read().splitlines()
    head = lines[0].split(",")
    w = head.index("wall_s")
    body = {}
    for ln in lines[1:]:
        c = ln.split(",")
        body[int(c[0])] = c[:w] + c[w + 1:]
    return body, sum(ln.startswith("step,") for ln in lines)


def same_snapshot(a, b):
    """Names of the fields (and Time, Step) where two snapshots differ."""
    sa, sb = snap.read_snapshot(a), snap.read_snapshot(b)
    keys = [k for k in sa if k not in ("path", "Scene")]
    return [k for k in keys if k not in sb or not np.array_equal(np.asarray(sa[k]), np.asarray(sb[k]))]


def restart_agrees(args, a, b):
    """(good, detail): snapshot b of a restarted run against a of the
    straight run: bit-identical on the CPU; on the GPU bit-identical or equal
    to round-off (module docstring)."""
    d = same_snapshot(a, b)
    if not d:
        return True, "bit-identical"
    if args.backend == "cpu":
        return False, "differs in %s" % d
    good, worst = roundoff(a, b)
    return good, "equal to round-off: max field difference %.2e of its scale (differs in %s)" % (worst, ", ".join(d))


def rows_agree(args, ra, rb, steps):
    """Diagnostics rows of the given steps: identical on the CPU; on the GPU
    numerically equal (module docstring)."""
    if not steps or any(s not in rb for s in steps):
        return False
    if args.backend == "cpu":
        return all(rb[s] == ra[s] for s in steps)
    a = np.array([[float(v) for v in ra[s]] for s in steps])
    b = np.array([[float(v) for v in rb[s]] for s in steps])
    return bool(np.allclose(b, a, rtol=TOL, atol=1e-12))


def by_time(out):
    return {snap.snapshot_time(p): p for p in snap.list_snapshots(out)}


def ckpt_header(path):
    with h5py.File(path, "r") as f:
        return {k: snap._attr(v) for k, v in f["Header"].attrs.items()}


def compare_runs(args, name, a, b, t_restart, step_restart):
    """B (restarted at t_restart, step_restart) against the straight run A."""
    ta, tb = by_time(a), by_time(b)
    after = [t for t in ta if t > t_restart]
    check("%s snapshots after restart" % name, after and all(t in tb for t in after),
          "A %s, B %s" % (sorted(ta), sorted(tb)))
    for t in after:
        if t in tb:
            good, how = restart_agrees(args, ta[t], tb[t])
            check("%s snapshot t=%g %s" % (name, t, AGREE[args.backend]), good,
                  "%s, %s vs %s" % (how, os.path.basename(ta[t]), os.path.basename(tb[t])))
    ra, ha = rows(a)
    rb, hb = rows(b)
    check("%s one header" % name, ha == 1 and hb == 1, "%d and %d header lines" % (ha, hb))
    post = [s for s in ra if s > step_restart]
    check("%s rows after restart %s" % (name, AGREE[args.backend]),
          rows_agree(args, ra, rb, post) and [s for s in rb if s > step_restart] == post,
          "%d rows after step %d" % (len(post), step_restart))
    pre = [s for s in ra if s <= step_restart]
    check("%s rows before restart kept" % name, all(rb.get(s) == ra[s] for s in pre) and
          set(s for s in rb if s <= step_restart) - set(pre) <= {step_restart}, "%d rows" % len(pre))
    with open(os.path.join(b, "snapshots.xmf")) as f:
        xmf = f.read()
    n = len(snap.list_snapshots(b))
    check("%s XDMF lists every snapshot" % name, xmf.count("<Grid Name=\"snapshot_") == n and
          "snapshot_%05d.h5" % (n - 1) in xmf, "%d snapshots" % n)


def test_shearbox(args):
    a, b, c = (os.path.join(args.work, "box_" + x) for x in "abc")
    ra = sphseg(args, BOX, a, BOX_P)
    nsteps = int(ra.stdout.split("done: ")[1].split()[0])
    sphseg(args, BOX, c, BOX_P + ["Output:checkpoint_dt=2"])
    d = same_snapshot(snap.list_snapshots(a)[-1], snap.list_snapshots(c)[-1])
    check("shearbox checkpoints change nothing", not d, "differs in %s" % d if d else "")
    half = nsteps // 2
    sphseg(args, BOX, b, BOX_P + ["Output:checkpoint_dt=2", "Run:max_steps=%d" % half])
    ck, prev = os.path.join(b, "checkpoint.h5"), os.path.join(b, "checkpoint_prev.h5")
    h, hp = ckpt_header(ck), ckpt_header(prev)
    check("shearbox checkpoint at stop", h["Step"] == half and hp["Step"] < half and hp["Time"] >= 2,
          "checkpoint step %d t=%.4g, previous step %d t=%.4g" % (h["Step"], h["Time"], hp["Step"], hp["Time"]))
    r = sphseg(args, BOX, b, BOX_P, ["--restart", ck])
    check("shearbox restart lists the changed run-control key", "run-control key(s) differ" in r.stdout
          and "Run:max_steps (%d in the checkpoint, 0 now)" % half in r.stdout, r.stdout.strip()[:300])
    compare_runs(args, "shearbox", a, b, h["Time"], h["Step"])
    return a


def dem_agrees(args, a, b):
    """(good, detail): the /DEM group of the last snapshot in b against a's:
    every dataset bit-identical on the CPU; on the GPU within TOL
    (dem_difference) or bit-identical."""
    da, db = last_dem(a), last_dem(b)
    if db is None or set(da) != set(db):
        return False, "no /DEM, or other datasets"
    d = [k for k in da if not np.array_equal(da[k], db[k])]
    if not d:
        return True, "bit-identical"
    worst = dem_difference(da, db)
    return args.backend == "gpu" and worst <= TOL, "max difference %.2e of the scale (differs in %s)" % (
        worst, ", ".join(d))


def stop_restart(args, name, scene, over, stop, end, inspect=None, logs=None):
    """Run A straight to step end; run B stopped with a checkpoint at step stop
    and restarted to end; A's and B's final snapshots (their /DEM groups too),
    and their diagnostics rows after stop, must agree (bit for bit on the
    CPU). inspect(checkpoint path) runs before the restart; logs (a dict), if
    given, takes A's and the restart's output ("a", "b"). Returns A's
    directory."""
    a, b = (os.path.join(args.work, name + "_" + x) for x in "ab")
    r = sphseg(args, scene, a, over + ["Run:max_steps=%d" % end])
    if logs is not None:
        logs["a"] = r.stdout + r.stderr
    sphseg(args, scene, b, over + ["Run:max_steps=%d" % stop, "Run:max_wall_time=1e6"])
    h = ckpt_header(os.path.join(b, "checkpoint.h5"))
    check("%s checkpoint at stop" % name, h["Step"] == stop, "step %d" % h["Step"])
    if inspect:
        inspect(os.path.join(b, "checkpoint.h5"))
    r = sphseg(args, scene, b, over + ["Run:max_steps=%d" % end], ["--restart", os.path.join(b, "checkpoint.h5")])
    if logs is not None:
        logs["b"] = r.stdout + r.stderr
    if args.backend == "gpu":  # the list builds are the restarted run's, and so must be the steps they are counted in
        m = re.search(r"gpu: (\d+) neighbour-list builds in (\d+) steps", r.stdout + r.stderr)
        check("%s restart's list-build report counts its own %d steps" % (name, end - stop),
              bool(m) and int(m.group(2)) == end - stop and int(m.group(1)) > 0, m.group(0) if m else "no report")
    good, how = restart_agrees(args, snap.list_snapshots(a)[-1], snap.list_snapshots(b)[-1])
    check("%s final snapshot %s (step %d)" % (name, AGREE[args.backend], end), good, how)
    if last_dem(a) is not None:
        good, how = dem_agrees(args, a, b)
        check("%s final /DEM %s (step %d)" % (name, AGREE[args.backend], end), good, how)
    ra, _ = rows(a)
    rb, _ = rows(b)
    post = [s for s in ra if s > stop]
    check("%s rows after restart %s" % (name, AGREE[args.backend]), rows_agree(args, ra, rb, post),
          "%d rows" % len(post))
    return a


def test_drum(args):
    stop_restart(args, "drum", DRUM, DRUM_P + PAPER_FLOW, 73, 160)


# Issue 30's options, each of which keeps state or changes what a step reads:
# the Riemann dissipation with shifting, the excluded background pressure and
# the tensorial yield surface together; the delta-SPH pressure diffusion alone;
# the partially regularised mu(I) with the bed damping (the drum scenes');
# the corrected kernel gradient (B made afresh in every prepare, none in the
# checkpoint's state that a restart could miss), alone. The cases without
# these keys (test_drum_ranks) run the drum scene's own flow: the corrected
# gradient with the shifting.
OPTION_CASES = [
    ("drum_riemann_shift_mu_I", ["Flow:stabilization=riemann", "Flow:shifting=fickian", "Flow:gradient_correction=off",
                                 "Flow:background_pressure=excluded", "Material:yield=mu_I"]),
    ("drum_delta", ["Flow:stabilization=delta", "Flow:gradient_correction=off", "Flow:shifting=off"]),
    ("drum_partial_bed", ["Flow:stabilization=riemann", "Flow:bed_damping=1", "Material:mu_law=partial",
                          "Flow:gradient_correction=off", "Flow:shifting=off"]),
    ("drum_kgc", ["Flow:stabilization=riemann", "Flow:gradient_correction=on", "Flow:shifting=off"]),
]


def test_options(args):
    for name, keys in OPTION_CASES:
        stop_restart(args, name, DRUM, DRUM_P + keys, 73, 160)


def mpi(np_):
    return ["mpirun", "--oversubscribe", "--allow-run-as-root", "-np", str(np_)]


def sphseg_np(args, np_, scene, out, over, extra=()):
    cmd = mpi(np_) + [args.sphseg, scene, "-o", out, "--backend", args.backend] + sum([["-P", o] for o in over], [])
    r = subprocess.run(cmd + list(extra), capture_output=True, text=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    if r.returncode != 0:
        print(r.stdout[-2000:], r.stderr[-2000:])
        sys.exit("FAIL: %s exited with %d" % (" ".join(cmd), r.returncode))
    return r


def roundoff(a, b, tol=TOL):
    sa, sb = snap.read_snapshot(a), snap.read_snapshot(b)
    worst = snap.max_field_difference(sa, sb)
    same = np.array_equal(sa["ParticleIDs"], sb["ParticleIDs"]) and np.array_equal(sa["BoundaryClass"],
                                                                                      sb["BoundaryClass"])
    return same and worst <= tol, worst


def test_drum_ranks(args):
    for method in ("slabs", "metis"):
        over = DRUM_P + ["Parallel:method=" + method]
        a, b, c = (os.path.join(args.work, "drum3r_%s_%s" % (method, x)) for x in "abc")
        sphseg_np(args, 3, DRUM, a, over + ["Run:max_steps=160"])
        sphseg_np(args, 3, DRUM, b, over + ["Run:max_steps=73", "Run:max_wall_time=1e6"])
        shutil.copytree(b, c)
        sphseg_np(args, 3, DRUM, b, over + ["Run:max_steps=160"], ["--restart", os.path.join(b, "checkpoint.h5")])
        good, how = restart_agrees(args, snap.list_snapshots(a)[-1], snap.list_snapshots(b)[-1])
        check("drum on 3 ranks (%s), restarted on 3: %s at step 160" % (method, AGREE[args.backend]), good, how)
        if method == "metis":
            metis_width(args, a, c, over)
        sphseg_np(args, 2, DRUM, c, over + ["Run:max_steps=160"], ["--restart", os.path.join(c, "checkpoint.h5")])
        good, worst = roundoff(snap.list_snapshots(a)[-1], snap.list_snapshots(c)[-1])
        check("drum on 3 ranks (%s), restarted on 2: equal to round-off at step 160" % method, good,
              "max field difference %.2e of its scale" % worst)


def test_chute(args):
    """Periodic axes: a layer sliding down an incline across the period boundary
    (images as ghosts, on one rank too), stopped midway and restarted: bit-identical
    on one rank (CPU); from 3 ranks restarted on 1, equal to round-off."""
    over = CHUTE_P
    a, b, c, d = (os.path.join(args.work, "chute_" + x) for x in "abcd")
    sphseg(args, COLUMN, a, over + ["Run:max_steps=900"])
    sphseg(args, COLUMN, b, over + ["Run:max_steps=450", "Run:max_wall_time=1e6"])
    sphseg(args, COLUMN, b, over + ["Run:max_steps=900"], ["--restart", os.path.join(b, "checkpoint.h5")])
    good, how = restart_agrees(args, snap.list_snapshots(a)[-1], snap.list_snapshots(b)[-1])
    check("periodic chute on 1 rank, restarted: %s at step 900" % AGREE[args.backend], good, how)
    sphseg_np(args, 3, COLUMN, c, over + ["Run:max_steps=900"])
    sphseg_np(args, 3, COLUMN, d, over + ["Run:max_steps=450", "Run:max_wall_time=1e6"])
    sphseg_np(args, 1, COLUMN, d, over + ["Run:max_steps=900"], ["--restart", os.path.join(d, "checkpoint.h5")])
    good, worst = roundoff(snap.list_snapshots(c)[-1], snap.list_snapshots(d)[-1])
    check("periodic chute on 3 ranks, restarted on 1: equal to round-off at step 900", good,
          "max field difference %.2e of its scale" % worst)
    good, worst = roundoff(snap.list_snapshots(a)[-1], snap.list_snapshots(c)[-1])
    check("periodic chute on 3 ranks against 1 rank: equal to round-off at step 900", good,
          "max field difference %.2e of its scale" % worst)


def test_silo(args):
    """An outlet under a silo's opening: material leaves the run before and after
    the checkpoint; the restart carries the outflow so far (count and sum C V) and
    ends as the straight run (bit-identical on the CPU), diagnostics rows, the
    outflow columns among them, included."""
    a = stop_restart(args, "silo", COLUMN, SILO_P, 1800, 3000)
    with open(os.path.join(a, "diagnostics.csv")) as f:
        rows_ = f.read().strip().splitlines()
    col = rows_[0].split(",").index("n_outflow")
    before = [int(r.split(",")[col]) for r in rows_[1:] if int(r.split(",")[0]) <= 1800]
    check("silo: material left before the checkpoint and after it", before[-1] > 0 and
          int(rows_[-1].split(",")[col]) > before[-1], "n_outflow %d at the checkpoint, %s at the end" % (
              before[-1], rows_[-1].split(",")[col]))


def dem_ckpt(path):
    """The /DEM group of a checkpoint: attributes, and its contacts as
    (grain-grain count, wall count, largest |spring|)."""
    with h5py.File(path, "r") as f:
        g = f["DEM"]
        attrs = {k: snap._attr(v) for k, v in g.attrs.items()}
        cmax = int(attrs["ContactsMax"])
        nc = g["Contacts"][()]
        cid = g["ContactPartners"][()].reshape(-1, cmax)
        xi = g["ContactSprings"][()].reshape(-1, cmax, 3)
    live = np.arange(cmax)[None, :] < nc[:, None]
    walls = int(np.sum(live & (cid < 0)))
    return attrs, int(np.sum(live)) - walls, walls, float(np.max(np.abs(xi[live]))) if live.any() else 0.0


def dem_inspect(name, grains, walls):
    """A check of the checkpoint at the stop: the DEM steps so far, and (for
    the cases that exercise the contact histories) grain and wall contacts
    whose springs carry load."""
    def f(path):
        attrs, ng, nw, xi = dem_ckpt(path)
        good = attrs["Steps"] > DEM_STOP and (ng > 0 or not grains) and (nw > 0 or not walls) and (
            xi > 0 or not (grains or walls))
        check("%s checkpoint holds the grains' state" % name, good, "%d DEM steps, %d grain and %d wall contacts, "
              "largest tangential spring %.2e m" % (attrs["Steps"], ng, nw, xi))
    return f


def test_dem(args, name, keys):
    inspect, logs = dem_inspect(name, name == "dem_pile", name != "dem_settling"), {}
    stop_restart(args, name, DEM_SCENE, DEM_P + keys, DEM_STOP, DEM_END, inspect, logs)
    # the end report counts the run's DEM steps, restarts included (the checkpoint carries them)
    steps = [re.search(r"dem: \d+ grains, (\d+) DEM steps in (\d+) fluid steps", logs[k]) for k in "ab"]
    check("%s end report: the restart's DEM steps are the straight run's" % name,
          all(steps) and steps[0].groups() == steps[1].groups() and int(steps[1].group(2)) == DEM_END,
          " and ".join(m.group(0) if m else "no dem: line" for m in steps))


def test_dem_ranks(args):
    """The pile on 2 ranks, restarted on 2 (bit-identical) and on 1 (round-off);
    the grains divided between the 2 ranks (src/dem/dem_halo.c)."""
    over = DEM_P + DEM_PILE + [DEM_TILT, "Parallel:axis=x", "Parallel:balance_every=0"]
    a, b, c = (os.path.join(args.work, "dem2r_" + x) for x in "abc")
    r = sphseg_np(args, 2, DEM_SCENE, a, over + ["Run:max_steps=%d" % DEM_END])
    m = re.search(r"dem: divided among 2 ranks: (\d+) to (\d+) grains owned", r.stdout + r.stderr)
    check("dem pile on 2 ranks: the grains divided (the end report)", m is not None and int(m.group(2)) < 108,
          m.group(0) if m else "no 'dem: divided among 2 ranks' line")
    sphseg_np(args, 2, DEM_SCENE, b, over + ["Run:max_steps=%d" % DEM_STOP, "Run:max_wall_time=1e6"])
    shutil.copytree(b, c)
    ck = ["--restart", os.path.join(b, "checkpoint.h5")]
    sphseg_np(args, 2, DEM_SCENE, b, over + ["Run:max_steps=%d" % DEM_END], ck)
    d = same_snapshot(snap.list_snapshots(a)[-1], snap.list_snapshots(b)[-1])
    good, how = dem_agrees(args, a, b)
    ra, rb = rows(a)[0], rows(b)[0]
    post = [s for s in ra if s > DEM_STOP]
    check("dem pile on 2 ranks, restarted on 2: bit-identical at step %d (fluid, /DEM, rows)" % DEM_END,
          not d and good and rows_agree(args, ra, rb, post), "fluid differs in %s; /DEM %s" % (d, how))
    sphseg_np(args, 1, DEM_SCENE, c, over + ["Run:max_steps=%d" % DEM_END], ["--restart",
                                                                             os.path.join(c, "checkpoint.h5")])
    fgood, fworst = roundoff(snap.list_snapshots(a)[-1], snap.list_snapshots(c)[-1])
    da, dc = last_dem(a), last_dem(c)
    dworst = dem_difference(da, dc)
    con = int(np.sum(da["Contacts"] != dc["Contacts"]))
    check("dem pile on 2 ranks, restarted on 1: equal to round-off at step %d" % DEM_END,
          fgood and dworst <= TOL_DEM and con == 0, "fluid %.2e, grains %.2e of the scale; %d grains with other "
          "contact counts" % (fworst, dworst, con))


def dem_bad(args, name, ckpt, extra, want):
    out = os.path.join(args.work, "dem_bad_out")
    cmd = [args.sphseg, DEM_SCENE, "-o", out, "--backend", args.backend, "--restart", ckpt] + sum(
        [["-P", o] for o in DEM_P + DEM_PILE + [DEM_TILT, "Run:max_steps=%d" % DEM_END] + extra], [])
    r = subprocess.run(cmd, capture_output=True, text=True)
    lines = r.stderr.strip().splitlines()
    check("dem_bad %s" % name, r.returncode == 2 and len(lines) == 1 and want in lines[0] and not os.path.exists(out),
          "exit %d: %s" % (r.returncode, r.stderr.strip()[-400:]))


def test_dem_bad(args):
    """A pile's checkpoint damaged in its /DEM group (then sealed again), and
    restarted with a DEM key changed: refused in one line."""
    b = os.path.join(args.work, "dem_bad")
    sphseg(args, DEM_SCENE, b, DEM_P + DEM_PILE + [DEM_TILT, "Run:max_steps=3", "Run:max_wall_time=1e6"])
    ck = os.path.join(b, "checkpoint.h5")
    dem_bad(args, "DEM:mu changed", ck, ["DEM:mu=0.5"],
            "1 state-defining key(s) differ: DEM:mu (0.3 in the checkpoint, 0.5 now)")
    for tag, edit, want in (("contacts", "count", "/DEM/Contacts[5] = 17 is out of range"),
                            ("nodem", "drop", "holds no DEM grains")):
        p = ck + "." + tag
        shutil.copy(ck, p)
        with h5py.File(p, "r+") as f:
            if edit == "drop":
                del f["DEM"]
            else:
                f["DEM/Contacts"][5] = 17
        reseal(p)
        dem_bad(args, tag, p, [], want)


def metis_width(args, a, c, over):
    """METIS parts are coarse cells as wide as the ghost depth, which the
    checkpoint records (/Decomposition CoarseCellWidth). A cut saved with
    other coarse cells (2: a run with DEM grains on the CPU, whose ghosts
    are 2 cells deep) is made again at the restart, and the run ends equal
    to the straight one to round-off; a checkpoint without the attribute
    (older) is taken as 2 and cut again alike (the code below keeps the
    bit-identical branch for a backend whose depth is 2)."""
    depth = DEPTH[args.backend]
    other = 3 if depth == 2 else 2
    for name, width in (("w%d" % other, other), ("nowidth", None)):
        e = c + "_" + name
        shutil.copytree(c, e)
        with h5py.File(os.path.join(e, "checkpoint.h5"), "r+") as f:
            g = f["Decomposition"]
            check("METIS checkpoint records its coarse-cell width (%d on the %s)" % (depth, args.backend.upper()),
                  int(g.attrs.get("CoarseCellWidth", -1)) == depth)
            if width is None:
                del g.attrs["CoarseCellWidth"]
            else:
                g.attrs["CoarseCellWidth"] = np.int64(width)
        reseal(os.path.join(e, "checkpoint.h5"))
        r = sphseg_np(args, 3, DRUM, e, over + ["Run:max_steps=160"], ["--restart", os.path.join(e, "checkpoint.h5")])
        again = "partitioning again" in r.stdout + r.stderr
        if width is None and depth == 2:
            d = same_snapshot(snap.list_snapshots(a)[-1], snap.list_snapshots(e)[-1])
            check("METIS checkpoint without a coarse-cell width restored: bit-identical at step 160",
                  not again and not d, "differs in %s" % d if d else "")
        else:
            good, worst = roundoff(snap.list_snapshots(a)[-1], snap.list_snapshots(e)[-1])
            check("METIS cut of coarse cells %d wide made again on the %s: equal to round-off at step 160"
                  % (width or 2, args.backend.upper()), again and good,
                  "re-cut %s, max field difference %.2e of its scale" % (again, worst))


def test_stopfile(args, box_a):
    b = os.path.join(args.work, "box_stop")
    os.makedirs(b)
    open(os.path.join(b, "STOP"), "w").close()
    r = sphseg(args, BOX, b, BOX_P)
    h = ckpt_header(os.path.join(b, "checkpoint.h5"))
    check("stopfile: stops with a checkpoint", h["Step"] == 1 and not os.path.exists(os.path.join(b, "STOP"))
          and "--restart" in r.stdout, "checkpoint step %d; STOP removed; how-to line printed" % h["Step"])
    sphseg(args, BOX, b, BOX_P, ["--restart", os.path.join(b, "checkpoint.h5")])
    good, how = restart_agrees(args, snap.list_snapshots(box_a)[-1], snap.list_snapshots(b)[-1])
    check("stopfile: restart ends %s" % AGREE[args.backend], good, how)


def test_walltime(args):
    a, b = (os.path.join(args.work, "wall_" + x) for x in "ab")
    over = [o for o in BOX_P if not o.startswith("Run:t_end")]
    t0 = time.monotonic()
    r = sphseg(args, BOX, b, over + ["Run:t_end=1e5", "Run:max_wall_time=1"])
    el = time.monotonic() - t0
    h = ckpt_header(os.path.join(b, "checkpoint.h5"))
    check("walltime: stops in time with a checkpoint", "max_wall_time" in r.stdout and h["Time"] < 1e5 and el < 10,
          "%.2f s, checkpoint at step %d, t = %.4g s" % (el, h["Step"], h["Time"]))
    t_end = float((np.floor(h["Time"] / 3.25) + 1) * 3.25)  # a Python float: numpy 2 reprs np.float64 as "np.float64(x)"
    sphseg(args, BOX, a, over + ["Run:t_end=%r" % t_end])
    sphseg(args, BOX, b, over + ["Run:t_end=%r" % t_end], ["--restart", os.path.join(b, "checkpoint.h5")])
    good, how = restart_agrees(args, snap.list_snapshots(a)[-1], snap.list_snapshots(b)[-1])
    check("walltime: restart to t = %g ends %s" % (t_end, AGREE[args.backend]), good, how)


def bad(args, name, path, want):
    out = os.path.join(args.work, "bad_out")
    cmd = [args.sphseg, BOX, "-o", out, "--backend", args.backend, "--restart", path] + sum(
        [["-P", o] for o in BOX_P], [])
    r = subprocess.run(cmd, capture_output=True, text=True)
    lines = r.stderr.strip().splitlines()
    check("badfile %s" % name, r.returncode == 2 and len(lines) == 1 and path in lines[0] and want in lines[0]
          and not os.path.exists(out), "exit %d: %s" % (r.returncode, r.stderr.strip()))


def test_badfile(args, box_a):
    ck = os.path.join(box_a + "_bad", "checkpoint.h5")
    os.makedirs(os.path.dirname(ck))
    sphseg(args, BOX, os.path.dirname(ck), BOX_P + ["Run:max_steps=2", "Run:max_wall_time=1e6"])
    bad(args, "snapshot", snap.list_snapshots(box_a)[0], "not a sphseg checkpoint")
    trunc = ck + ".trunc"
    with open(ck, "rb") as f, open(trunc, "wb") as g:
        g.write(f.read(3000))
    bad(args, "truncated", trunc, "damaged: 3000 bytes long")
    for name, attr, value, want in [("precision", "Precision", None, "precision"),
                                    ("dimension", "Dimension", 3, "3D run")]:
        p = ck + "." + name
        shutil.copy(ck, p)
        with h5py.File(p, "r+") as f:
            if value is None:
                value = "single" if f["Header"].attrs["Precision"] == "double" else "double"
                del f["Header"].attrs["Precision"]
                f["Header"].attrs.create("Precision", value, dtype=h5py.string_dtype("utf-8"))
            else:
                f["Header"].attrs.modify(attr, np.int64(value))
        reseal(p)
        bad(args, name, p, want)
    # the store's array count: a later version's (one more) is refused; an earlier version's (its last
    # array, phi, not there: issue 58) restarts where the run does not hold that array (src/output/checkpoint_read.c)
    with h5py.File(ck, "r") as f:
        na = int(f["Header"].attrs["NumArrays"])
    for name, count in [("later", na + 1), ("earlier", na - 1)]:
        p = ck + "." + name
        shutil.copy(ck, p)
        with h5py.File(p, "r+") as f:
            f["Header"].attrs.modify("NumArrays", np.int64(count))
            if count < na:
                del f["Particles"]["%02d" % (na - 1)]
        reseal(p)
        if count > na:
            bad(args, name, p, "written by a later version")
            continue
        out = os.path.join(args.work, "earlier_out")
        cmd = [args.sphseg, BOX, "-o", out, "--backend", args.backend, "--restart", p] + sum(
            [["-P", o] for o in BOX_P], [])
        r = subprocess.run(cmd, capture_output=True, text=True)
        check("badfile earlier", r.returncode == 0 and "done:" in r.stdout,
              "a checkpoint of %d arrays (this build's %d) restarts: exit %d %s" % (count, na, r.returncode,
                                                                                   r.stderr.strip()[:200]))


CASES = ["shearbox", "stopfile", "walltime", "badfile", "drum", "options", "drum_ranks", "chute", "silo"] + [
    c[0] for c in DEM_CASES] + ["dem_ranks", "dem_bad"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--backend", choices=("cpu", "gpu"), default="cpu",
                    help="sphseg backend of every run (default cpu; module docstring)")
    ap.add_argument("--cases", default=None, help="NAME,NAME: only these cases (module docstring)")
    args = ap.parse_args()
    cases = [c[0] for c in pick_cases(ap, [(n,) for n in CASES], args.cases)]
    os.makedirs(args.work, exist_ok=True)
    if args.backend == "gpu":
        out = os.path.join(args.work, "probe")
        probe = subprocess.run([args.sphseg, BOX, "-o", out, "--backend", "gpu", "-P", "Run:max_steps=1"],
                               capture_output=True, text=True)
        if probe.returncode == 2 and "--backend gpu" in probe.stderr:
            print("SKIP: " + probe.stderr.strip())
            sys.exit(77)
    box_a = None
    for name in cases:
        t0 = time.monotonic()
        if name in ("shearbox", "stopfile", "badfile") and box_a is None:
            box_a = test_shearbox(args)  # the straight box run the others compare with
        if name == "stopfile":
            test_stopfile(args, box_a)
        elif name == "badfile":
            test_badfile(args, box_a)
        elif name in dict(DEM_CASES):
            test_dem(args, name, dict(DEM_CASES)[name])
        elif name != "shearbox":
            globals()["test_" + name](args)
        print("     (%s: %.1f s)" % (name, time.monotonic() - t0))
    print("validate_restart:", "PASS" if OK else "FAIL")
    sys.exit(0 if OK else 1)


if __name__ == "__main__":
    main()
