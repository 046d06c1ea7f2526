"""The example models (meshes/galileo, meshes/frames.py) and the dense reference (reference.py) they are checked with."""
import importlib.util
import os
import sys

import numpy as np
import pytest
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
sys.path.insert(0, SUPPORT)
import reference as ref  # noqa: E402

pytestmark = pytest.mark.fast   # the fast tier (tests/README.md)


def load_module(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


frames = load_module("frames", os.path.join(ROOT, "meshes", "frames.py"))
generate = load_module("galileo_generate", os.path.join(ROOT, "meshes", "galileo", "generate.py"))

# Lee's Table 1: free-free component frequencies (Hz) of the paper's model, flexible modes only.
PAPER_ROTOR = [0.1221, 1.0579, 2.8638, 3.4223, 4.9894, 5.2217, 73.425, 75.821, 76.998, 116.50, 116.51,
               994.70, 994.70, 2108.5, 2431.9]
PAPER_STATOR = [57.253, 57.455, 225.24, 225.31, 1217.7, 1404.7]
RESEMBLE = 1e-4          # docs/guide/paper-example.md: Table 1's component frequencies are the model's eigenvalues (to its digits)


def flexible_hz(M, K, nzero):
    lam = sl.eigh(K, M, eigvals_only=True)
    return np.sqrt(lam[nzero:]) / (2 * np.pi)


def zero_count_with_gap(M, K, rtol=ref.RIGID_RTOL):
    """Number of zero eigenvalues, insisting on a clear gap (1e3) to the first nonzero one."""
    lam = sl.eigh(K, M, eigvals_only=True)
    top = np.abs(lam).max()
    nz = int(np.sum(np.abs(lam) <= rtol * top))
    assert lam[nz] > 1e3 * rtol * top, f"no clear gap after {nz} zero eigenvalues: {lam[:nz + 2]}"
    return nz


@pytest.fixture(scope="module")
def galileo():
    return ref.load_scene(GALILEO)


# ------------------------------------------------------------------ Galileo

def test_galileo_sizes_and_free_free_bodies(galileo):
    sizes = {b.name: b.n for b in galileo.bodies}
    assert sizes == {"stator": 12, "rotor": 21}
    for b in galileo.bodies:
        M, K = b.M.toarray(), b.K.toarray()
        assert np.linalg.eigvalsh(M).min() > 0, b.name
        assert zero_count_with_gap(M, K) == 6, b.name


@pytest.mark.parametrize("alpha", [0, 15, 30, 45, 60, 72])
def test_galileo_system_has_28_dofs_and_7_zero_modes(galileo, alpha):
    Ms, Ks, Gs, Hs = ref.assemble(galileo, alpha)
    assert Ms.shape == (28, 28) and Gs.shape == (28, 1) and Hs.shape == (1, 28)
    assert zero_count_with_gap(Ms, Ks) == 7


def test_galileo_scene_angles_are_the_papers(galileo):
    assert [c[0] for c in ref.configurations(galileo)] == [0, 15, 30, 45, 60, 72]


def test_galileo_component_frequencies_resemble_table_1(galileo):
    body = {b.name: b for b in galileo.bodies}
    for name, paper in (("rotor", PAPER_ROTOR), ("stator", PAPER_STATOR)):
        f = flexible_hz(body[name].M.toarray(), body[name].K.toarray(), 6)
        np.testing.assert_allclose(f, paper, rtol=RESEMBLE, err_msg=name)
    # the features the design is about: a very soft boom, then booms in the 1-6 Hz range
    rotor = flexible_hz(body["rotor"].M.toarray(), body["rotor"].K.toarray(), 6)
    assert 0.10 < rotor[0] < 0.15 and 0.9 < rotor[1] < 1.2 and np.all((rotor[2:6] > 2.5) & (rotor[2:6] < 6))


def test_galileo_files_match_the_generator(galileo):
    """The committed .mtx files are what generate.py builds now from fit.json (no stale example). K is dense and made
    of products (K = M Phi Lambda Phi^T M): equal to rounding of the largest entry."""
    (Ms, Ks, _), (Mr, Kr, _) = generate.build_bodies()
    body = {b.name: b for b in galileo.bodies}
    for name, M, K in (("stator", Ms, Ks), ("rotor", Mr, Kr)):
        np.testing.assert_allclose(body[name].M.toarray(), M, rtol=1e-15, atol=0, err_msg=name)
        np.testing.assert_allclose(body[name].K.toarray(), K, rtol=0, atol=1e-12 * np.abs(K).max(), err_msg=name)


def test_galileo_transfer_depends_on_clock_angle(galileo):
    w = 2 * np.pi * np.logspace(np.log10(0.01), np.log10(10.0), 200)
    T0 = ref.modal_frf(*ref.assemble(galileo, 0), w, 0.0025)[:, 0, 0]
    for alpha in (15, 30, 45, 60, 72):
        Ta = ref.modal_frf(*ref.assemble(galileo, alpha), w, 0.0025)[:, 0, 0]
        assert np.max(np.abs(Ta - T0) / np.abs(T0)) > 0.1, alpha
    L = np.array([ref.moments(*ref.assemble(galileo, a), 3)[:, 0, 0] for a in (0, 30, 60)])
    assert np.all(np.abs(L[1:] - L[0]) > 0.1 * np.abs(L).max(axis=0))


def rigid_motion(scene, angle_deg, t, w):
    """Body dof vector of a rigid motion (translation t, rotation w, in the stator frame) of the Galileo scene.

    Built from node coordinates, independently of the constraint rows: the rotor frame is Rot(z, alpha) and
    its bearing node sits at the stator's bearing node, both at the origin.
    """
    R = ref.rotation([0, 0, 1], np.radians(angle_deg))
    coords = {"stator": (np.eye(3), t, w), "rotor": (R, R.T @ t, R.T @ w)}
    parts = []
    for b in scene.bodies:
        _, tb, wb = coords[b.name]
        x = np.zeros(b.n)
        nodes = np.loadtxt(os.path.join(scene.here, f"{b.name}_nodes.txt"), ndmin=2)
        for node_id, px, py, pz, nd in nodes:
            d = b.first_dof[int(node_id)]
            x[d:d + 3] = tb + np.cross(wb, [px, py, pz])
            if nd == 6:
                x[d + 3:d + 6] = wb
        parts.append(x)
    return np.concatenate(parts)


@pytest.mark.parametrize("alpha", [0, 45])
def test_constraint_convention_admits_rigid_motions(galileo, alpha):
    """Rigid motions from geometry satisfy C(alpha) x = 0 and cost no strain energy: the rows follow u_p = R u_c."""
    C = ref.constraint_matrix(galileo, alpha)
    assert C.shape[0] == 5
    rng = np.random.default_rng(0)
    K = sl.block_diag(*[b.K.toarray() for b in galileo.bodies])
    for _ in range(3):
        x = rigid_motion(galileo, alpha, rng.normal(size=3), rng.normal(size=3))
        assert np.abs(C @ x).max() < 1e-12 * np.abs(x).max()
        assert np.abs(K @ x).max() < 1e-9 * np.abs(K).max() * np.abs(x).max()


def test_reference_transfer_modal_and_moments_agree(galileo):
    Ms, Ks, Gs, Hs = ref.assemble(galileo, 30)
    w = 2 * np.pi * np.array([0.03, 0.4, 1.7, 7.0])
    T = ref.transfer(Ms, Ks, Gs, Hs, w)
    np.testing.assert_allclose(ref.modal_frf(Ms, Ks, Gs, Hs, w, 0.0), T, rtol=1e-6)
    # below the first flexible frequency the moment series sums to the flexible part of T
    lam, phi = sl.eigh(Ks, Ms)
    rigid = np.abs(lam) <= ref.RIGID_RTOL * lam.max()
    w0 = 0.3 * np.sqrt(lam[~rigid][0])
    rigid_part = (Hs @ phi[:, rigid]) @ (phi[:, rigid].T @ Gs) / (-w0**2)
    flex = ref.transfer(Ms, Ks, Gs, Hs, [w0])[0] - rigid_part
    L = ref.moments(Ms, Ks, Gs, Hs, 40)
    series = sum(w0 ** (2 * k) * L[k] for k in range(40))
    np.testing.assert_allclose(series, flex, rtol=1e-5)   # T minus the large rigid part: cancellation (3e-6 here)


# ------------------------------------------------------------------ random frames

@pytest.mark.parametrize("total, nbodies, fixed, seed", [(30, 3, False, 0), (240, 3, True, 1), (360, 4, False, 2)])
def test_random_scene_bodies_free_free_and_system_mechanisms(tmp_path, total, nbodies, fixed, seed):
    path = frames.write_random_scene(str(tmp_path), total, nbodies=nbodies, seed=seed, fixed_joint=fixed)
    scene = ref.load_scene(path)
    assert len(scene.bodies) == nbodies and len(scene.inputs) == 3 and len(scene.outputs) == 2
    assert abs(sum(b.n for b in scene.bodies) - total) <= 6 * nbodies + 12
    assert len({t["body"] for _, terms in scene.inputs for t in terms}) > 1      # loads on different bodies
    for b in scene.bodies:
        assert zero_count_with_gap(b.M.toarray(), b.K.toarray()) == 6, b.name
    revolute = [j for j in scene.joints if j["type"] == "revolute"]
    assert scene.nrevolute == nbodies - 1 - int(fixed)
    for j in revolute:
        axis = np.asarray(j["axis"])
        assert abs(np.linalg.norm(axis) - 1) < 1e-12 and np.all(np.abs(axis) > 0.1)   # not along a coordinate axis
    configs = ref.configurations(scene)
    assert len(configs) >= 2 and all(len(c) == scene.nrevolute for c in configs)
    for angles in configs:
        Ms, Ks, Gs, Hs = ref.assemble(scene, angles)
        n_rows = sum(5 if j["type"] == "revolute" else 6 for j in scene.joints)
        assert Ms.shape[0] == sum(b.n for b in scene.bodies) - n_rows
        assert zero_count_with_gap(Ms, Ks) == 6 + scene.nrevolute


def test_petsc_binary_and_matrix_market_bodies_are_identical(tmp_path):
    pytest.importorskip("petsc4py")
    a = ref.load_scene(frames.write_random_scene(str(tmp_path / "mtx"), 120, seed=7, fmt="mtx"))
    b = ref.load_scene(frames.write_random_scene(str(tmp_path / "petsc"), 120, seed=7, fmt="petsc"))
    assert os.path.exists(tmp_path / "petsc" / "body0_K.petsc")
    for ba, bb in zip(a.bodies, b.bodies):
        assert abs(ba.K - bb.K).max() <= 1e-15 * abs(ba.K).max()
        assert abs(ba.M - bb.M).max() <= 1e-15 * abs(ba.M).max()


def test_frame_body_scales_and_stays_free_free():
    """A larger body (sparse shift-invert): still exactly 6 zero modes, generated fast."""
    import time
    import scipy.sparse.linalg as sla
    t = time.perf_counter()
    body = frames.random_frame_body(6000, np.random.default_rng(4))
    assert time.perf_counter() - t < 5.0
    assert body.ndofs == 6000
    lam = np.sort(sla.eigsh(body.K, k=8, M=body.M, sigma=-1.0, return_eigenvectors=False))
    top = sla.eigsh(body.K, k=1, M=body.M, which="LA", return_eigenvectors=False)[0]
    assert np.sum(np.abs(lam) <= ref.RIGID_RTOL * top) == 6 and lam[6] > 1e3 * ref.RIGID_RTOL * top
