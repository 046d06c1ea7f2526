"""Time integration of the articulated structure along an angle history: Newmark's average-acceleration rule
(trapezoidal: second order, A-stable, no numerical damping) with the joint ties imposed on the positions at every
step (index-3 form, Lagrange multipliers):

    M z'' + C z' + K z + D(alpha(t))^T lambda = G u(t),      D(alpha(t)) z = 0

with z the bodies' own coordinates and C the frequency domain's damping model as a viscous operator (damping.py:
Rayleigh on the bodies, modal ratios on the model's own modes, C = Cs + U diag(d) U^T), or C = beta K. With the
effective stiffness Keff = K + gamma/(beta_N h) C + M/(beta_N h^2), its sparse part factored once (SciPy's SuperLU)
and the modal part U by the Woodbury identity (n solves once), a step is one solve and a small dense
system of the ties: D = T(alpha) I (bodies.py), W = Keff^-1 I^T is formed once, so the ties' Schur complement
T (I W) T^T is (ties x ties) at every step; its correction W T^T (T S T^T)^-1 T is kept while the angle does not
change. Bodies up to DENSE_MAX dofs step with Keff^-1 products formed once (a few dense products per step). Outputs
y = H z and their elastic parts are recorded every record_every steps.
"""
import numpy as np
import scipy.sparse.linalg as spla
from scipy.sparse import issparse as sp_issparse

from .damping import ViscousDamping

BETA, GAMMA = 0.25, 0.5


DENSE_MAX = 600   # below this many dofs the step is a few dense products (Keff^-1 formed), above it a sparse solve


