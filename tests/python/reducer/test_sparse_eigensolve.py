"""The sparse verification eigensolve (the block Krylov path by default, SLEPc's Krylov-Schur on the reduction's
factor with -kf_verify_eigen_method slepc, its vectors purified in one block solve; tests/python/reducer/
test_block_eigensolve.py compares the two). Small models forced through the sparse path (-kf_verify_dense_max_dofs 0): the full-order frequencies
against a dense SciPy eigensolve (M's null space condensed), on a free-free frame with rigid and mechanism modes at
two joint angles, a clamped beam, a beam with double bending frequencies (equal section inertias) and a frame whose
rotations are massless (M singular). Serially and on 2 ranks (which must agree with the serial run)."""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl
from petsc4py import PETSc

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import bc_models  # noqa: E402
import frames  # noqa: E402
import reference as ref  # noqa: E402

pytestmark = [pytest.mark.fast, pytest.mark.usefixtures("quiet_library")]
PROBE = os.path.join(SUPPORT, "sparse_eigen_probe.py")
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)


def dense_flexible_frequencies(M, K, rigid_rtol=1e-8):
    """Every finite flexible frequency (Hz, ascending) of (K, M) by SciPy: M's null space condensed statically (numpy
    eigh of M), the condensed pencil by scipy.linalg.eigh, the rigid and mechanism modes (|lambda| <= rigid_rtol
    times the largest) left out."""
    mu, U = np.linalg.eigh(0.5 * (M + M.T))
    null = mu <= 1e-8 * mu.max()
    Z, Y = U[:, null], U[:, ~null]
    T = Y - Z @ np.linalg.solve(Z.T @ K @ Z, Z.T @ K @ Y) if null.any() else Y
    Kc, Mc = T.T @ K @ T, T.T @ M @ T
    lam = sl.eigh(0.5 * (Kc + Kc.T), 0.5 * (Mc + Mc.T), eigvals_only=True)
    lam = lam[lam > rigid_rtol * np.abs(lam).max()]
    return np.sqrt(lam) / (2 * np.pi)


def clustered_beam():
    """The clamped cantilever of bc_models with equal section inertias: its bending frequencies in y and z pair up."""
    spec = bc_models.clamped_beam()
    pts = [(x, 0.0, 0.0) for x in np.linspace(0, 2.0, 11)]
    n = len(pts)
    K, M = np.zeros((6 * n, 6 * n)), np.zeros((6 * n, 6 * n))
    for e in range(n - 1):
        k, m = bc_models.beam_element(pts[e], pts[e + 1], Iy=3e-7, Iz=3e-7)
        K[6 * e:6 * e + 12, 6 * e:6 * e + 12] += k
        M[6 * e:6 * e + 12, 6 * e:6 * e + 12] += m
    M[6 * (n - 1):6 * (n - 1) + 3, 6 * (n - 1):6 * (n - 1) + 3] += 0.5 * np.eye(3)
    spec["bodies"]["beam"].update(mass=M, stiffness=K)
    spec["name"] = "clustered"
    return spec


def case(name, tmp):
    """(scene, [(M_S, K_S) per configuration]) of a named small model."""
    if name == "frame":
        path = frames.write_random_scene(str(tmp), 360, nbodies=3, ninputs=2, noutputs=2, seed=5, nangles=2)
        scene, dense = kryflex.load_scene(path), ref.load_scene(path)
        return scene, [ref.assemble(dense, a)[:2] for a in scene.configurations]
    spec = {"clamped": bc_models.clamped_beam, "clustered": clustered_beam, "lumped": bc_models.lumped_frame}[name]()
    Ms, Ks = bc_models.single_body_reference(spec)[:2]
    return kryflex.scene_from_dict(spec), [(Ms, Ks)]


def reduce_sparse(scene, **options):
    opts = PETSc.Options()
    values = dict(kf_verify_dense_max_dofs=0, **options)
    for k, v in values.items():
        opts.setValue(k, v)
    try:
        reducer = kryflex.Reducer(scene, quiet=True, search=False)
        reducer.reduce()
    finally:
        for k in values:
            opts.delValue(k)
    return reducer


