#!/usr/bin/env python3
"""A continuum reference for the 2D rotating drum (inputs/drum_2d_EV.yml),
independent of the SPH code: the steady, incompressible, plane-strain mu(I)
viscoplastic flow of the drum's segment, solved by finite elements.

Equations (SI units):

  div sigma + rho g = 0 (+ rho u.grad u with --inertia),  div u = 0,
  sigma = -p I + 2 eta D,  D = sym grad u (trace free),  gdot = sqrt(2 D:D),
  eta = k(mu(I)) max(p, 0) / sqrt(gdot^2 + gdot_min^2)   (clipped to
        [eta_min, eta_max]),
  mu(I) = mu_s + (mu_d - mu_s) gdot / (I0 sqrt(p / (rho_s d^2)) + gdot)
        (I = gdot d / sqrt(p / rho_s)),
  k = 3 mu / sqrt(9 + 12 mu^2) (--yield drucker_prager, the drum scenes'
      default: tau / p = k in simple shear, sqrt(J2) = eta gdot = k p) or
  k = mu (--yield mu_I),
  and with --pr-alpha ALPHA (sphseg's Material:mu_law partial), below the lower
  edge I_N1 of the well-posed window (tools/analysis/inertial_range.py)
  mu = sqrt(ALPHA / ln(A / I)), A = I_N1 exp(ALPHA / mu(I_N1)^2), its I taken at
  sqrt(gdot^2 + gdot_min^2) (as the solver takes it at sqrt(gdot^2 + lambda^2)),

with rho = 1500 (momentum and pressure), rho_s = 2500 (inertial number only),
d = 0.375 mm (the well-mixed mean of 0.25 and 0.5 mm), mu_s 0.382, mu_d
0.682, I0 0.279, R = 35 mm, fill R_f = 0.42 (the flat surface is the chord
y = y_s = (2 R_f - 1) R = -5.6 mm), 5 rpm clockwise, g = 9.81.

Formulation. The frame is turned so that the free surface is the horizontal
chord y = y_s, |x| <= L = sqrt(R^2 - y_s^2), and gravity is tilted by the
dynamic angle theta: g = g (sin theta, -cos theta) (the clockwise wall
carries the bed up at x < 0 and the surface layer flows to +x). The domain
is the disk segment below the chord, triangulated (scipy.spatial.Delaunay)
from a point set graded in depth: h_fine in the flowing layer (depth below
the surface < 9 mm), growing to h_coarse at 18 mm; straight-sided triangles.
Elements: Taylor-Hood P2-P1, assembled vectorised (7-point degree-5
quadrature; eta is evaluated at the quadrature points from the P2 velocity
gradient), solved by SuperLU (scipy.sparse.linalg.splu, COLAMD, two steps of
iterative refinement). Boundary conditions: the wall (polygonal, vertices on
the circle) u = Omega x r (no slip, Omega = -5 rpm: clockwise; the two
corners take the wall's velocity); the surface: u_y = 0 (a flat streamline)
and zero shear traction (natural). Every normal velocity is then prescribed,
so p is fixed up to a constant; the gauge is that the surface's consistent
normal reaction (the residual of the momentum equation at the surface's u_y
dofs, = int sigma_yy phi_i dx) sums to zero over the chord.

The pressure in eta. By default (--pressure lithostatic) eta uses
p = rho g cos(theta) (y_s - y), the pressure of a flat-surfaced bed; the FE
pressure (gauged as above) is reported against it (p-dev, the bed below
10 mm depth: it agrees to round-off, the bed turning rigidly). --pressure
coupled puts the FE pressure itself in eta: that iteration (Picard in p) did
not converge on the drum (it oscillates; the Bagnold layer, where p is
lithostatic, converges either way), so the baseline is the lithostatic
closure: this is an assumption of the reference (it differs from the SPH,
whose p is its own, mainly near the corners of the surface). --p-factor CSV
multiplies that lithostatic p by a table of the depth (depth_m, factor;
linear between rows, 1 outside), to give the FE a run's own pressure under
its layer (tools/analysis/drum_stress_map.py factor; docs/granular.md "The
bed's stress under the layer"); it applies to the lithostatic closure only.

The nonlinearity. Newton in the velocity (the exact tangent of eta's
dependence on gdot: int c (D(v):D)(D:D(du)), c = (4 / gdot) d eta/d gdot),
with a backtracking line search on the residual, to a relative velocity
change < 1e-6 (--tol); from a Newtonian start it is continued in gdot_min
(1, 0.3, 0.1, ... 1/s down to the target), and each further angle starts
from the previous angle's solution. --method picard (eta of the last
iterate, under-relaxed in log eta) converges only slowly (hundreds of
iterations on the Bagnold layer: the flow is nearly plastic).

The angle. The flat-surface problem has a solution for every theta; the
physical theta* is the one for which the surface's (spurious) normal reaction
exerts no net torque about the drum axis: M = int_chord x sigma_yy dx = 0
(independent of the gauge, the chord being symmetric; computed from the
consistent reactions, M = sum x_i R_i, and checked against the pointwise
sigma_yy = -p + 2 eta du_y/dy integrated by Gauss points). Equivalently the
wall's friction torque T_wall balances gravity's torque T_g on the segment:
T_wall + T_g + M = 0 holds discretely (checked). theta* is found by brentq
between the grid angles that bracket the sign change of M.

Outputs at each theta: the surface speed (largest |u| on the mid-chord x = 0),
the flowing layer's depth delta (depth at x = 0 where u_x changes sign), the
fluxes through x = 0 above (q_layer) and below (q_bed) that point (equal by
mass conservation) and the bed's rigid-rotation flux |Omega| (R^2 - y0^2)/2
(equal if the bed turns rigidly; |Omega| L^2 / 2 is that of a bed rigid up to
the surface), the torques, the pressure's deviation from the lithostatic
rho g cos(theta) (y_s - y) in the bed, the surface's normal traction read as
the height a free surface would move by, sigma_yy / (rho g cos theta), less
its mean, max and rms over the chord's middle 80 % (dh-max, dh-rms: small
against the layer's depth where the flat surface is a fair approximation),
and the nonlinear iterations.

What sets the speed. Gravity is a potential force, and the flat-surface
problem prescribes the normal velocity on the whole boundary, so gravity
moves the velocity only through the pressure in eta (cos theta): the
surface speed hardly depends on theta. It is set by the wall's kinematics
(the bed feeds the layer the flux of its rotation) and by how mu(I), with
eta ~ k p / gdot, localises the shear under the surface: the rate
dependence of mu(I) (through I ~ gdot d / sqrt(p / rho_s)) sets the layer's
depth against d. The torque balance sets theta*.

  /usr/bin/python3 -m tools.analysis.drum_mui_ref                 # meshes 1 and 2 x 2 gdot_min (about 15 min on 2 cores)
  /usr/bin/python3 -m tools.analysis.drum_mui_ref --rpm 10 --angles 21.5 22 22.5 23 --gdot-min 1e-3
  /usr/bin/python3 -m tools.analysis.drum_mui_ref --fill 0.591 --d 0.0004725 --angles 20.5 21 21.5 22   # the EN drum
  /usr/bin/python3 -m tools.analysis.drum_mui_ref --theta 21.3 --meshes 1 --gdot-min 1e-3 --profile p.csv
  /usr/bin/python3 -m tools.analysis.drum_mui_ref --yield mu_I --angles 23 24 25 26 27
  /usr/bin/python3 -m tools.analysis.drum_mui_ref --radius 0.07 --rpm 1.25 --fine-depth 0.014 \
      --angles 19.6 20.0 20.4 20.8 --meshes 1 --gdot-min 1e-3    # twice the radius at the scene's flux

Assumptions: steady flow (the SPH's t = 3-5 s), a flat surface (the SPH's
surface is S-shaped near the corners, where material climbs the wall), a
continuum without wall slip, Stokes flow unless --inertia (Picard on the
convective term u_old . grad u, in the fixed lab frame: the flow is steady
there), constant density (no dilatancy), well-mixed d (no segregation).
"""
import argparse
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.optimize import brentq
from scipy.spatial import Delaunay

