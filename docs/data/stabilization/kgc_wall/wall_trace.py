# issue 30, the corrected gradient at the drum's wall (README.md here): per snapshot the material's deepest
# reach past the wall (|x| - R) and, when the run's log names a lost particle, its track and, for the last 12
# snapshots, its neighbourhood (3 h) as RUN.npz. python3 wall_trace.py RUNDIR RUN.log OUT (run from the repository root)
import glob
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.getcwd())
from tools.analysis import snap
run, log, out = sys.argv[1], sys.argv[2], sys.argv[3]
R, h = 0.035, 0.00075
lost = None
m = re.search(r"particle (\d+) at", open(log).read())
if m: lost = int(m.group(1))
files = sorted(glob.glob(run + "/snapshot_*.h5"))
d, rows = {}, []
for k, f in enumerate(files):
    s = snap.read_snapshot(f)
    t = float(s["Time"]); X = np.asarray(s["Coordinates"]); kind = np.asarray(s["Kind"]); ids = np.asarray(s["ParticleIDs"])
    mat = kind == snap.MATERIAL
    r = np.hypot(X[:, 0], X[:, 1]); pen = np.where(mat, r - R, -1)
    j = int(np.argmax(pen)); n_in = int(np.sum(pen > -0.25e-3))
    row = [t, pen[j] * 1e3, ids[j], X[j, 0] * 1e3, X[j, 1] * 1e3, n_in]
    if lost is not None:
        q = np.where(ids == lost)[0]
        if len(q):
            q = q[0]; V = np.asarray(s["Velocities"])[q]; S = np.asarray(s["Stress"])[q]
            row += [X[q, 0] * 1e3, X[q, 1] * 1e3, (r[q] - R) * 1e3, V[0], V[1], S[0], S[1], S[3] if S.size > 3 else 0]
            if k >= len(files) - 12:
                nb = np.where(np.hypot(X[:, 0] - X[q, 0], X[:, 1] - X[q, 1]) < 3 * h)[0]
                key = "t%.4f_" % t
                for name in ("Coordinates", "Velocities", "Stress", "Volume", "Kind", "ParticleIDs"):
                    d[key + name] = np.asarray(s[name])[nb]
    rows.append(row)
np.savez_compressed(out + ".npz", **d)
with open(out + ".txt", "w") as f:
    f.write("# t  deepest(mm beyond R)  id  x y (mm)  n within 0.25mm of R | lost %s: x y (mm) r-R (mm) u v sxx syy sxy\n" % lost)
    for row in rows: f.write(" ".join("%.6g" % v for v in row) + "\n")
