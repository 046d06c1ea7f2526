"""The closed-form reassembly (KFReassemblyApply on a tree of bodies, no SVD per angle) against the SVD path
(KFReassemblySetUseSVD: the null space of the ties by SVD at every call), on Galileo (with body damping matrices and
Rayleigh damping), a 3-body chain of two skew revolute joints, a scene with a fixed joint (random R0), a clamped arm
(revolute joint to ground), one free body with massless rotations and no joint, and the solid bus/rotor pair, at the
angles of interest and far from them.

The two paths use different bases of the same null space, so the comparison is on what does not depend on the basis:
the generalized eigenvalues, each well-separated mode's residue H phi phi^T G, the rigid modes' residue, and the
damped transfer function H (K - w^2 M + i w C)^-1 G across the band; and the constraint rank, sigma ratio and rigid
count, which both paths take from the same SVDs.
"""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl
import yaml

import kryflex
from kryflex import _core

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "support"))
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import bc_models  # noqa: E402
import frames  # noqa: E402
import reference as ref  # noqa: E402

ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
FAR = [[0.0], [90.0], [181.0], [-135.0], [359.0]]
FAR2 = [[0.0, 0.0], [10.0, 250.0], [-170.0, 95.0], [333.0, -17.0]]

pytestmark = pytest.mark.usefixtures("quiet_library")   # tests/python/conftest.py


# split models (shared_directions false): the closed form eliminates joint ties only, and under the default (auto) a
# tied model, which takes the SVD path, wins on some of these scenes (Galileo damped, the solid)
SPLIT = {"shared_directions": False}


def galileo_damped():
    """Galileo with per body a non-proportional damping matrix and Rayleigh damping on top."""
    with open(GALILEO) as f:
        spec = yaml.safe_load(f)
    base = os.path.dirname(GALILEO)
    rng = np.random.default_rng(5)
    for b, body in zip(spec["bodies"].values(), ref.load_scene(GALILEO).bodies):
        for k in ("mass", "stiffness", "nodes"):
            b[k] = os.path.join(base, b[k])
        A = rng.standard_normal((body.n, 3))
        C = 1e-3 * body.K.toarray() + 0.2 * (A @ A.T) * np.abs(body.M.diagonal()).mean()
        b["damping"] = 0.5 * (C + C.T)
    spec.pop("reduction")
    spec["damping"] = {"modal": 0.0, "rayleigh": {"alpha": 0.02, "beta": 2e-5}}
    return kryflex.reduce(kryflex.scene_from_dict(spec), quiet=True, **SPLIT).model, FAR


def chain(tmp):
    path = frames.write_random_scene(str(tmp), 600, nbodies=3, ninputs=3, noutputs=3, seed=1)
    model = kryflex.reduce(kryflex.load_scene(path), quiet=True, accuracy=1e-4, **SPLIT).model
    assert [(j["parent"], j["child"]) for j in model.joints] == [(0, 1), (1, 2)]    # a chain: 0 - 1 - 2
    return model, FAR2


def fixed(tmp):
    path = frames.write_random_scene(str(tmp), 240, nbodies=3, ninputs=3, noutputs=2, seed=2, fixed_joint=True)
    model = kryflex.reduce(kryflex.load_scene(path), quiet=True, **SPLIT).model
    assert any(j["type"] == "fixed" for j in model.joints)
    return model, FAR


def clamped(tmp):
    model = kryflex.reduce(kryflex.scene_from_dict(bc_models.grounded_arm()), quiet=True, **SPLIT).model
    return model, FAR if len(model.revolute) == 1 else FAR2


def lumped(tmp):
    """One free body with massless rotations (no joint: its coordinates are kept as they are)."""
    model = kryflex.reduce(kryflex.scene_from_dict(bc_models.lumped_frame()), quiet=True, **SPLIT).model
    return model, [[]]


def solid(tmp):
    subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "solid", "generate.py"), "--refine", "0.25",
                    "-o", str(tmp)], check=True, capture_output=True, env=ENV)
    model = kryflex.reduce(kryflex.load_scene(str(tmp / "spacecraft.yaml")), quiet=True, **SPLIT).model
    return model, FAR


SCENES = {"galileo_damped": galileo_damped, "chain": chain, "fixed": fixed, "clamped": clamped, "lumped": lumped,
          "solid": solid}


@pytest.fixture(scope="module", params=list(SCENES))
def case(request, tmp_path_factory):
    make = SCENES[request.param]
    return make() if request.param == "galileo_damped" else make(tmp_path_factory.mktemp(request.param))


