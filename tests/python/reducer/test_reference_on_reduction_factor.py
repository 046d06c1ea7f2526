"""The sparse full-order reference takes the reduction's own factor (K+) as its shift-and-invert step: no
factorization of its own per angle (src/reducer/compare.c). Checked against the path that factors K_S - target M_S
itself (-kf_verify_target given) and against the dense SciPy response (tests/python/support/reference.py): the same
modes, the same reference, and the reduction's own solve counts untouched by the eigensolve's applications."""
import os
import sys

import numpy as np
import pytest

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, SUPPORT)
sys.path.insert(0, os.path.join(ROOT, "meshes"))
sys.path.insert(0, HERE)
import frames  # noqa: E402
import reference as ref  # noqa: E402
from test_sparse_eigensolve import reduce_sparse  # noqa: E402

pytestmark = [pytest.mark.fast, pytest.mark.usefixtures("quiet_library")]


def test_reference_on_the_reduction_factor_equals_its_own_factorization(tmp_path):
    path = frames.write_random_scene(str(tmp_path), 360, nbodies=3, ninputs=2, noutputs=2, seed=5, nangles=2)
    scene, dense = kryflex.load_scene(path), ref.load_scene(path)
    Ms, Ks = ref.assemble(dense, scene.configurations[0])[:2]
    lam, _, rigid = ref._modes(Ms, Ks, ref.RIGID_RTOL)
    target = -1e-3 * lam[~rigid].min()              # a factorization of K - target M of the eigensolve's own
    shared = reduce_sparse(scene)
    own = reduce_sparse(scene, kf_verify_target=target)
    for c, angles in enumerate(shared.configurations):
        f_shared = np.ravel(shared.result(c, "full_frequencies_hz"))
        f_own = np.ravel(own.result(c, "full_frequencies_hz"))
        assert f_shared.size == f_own.size > 0
        assert np.allclose(f_shared, f_own, rtol=1e-8, atol=0), np.abs(f_shared / f_own - 1).max()
        w = 2 * np.pi * np.ravel(shared.result(c, "frf_frequencies_hz"))
        exact = ref.modal_frf(*ref.assemble(dense, angles), w, scene.damping)
        peak = np.abs(exact).max()
        T_shared, T_own = shared.frf(c, "full"), own.frf(c, "full")
        print("angle %d: reference on the reduction's factor vs its own factorization %.2e, vs dense SciPy %.2e "
              "(own: %.2e) of the peak" % (c, np.abs(T_shared - T_own).max() / peak,
                                           np.abs(T_shared - exact).max() / peak, np.abs(T_own - exact).max() / peak))
        assert np.abs(T_shared - T_own).max() <= 1e-8 * peak
        assert np.abs(T_shared - exact).max() <= 2 * np.abs(T_own - exact).max() + 1e-10 * peak
    # the eigensolve's applications of K+ are the verification's: the reduction's solve counts are the same
    for name in ("solve_calls", "solve_columns"):
        assert float(shared.result(-1, name).ravel()[0]) == float(own.result(-1, name).ravel()[0]), name
    assert float(shared.result(-1, "time_reference_eigensolve").ravel()[0]) > 0
