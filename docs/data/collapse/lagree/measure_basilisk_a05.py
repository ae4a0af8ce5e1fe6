"""Front and wall height of the Basilisk mu(I) continuum collapse at a = 0.5 (Lagree's
sandbox/M1EMN/Exemples/granular_column.c with granular.h: mu_s 0.32, dmu 0.28, I0 0.4, D = H0/30,
no-slip base, symmetry at x = 0; H0 = 1, R0 = 2, g = 1; REFCASES/out05_granular_column.dat holds
output_facets at t = 0, 1, 2, 3, 4 (event interface), t in sqrt(H0/g)).
Front: foremost x of any facet, and foremost x where the layer is thicker than thr (R0 units)."""
import numpy as np
segs = []; cur = []
for line in open("Exemples__REFCASES__out05_granular_column.dat"):
    s = line.split()
    if len(s) < 2:
        if cur: segs.append(cur); cur = []
        continue
    cur.append((float(s[0]), float(s[1])))
if cur: segs.append(cur)
blocks = []
for sg in segs:
    if sg[0][0] == 0.0 and (not blocks or len(blocks[-1]) > 10):
        blocks.append([])
    blocks[-1].append(sg)
R0, H0 = 2.0, 1.0
for t, b in enumerate(blocks):
    pts = np.array([p for sg in b for p in sg])
    xf = pts[:, 0].max()
    # thickness profile: top surface at x ~ max y of facet points near x (bins of 0.039)
    bins = np.arange(0, xf + 0.04, 0.0390625)
    k = np.digitize(pts[:, 0], bins)
    top = {kk: pts[k == kk, 1].max() for kk in np.unique(k)}
    line = "t = %d sqrt(H0/g): front (any facet) x = %.3f H0 -> (x-R0)/R0 = %.3f; height at x=0: %.4f H0 = %.4f R0" % (
        t, xf, (xf - R0) / R0, pts[pts[:, 0] < 0.04, 1].max(), pts[pts[:, 0] < 0.04, 1].max() / R0)
    for thr in (0.05, 0.1):  # layer thickness in R0 (0.05 R0 = one SPH dr at L0/dr = 20)
        ok = [bins[kk - 1] + 0.039 for kk, v in top.items() if v / R0 > thr and kk >= 1]
        line += "; front where h > %.2f R0: %.3f" % (thr, (max(ok) - R0) / R0)
    print(line)
