"""The time domain's damping: the frequency domain's damping model as a viscous operator on the bodies' coordinates.

Modal ratios zeta_k are defined on the undamped modes of the assembled structure at one configuration: on the
structure's flexible modes Phi (body coordinates, M-orthonormal, the ties of the configuration satisfied, the rigid
and mechanism modes left undamped) the viscous matrix U diag(d) U^T with U = M Phi, d = 2 zeta_k omega_k damps each
mode by its own ratio and no other, which is what the frequency responses of both models apply (each model on its own
modes). Rayleigh damping is alpha M + beta K on the bodies as they are (exact under projection). Each model gets the
operator from its own modes, computed once at the study's first angles (modal damping is defined per configuration;
during a slew the operator stays that of the first angles, see docs/guide/slewing.md).

Structural (hysteretic) damping has no viscous equivalent in time and the bodies' damping matrices are not carried by
the full-order slew bodies: a scene with either is integrated without them, and the study says so (notes).
"""
import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp

from .. import _core

MODAL_DENSE_MAX = 8000   # the full order's modes by one dense eigendecomposition up to this many dofs


class ViscousDamping:
    """C = Cs + U diag(d) U^T: Cs sparse (N x N), U (N x n) dense, d (n); products without forming C."""

    def __init__(self, Cs, U=None, d=None):
        self.Cs = sp.csr_matrix(Cs)
        N = self.Cs.shape[0]
        self.U = np.zeros((N, 0)) if U is None else np.asarray(U, float)
        self.d = np.zeros(0) if d is None else np.asarray(d, float)

    @property
    def nnz(self):
        return self.Cs.nnz + self.U.size

    def __matmul__(self, x):
        return self.Cs @ x + self.U @ (self.d[:, None] * (self.U.T @ x) if np.ndim(x) == 2 else self.d * (self.U.T @ x))

    def toarray(self):
        return self.Cs.toarray() + (self.U * self.d) @ self.U.T


def structure_modes(bodies, angles_rad):
    """The flexible modes of the tied structure at the angles: (eigenvalues, Phi (N x n) in body coordinates,
    M-orthonormal), the rigid and mechanism modes (bodies.rigid_modes) excluded exactly (the eigenproblem is solved on
    their M-orthogonal complement within the ties' null space)."""
    N = bodies.dofs
    if N > MODAL_DENSE_MAX:
        raise ValueError("modal damping in time needs the structure's modes by a dense eigendecomposition, done up to "
                         "%d dofs; this model has %d" % (MODAL_DENSE_MAX, N))
    M, K = bodies.M.toarray(), bodies.K.toarray()
    D = bodies.ties(angles_rad)
    Z = sl.null_space(D) if D.shape[0] else np.eye(N)
    R = np.asarray(bodies.rigid_modes(angles_rad))
    Mz, Kz = Z.T @ M @ Z, Z.T @ K @ Z
    Rz = Z.T @ R
    Y = sl.null_space((Mz @ Rz).T) if Rz.shape[1] else np.eye(Z.shape[1])
    lam, V = sl.eigh(Y.T @ Kz @ Y, Y.T @ Mz @ Y)
    return lam, Z @ (Y @ V)


def time_damping(bodies, angles_rad, damping_model, extra_beta=0.0):
    """The viscous operator of one model (SlewBodies) under the scene's damping model (its dict: modal, rayleigh,
    structural), with the modal ratios on the model's own modes at angles_rad."""
    ray = damping_model.get("rayleigh") or {}
    Cs = float(ray.get("alpha", 0.0)) * bodies.M + (float(ray.get("beta", 0.0)) + extra_beta) * bodies.K
    modal = damping_model.get("modal", 0.0)
    if not np.any(np.asarray(modal if not isinstance(modal, list) else [z for _, z in modal], float) > 0):
        return ViscousDamping(Cs)
    lam, Phi = structure_modes(bodies, angles_rad)
    w = np.sqrt(np.maximum(lam, 0.0))
    zeta = _core.modal_ratios({"modal": modal}, w / (2 * np.pi))
    return ViscousDamping(Cs, bodies.M @ Phi, 2 * zeta * w)