def residues(M, K, G, H, nr):
    """(eigenvalues, per well-separated flexible mode its residue H phi phi^T G, mask of those modes)."""
    lam, Phi = sl.eigh(K, M)
    gap = np.full(len(lam), np.inf)
    d = np.diff(lam)
    gap[:-1] = np.minimum(gap[:-1], d)
    gap[1:] = np.minimum(gap[1:], d)
    keep = (np.arange(len(lam)) >= nr) & (gap > 1e-6 * np.abs(lam).max())
    res = np.einsum("ti,ia->ita", H @ Phi, Phi.T @ G)
    return lam, res, keep


def rigid_residue(M, G, H, Phir):
    """H Phir (Phir^T M Phir)^-1 Phir^T G: the rigid modes' share of the response, whatever their basis."""
    return H @ Phir @ np.linalg.solve(Phir.T @ M @ Phir, Phir.T @ G)


def transfer(M, K, C, G, H, w):
    return H @ np.linalg.solve(K - w ** 2 * M + 1j * w * C, G)


def test_closed_form_against_the_svd_path(case):
    model, angles_list = case
    closed, svd = _core.CReassembly(model), _core.CReassembly(model, svd=True)
    assert not closed.svd and svd.svd
    for deg in angles_list:
        rad = np.radians(deg)
        Mp, Kp, Cp, Gp, Hp, Rp, rank_p, ratio_p = closed.apply(rad)
        Ms, Ks, Cs, Gs, Hs, Rs, rank_s, ratio_s = svd.apply(rad)
        assert Mp.shape == Ms.shape and (rank_p, ratio_p) == (rank_s, ratio_s), deg
        assert Rp.shape == Rs.shape, deg
        nr = Rs.shape[1]
        lp, res_p, keep = residues(Mp, Kp, Gp, Hp, nr)
        ls, res_s, keep_s = residues(Ms, Ks, Gs, Hs, nr)
        lmax = np.abs(ls).max()
        assert np.abs(lp - ls).max() <= 1e-12 * lmax, deg
        # the flexible eigenvalues one by one: both paths round the soft ones at eps lambda_max / lambda
        flex = slice(nr, None)
        assert np.all(np.abs(lp[flex] - ls[flex]) <= 1e-9 * ls[flex] + 1e-13 * lmax), deg
        both = keep & keep_s
        scale = np.abs(res_s[both]).max()
        assert np.abs(res_p[both] - res_s[both]).max() <= 1e-9 * scale, deg
        # rigid modes: annihilated by K, and the same subspace
        assert np.abs(Kp @ Rp).max() <= 1e-10 * np.abs(Kp).max() * np.abs(Rp).max(), deg
        if nr:
            Tr_p, Tr_s = rigid_residue(Mp, Gp, Hp, Rp), rigid_residue(Ms, Gs, Hs, Rs)
            assert np.abs(Tr_p - Tr_s).max() <= 1e-10 * np.abs(Tr_s).max(), deg
        Cp = np.zeros_like(Mp) if Cp is None else Cp
        Cs = np.zeros_like(Ms) if Cs is None else Cs
        f1 = np.sqrt(ls[nr]) / (2 * np.pi)
        for f in (0.3 * f1, 1.7 * f1, 10 * f1):
            w = 2 * np.pi * f
            Tp, Ts = transfer(Mp, Kp, Cp, Gp, Hp, w), transfer(Ms, Ks, Cs, Gs, Hs, w)
            cond = np.linalg.cond(Ks - w ** 2 * Ms + 1j * w * Cs)
            assert np.abs(Tp - Ts).max() <= max(1e-12, 1e3 * np.finfo(float).eps * cond) * np.abs(Ts).max(), (deg, f)


def test_at_uses_the_closed_form_and_reads_rank_and_rigid_modes_lazily(case):
    model, angles_list = case
    closed = _core.CReassembly(model)
    for deg in angles_list[:2]:
        s = model.at(deg)
        M, K, C, G, H, Phir, rank, ratio = closed.apply(np.radians(deg))
        np.testing.assert_array_equal(s.M, M)
        np.testing.assert_array_equal(s.K, K)
        np.testing.assert_array_equal(s.B, G)
        assert s._info is None                      # nothing of the SVDs yet
        assert (s.constraint_rank, s.sigma_ratio) == (rank, ratio)
        np.testing.assert_array_equal(s.rigid_modes, Phir)
        np.testing.assert_array_equal(s.M, M)       # reading them changed nothing


def test_svd_path_is_the_one_shot_reassembly(case):
    """KFReassemblySetUseSVD gives KFReducedModelReassemble's arrays (the orthonormal basis), array for array."""
    model, angles_list = case
    svd = _core.CReassembly(model, svd=True)
    for deg in angles_list[:2]:
        M, K, C, G, H, Phir, rank, ratio = svd.apply(np.radians(deg))
        Mo, Ko, Go, Ho = model.reassemble(np.radians(deg)).matrices()
        for got, want in ((M, Mo), (K, Ko), (G, Go), (H, Ho)):
            np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13 * np.abs(want).max())