@pytest.mark.parametrize("method", ["block", "slepc"])
@pytest.mark.parametrize("name", ["frame", "clamped", "clustered", "lumped"])
def test_sparse_eigensolve_against_dense_scipy(tmp_path, name, method):
    scene, systems = case(name, tmp_path)
    slepc = reduce_sparse(scene, kf_verify_eigen_method=method)
    for c, (Ms, Ks) in enumerate(systems):
        f_slepc = np.ravel(slepc.result(c, "full_frequencies_hz"))
        f_dense = dense_flexible_frequencies(np.asarray(Ms), np.asarray(Ks))
        n = f_slepc.size
        assert 0 < n <= f_dense.size, (n, f_dense.size)
        if name == "clustered":      # the pairs are there, each frequency twice
            assert np.sum(np.isclose(f_dense[1:n], f_dense[:n - 1], rtol=1e-9)) >= 3
        d_dense = np.abs(f_slepc / f_dense[:n] - 1).max()
        print("%s, configuration %d: %d modes; %s vs dense SciPy %.1e" % (name, c, n, method, d_dense))
        assert d_dense <= 1e-8


@pytest.mark.parametrize("name", ["frame", "clustered"])
def test_sampled_residual_check_matches_checking_every_application(tmp_path, name):
    """The eigensolve checks the residual of only some one-vector K+ applications; with -kf_refine_rtol 0 every
    sampled one is refined, which turns the check (and a refinement step) on for every application: both must give
    the reference of dense SciPy, and the same one."""
    scene, systems = case(name, tmp_path)
    sampled = reduce_sparse(scene)
    every = reduce_sparse(scene, kf_refine_rtol=0)
    for c, (Ms, Ks) in enumerate(systems):
        f1, f2 = np.ravel(sampled.result(c, "full_frequencies_hz")), np.ravel(every.result(c, "full_frequencies_hz"))
        f_dense = dense_flexible_frequencies(np.asarray(Ms), np.asarray(Ks))
        # the grids hold each reduced model's resonances too: compare at the frequencies both have
        w1, w2 = np.ravel(sampled.result(c, "frf_frequencies_hz")), np.ravel(every.result(c, "frf_frequencies_hz"))
        _, i1, i2 = np.intersect1d(w1, w2, return_indices=True)
        assert i1.size > 100
        T1, T2 = sampled.frf(c, "full")[i1], every.frf(c, "full")[i2]
        print("%s, configuration %d: sampled vs every application checked: frequencies %.1e, reference %.1e of the "
              "peak; sampled vs dense SciPy %.1e" % (name, c, np.abs(f1 / f2 - 1).max(),
                                                    np.abs(T1 - T2).max() / np.abs(T2).max(),
                                                    np.abs(f1 / f_dense[:f1.size] - 1).max()))
        assert f1.size == f2.size > 0
        assert np.abs(f1 / f_dense[:f1.size] - 1).max() <= 1e-8
        assert np.allclose(f1, f2, rtol=1e-9, atol=0)
        assert np.abs(T1 - T2).max() <= 1e-8 * np.abs(T2).max()


@pytest.mark.mpi
def test_sparse_eigensolve_two_ranks_agree_with_one(tmp_path):
    path = frames.write_random_scene(str(tmp_path), 360, nbodies=3, ninputs=2, noutputs=2, seed=5, nangles=2)
    serial = reduce_sparse(kryflex.load_scene(path))
    out = tmp_path / "two.npz"
    p = subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, path, str(out)],
                       env=ENV, capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stdout + p.stderr[-3000:]
    two = np.load(out)
    dense = ref.load_scene(path)
    for c, angles in enumerate(serial.configurations):
        f1, f2 = np.ravel(serial.result(c, "full_frequencies_hz")), two["f%d" % c]
        f_dense = dense_flexible_frequencies(*ref.assemble(dense, angles)[:2])
        assert f1.size == f2.size > 0
        T1, T2 = serial.frf(c, "full"), two["T%d" % c]
        print("configuration %d: 2 ranks vs 1: frequencies %.1e, reference response %.1e of the peak; 2 ranks vs "
              "dense SciPy %.1e" % (c, np.abs(f2 / f1 - 1).max(), np.abs(T2 - T1).max() / np.abs(T1).max(),
                                    np.abs(f2 / f_dense[:f2.size] - 1).max()))
        assert np.allclose(f2, f1, rtol=1e-9, atol=0)
        assert np.abs(f2 / f_dense[:f2.size] - 1).max() <= 1e-8
        assert np.abs(T2 - T1).max() <= 1e-8 * np.abs(T1).max()


