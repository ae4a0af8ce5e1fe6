"""Results do not depend on the rank count (DESIGN.md "Parallel model"): the
CPU backend's fields on 1, 2 and 3 ranks are bit-identical after N steps.

A rank sums a particle's neighbours cell by cell on the global lattice
(grid_fit_lattice) and, inside a cell, in a canonical order: nbr_build sorts
each cell's run by (periodic image last, global particle ID). A cell is owned
by one rank whole, so it holds owned particles or ghosts alone, but where a
period's end cuts it: owned particles inside the period, images beyond, in
that order on any rank count. So every sum is taken in the one-rank order
and every ghost holds its owner's bits. Before that (4dab9c2) a cell's order was the store's previous
order, which migration and the owned/ghost split change, and the runs parted
by a few ulps within a few hundred steps (1e-15 relative here, 1.5e-2 in C
after 5 s of a drum): this test fails there.

Cases, each run on 1, 2 and 3 ranks (slabs, with migration; OMP_NUM_THREADS=1)
and compared dataset by dataset in the last snapshot, particles matched by
ParticleIDs, with array_equal on the bits:
  drum_EV   the EV drum's own flow (riemann, bed damping, the corrected
            gradient, fickian shifting) and concentration windows;
  drum_EN   the paper's scheme (HCSR classification every step, C1
            gradients) under monaghan;
  chute_y   a layer periodic along x cut into slabs along y: the cells at the
            period's ends hold owned particles and images (the image rule;
            ID order alone fails here);
  drum_metis the METIS partition.
Not compared: diagnostics.csv, whose kinetic energy is an MPI_SUM over ranks
(a diagnostic only; nothing in the step reads it).

--backend gpu runs the same cases on the GPU backend (ranks share the
visible devices; exit 77 without one): there the cells are sorted alike
(gpu/gpu_nbr.cu), the Verlet lists take a cell's owned particles and ghosts
merged in that order (grid_list_fill_ranked: their cells of 2h + skin are
not cut on slab lines), they are built on the same steps on every rank
count (the skin test on the largest displacements of all ranks, a fresh
build at every load-balance check: src/run.c parallel_balance), on the one
lattice (the halo's corner), and the team size comes from the particles of
all ranks. Written for issue 55 without a GPU at hand: not yet run.

--sphseg (default build/sphseg), --work (default a temporary folder, removed
when every check passes). About 30 s on 2 cores.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..")
sys.path.insert(0, ROOT)
from tools.analysis import snap  # noqa: E402
from tests.containers import CHUTE, PLAIN  # noqa: E402

DRUM = ["Geometry:dr=0.0025", "Material:E=1e5", "Flow:shepard_every=20"]
CASES = [
    ("drum_EV", "drum_2d_EV.yml", 600, DRUM),
    ("drum_EN", "drum_2d_EN.yml", 200, DRUM + PLAIN + ["Segregation:scheme=paper", "Flow:stabilization=monaghan"]),
    ("chute_y", "column_2d.yml", 400, CHUTE + ["Parallel:axis=y", "Geometry:height=0.07"]),
    ("drum_metis", "drum_2d_EV.yml", 400, DRUM + ["Parallel:method=metis"]),
]
RANKS = (1, 2, 3)


def run(sphseg, np_, scene, out, steps, over, backend):
    cmd = ["mpirun", "--oversubscribe", "--allow-run-as-root", "-np", str(np_), sphseg,
           os.path.join(ROOT, "inputs", scene), "-o", out, "--overwrite", "--backend", backend,
           "-P", "Run:max_steps=%d" % steps, "-P", "Run:progress_s=1e9", "-P", "Output:dt=1e3"]
    cmd += sum([["-P", o] for o in over], [])
    r = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    if r.returncode != 0:
        print(r.stdout[-2000:], r.stderr[-2000:])
        sys.exit("FAIL: %s on %d ranks exited with %d" % (scene, np_, r.returncode))
    s = snap.read_snapshot(snap.list_snapshots(out)[-1])
    order = np.argsort(s["ParticleIDs"], kind="stable")
    fields = {k: np.ascontiguousarray(v[order]) for k, v in s.items()
              if isinstance(v, np.ndarray) and v.ndim >= 1 and len(v) == len(order)}
    return int(s["Step"]), fields


def differences(one, many):
    """Per dataset: how many particles' values differ in any bit."""
    out = {}
    for k in sorted(set(one) | set(many)):
        a, b = one.get(k), many.get(k)
        if a is None or b is None or a.shape != b.shape or a.dtype != b.dtype:
            out[k] = -1
            continue
        ab, bb = a.view(np.uint8).reshape(len(a), -1), b.view(np.uint8).reshape(len(b), -1)
        n = int(np.any(ab != bb, axis=1).sum())
        if n:
            out[k] = n
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sphseg", default=os.path.join(ROOT, "build", "sphseg"))
    ap.add_argument("--work", default=None)
    ap.add_argument("--backend", default="cpu", choices=["cpu", "gpu"])
    a = ap.parse_args()
    if a.backend == "gpu":
        try:
            r = subprocess.run(["nvidia-smi", "-L"], capture_output=True, text=True)
            seen = r.returncode == 0 and "GPU" in r.stdout
        except OSError:
            seen = False
        if not seen:
            print("SKIP: no GPU visible")
            sys.exit(77)
    sphseg = os.path.abspath(a.sphseg)
    work = a.work or tempfile.mkdtemp(prefix="ranks_bitwise_")
    ok = True
    for name, scene, steps, over in CASES:
        res = {np_: run(sphseg, np_, scene, os.path.join(work, "%s_%d" % (name, np_)), steps, over, a.backend)
               for np_ in RANKS}
        for np_ in RANKS[1:]:
            d = differences(res[1][1], res[np_][1])
            worst = 0.0
            for k in d:
                x, y = res[1][1].get(k), res[np_][1].get(k)
                if x is not None and y is not None and x.shape == y.shape and x.dtype.kind == "f":
                    worst = max(worst, float(np.max(np.abs(x - y))) / max(float(np.max(np.abs(x))), 1e-300))
            good = not d and res[np_][0] == res[1][0] == steps
            ok &= good
            print("%s %-10s %d vs 1 rank, %d steps: %s" % (
                "ok  " if good else "FAIL", name, np_, steps,
                "bit-identical (%d datasets)" % len(res[1][1]) if not d else
                "differ: %s (worst relative %.2e)" % (", ".join("%s %d" % kv for kv in d.items()), worst)))
    if ok and not a.work:
        shutil.rmtree(work, ignore_errors=True)
    print("ok: every field bit-identical on 1, 2 and 3 ranks" if ok else "FAIL: the rank count changes the fields")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
