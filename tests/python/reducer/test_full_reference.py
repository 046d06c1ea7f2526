"""The full-order reference every accuracy verdict is measured against (src/reducer/compare.c, evaluate.c:
KFFullFRF_Private), checked against an independent dense SciPy response (tests/python/support/reference.py: the scene
assembled from its files, every mode by scipy.linalg.eigh).

Two paths: a small system (<= -kf_verify_dense_max_dofs) takes every mode, no residual; a larger one the modes up to
verify_cover x the band's top plus the rest by their first two residual moments (R0 + w^2 R1). The sparse path is
forced on a small scene (-kf_verify_dense_max_dofs 0, -kf_verify_modes leaving modes out) so that the dense
reference stays cheap. The measure is the accuracy measure itself (relative H-inf per pair, pairs below KF_FRF_PAIR_FLOOR of
the largest peak against that floor).
"""
import os
import subprocess
import sys

import numpy as np
import pytest
from petsc4py import PETSc

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, SUPPORT)
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402
import reference as ref  # noqa: E402

GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
PAIR_FLOOR = 1e-4

pytestmark = [pytest.mark.fast, pytest.mark.usefixtures("quiet_library")]


def reference_errors(path, **options):
    """Per angle of interest: the relative H-inf distance per pair between the C reference (frf_full) and the dense
    SciPy response on the C grid; and the reducer."""
    scene = kryflex.load_scene(path)
    dense = ref.load_scene(path)
    reducer = kryflex.Reducer(scene, quiet=True, search=False, **options)
    reducer.reduce()
    errors = []
    for c, angles in enumerate(reducer.configurations):
        w = 2 * np.pi * np.ravel(reducer.result(c, "frf_frequencies_hz"))
        Tf = ref.modal_frf(*ref.assemble(dense, angles), w, scene.damping)
        Tc = reducer.frf(c, "full")
        assert Tc.shape == Tf.shape
        peak = np.abs(Tf).max(axis=0)
        errors.append(float((np.abs(Tf - Tc).max(axis=0) / np.maximum(peak, PAIR_FLOOR * peak.max())).max()))
    return errors, reducer


@pytest.fixture(scope="module")
def stress_scenes(tmp_path_factory):
    # written by its own process: meshes/stress.py imports Galileo's generate.py, whose module name meshes/solid's
    # generator shares (test_solid_mesh.py imports that one)
    out = str(tmp_path_factory.mktemp("stress"))
    subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "stress.py"), "--out", out, "--names",
                    "mimo-8x8"], check=True, capture_output=True, timeout=120)
    return {"mimo-8x8": os.path.join(out, "mimo-8x8", "scene.yaml")}


def test_small_system_every_mode(stress_scenes):
    """Galileo (28 system dofs) and its 8 x 8 variant: every mode, no residual. The first version took 20 of 21
    modes plus a static residual: 2e-6 on Galileo, and 4e-3 on a near-zero pair of the 8 x 8 variant."""
    for path, bound in ((GALILEO, 5e-6), (stress_scenes["mimo-8x8"], 1e-4)):
        errors, reducer = reference_errors(path)
        print("%s: reference vs dense SciPy, worst over the angles %.2e" % (os.path.basename(os.path.dirname(path)),
                                                                          max(errors)))
        assert max(errors) <= bound, errors


def test_sparse_path_residual_moments(tmp_path):
    """A 3-body frame through the sparse path with the modes to about 2x the band's top only (-kf_verify_modes): the
    modes left out enter by R0 + w^2 R1. The C reference equals that formula evaluated here on dense modes, and is
    closer to the exact response than the static residual alone (what the first version did)."""
    path = frames.write_random_scene(str(tmp_path), 360, nbodies=3, ninputs=2, noutputs=2, seed=5, nangles=1)
    scene, dense = kryflex.load_scene(path), ref.load_scene(path)
    angles = scene.configurations[0]
    Ms, Ks, Gs, Hs = ref.assemble(dense, angles)
    lam, phi, rigid = ref._modes(Ms, Ks, ref.RIGID_RTOL)
    flex = np.flatnonzero(~rigid)
    f_hz = np.sqrt(lam[flex]) / (2 * np.pi)
    n = int(np.count_nonzero(f_hz <= 2 * scene.band[1]))
    assert 0 < n < flex.size - 5, (n, flex.size)          # modes are left out, some of them near the band
    opts = PETSc.Options()
    opts.setValue("kf_verify_dense_max_dofs", 0)
    try:
        reducer = kryflex.Reducer(scene, quiet=True, search=False, verify_modes=n)
        reducer.reduce()
    finally:
        opts.delValue("kf_verify_dense_max_dofs")
    w = 2 * np.pi * np.ravel(reducer.result(0, "frf_frequencies_hz"))
    Tc = reducer.frf(0, "full")
    exact = ref.modal_frf(Ms, Ks, Gs, Hs, w, scene.damping)
    # the same formula on dense modes: rigid + computed (damped) + R0 + w^2 R1 of the rest
    hp, pg = Hs @ phi, phi.T @ Gs
    kept, rest = flex[:n], flex[n:]
    part = np.array([(hp[:, rigid] / (-x ** 2)) @ pg[rigid]
                     + (hp[:, kept] / (lam[kept] - x ** 2 + 2j * scene.damping * np.sqrt(lam[kept]) * x)) @ pg[kept]
                     for x in w])
    R0 = (hp[:, rest] / lam[rest]) @ pg[rest]
    R1 = (hp[:, rest] / lam[rest] ** 2) @ pg[rest]
    formula = part + R0 + (w ** 2)[:, None, None] * R1

    def distance(T):
        peak = np.abs(exact).max(axis=0)
        return float((np.abs(T - exact).max(axis=0) / np.maximum(peak, PAIR_FLOOR * peak.max())).max())

    static_only = distance(part + R0)
    print("sparse path: %d of %d flexible modes (to %.1f Hz, band top %.1f Hz); vs exact: C reference %.2e, "
          "static residual alone %.2e" % (n, flex.size, f_hz[n - 1], scene.band[1], distance(Tc), static_only))
    peak = np.abs(formula).max()
    assert np.abs(Tc - formula).max() <= 1e-7 * peak
    assert distance(Tc) < 0.5 * static_only