def cut_scene(tmp_path):
    """The frame with the cover's cut between its 6th and 7th flexible modes at the first angle (from dense SciPy):
    (scene path, -kf_verify_cover value, the dense frequencies per configuration)."""
    path = frames.write_random_scene(str(tmp_path), 360, nbodies=3, ninputs=2, noutputs=2, seed=5, nangles=2)
    scene, dense = kryflex.load_scene(path), ref.load_scene(path)
    f_dense = [dense_flexible_frequencies(*ref.assemble(dense, a)[:2]) for a in scene.configurations]
    cut = np.sqrt(f_dense[0][5] * f_dense[0][6])
    return path, cut / scene.band[1], f_dense


def test_sparse_eigensolve_stops_at_the_cut(tmp_path):
    """The automatic count: the eigensolve stops once its modes reach cover x the band's top, and the reference keeps
    the modes up to the first at or above the cut (the rest by its residual), each against dense SciPy; its response
    against the dense modal one to the reference's 1e-6 of the peak."""
    path, cover, f_dense = cut_scene(tmp_path)
    scene = kryflex.load_scene(path)
    red = reduce_sparse(scene, kf_verify_cover=cover)
    cut = cover * scene.band[1]
    dense = ref.load_scene(path)
    for c, angles in enumerate(red.configurations):
        f = np.ravel(red.result(c, "full_frequencies_hz"))
        below = int(np.sum(f_dense[c] < cut))
        w = 2 * np.pi * np.ravel(red.result(c, "frf_frequencies_hz"))
        exact = ref.modal_frf(*ref.assemble(dense, angles), w, scene.damping)
        err = np.abs(red.frf(c, "full") - exact).max() / np.abs(exact).max()
        print("configuration %d: cut %.4g Hz, %d modes (dense SciPy: %d below the cut), reference vs dense %.1e of "
              "the peak" % (c, cut, f.size, below, err))
        assert f.size == below + 1 and f[-1] >= cut > f[-2]
        assert np.abs(f / f_dense[c][:f.size] - 1).max() <= 1e-8
        assert err <= 1e-6


@pytest.mark.mpi
def test_sparse_eigensolve_stops_at_the_cut_two_ranks(tmp_path):
    path, cover, _ = cut_scene(tmp_path)
    serial = reduce_sparse(kryflex.load_scene(path), kf_verify_cover=cover)
    out = tmp_path / "two.npz"
    p = subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, path, str(out), "-kf_verify_cover", repr(cover)],
                       env=ENV, capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stdout + p.stderr[-3000:]
    two = np.load(out)
    for c in range(len(serial.configurations)):
        f1, f2 = np.ravel(serial.result(c, "full_frequencies_hz")), two["f%d" % c]
        T1, T2 = serial.frf(c, "full"), two["T%d" % c]
        assert f1.size == f2.size and np.allclose(f2, f1, rtol=1e-9, atol=0)
        assert np.abs(T2 - T1).max() <= 1e-8 * np.abs(T1).max()


def block_and_single(scene, **options):
    """The same scene's reference by Krylov-Schur (single K+ applications) and by subspace iteration (K+ applied to
    blocks through the flexible solver's block solve)."""
    return (reduce_sparse(scene, kf_verify_eigen_method="slepc", kf_verify_eps_type="krylovschur", **options),
            reduce_sparse(scene, kf_verify_eigen_method="slepc", kf_verify_eps_type="subspace", **options))


# the free beam's modes are all pairs: the cut's rule (the modes up to the first at or above the cut) keeps one of a
# pair, which either solver may pick, and the residual term then differs by ~1e-9 of the peak; 8 modes keep 4 pairs
BLOCK_CASES = {"free_clustered": dict(kf_verify_modes=8), "frame": {}}


def common_grid(fa, Ta, fb, Tb):
    """Two responses on the frequencies their grids share (a grid holds points across each run's resonances)."""
    common, ia, ib = np.intersect1d(np.round(fa, 9), np.round(fb, 9), return_indices=True)
    assert common.size >= 0.9 * min(fa.size, fb.size), (common.size, fa.size, fb.size)
    return Ta[ia], Tb[ib]


