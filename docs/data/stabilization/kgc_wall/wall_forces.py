# issue 30, the corrected gradient at the drum's wall (README.md here): for the lost particle of a
# wall_trace.py npz, at each saved snapshot, its moment matrix M (every neighbour, material and dummy),
# the wall-normal part of its pair stress force (standard grad W, and B_i grad W with B_j taken as B_i)
# split into the dummy and material pairs, and its strain rate (standard and corrected), against the
# drum's rigid rotation. python3 wall_forces.py k01.npz 6021 (the 2D EV drum, dr 0.5 mm, h 0.75 mm)
import sys
import numpy as np

d = np.load(sys.argv[1])
lost = int(sys.argv[2])
h, R, rho = 0.00075, 0.035, 1500.0
alpha = 7 / (4 * np.pi * h * h)     # Wendland C2, 2D (src/physics/kernel.h)
omega = -5 * 2 * np.pi / 60          # clockwise, 5 rpm
g = np.array([0.0, -9.81])


def kf(r):  # (1/r) dW/dr, kernel_f
    a = np.clip(1 - 0.5 * r / h, 0, None)
    return -5 * alpha * a**3 / h**2


def sig(s):  # (xx, yy, zz, xy, xz, yz) -> the 2D tensor
    return np.array([[s[0], s[3]], [s[3], s[1]]])


print("# t: r-R (mm), det M, eigenvalues of M, M_nn | a.n (m/s^2, + toward the wall) of the stress pairs, "
      "standard: dummies, material, sum; corrected (B_j = B_i): the same; g.n | u_n, u_t against the rigid "
      "rotation (mm/s) | div u and e_nn (1/s), standard and corrected")
for t in sorted(set(k.split("_")[0] for k in d.keys())):
    X = d[t + "_Coordinates"][:, :2]
    S, V, K, ID = d[t + "_Stress"], d[t + "_Volume"], d[t + "_Kind"], d[t + "_ParticleIDs"]
    U = d[t + "_Velocities"][:, :2]
    i = np.where(ID == lost)[0][0]
    xij = X[i] - X
    r = np.hypot(*xij.T)
    m = (r < 2 * h) & (r > 0)
    G = kf(r[m])[:, None] * xij[m]           # grad_i W_ij
    Vj, dm = V[m], K[m] != 0
    M = -(Vj[:, None, None] * xij[m][:, :, None] * G[:, None, :]).sum(0)
    M = 0.5 * (M + M.T)
    B = np.linalg.inv(M)
    n = X[i] / np.hypot(*X[i])
    tt = np.array([-n[1], n[0]])
    si = sig(S[i])
    pair = [Vj[k] * (si + sig(S[m][k])) / rho for k in range(len(Vj))]
    a_s = [sum(pair[k] @ G[k] for k in range(len(Vj)) if dm[k] == w) @ n for w in (True, False)]
    a_c = [sum(pair[k] @ (B @ G[k]) for k in range(len(Vj)) if dm[k] == w) @ n for w in (True, False)]
    urel = U[i] - omega * np.array([-X[i, 1], X[i, 0]])
    L = (Vj[:, None, None] * (U[m] - U[i])[:, :, None] * G[:, None, :]).sum(0)
    Lb = L @ B
    ev = np.linalg.eigvalsh(M)
    print("%s %.3f %.3f %.3f %.3f %.3f | %+.1f %+.1f %+.1f | %+.1f %+.1f %+.1f | %+.2f | %+.2f %+.2f | %+.2f %+.2f %+.2f %+.2f" % (
        t[1:], (np.hypot(*X[i]) - R) * 1e3, np.linalg.det(M), ev[0], ev[1], n @ M @ n,
        a_s[0], a_s[1], a_s[0] + a_s[1], a_c[0], a_c[1], a_c[0] + a_c[1], g @ n,
        urel @ n * 1e3, urel @ tt * 1e3, np.trace(L), np.trace(Lb), n @ L @ n, n @ Lb @ n))