from tools.analysis.inertial_range import kmu, mu_partial, partial_regularisation  # noqa: E402
from tools.studies import chute_study  # noqa: E402

# the drum of inputs/drum_2d_EV.yml and the Table 1 material
R, FILL, RPM, G = 0.035, 0.42, 5.0, 9.81
RHO, RHO_S, D_GRAIN = 1500.0, 2500.0, 0.375e-3
MU_S, MU_D, I0 = 0.382, 0.682, 0.279
OMEGA = -RPM * 2 * np.pi / 60  # clockwise
YS = (2 * FILL - 1) * R  # the surface chord's height above the centre (-5.6 mm)

# Dunavant degree-5 rule on the reference triangle (barycentric, weights sum 1)
_a1, _b1, _a2, _b2 = 0.059715871789770, 0.470142064105115, 0.797426985353087, 0.101286507323456
QL = np.array([[1 / 3, 1 / 3, 1 / 3], [_a1, _b1, _b1], [_b1, _a1, _b1], [_b1, _b1, _a1],
               [_a2, _b2, _b2], [_b2, _a2, _b2], [_b2, _b2, _a2]])
QW = np.array([0.225] + [0.132394152788506] * 3 + [0.125939180544827] * 3)


def k_of_mu(mu, yld):
    """sqrt(J2) / p for a friction coefficient mu: drucker_prager k_mu = 3 mu / sqrt(9 + 12 mu^2)
    (inertial_range.kmu), mu_I mu."""
    return kmu(mu) if yld == "drucker_prager" else mu


# --pr-alpha: Barker & Gray's (2017) partial regularisation, (alpha, A, I_N1) of
# inertial_range.partial_regularisation (Material:mu_law partial); None: off
PARTIAL = None


def set_partial(alpha):
    """Below I_N1, mu = sqrt(alpha / ln(A / I)) (alpha None: the unregularised law)."""
    global PARTIAL
    if alpha is None:
        PARTIAL = None
        return
    IN1, A, _ = partial_regularisation(MU_S, MU_D, I0, alpha)
    PARTIAL = (alpha, A, IN1)


def mu_of(gdot, p, d=D_GRAIN, gdot_min=0.0):
    """mu(I) = mu_s + (mu_d - mu_s) gdot / (I0 sqrt(p / (rho_s d^2)) + gdot); mu_d at p <= 0.
    With PARTIAL, below I_N1 sqrt(alpha / ln(A / I)) at the regularised rate's I,
    I = sqrt(gdot^2 + gdot_min^2) d / sqrt(p / rho_s) (the viscosity's gdot_min: mu stays
    positive in the rigid bed, where gdot -> 0)."""
    a = I0 * np.sqrt(np.maximum(p, 0.0) / (RHO_S * d * d))
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.where(a + gdot > 0, gdot / (a + gdot), 1.0)
    mu = MU_S + (MU_D - MU_S) * f
    if PARTIAL is None:
        return mu
    alpha, A, IN1 = PARTIAL
    with np.errstate(invalid="ignore", divide="ignore"):
        I = np.where(a > 0, I0 * np.sqrt(gdot * gdot + gdot_min * gdot_min) / a, np.inf)
    return mu_partial(I, IN1, A, alpha, mu)


# ---------------------------------------------------------------- meshes
def segment_points(h_fine, h_coarse, R=R, ys=YS, d1=0.009, d2=0.018):
    """Points of the disk segment {|r| <= R, y <= ys} (or the full disk, ys >= R),
    symmetric about x = 0: rows graded in depth (h_fine above depth d1, h_coarse
    below d2, linear between), offset every other row, and the boundary."""
    full = ys >= R
    top = R if full else ys

    def h(y):
        dep = top - y
        return np.interp(dep, [d1, d2], [h_fine, h_coarse]) if not full else h_fine + 0 * y

    pts = []
    # the arc, from the bottom (angle -pi/2) to the right corner, then mirrored
    a_end = np.pi / 2 if full else np.arcsin(ys / R)
    ang = [-np.pi / 2]
    while ang[-1] < a_end:
        ang.append(ang[-1] + h(R * np.sin(ang[-1])) / R)
    n = max(len(ang) - 1, 2)
    ang = np.array(ang[:n + 1])
    ang = -np.pi / 2 + (ang - ang[0]) * (a_end + np.pi / 2) / (ang[-1] - ang[0])
    if full:
        ang = ang[:-1]  # the top point is the mirror's too
    right = np.c_[R * np.cos(ang), R * np.sin(ang)]
    left = right[1:] * [-1, 1]
    if full:
        left = np.vstack([left, [[0.0, R]]])
    pts += [right, left]
    # the chord
    if not full:
        L = np.sqrt(R * R - ys * ys)
        m = int(np.ceil(2 * L / h_fine))
        xc = np.linspace(-L, L, m + 1)[1:-1]
        pts.append(np.c_[xc, np.full_like(xc, ys)])
    # interior rows
    y, j = top, 0
    while True:
        hy = h(y)
        y = y - hy * np.sqrt(3) / 2
        j += 1
        if y < -R + 0.4 * hy:
            break
        hy = h(y)
        xmax = np.sqrt(max(R * R - y * y, 0.0))
        off = 0.5 * hy * (j % 2)
        k = np.arange(0, int(xmax / hy) + 2)
        xr = off + k * hy
        xr = np.unique(np.r_[-xr, xr])
        keep = R - np.hypot(xr, y) > 0.55 * hy
        pts.append(np.c_[xr[keep], np.full(keep.sum(), y)])
    P = np.vstack(pts)
    P = P[np.unique(np.round(P / 1e-9).astype(np.int64), axis=0, return_index=True)[1]]
    return P


def triangulate(P):
    """Delaunay triangles (counter-clockwise) of a point set, zero-area ones dropped."""
    tri = Delaunay(P).simplices
    a = _area2(P, tri)
    tri = tri[np.abs(a) > 1e-12 * np.abs(a).max()]
    a = _area2(P, tri)
    tri[a < 0] = tri[a < 0][:, [0, 2, 1]]
    return tri


def _area2(P, t):
    p0, p1, p2 = P[t[:, 0]], P[t[:, 1]], P[t[:, 2]]
    return (p1[:, 0] - p0[:, 0]) * (p2[:, 1] - p0[:, 1]) - (p1[:, 1] - p0[:, 1]) * (p2[:, 0] - p0[:, 0])