def assert_two_ranks_agree(serial, builder, out, options, label):
    """bc_models.<builder> reduced on 2 ranks with the -kf_ options given (a list of words) against the serial
    reduction: the same modes (1e-9) and reference response (1e-9 of the peak)."""
    p = subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, "bc_models:" + builder, str(out)] + list(options),
                       env=ENV, capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stdout + p.stderr[-3000:]
    two = np.load(out)
    f1, f2 = np.ravel(serial.result(0, "full_frequencies_hz")), two["f0"]
    T1, T2 = common_grid(np.ravel(serial.result(0, "frf_frequencies_hz")), serial.frf(0, "full"), two["w0"], two["T0"])
    print("%s: frequencies %.1e, response %.1e of the peak"
          % (label, np.abs(f2 / f1 - 1).max(), np.abs(T2 - T1).max() / np.abs(T1).max()))
    assert f1.size == f2.size > 0 and np.allclose(f2, f1, rtol=1e-9, atol=0)
    assert np.abs(T2 - T1).max() <= 1e-9 * np.abs(T1).max()


@pytest.mark.parametrize("name", sorted(BLOCK_CASES))
def test_block_eigensolve_matches_krylov_schur(tmp_path, name):
    """Subspace iteration with block K+ applications gives Krylov-Schur's modes and reference response (1e-9), both
    against dense SciPy; on the free beam with double frequencies the pairs are all there."""
    if name == "frame":
        scene, systems = case("frame", tmp_path)
    else:
        spec = bc_models.free_clustered_beam()
        scene, systems = kryflex.scene_from_dict(spec), [bc_models.single_body_reference(spec)[:2]]
    ks, sub = block_and_single(scene, **BLOCK_CASES[name])
    for c, (Ms, Ks) in enumerate(systems):
        f1, f2 = np.ravel(ks.result(c, "full_frequencies_hz")), np.ravel(sub.result(c, "full_frequencies_hz"))
        f_dense = dense_flexible_frequencies(np.asarray(Ms), np.asarray(Ks))
        T1, T2 = common_grid(np.ravel(ks.result(c, "frf_frequencies_hz")), ks.frf(c, "full"),
                             np.ravel(sub.result(c, "frf_frequencies_hz")), sub.frf(c, "full"))
        dT = np.abs(T2 - T1).max() / np.abs(T1).max()
        print("%s, configuration %d: %d and %d modes; subspace vs Krylov-Schur: frequencies %.1e, response %.1e of "
              "the peak; subspace vs dense SciPy %.1e" % (name, c, f1.size, f2.size, np.abs(f2[:f1.size] / f1 - 1).max(),
                                                          dT, np.abs(f2 / f_dense[:f2.size] - 1).max()))
        assert f1.size == f2.size > 0
        if name == "free_clustered":
            assert np.sum(np.isclose(f_dense[1:f2.size], f_dense[:f2.size - 1], rtol=1e-9)) >= 3
        assert np.abs(f2 / f1 - 1).max() <= 1e-9
        assert np.abs(f2 / f_dense[:f2.size] - 1).max() <= 1e-8
        assert dT <= 1e-9


@pytest.mark.mpi
def test_block_eigensolve_two_ranks(tmp_path):
    """Subspace iteration on 2 ranks against Krylov-Schur on 1: the same modes and reference response (1e-9)."""
    serial = reduce_sparse(kryflex.scene_from_dict(bc_models.free_clustered_beam()), kf_verify_eigen_method="slepc",
                           kf_verify_eps_type="krylovschur", kf_verify_modes=8)
    assert_two_ranks_agree(serial, "free_clustered_beam", tmp_path / "two.npz",
                           ["-kf_verify_eigen_method", "slepc", "-kf_verify_eps_type", "subspace", "-kf_verify_modes", "8"],
                           "2 ranks subspace vs 1 rank Krylov-Schur")


def test_eigensolver_needing_a_preconditioner_is_refused(tmp_path):
    """A SLEPc solver that would take K+ as a preconditioner instead of the shift-and-invert operator (LOBPCG: its
    residual K x - lambda M x has a rounding floor above the reference's tolerance, and its block Gram matrix broke
    down with the exact K+ on the 57k solid) is refused by name with the types that work."""
    scene, _ = case("frame", tmp_path)
    with pytest.raises(Exception, match=r"-kf_verify_eps_type lobpcg: .*krylovschur.*subspace"):
        reduce_sparse(scene, kf_verify_eigen_method="slepc", kf_verify_eps_type="lobpcg")