class Integrator:
    """The Newmark integrator of one SlewBodies with step h and damping: a ViscousDamping (damping.py), or without
    it stiffness-proportional damping with coefficient damping_beta (s)."""

    def __init__(self, bodies, h, damping_beta=0.0, damping=None):
        self.bodies, self.h, self.cb = bodies, float(h), float(damping_beta)
        b, h = bodies, self.h
        self.C = damping if damping is not None else ViscousDamping(self.cb * b.K)
        g = GAMMA / (BETA * h)
        keff = (b.K + g * self.C.Cs + b.M / (BETA * h * h)).tocsc()
        self.lu = spla.splu(keff)
        U = self.C.U
        if U.shape[1]:      # Keff = A + U (g d) U^T: Woodbury, A^-1 U (S)^-1 formed once
            AU = self.lu.solve(U)
            S = np.diag(1.0 / (g * self.C.d)) + U.T @ AU
            self._X = np.linalg.solve(S.T, AU.T).T          # A^-1 U S^-1
        It = b.I.T.toarray()
        self.W = self.solve(It) if It.shape[1] else np.zeros((b.dofs, 0))
        self.S = np.asarray(b.I @ self.W)
        self.dense = b.dofs <= DENSE_MAX
        self._ties_at, self._rigid = None, {}

    def solve(self, rhs):
        """Keff^-1 rhs (a vector or columns)."""
        y = self.lu.solve(rhs)
        if self.C.U.shape[1]:
            y = y - self._X @ (self.C.U.T @ y)
        return y

    def _correction(self, alpha):
        """X = W T^T (T S T^T)^-1 T (N x interface rows): z = y0 - X I y0 meets the ties D(alpha) z = 0 (the Schur
        complement of the ties is small and SPD); kept while alpha does not change (after a slew)."""
        key = alpha.tobytes()
        if self._ties_at is None or self._ties_at[0] != key:
            T = self.bodies.tie_matrix(alpha)
            self._ties_at = (key, self.W @ (T.T @ np.linalg.solve(T @ self.S @ T.T, T)))
        return self._ties_at[1]

    def elastic_outputs(self, z, angles_rad):
        """H z_e with z_e = z - Phi (Phi^T M Phi)^-1 Phi^T M z: the output of the elastic part of z, the rigid-body and
        mechanism modes Phi at alpha (bodies.rigid_modes) taken out M-orthogonally."""
        b = self.bodies
        key = np.asarray(angles_rad, float).tobytes()
        if key not in self._rigid:
            Phi = b.rigid_modes(angles_rad)
            Phi = _range(Phi.toarray() if sp_issparse(Phi) else np.asarray(Phi))
            MPhi = np.asarray(b.M @ Phi)
            if len(self._rigid) > 4:          # a slew visits each angle once: keep only the last few
                self._rigid.clear()
            self._rigid[key] = (b.H @ Phi, np.linalg.solve(Phi.T @ MPhi, MPhi.T))
        HPhi, Q = self._rigid[key]
        return b.H @ z - HPhi @ (Q @ z)

    def record(self, z, v, a, angles_rad):
        """The outputs and their elastic parts at one step: H z, or H v, H a for the outputs that read a velocity or
        an acceleration (bodies.quantities; the rigid part taken out of the state they read)."""
        q = self.bodies.quantities
        y, ye = self.bodies.H @ z, self.elastic_outputs(z, angles_rad)
        for name, x in (("velocity", v), ("acceleration", a)):
            rows = [i for i, qi in enumerate(q) if qi == name]
            if rows:
                y[rows] = (self.bodies.H[rows] @ x)
                ye[rows] = self.elastic_outputs(x, angles_rad)[rows]
        return y, ye

    def run(self, profile, t_end, record_every=1, state=False):
        """Integrates from rest at t = 0 to t_end along profile (profiles.Profile: angles and torque); returns the
        sample times, the outputs (samples, outputs) and their elastic parts (elastic_outputs), and with state=True
        also the states z (samples, N)."""
        b, h = self.bodies, self.h
        nsteps = int(np.ceil(t_end / h - 1e-9))
        t = h * np.arange(nsteps + 1)
        u = profile.torque(t)
        alpha = profile.angles(t)
        N = b.dofs
        z, v, a = np.zeros(N), np.zeros(N), np.zeros(N)
        G1 = b.G.sum(axis=1)                       # every input driven by the same torque profile
        M, C = b.M, self.C
        c0, c1, c2 = 1 / (BETA * h * h), 1 / (BETA * h), 1 / (2 * BETA) - 1
        d0, d1, d2 = GAMMA / (BETA * h), GAMMA / BETA - 1, h * (GAMMA / (2 * BETA) - 1)
        if self.dense:
            # y0 = Keff^-1 (G1 u + (c0 M + d0 C) z + (c1 M + d1 C) v + (c2 M + d2 C) a), the products formed once
            Md, Cd = M.toarray(), C.toarray()
            Pu = self.solve(G1)
            Pz, Pv, Pa = (self.solve(ci * Md + di * Cd) for ci, di in ((c0, d0), (c1, d1), (c2, d2)))
            Id = b.I.toarray()
        keep = np.arange(0, nsteps + 1, record_every)
        ys = np.zeros((len(keep), b.H.shape[0]))
        ye = np.zeros_like(ys)
        zs = np.zeros((len(keep), N)) if state else None
        k = 1
        for n in range(1, nsteps + 1):
            if self.dense:
                y0 = Pu * u[n] + Pz @ z + Pv @ v + Pa @ a
                Iy0 = Id @ y0
            else:
                rhs = G1 * u[n] + M @ (c0 * z + c1 * v + c2 * a)
                if C.nnz:
                    rhs += C @ (d0 * z + d1 * v + d2 * a)
                y0 = self.solve(rhs)
                Iy0 = b.I @ y0
            if b.nties:
                znew = y0 - self._correction(alpha[n]) @ Iy0
            else:
                znew = y0
            anew = c0 * (znew - z) - c1 * v - c2 * a
            v = v + h * ((1 - GAMMA) * a + GAMMA * anew)
            z, a = znew, anew
            if k < len(keep) and keep[k] == n:
                ys[k], ye[k] = self.record(z, v, a, alpha[n])
                if state:
                    zs[k] = z
                k += 1
        return (t[keep], ys, ye, zs) if state else (t[keep], ys, ye)


def _range(Phi, rtol=1e-10):
    """An orthonormal basis of the columns' span: the zero columns of motions a boundary condition does not admit
    (and any dependent ones) dropped, so that Phi^T M Phi is invertible."""
    if not Phi.shape[1]:
        return Phi
    U, s, _ = np.linalg.svd(Phi, full_matrices=False)
    return U[:, s > rtol * s.max()] if s.max() > 0 else Phi[:, :0]