def rect_mesh(Lx, Ly, nx, ny, x0=0.0, y0=0.0):
    """Structured triangles of [x0, x0 + Lx] x [y0, y0 + Ly], alternating diagonals."""
    xs, ys = np.linspace(x0, x0 + Lx, nx + 1), np.linspace(y0, y0 + Ly, ny + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    P = np.c_[X.ravel(), Y.ravel()]
    idx = lambda i, j: i * (ny + 1) + j  # noqa: E731
    T = []
    for i in range(nx):
        for j in range(ny):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            T += [[a, b, c], [a, c, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, c, d]]
    return P, np.array(T)


# ---------------------------------------------------------------- P2-P1 space
class Space:
    """Taylor-Hood P2-P1 on triangles (pts, tris). vmap (optional, on the vertices)
    identifies periodic vertices; edges are identified through their vertices."""

    def __init__(self, pts, tris, vmap=None):
        self.pts, self.tris = pts, tris
        nv = len(pts)
        vmap = np.arange(nv) if vmap is None else vmap
        E = len(tris)
        loc = [(0, 1), (1, 2), (2, 0)]
        ed = np.vstack([np.sort(tris[:, list(e)], axis=1) for e in loc])  # (3E, 2) geometric edges
        edges, inv, cnt = np.unique(ed, axis=0, return_inverse=True, return_counts=True)
        inv = inv.ravel()
        self.edges = edges
        self.bedges = edges[cnt == 1]  # boundary edges (geometric)
        self.X = np.vstack([pts, 0.5 * (pts[edges[:, 0]] + pts[edges[:, 1]])])  # node coordinates
        self.enodes_geo = np.c_[tris, nv + inv.reshape(3, E).T]  # (E, 6): v0 v1 v2 m01 m12 m20
        # dof identification (periodic): vertices through vmap, midpoints through their mapped edge
        med = np.sort(vmap[edges], axis=1)
        _, einv = np.unique(med, axis=0, return_inverse=True)
        nodemap = np.r_[vmap, nv + einv.ravel()]
        # compress to 0..N-1
        un, self.nodemap = np.unique(nodemap, return_inverse=True)
        self.N = len(un)
        self.enodes = self.nodemap[self.enodes_geo]
        vun, self.vdof = np.unique(vmap, return_inverse=True)
        self.NP = len(vun)
        self.pnodes = self.vdof[tris]
        self.ndof = 2 * self.N + self.NP
        # geometry
        p0, p1, p2 = pts[tris[:, 0]], pts[tris[:, 1]], pts[tris[:, 2]]
        self.area = 0.5 * _area2(pts, tris)
        # grad lambda_i = rot(edge opposite) / (2A)
        gl = np.empty((E, 3, 2))
        for i, (a, b) in enumerate([(p1, p2), (p2, p0), (p0, p1)]):
            gl[:, i, 0] = (a[:, 1] - b[:, 1])
            gl[:, i, 1] = (b[:, 0] - a[:, 0])
        self.gl = gl / (2 * self.area)[:, None, None]
        self.W = self.area[:, None] * QW[None, :]  # (E, Q)
        self.phi = p2_phi(QL)  # (Q, 6)
        self.G = p2_grad(QL, self.gl)  # (E, Q, 6, 2)
        self.xq = np.einsum("qi,eid->eqd", QL, np.stack([p0, p1, p2], axis=1))  # (E, Q, 2)
        self._build_structure()

    def _build_structure(self):
        N = self.N
        vd = np.c_[self.enodes, N + self.enodes]  # (E, 12) velocity dofs
        rows = np.repeat(vd, 12, axis=1).ravel()
        cols = np.tile(vd, (1, 12)).ravel()
        lin = rows.astype(np.int64) * (2 * N) + cols
        self.A_keys, self.A_inv = np.unique(lin, return_inverse=True)
        self.A_rows, self.A_cols = self.A_keys // (2 * N), self.A_keys % (2 * N)
        self.vd = vd
        # B[c, vdof] = int psi_c d_k phi_a
        Bx = np.einsum("eq,qc,eqa->eca", self.W, QL, self.G[..., 0])
        By = np.einsum("eq,qc,eqa->eca", self.W, QL, self.G[..., 1])
        Bv = np.concatenate([Bx, By], axis=2)  # (E, 3, 12)
        r = np.repeat(self.pnodes, 12, axis=1).ravel()
        c = np.tile(vd, (1, 3)).ravel()
        self.B = sp.csr_matrix((Bv.ravel(), (r, c)), shape=(self.NP, 2 * N))

    def stiffness(self, eta_q, rho=0.0, uq=None):
        """The viscous block int 2 eta D(u):D(v) (+ rho (uq . grad u) . v), (2N x 2N) CSR."""
        Wt = self.W * eta_q
        Gx, Gy = self.G[..., 0], self.G[..., 1]
        gg = np.einsum("eq,eqad,eqbd->eab", Wt, self.G, self.G)
        Kxx = gg + np.einsum("eq,eqa,eqb->eab", Wt, Gx, Gx)
        Kyy = gg + np.einsum("eq,eqa,eqb->eab", Wt, Gy, Gy)
        Kxy = np.einsum("eq,eqa,eqb->eab", Wt, Gy, Gx)  # row a (x), col b (y): eta dy phi_a dx phi_b
        if uq is not None:
            conv = np.einsum("eq,qa,eqd,eqbd->eab", self.W * rho, self.phi, uq, self.G)
            Kxx = Kxx + conv
            Kyy = Kyy + conv
            Kyx = Kxy.transpose(0, 2, 1)
        else:
            Kyx = Kxy.transpose(0, 2, 1)
        Ke = np.concatenate([np.concatenate([Kxx, Kxy], 2), np.concatenate([Kyx, Kyy], 2)], 1)  # (E, 12, 12)
        data = np.bincount(self.A_inv, weights=Ke.ravel(), minlength=len(self.A_keys))
        return sp.csr_matrix((data, (self.A_rows, self.A_cols)), shape=(2 * self.N, 2 * self.N))

    def newton_term(self, c, gu):
        """int c (D(v):D)(D:D(du)), D the strain rate of gu (E, Q, 2, 2)."""
        Dxx, Dyy = gu[..., 0, 0], gu[..., 1, 1]
        Dxy = 0.5 * (gu[..., 0, 1] + gu[..., 1, 0])
        Gx, Gy = self.G[..., 0], self.G[..., 1]
        H = np.concatenate([Dxx[..., None] * Gx + Dxy[..., None] * Gy, Dxy[..., None] * Gx + Dyy[..., None] * Gy], -1)
        Ke = np.einsum("eq,eqi,eqj->eij", self.W * c, H, H)
        data = np.bincount(self.A_inv, weights=Ke.ravel(), minlength=len(self.A_keys))
        return sp.csr_matrix((data, (self.A_rows, self.A_cols)), shape=(2 * self.N, 2 * self.N))

    def load(self, fq):
        """int f . v for f at the quadrature points (E, Q, 2)."""
        Fe = np.einsum("eq,qa,eqk->eka", self.W, self.phi, fq).reshape(len(self.tris), 12)
        return np.bincount(self.vd.ravel(), weights=Fe.ravel(), minlength=2 * self.N)

    def at_quad(self, U, P):
        """Velocity (E,Q,2), its gradient (E,Q,2,2) [i, j] = d u_i / d x_j, and p (E,Q)."""
        ux, uy = U[: self.N][self.enodes], U[self.N:][self.enodes]
        u = np.stack([np.einsum("ea,qa->eq", ux, self.phi),
                      np.einsum("ea,qa->eq", uy, self.phi)], axis=-1)
        gu = np.stack([np.einsum("ea,eqad->eqd", ux, self.G), np.einsum("ea,eqad->eqd", uy, self.G)], axis=2)
        p = np.einsum("ec,qc->eq", P[self.pnodes], QL)
        return u, gu, p

    def eval_points(self, U, P, elem, lam):
        """u (n,2), grad u (n,2,2), p (n) at points given by element and barycentrics (n, 3)."""
        phi = p2_phi(lam)  # (n, 6)
        gl = self.gl[elem]
        G = p2_grad_pts(lam, gl)  # (n, 6, 2)
        en = self.enodes[elem]
        ux, uy = U[: self.N][en], U[self.N:][en]
        u = np.c_[(ux * phi).sum(1), (uy * phi).sum(1)]
        gu = np.stack([np.einsum("na,nad->nd", ux, G), np.einsum("na,nad->nd", uy, G)], axis=1)
        p = (P[self.pnodes[elem]] * lam).sum(1)
        return u, gu, p

    def locate(self, xy):
        """Element and barycentrics of each point (brute force, chunked)."""
        P, t = self.pts, self.tris
        p0 = P[t[:, 0]]
        # barycentric: lam_i = 1/3 + ... use gl: lam_i(x) = lam_i(p0) + gl_i . (x - p0)
        el, lam = np.empty(len(xy), int), np.empty((len(xy), 3))
        for i0 in range(0, len(xy), 64):
            x = xy[i0:i0 + 64]
            dx = x[:, None, :] - p0[None, :, :]  # (n, E, 2)
            L = np.einsum("ned,eid->nei", dx, self.gl)
            L[..., 0] += 1.0
            mn = L.min(axis=2)
            k = mn.argmax(axis=1)
            el[i0:i0 + 64] = k
            lam[i0:i0 + 64] = L[np.arange(len(x)), k]
        return el, lam


def p2_phi(lam):
    l0, l1, l2 = lam[:, 0], lam[:, 1], lam[:, 2]
    return np.c_[l0 * (2 * l0 - 1), l1 * (2 * l1 - 1), l2 * (2 * l2 - 1), 4 * l0 * l1, 4 * l1 * l2, 4 * l2 * l0]


def p2_grad(lam, gl):
    """(E, Q, 6, 2) gradients at the barycentric points lam (Q, 3), gl (E, 3, 2)."""
    Q = len(lam)
    E = len(gl)
    G = np.empty((E, Q, 6, 2))
    for i in range(3):
        G[:, :, i, :] = (4 * lam[None, :, i, None] - 1) * gl[:, None, i, :]
    for k, (i, j) in enumerate([(0, 1), (1, 2), (2, 0)]):
        G[:, :, 3 + k, :] = 4 * (lam[None, :, j, None] * gl[:, None, i, :] + lam[None, :, i, None] * gl[:, None, j, :])
    return G


def p2_grad_pts(lam, gl):
    """(n, 6, 2) gradients, one point per element row."""
    n = len(lam)
    G = np.empty((n, 6, 2))
    for i in range(3):
        G[:, i, :] = (4 * lam[:, i, None] - 1) * gl[:, i, :]
    for k, (i, j) in enumerate([(0, 1), (1, 2), (2, 0)]):
        G[:, 3 + k, :] = 4 * (lam[:, j, None] * gl[:, i, :] + lam[:, i, None] * gl[:, j, :])
    return G


# ---------------------------------------------------------------- the linear Stokes solve
class Problem:
    """A Stokes problem on a Space: Dirichlet velocity dofs (index, value), a body
    force, and a pressure gauge: either 'mean' (int p = 0) or a set of surface
    u_y dofs whose consistent reactions must sum to zero."""

    def __init__(self, S, ddofs, dvals, fq, gauge_dofs=None):
        self.S = S
        self.ddofs, self.dvals = np.asarray(ddofs), np.asarray(dvals, float)
        self.F = np.r_[S.load(fq), np.zeros(S.NP)]
        self.gauge_dofs = gauge_dofs
        nd = S.ndof
        fixed = np.zeros(nd, bool)
        fixed[self.ddofs] = True
        fixed[2 * S.N] = True  # pin the first pressure dof (gauge applied after the solve)
        self.free = np.flatnonzero(~fixed)
        self.fixed = np.flatnonzero(fixed)
        self.xfix = np.zeros(nd)
        self.xfix[self.ddofs] = self.dvals
        self.Bt = S.B.T.tocsr()
        # int div v_i for each velocity dof: how a constant added to p changes the reactions
        self.divv = np.asarray(S.B.sum(axis=0)).ravel()
        self.pmass = np.bincount(S.pnodes.ravel(), weights=np.repeat(S.area / 3, 3), minlength=S.NP)

    def matrix(self, A):
        return sp.bmat([[A, -self.Bt], [-self.S.B, None]], format="csr")

    def solve(self, A):
        """The solution with the Dirichlet values, gauged; and the full matrix."""
        K = self.matrix(A)
        rhs = self.F - K @ self.xfix
        x = self.xfix.copy()
        x[self.free] = self._solve(K, rhs[self.free])
        return self.gauge_shift(x, K), K

    def _solve(self, K, b, refine=2):
        """SuperLU (COLAMD ordering) and iterative refinement (the viscosity spans many decades)."""
        Kff = K[self.free][:, self.free].tocsc()
        lu = spla.splu(Kff, permc_spec="COLAMD")
        x = lu.solve(b)
        for _ in range(refine):
            x += lu.solve(b - Kff @ x)
        return x

    def solve_delta(self, J, r):
        """The Newton step: J dx = -r at the free dofs, dx = 0 at the fixed ones."""
        dx = np.zeros(self.S.ndof)
        dx[self.free] = self._solve(J, -r[self.free])
        return dx

    def embed(self, Av):
        """A velocity-block matrix as a full (ndof x ndof) one."""
        n = self.S.NP
        return sp.bmat([[Av, None], [None, sp.csr_matrix((n, n))]], format="csr")

    def gauge_shift(self, x, K):
        """Add the constant to p that makes the gauge hold (K: the matrix whose
        reactions define it; the shift is exact for any K, the pressure entering
        the reactions linearly through -B^T)."""
        x = x.copy()
        N2 = 2 * self.S.N
        if self.gauge_dofs is None:
            x[N2:] -= (self.pmass @ x[N2:]) / self.pmass.sum()
        else:
            r = K @ x - self.F
            g = self.gauge_dofs
            x[N2:] += r[g].sum() / self.divv[g].sum()
        return x

    def reactions(self, K, x):
        return K @ x - self.F


# ---------------------------------------------------------------- mu(I) viscosity
def viscosity(gdot, p, yld, gdot_min, eta_min, eta_max, d=D_GRAIN, tangent=False):
    """eta = k(mu(I)) max(p, 0) / sqrt(gdot^2 + gdot_min^2), clipped to [eta_min, eta_max];
    with tangent, also c = (4 / gdot) d eta / d gdot (0 where clipped), the coefficient
    of the Newton term (D(v):D)(D:D(du))."""
    pp = np.maximum(p, 0.0)
    a = I0 * np.sqrt(pp / (RHO_S * d * d))
    mu = mu_of(gdot, pp, d, gdot_min)
    k = k_of_mu(mu, yld)
    gr = np.sqrt(gdot * gdot + gdot_min * gdot_min)
    eta_raw = k * pp / gr
    eta = np.clip(eta_raw, eta_min, eta_max)
    if not tangent:
        return eta
    kp = 27 / (9 + 12 * mu * mu) ** 1.5 if yld == "drucker_prager" else np.ones_like(mu)
    gs = np.maximum(gdot, 1e-12 * max(gdot_min, 1e-30))
    with np.errstate(invalid="ignore", divide="ignore"):
        mug_over_g = np.where(a + gs > 0, (MU_D - MU_S) * a / ((a + gs) ** 2 * gs), 0.0)
        if PARTIAL is not None:  # d mu / d gdot / gdot = mu / (2 gr^2 ln(A / I)) below I_N1
            alpha, A, IN1 = PARTIAL
            I = np.where(a > 0, I0 * gr / a, np.inf)
            low = I < IN1
            mug_over_g = np.where(low, mu / (2 * gr * gr * np.log(A / np.maximum(I, 1e-300))), mug_over_g)
    c = 4 * (pp * kp * mug_over_g / gr - k * pp / gr ** 3)
    c[(eta_raw <= eta_min) | (eta_raw >= eta_max)] = 0.0
    return eta, c


def shear_rate(gu):
    Dxx, Dyy = gu[..., 0, 0], gu[..., 1, 1]
    Dxy = 0.5 * (gu[..., 0, 1] + gu[..., 1, 0])
    return np.sqrt(2 * (Dxx ** 2 + Dyy ** 2 + 2 * Dxy ** 2))


def solve_mui(prob, yld, gdot_min, eta_min=1e-5, eta_max=1e12, d=D_GRAIN, x0=None, tol=1e-6, maxit=200,
              method="newton", relax=1.0, inertia=False, p_frozen=None, verbose=False):
    """Solve the mu(I) problem. method 'picard': eta(gdot, p) of the last iterate,
    under-relaxed in log eta (relax); 'newton': Newton in the velocity (the tangent of
    eta's gdot dependence, with a backtracking line search on the residual) with the
    pressure's part of eta lagged (Picard), the gauge applied after every solve.
    Convergence: the relative change of the velocity < tol. x0: a starting state
    (else a Newtonian first solve). Returns x, K (the last Picard matrix), iterations,
    converged."""
    S = prob.S
    N2 = 2 * S.N
    if x0 is None:
        x, K = prob.solve(S.stiffness(np.full(S.W.shape, 1.0)))
    else:
        x = x0.copy()
    eta_old = None
    for it in range(1, maxit + 1):
        U, P = x[:N2], x[N2:]
        u, gu, p = S.at_quad(U, P)
        if p_frozen is not None:
            p = p_frozen
        uq = u if inertia else None
        gd = shear_rate(gu)
        if method == "picard":
            eta = viscosity(gd, p, yld, gdot_min, eta_min, eta_max, d)
            if eta_old is not None and relax != 1.0:
                eta = np.exp(relax * np.log(eta) + (1 - relax) * np.log(eta_old))
            eta_old = eta
            xn, K = prob.solve(S.stiffness(eta, RHO, uq))
        else:
            eta, c = viscosity(gd, p, yld, gdot_min, eta_min, eta_max, d, tangent=True)
            Kp = prob.matrix(S.stiffness(eta, RHO, uq))
            r = Kp @ x - prob.F
            J = Kp + prob.embed(S.newton_term(c, gu))
            dx = prob.solve_delta(J, r)
            r0 = np.linalg.norm(r[prob.free])
            lam = 1.0
            for _ in range(12):
                xn = prob.gauge_shift(x + lam * dx, Kp)
                un, gun, pn = S.at_quad(xn[:N2], xn[N2:])
                if p_frozen is not None:
                    pn = p_frozen
                en = viscosity(shear_rate(gun), pn, yld, gdot_min, eta_min, eta_max, d)
                Kn = prob.matrix(S.stiffness(en, RHO, un if inertia else None))
                r1 = np.linalg.norm((Kn @ xn - prob.F)[prob.free])
                if r1 < r0 or lam < 1e-3:
                    break
                lam *= 0.5
            K = Kn
        ch = np.linalg.norm(xn[:N2] - U) / max(np.linalg.norm(xn[:N2]), 1e-300)
        if verbose:
            print("  %s %3d  du/u %.2e%s" % (method, it, ch, "" if method == "picard" else
                                             "  |r| %.2e -> %.2e  step %.3g" % (r0, r1, lam)))
        x = xn
        if ch < tol:
            return x, K, it, True
    return x, K, maxit, False


# ---------------------------------------------------------------- the drum
class Drum:
    """The drum's segment mesh and its boundary sets."""

    def __init__(self, h_fine, h_coarse, R=R, ys=YS, omega=OMEGA, d1=0.009):
        P = segment_points(h_fine, h_coarse, R, ys, d1, 2 * d1)
        self.omega = omega  # the wall's rate, rad/s about +z (clockwise negative)
        T = triangulate(P)
        self.S = S = Space(P, T)
        self.R, self.ys = R, ys
        self.L = np.sqrt(R * R - ys * ys)
        X = S.X
        be = S.bedges
        chord_edge = (np.abs(P[be[:, 0], 1] - ys) < 1e-12 * R) & (np.abs(P[be[:, 1], 1] - ys) < 1e-12 * R)
        # boundary nodes: the edges' vertices and midpoints (node index of an edge's midpoint)
        edge_id = {tuple(e): i for i, e in enumerate(map(tuple, S.edges))}
        nv = len(P)

        def nodes_of(edges):
            mids = np.array([nv + edge_id[tuple(e)] for e in edges], int)
            return np.unique(np.r_[edges.ravel(), mids])

        wall = nodes_of(be[~chord_edge])
        chord = np.setdiff1d(nodes_of(be[chord_edge]), wall)
        self.wall, self.chord = wall, chord
        self.chord_edges = be[chord_edge]
        Xw = X[wall]
        uw = omega * np.c_[-Xw[:, 1], Xw[:, 0]]
        self.ddofs = np.r_[wall, S.N + wall, S.N + chord]
        self.dvals = np.r_[uw[:, 0], uw[:, 1], np.zeros(len(chord))]
        self.gauge = S.N + chord
        self.nodes = len(X)

    def problem(self, theta_deg):
        th = np.radians(theta_deg)
        g = G * np.array([np.sin(th), -np.cos(th)])
        fq = np.broadcast_to(RHO * g, self.S.W.shape + (2,))
        return Problem(self.S, self.ddofs, self.dvals, fq, self.gauge), g


P_FACTOR = None  # --p-factor: (depth m, factor) arrays, or None


def set_p_factor(path):
    """--p-factor CSV: the table (depth_m, factor) by which the lithostatic p in eta is multiplied,
    linear between its rows and 1 outside them (None: off)."""
    global P_FACTOR
    if path is None:
        P_FACTOR = None
        return
    t = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    P_FACTOR = (t[:, 0], t[:, 1])


def eta_pressure(depth, theta_deg):
    """The p in eta at these depths below the flat surface: rho g cos(theta) depth, times the
    --p-factor table's factor where one is set (an attribution study: the SPH's own pressure, whose
    elastic bed carries a stress of its history, in the memoryless FE)."""
    p = RHO * G * np.cos(np.radians(theta_deg)) * depth
    if P_FACTOR is None:
        return p
    return p * np.interp(depth, P_FACTOR[0], P_FACTOR[1], left=1.0, right=1.0)


def drum_solve(drum, theta_deg, yld="drucker_prager", gdot_min=1e-3, eta_max=1e12, d=D_GRAIN, x0=None,
               tol=1e-6, inertia=False, method="newton", pressure="lithostatic", nprof=400, verbose=False):
    """Solve the drum at theta (degrees); a dict of the outputs (see the docstring).
    pressure: the p in eta, 'lithostatic' rho g cos(theta) (y_s - y) or 'coupled' (the
    FE pressure). Without x0, a continuation in gdot_min (1, 0.3, ... down to gdot_min)."""
    S = drum.S
    prob, g = drum.problem(theta_deg)
    pf = eta_pressure(drum.ys - S.xq[..., 1], theta_deg) if pressure == "lithostatic" else None
    its = 0
    ok = False
    if x0 is not None:
        x, K, its, ok = solve_mui(prob, yld, gdot_min, eta_max=eta_max, d=d, x0=x0, tol=tol, method=method,
                                  inertia=inertia, p_frozen=pf, maxit=25, verbose=verbose)
    if not ok:
        x = None
        levels = [gm for gm in (1.0, 0.3, 0.1, 0.03, 0.01, 3e-3, 1e-3, 3e-4, 1e-4) if gm > gdot_min * 1.01] + [gdot_min]
        for gm in levels:
            x, K, it, ok = solve_mui(prob, yld, gm, eta_max=eta_max, d=d, x0=x, tol=tol if gm == gdot_min else 1e-4,
                                     method=method, inertia=inertia, p_frozen=pf, maxit=40, verbose=verbose)
            its += it
    U, P = x[: 2 * S.N], x[2 * S.N:]
    r = prob.reactions(K, x)
    X = S.X
    # torques about the axis (counter-clockwise positive) on the material
    w = drum.wall
    T_wall = np.sum(X[w, 0] * r[S.N + w] - X[w, 1] * r[w])
    c = drum.chord
    M = np.sum(X[c, 0] * r[S.N + c])
    # gravity's torque: int rho (x g_y - y g_x)
    T_g = np.sum(S.W * RHO * (S.xq[..., 0] * g[1] - S.xq[..., 1] * g[0]))
    # the pointwise surface traction sigma_yy = -p + 2 eta du_y/dy, 3 Gauss points per chord edge
    M_pt, N_pt, syy_max, syy_rms = _chord_moment(drum, U, P, yld, gdot_min, eta_max, d, pressure, theta_deg)
    # the surface's normal traction read as the height a free surface would move by, m
    rgc = RHO * G * np.cos(np.radians(theta_deg))
    # the mid-chord profile
    ys = drum.ys
    yy = np.linspace(ys, -drum.R, nprof)
    yy[-1] = -drum.R * (1 - 1e-9)
    xy = np.c_[np.full(nprof, 0.0), yy]
    el, lam = S.locate(xy)
    u, gu, p = S.eval_points(U, P, el, lam)
    spd = np.hypot(u[:, 0], u[:, 1])
    ux = u[:, 0]
    # the flowing layer: from the surface down to the first sign change of u_x
    s0 = np.sign(ux[0])
    k = np.flatnonzero(np.sign(ux) != s0)
    if len(k):
        k = k[0]
        y0 = yy[k - 1] + (yy[k] - yy[k - 1]) * ux[k - 1] / (ux[k - 1] - ux[k])
    else:
        y0 = np.nan
    q_layer = -np.trapz(np.where(yy >= y0, ux, 0), yy)
    q_bed = np.trapz(np.where(yy < y0, ux, 0), yy)
    q_rigid = abs(drum.omega) * (drum.R ** 2 - y0 ** 2) / 2
    # the bed's pressure against the lithostatic rho g cos(theta) (ys - y), 10 mm below the surface and deeper
    deep = (ys - yy > 0.010) & (yy > -drum.R + 0.003)
    plith = RHO * G * np.cos(np.radians(theta_deg)) * (ys - yy)
    pdev = np.max(np.abs(p[deep] - plith[deep])) / np.max(plith[deep])
    return dict(theta=theta_deg, speed=spd.max(), us=ux[0], delta=ys - y0, q_layer=q_layer, q_bed=q_bed,
                q_rigid=q_rigid, q_rigid_surface=abs(drum.omega) * drum.L ** 2 / 2, T_wall=T_wall, T_g=T_g, M=M,
                M_pt=M_pt, N_pt=N_pt, dh_max=syy_max / rgc, dh_rms=syy_rms / rgc, resid=T_wall + T_g + M, its=its, ok=ok, x=x, pdev=pdev,
                depth=ys - yy, ux=ux, p=p, nodes=drum.nodes, elems=len(S.tris))


def _chord_moment(drum, U, P, yld, gdot_min, eta_max, d, pressure, theta_deg):
    S = drum.S
    ce = drum.chord_edges
    # the element of each chord edge
    tri = S.tris
    key = {}
    for e, t in enumerate(tri):
        for a, b in ((0, 1), (1, 2), (2, 0)):
            key[(min(t[a], t[b]), max(t[a], t[b]))] = (e, a, b)
    gp, gw = np.polynomial.legendre.leggauss(3)
    s = 0.5 * (gp + 1)
    els, lams, xs, ws = [], [], [], []
    for v0, v1 in ce:
        e, a, b = key[(min(v0, v1), max(v0, v1))]
        va, vb = tri[e, a], tri[e, b]
        ln = np.linalg.norm(S.pts[vb] - S.pts[va])
        for si, wi in zip(s, gw):
            lam = np.zeros(3)
            lam[a], lam[b] = 1 - si, si
            els.append(e)
            lams.append(lam)
            xs.append((1 - si) * S.pts[va, 0] + si * S.pts[vb, 0])
            ws.append(0.5 * wi * ln)
    els, lams, xs, ws = np.array(els), np.array(lams), np.array(xs), np.array(ws)
    u, gu, p = S.eval_points(U, P, els, lams)
    # on the chord the lithostatic pressure is 0
    eta = viscosity(shear_rate(gu), p if pressure == "coupled" else 0 * p, yld, gdot_min, 1e-5, eta_max, d)
    syy = -p + 2 * eta * gu[:, 1, 1]
    # max and rms over the chord's middle 80 % (the corners, where the wall's speed meets the
    # surface's, carry a singular reaction), less the chord's mean (the gauge)
    inner = np.abs(xs) < 0.8 * drum.L
    sd = syy[inner] - np.sum(ws[inner] * syy[inner]) / np.sum(ws[inner])
    return (np.sum(ws * xs * syy), np.sum(ws * syy), np.max(np.abs(sd)),
            np.sqrt(np.sum(ws[inner] * sd ** 2) / np.sum(ws[inner])))


# ---------------------------------------------------------------- verification problems
def rigid_disk(h=0.004, R=R):
    """A full disk, constant viscosity, no gravity, wall u = Omega x r: the
    solution is the rigid rotation and p = const. Returns (max |u - Omega x r| /
    (|Omega| R), max |p - mean p|)."""
    P = segment_points(h, h, R, ys=2 * R)
    T = triangulate(P)
    S = Space(P, T)
    be = S.bedges
    edge_id = {tuple(e): i for i, e in enumerate(map(tuple, S.edges))}
    wall = np.unique(np.r_[be.ravel(), [len(P) + edge_id[tuple(e)] for e in be]])
    uw = OMEGA * np.c_[-S.X[wall, 1], S.X[wall, 0]]
    prob = Problem(S, np.r_[wall, S.N + wall], np.r_[uw[:, 0], uw[:, 1]], np.zeros(S.W.shape + (2,)))
    x, _ = prob.solve(S.stiffness(np.full(S.W.shape, 3.7)))
    U = x[: 2 * S.N]
    ue = OMEGA * np.c_[-S.X[:, 1], S.X[:, 0]]
    err = np.max(np.abs(np.r_[U[: S.N] - ue[:, 0], U[S.N:] - ue[:, 1]])) / (abs(OMEGA) * R)
    p = x[2 * S.N:]
    return err, np.max(np.abs(p - p.mean()))


def _rect_dirichlet(S):
    X = S.X
    lo, hi = X.min(0), X.max(0)
    tol = 1e-12 * (hi - lo).max()
    b = np.flatnonzero((np.abs(X[:, 0] - lo[0]) < tol) | (np.abs(X[:, 0] - hi[0]) < tol)
                       | (np.abs(X[:, 1] - lo[1]) < tol) | (np.abs(X[:, 1] - hi[1]) < tol))
    return b


def poiseuille(n=4):
    """A channel [0, 2] x [0, 1], eta = 1, pressure gradient -dp/dx = Gp = 2 with the
    exact parabola u_x = y (1 - y) imposed on the boundary: P2-P1 holds it exactly.
    Returns (max |u - u_exact|, max |p - p_exact|) at the nodes."""
    P, T = rect_mesh(2.0, 1.0, 2 * n, n)
    S = Space(P, T)
    b = _rect_dirichlet(S)
    X = S.X
    ue = X[:, 1] * (1 - X[:, 1])
    prob = Problem(S, np.r_[b, S.N + b], np.r_[ue[b], 0 * b], np.zeros(S.W.shape + (2,)))
    x, _ = prob.solve(S.stiffness(np.full(S.W.shape, 1.0)))
    pe = -2 * (P[:, 0] - 1.0)  # mean zero on [0, 2]
    return (np.max(np.abs(x[: S.N] - ue)) + np.max(np.abs(x[S.N: 2 * S.N])),
            np.max(np.abs(x[2 * S.N:] - pe)))


def manufactured(n):
    """Variable viscosity eta = 1 + x on [0, 1]^2, u = (sin pi x cos pi y, -cos pi x sin pi y),
    p = cos pi x cos pi y - mean; f = -div(2 eta D(u)) + grad p. Returns the L2 errors of
    u and p (7-point quadrature)."""
    pi = np.pi
    P, T = rect_mesh(1.0, 1.0, n, n)
    S = Space(P, T)
    xq, yq = S.xq[..., 0], S.xq[..., 1]
    eta = 1 + xq
    fx = -2 * pi * np.cos(pi * yq) * (np.cos(pi * xq) - eta * pi * np.sin(pi * xq)) - pi * np.sin(pi * xq) * np.cos(pi * yq)
    fy = -2 * eta * pi ** 2 * np.cos(pi * xq) * np.sin(pi * yq) - pi * np.cos(pi * xq) * np.sin(pi * yq)
    b = _rect_dirichlet(S)
    X = S.X
    uex = lambda X: np.c_[np.sin(pi * X[:, 0]) * np.cos(pi * X[:, 1]), -np.cos(pi * X[:, 0]) * np.sin(pi * X[:, 1])]  # noqa: E731
    ub = uex(X[b])
    prob = Problem(S, np.r_[b, S.N + b], np.r_[ub[:, 0], ub[:, 1]], np.stack([fx, fy], -1))
    x, _ = prob.solve(S.stiffness(eta))
    u, _, p = S.at_quad(x[: 2 * S.N], x[2 * S.N:])
    ue = np.stack([np.sin(pi * xq) * np.cos(pi * yq), -np.cos(pi * xq) * np.sin(pi * yq)], -1)
    pe = np.cos(pi * xq) * np.cos(pi * yq)  # mean zero on the square
    eu = np.sqrt(np.sum(S.W[..., None] * (u - ue) ** 2))
    ep = np.sqrt(np.sum(S.W * (p - pe) ** 2))
    return eu, ep


def bagnold_exact(y, h, theta_deg, yld="drucker_prager", d=D_GRAIN):
    """The steady mu(I) layer of depth h on a plane inclined at theta (u = 0 at y = 0):
    the chute study's analytic Bagnold profile (tools/studies/chute_study.py bagnold, the
    reference of tests/validate_chute.py; same Table 1 material)."""
    return chute_study.bagnold(y, theta_deg, h, chute_study.READING[yld], d, PARTIAL[0] if PARTIAL else None)


def bagnold(theta_deg=23.0, h=0.005, ny=16, nx=4, yld="drucker_prager", gdot_min=1e-3, tol=1e-8, method="newton",
            verbose=False):
    """The mu(I) layer on the inclined plane by the drum's own machinery: a strip
    [0, h] x [0, h], periodic in x, no slip at y = 0, the surface y = h with u_y = 0,
    zero shear traction and the reaction gauge; gravity g (sin, -cos). Returns the
    max |u_x - u_exact| / u_exact(h) at the nodes, the relative error of the surface
    speed, the max |p - rho g cos (h - y)| / (rho g cos h), Picard iterations."""
    Lx = h * nx / ny
    P, T = rect_mesh(Lx, h, nx, ny)
    tolx = 1e-9 * h
    vmap = np.arange(len(P))
    right = np.flatnonzero(np.abs(P[:, 0] - Lx) < tolx)
    for i in right:
        j = np.flatnonzero((np.abs(P[:, 0]) < tolx) & (np.abs(P[:, 1] - P[i, 1]) < tolx))[0]
        vmap[i] = j
    S = Space(P, T, vmap)
    X = S.X
    assert S.N == len(X) - 2 * ny - 1, "periodic identification (nx >= 3)"
    # the reduced node of each geometric node; the bottom and the top by geometry
    bot = np.unique(S.nodemap[np.flatnonzero(np.abs(X[:, 1]) < tolx)])
    top = np.unique(S.nodemap[np.flatnonzero(np.abs(X[:, 1] - h) < tolx)])
    th = np.radians(theta_deg)
    g = G * np.array([np.sin(th), -np.cos(th)])
    fq = np.broadcast_to(RHO * g, S.W.shape + (2,))
    prob = Problem(S, np.r_[bot, S.N + bot, S.N + top], np.zeros(2 * len(bot) + len(top)), fq, S.N + top)
    x, K, its, ok = solve_mui(prob, yld, gdot_min, tol=tol, method=method, verbose=verbose)
    U, Pp = x[: 2 * S.N], x[2 * S.N:]
    # compare at the geometric nodes on x = 0
    k = np.flatnonzero(np.abs(X[:, 0]) < tolx)
    y = X[k, 1]
    ux = U[S.nodemap[k]]
    ue = bagnold_exact(y, h, theta_deg, yld)
    us = bagnold_exact(h, h, theta_deg, yld)
    err = np.max(np.abs(ux - ue)) / us
    es = abs(ux[np.argmax(y)] - us) / us
    kv = np.flatnonzero(np.abs(P[:, 0]) < tolx)
    pe = RHO * G * np.cos(th) * (h - P[kv, 1])
    ep = np.max(np.abs(Pp[S.vdof[kv]] - pe)) / (RHO * G * np.cos(th) * h)
    return err, es, ep, its, ok


# ---------------------------------------------------------------- the study
MESHES = {1: (0.6e-3, 2.4e-3), 2: (0.42e-3, 1.7e-3), 3: (0.3e-3, 1.2e-3), 4: (0.21e-3, 0.85e-3)}


def study_one(drum, angles, yld, gdot_min, eta_max, d, inertia, root, tol, verbose, profile=None, method="newton",
              pressure="lithostatic"):
    rows = []
    x = None
    t0 = time.time()
    for th in angles:
        o = drum_solve(drum, th, yld, gdot_min, eta_max, d, x0=x, tol=tol, inertia=inertia, method=method,
                       pressure=pressure, verbose=verbose)
        x = o["x"]
        rows.append(o)
        _print_row(o)
    res = dict(rows=rows)
    if root and len(angles) > 1:
        Ms = np.array([o["M"] for o in rows])
        s = np.flatnonzero(np.sign(Ms[:-1]) != np.sign(Ms[1:]))
        if len(s):
            i = s[0]
            cache = {}

            def f(th):
                o = drum_solve(drum, th, yld, gdot_min, eta_max, d, x0=rows[i]["x"], tol=tol, inertia=inertia,
                               method=method, pressure=pressure)
                cache[th] = o
                return o["M"]

            th_star = brentq(f, angles[i], angles[i + 1], xtol=5e-3, rtol=1e-6, maxiter=30)
            o = cache.get(th_star) or drum_solve(drum, th_star, yld, gdot_min, eta_max, d, x0=rows[i]["x"], tol=tol,
                                                 inertia=inertia, method=method, pressure=pressure)
            print("  theta* (M = 0):")
            _print_row(o)
            res["star"] = o
        else:
            print("  M does not change sign over the angles given: no theta*")
    if profile:
        o = res.get("star", rows[-1])
        np.savetxt(profile, np.c_[o["depth"], o["ux"], o["p"]], delimiter=",",
                   header="depth_m,u_x_m_per_s,p_Pa (theta %.4f deg)" % o["theta"], comments="")
        print("  profile at theta %.3f written to %s" % (o["theta"], profile))
    res["wall"] = time.time() - t0
    return res


HEAD = ("  theta   u_surf   delta   q_layer   q_bed    q_rig   T_wall    T_g      M(react) M(point)  "
        "resid    p-dev  dh-max dh-rms  its")


def _print_row(o):
    print("  %6.3f  %6.4f  %6.2f  %8.3e %8.3e %8.3e %8.4f %8.4f %9.2e %9.2e %8.1e %6.3f %6.2f %6.2f %4d%s" % (
        o["theta"], o["speed"], o["delta"] * 1e3, o["q_layer"], o["q_bed"], o["q_rigid"], o["T_wall"], o["T_g"],
        o["M"], o["M_pt"], o["resid"], o["pdev"], o["dh_max"] * 1e3, o["dh_rms"] * 1e3, o["its"],
        "" if o["ok"] else " (not converged)"))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--yield", dest="yld", choices=("drucker_prager", "mu_I"), default="drucker_prager")
    ap.add_argument("--angles", type=float, nargs="+", default=None,
                    help="degrees; default 20.5 21.0 21.3 21.6 22.0 22.5 (drucker_prager), 23..28 (mu_I)")
    ap.add_argument("--theta", type=float, default=None, help="one angle only (no root find)")
    ap.add_argument("--meshes", type=int, nargs="+", default=[1, 2],
                    help="mesh levels: " + ", ".join("%d: h %.2f/%.2f mm" % (k, v[0] * 1e3, v[1] * 1e3)
                                                      for k, v in MESHES.items()))
    ap.add_argument("--h-fine", type=float, default=None, help="a custom mesh: layer element size, m")
    ap.add_argument("--h-coarse", type=float, default=None, help="a custom mesh: bed element size, m")
    ap.add_argument("--gdot-min", type=float, nargs="+", default=[1e-3, 1e-2], help="regularisation(s), 1/s")
    ap.add_argument("--eta-max", type=float, default=1e12, help="viscosity cap, Pa s")
    ap.add_argument("--d", type=float, default=D_GRAIN, help="grain diameter, m")
    ap.add_argument("--rpm", type=float, default=RPM, help="the wall's rate, rev/min, clockwise (default 5)")
    ap.add_argument("--radius", type=float, default=R, help="the drum's radius, m (default 0.035, Table 1)")
    ap.add_argument("--fine-depth", type=float, default=0.009,
                    help="depth below the surface to which the mesh keeps its layer size h_fine, m; it grows to "
                         "h_coarse at twice that (default 0.009: the 5-rpm layer is 7 mm deep)")
    ap.add_argument("--fill", type=float, default=FILL,
                    help="filling level R_f = (H + R) / 2R (default 0.42, the EV drum; the EN drum's is 0.591)")
    ap.add_argument("--pr-alpha", type=float, default=None,
                    help="Barker & Gray's (2017) partial regularisation below the well-posed window with this "
                         "alpha (theirs: 1.9; sphseg's Material:mu_law partial, Material:pr_alpha); default off")
    ap.add_argument("--inertia", action="store_true", help="add rho u_old . grad u (Picard)")
    ap.add_argument("--pressure", choices=("lithostatic", "coupled"), default="lithostatic",
                    help="the p in eta: rho g cos(theta) (y_s - y) (default), or the FE pressure (see the docstring)")
    ap.add_argument("--p-factor", default=None,
                    help="CSV (header; depth_m, factor): multiply the lithostatic p in eta by this factor of the "
                         "depth, linear between rows, 1 outside (to hold the SPH's own pressure in the FE)")
    ap.add_argument("--method", choices=("newton", "picard"), default="newton")
    ap.add_argument("--tol", type=float, default=1e-6)
    ap.add_argument("--profile", default=None, help="CSV of the mid-chord profile at theta* (or the last theta)")
    ap.add_argument("--verbose", action="store_true")
    a = ap.parse_args(argv)
    set_partial(a.pr_alpha)
    if a.p_factor and a.pressure != "lithostatic":
        ap.error("--p-factor multiplies the lithostatic p in eta; it does not apply with --pressure coupled")
    set_p_factor(a.p_factor)
    if a.theta is not None:
        angles = [a.theta]
    elif a.angles:
        angles = sorted(a.angles)
    else:
        angles = [20.5, 21.0, 21.3, 21.6, 22.0, 22.5] if a.yld == "drucker_prager" else [24.0, 25.0, 26.0, 27.0, 28.0]
    meshes = [(a.h_fine, a.h_coarse or 4 * a.h_fine)] if a.h_fine else [MESHES[k] for k in a.meshes]
    print("drum mu(I) reference: R %.4f m, y_s %.4f m, %.1f rpm clockwise, rho %.0f, rho_s %.0f, d %.3g m, "
          "yield %s, inertia %s, p in eta %s%s" % (a.radius, (2 * a.fill - 1) * a.radius, a.rpm, RHO, RHO_S, a.d, a.yld, "on" if a.inertia else "off",
                                             a.pressure, " times the factor of " + a.p_factor if a.p_factor else ""))
    if PARTIAL:
        print("mu(I) partially regularised (Barker & Gray 2017): sqrt(%g / ln(%.1f / I)) below I_N1 = %.5f"
              % PARTIAL)
    print("u_surf m/s, delta mm, q m^2/s, torques N m/m (ccw +), p-dev = max|p - p_lith|/p_lith max in the bed")
    summary = []
    T0 = time.time()
    for hf, hc in meshes:
        t = time.time()
        drum = Drum(hf, hc, R=a.radius, ys=(2 * a.fill - 1) * a.radius, omega=-a.rpm * 2 * np.pi / 60,
                    d1=a.fine_depth)
        print("\nmesh h_fine %.2f mm h_coarse %.2f mm: %d elements, %d P2 nodes, %d dofs (%.1f s)"
              % (hf * 1e3, hc * 1e3, len(drum.S.tris), drum.nodes, drum.S.ndof, time.time() - t))
        for gm in a.gdot_min:
            print(" gdot_min %.0e 1/s, eta_max %.0e Pa s" % (gm, a.eta_max))
            print(HEAD)
            r = study_one(drum, angles, a.yld, gm, a.eta_max, a.d, a.inertia, a.theta is None, a.tol, a.verbose,
                          a.profile, a.method, a.pressure)
            print("  wall-clock %.0f s" % r["wall"])
            summary.append((hf, gm, r))
    print("\nsummary (%s): u_surf m/s at each theta, and at theta*" % a.yld)
    print("  h_fine  gdot_min  " + " ".join("%7.2f" % t for t in angles) + "   theta*   u*      delta*  time")
    for hf, gm, r in summary:
        st = r.get("star")
        print("  %5.2f   %7.0e  " % (hf * 1e3, gm) + " ".join("%7.4f" % o["speed"] for o in r["rows"])
              + ("   %6.3f  %6.4f  %5.2f" % (st["theta"], st["speed"], st["delta"] * 1e3) if st else "   -") +
              "  %5.0f s" % r["wall"])
    print("total %.0f s" % (time.time() - T0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
