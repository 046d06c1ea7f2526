"""The full order's modes at 50 digits (mpmath), for scenes whose double-precision references disagree (helpers only).

The pencil of the assembled full order (reference.assemble, in double) solved on the M-orthogonal complement of the
geometric rigid modes (reference.geometric_rigid_modes, exact): K is projected there, K' = P^T K P with P = I - Q Q^T M
and Q^T M Q = I, so the rigid modes are K's null space to 50 digits, not to eps ||K|| as the assembled K has them. On a
light rotor (meshes/stress.py light-mass, masses 2e-9 of the stator's) that rounding, divided by the rotor's masses,
is a mode at 2.3e-6 rad^2/s^2 in a whole-pencil eigensolve. Small scenes only: 28 dofs take about a second per
configuration.

Used by tests/python/reducer/test_estimator_light_mass.py and benchmarks/estimator/light_mass_truth.py.
"""
import numpy as np

import accuracy_scenes as acc
import reference as ref

DIGITS = 50


class ExtendedTruth:
    """accuracy_scenes.ModalData per configuration, at DIGITS digits (memoized)."""

    def __init__(self, scene):
        self.scene, self._memo = scene, {}

    def at(self, angles):
        import mpmath as mp
        key = tuple(float(a) for a in angles)
        if key not in self._memo:
            with mp.workdps(DIGITS):
                Ms, Ks, Gs, Hs = ref.assemble(self.scene, list(key))
                R = ref.geometric_rigid_modes(self.scene, list(key))
                M, K, Rm = mp.matrix(Ms.tolist()), mp.matrix(Ks.tolist()), mp.matrix(R.tolist())
                Q = Rm * mp.inverse(mp.cholesky(Rm.T * M * Rm)).T                 # Q^T M Q = I
                P = mp.eye(M.rows) - Q * Q.T * M
                Li = mp.inverse(mp.cholesky(M))
                A = Li * (P.T * K * P) * Li.T
                lam, V = mp.eigsy((A + A.T) / 2)
                phi = Li.T * V
                lam = np.array([float(x) for x in lam])
                rigid = np.zeros(lam.size, bool)
                rigid[np.argsort(np.abs(lam))[:R.shape[1]]] = True
                self._memo[key] = acc.ModalData(np.where(rigid, 0.0, lam), rigid,
                                                np.array((mp.matrix(Hs.tolist()) * phi).tolist(), float),
                                                np.array((phi.T * mp.matrix(Gs.tolist())).tolist(), float))
        return self._memo[key]
