"""The trimmed reduced model in time (reduction.max_frequency, docs/guide/trimming.md) along a slew.

At a fixed angle the C library trims the reassembled system: the modes above the limit leave the dynamics and their
static share stays as a feedthrough. In the bodies' own coordinates, where the slew integrates (the ties turn with
the angle), the same system is the bodies with the trimmed modes' mass taken out:

    M'(alpha) = M - (M N Phi_h) (M N Phi_h)^T

with N = null(D(alpha)) the coordinates that meet the ties and Phi_h the reassembled system's M-orthonormal modes
above the limit (N^T M' N = M - M Phi_h Phi_h^T M: the kept modes keep their mass and frequency, the trimmed ones
have none and respond quasi-statically, which is the feedthrough). M' leaves the rigid-body and mechanism modes'
mass as it is (they are M-orthogonal to Phi_h). The null space and the eigenpairs come from the C library
(_core.null_space, _core.dense_eig), as KFReassemble and KFReducedModelReassemble form them.

M' depends on the angle, so the trimmed integrator forms the step's matrix at every new angle (the reduced model is
small and dense) and imposes the ties in a saddle-point solve.
"""
import numpy as np

from .. import _core
from .damping import ViscousDamping
from .integrator import BETA, GAMMA, Integrator


class TrimmedMass:
    """M'(alpha) of a reduced SlewBodies for the limit limit_hz (see the module doc); rtol: the model's reassembly
    tolerance. Keeps the last few angles' matrices."""

    def __init__(self, bodies, limit_hz, rtol=1e-9):
        self.bodies, self.limit_hz, self.rtol = bodies, float(limit_hz), float(rtol)
        self.M = bodies.M.toarray()
        self.K = bodies.K.toarray()
        self._memo = {}
        self.top_hz = {}

    def at(self, angles_rad, ties=None):
        """M'(alpha); ties: D(alpha) when the caller has it (bodies.ties otherwise)."""
        key = np.asarray(angles_rad, float).tobytes()
        if key not in self._memo:
            D = self.bodies.ties(angles_rad) if ties is None else ties
            N, _, _ = _core.null_space(D, self.rtol)
            lam, Phi = _core.dense_eig(N.T @ self.K @ N, N.T @ self.M @ N)
            freq = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
            high = freq > self.limit_hz
            W = self.M @ (N @ Phi[:, high])
            if len(self._memo) > 4:
                self._memo.clear()
            self._memo[key] = self.M - W @ W.T
            kept = freq[~high]
            self.top_hz[key] = float(kept.max()) if kept.size else 0.0
        return self._memo[key]


class TrimmedIntegrator(Integrator):
    """Newmark's average-acceleration rule (integrator.py) on the bodies with the trimmed mass M'(alpha(t)): at each
    step K + gamma/(beta h) C + M'/(beta h^2) and the ties D(alpha) in one dense saddle-point solve."""

    def __init__(self, bodies, h, damping_beta=0.0, limit_hz=None, rtol=1e-9, damping=None):
        if not limit_hz or limit_hz <= 0:
            raise ValueError("the trimmed integrator needs a trimming limit (Hz) > 0")
        self.bodies, self.h, self.cb = bodies, float(h), float(damping_beta)
        self.C = damping if damping is not None else ViscousDamping(self.cb * bodies.K)
        self.mass = TrimmedMass(bodies, limit_hz, rtol)
        self._rigid = {}

    def run(self, profile, t_end, record_every=1, state=False):
        b, h = self.bodies, self.h
        nsteps = int(np.ceil(t_end / h - 1e-9))
        t = h * np.arange(nsteps + 1)
        u = profile.torque(t)
        alpha = profile.angles(t)
        N = b.dofs
        z, v, a = np.zeros(N), np.zeros(N), np.zeros(N)
        G1 = b.G.sum(axis=1)
        K, Cd = self.mass.K, self.C.toarray()
        c0, c1, c2 = 1 / (BETA * h * h), 1 / (BETA * h), 1 / (2 * BETA) - 1
        d0, d1, d2 = GAMMA / (BETA * h), GAMMA / BETA - 1, h * (GAMMA / (2 * BETA) - 1)
        keep = np.arange(0, nsteps + 1, record_every)
        ys = np.zeros((len(keep), b.H.shape[0]))
        ye = np.zeros_like(ys)
        zs = np.zeros((len(keep), N)) if state else None
        k, last, S, M = 1, None, None, None
        Id = b.I.toarray()
        for n in range(1, nsteps + 1):
            key = alpha[n].tobytes()
            if key != last:    # a new angle: the trimmed mass and the step's saddle-point matrix again
                D = b.tie_matrix(alpha[n]) @ Id
                M = self.mass.at(alpha[n], D)
                m = D.shape[0]
                A = np.zeros((N + m, N + m))
                A[:N, :N] = K + d0 * Cd + c0 * M
                A[:N, N:] = D.T
                A[N:, :N] = D
                S = np.linalg.inv(A)[:N, :N]      # z = S rhs meets the ties (the multipliers are not needed)
                last = key
            rhs = G1 * u[n] + M @ (c0 * z + c1 * v + c2 * a) + Cd @ (d0 * z + d1 * v + d2 * a)
            znew = S @ rhs
            anew = c0 * (znew - z) - c1 * v - c2 * a
            v = v + h * ((1 - GAMMA) * a + GAMMA * anew)
            z, a = znew, anew
            if k < len(keep) and keep[k] == n:
                ys[k], ye[k] = self.record(z, v, a, alpha[n])
                if state:
                    zs[k] = z
                k += 1
        return (t[keep], ys, ye, zs) if state else (t[keep], ys, ye)
