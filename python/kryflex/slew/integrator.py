"""Time integration of the articulated structure along an angle history: Newmark's average-acceleration rule
(trapezoidal: second order, A-stable, no numerical damping) with the joint ties imposed on the positions at every
step (index-3 form, Lagrange multipliers):

    M z'' + C z' + K z + D(alpha(t))^T lambda = G u(t),      D(alpha(t)) z = 0

with z the bodies' own coordinates and C = beta K (stiffness-proportional damping, the same beta for the full and
the reduced bodies, so the reduced C is the projection of the full one). With the effective stiffness
Keff = K + gamma/(beta_N h) C + M/(beta_N h^2) factored once (SciPy's SuperLU), a step is one solve and a small dense
system of the ties: D = T(alpha) I (bodies.py), W = Keff^-1 I^T is formed once, so the ties' Schur complement
T (I W) T^T is (ties x ties) at every step. Outputs y = H z are recorded at every step.
"""
import numpy as np
import scipy.sparse.linalg as spla
from scipy.sparse import issparse as sp_issparse

BETA, GAMMA = 0.25, 0.5


class Integrator:
    """The Newmark integrator of one SlewBodies with step h and stiffness-proportional damping coefficient
    damping_beta (s)."""

    def __init__(self, bodies, h, damping_beta=0.0):
        self.bodies, self.h, self.cb = bodies, float(h), float(damping_beta)
        b, h = bodies, self.h
        self.C = self.cb * b.K
        keff = (b.K + (GAMMA / (BETA * h)) * self.C + b.M / (BETA * h * h)).tocsc()
        self.lu = spla.splu(keff)
        It = b.I.T.toarray()
        self.W = self.lu.solve(It) if It.shape[1] else np.zeros((b.dofs, 0))
        self.S = np.asarray(b.I @ self.W)

    def elastic_outputs(self, z, angles_rad):
        """H z_e with z_e = z - Phi (Phi^T M Phi)^-1 Phi^T M z: the output of the elastic part of z, the rigid-body and
        mechanism modes Phi at alpha (bodies.rigid_modes) taken out M-orthogonally."""
        b = self.bodies
        Phi = b.rigid_modes(angles_rad)
        MPhi = b.M @ Phi
        if sp_issparse(MPhi):
            MPhi = MPhi.toarray()
        Phi = Phi.toarray() if sp_issparse(Phi) else Phi
        coef = np.linalg.solve(Phi.T @ MPhi, MPhi.T @ z)
        return b.H @ (z - Phi @ coef)

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
        keep = np.arange(0, nsteps + 1, record_every)
        ys = np.zeros((len(keep), b.H.shape[0]))
        ye = np.zeros_like(ys)
        zs = np.zeros((len(keep), N)) if state else None
        k = 1
        for n in range(1, nsteps + 1):
            rhs = G1 * u[n] + M @ (c0 * z + c1 * v + c2 * a)
            if self.cb:
                rhs += C @ (d0 * z + d1 * v + d2 * a)
            y0 = self.lu.solve(rhs)
            if b.nties:
                T = b.tie_matrix(alpha[n])
                lam = np.linalg.solve(T @ self.S @ T.T, T @ (b.I @ y0))
                znew = y0 - self.W @ (T.T @ lam)
            else:
                znew = y0
            anew = c0 * (znew - z) - c1 * v - c2 * a
            v = v + h * ((1 - GAMMA) * a + GAMMA * anew)
            z, a = znew, anew
            if k < len(keep) and keep[k] == n:
                ys[k] = b.H @ z
                ye[k] = self.elastic_outputs(z, alpha[n])
                if state:
                    zs[k] = z
                k += 1
        return (t[keep], ys, ye, zs) if state else (t[keep], ys, ye)
