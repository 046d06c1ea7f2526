"""The verification's block Krylov eigensolve (-kf_verify_eigen_method block, the default on the sparse path: Ritz
pairs of a block Krylov space of K+ M started from the inputs, outputs and random columns), against dense SciPy and
against SLEPc's Krylov-Schur (-kf_verify_eigen_method slepc): on a free-free beam with double bending frequencies, a
clamped beam, a clamped beam with paired frequencies and a free frame with a mechanism at two angles; on 2 ranks
against 1; with damping matrices (Galileo) against the dense damped direct solve; and its fall back to Krylov-Schur
when it has not converged within its cap of blocks. On models with massless dofs (a frame whose rotations carry no
mass; a stick aircraft with lumped masses, some offset, exported as a DMIG punch and read back: M singular beyond its
zero diagonal) the block path converges without falling back, to the dense reference with M's null space condensed
by SciPy here."""
import os
import re
import subprocess
import sys

import numpy as np
import pytest
from petsc4py import PETSc

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
sys.path.insert(0, HERE)
import bc_models  # noqa: E402
import reference as ref  # noqa: E402
from test_sparse_eigensolve import assert_two_ranks_agree, case, common_grid, dense_flexible_frequencies  # noqa: E402
from test_sparse_eigensolve import reduce_sparse as sparse_reduction  # noqa: E402

pytestmark = [pytest.mark.fast, pytest.mark.usefixtures("quiet_library")]


def reduce_sparse(scene, method, **options):
    """The scene reduced with the sparse verification path and the eigensolve method named."""
    return sparse_reduction(scene, kf_verify_eigen_method=method, **options)


def model(name, tmp_path):
    """(scene, [(M_S, K_S) per configuration], options): the free beam keeps 8 modes (4 whole pairs: the cut's rule
    would keep one vector of a pair, which two solvers may pick differently)."""
    if name == "free_clustered":
        spec = bc_models.free_clustered_beam()
        return kryflex.scene_from_dict(spec), [bc_models.single_body_reference(spec)[:2]], dict(kf_verify_modes=8)
    scene, systems = case(name, tmp_path)
    return scene, systems, {}


@pytest.mark.parametrize("name", ["free_clustered", "clamped", "clustered", "frame"])
def test_block_eigensolve_against_slepc_and_dense(tmp_path, name):
    """The block path's frequencies against dense SciPy (1e-9) and Krylov-Schur's (1e-9), its reference response
    against Krylov-Schur's (1e-9 of the peak); on the paired models the pairs are all there."""
    scene, systems, options = model(name, tmp_path)
    block, slepc = reduce_sparse(scene, "block", **options), reduce_sparse(scene, "slepc", **options)
    for c, (Ms, Ks) in enumerate(systems):
        fb, fs = np.ravel(block.result(c, "full_frequencies_hz")), np.ravel(slepc.result(c, "full_frequencies_hz"))
        f_dense = dense_flexible_frequencies(np.asarray(Ms), np.asarray(Ks))
        Tb, Ts = common_grid(np.ravel(block.result(c, "frf_frequencies_hz")), block.frf(c, "full"),
                             np.ravel(slepc.result(c, "frf_frequencies_hz")), slepc.frf(c, "full"))
        dT = np.abs(Tb - Ts).max() / np.abs(Ts).max()
        d_dense = np.abs(fb / f_dense[:fb.size] - 1).max()
        print("%s, configuration %d: %d modes (Krylov-Schur %d); block vs dense SciPy %.1e, vs Krylov-Schur: "
              "frequencies %.1e, response %.1e of the peak" % (name, c, fb.size, fs.size, d_dense,
                                                               np.abs(fb[:fs.size] / fs - 1).max(), dT))
        assert fb.size == fs.size > 0
        if name in ("free_clustered", "clustered"):
            assert np.sum(np.isclose(f_dense[1:fb.size], f_dense[:fb.size - 1], rtol=1e-9)) >= 3
        assert d_dense <= 1e-9
        assert np.abs(fb / fs - 1).max() <= 1e-9
        assert dT <= 1e-9


@pytest.mark.parametrize("name", ["free_clustered", "clamped"])
def test_block_reference_against_dense_response(tmp_path, name):
    """The block path's reference response (its modes, the rigid ones, the residual of the modes not computed) against
    the dense modal response with every mode (SciPy) to 1e-9 of the peak where every flexible mode is asked for,
    so that no residual is approximated."""
    spec = bc_models.free_clustered_beam() if name == "free_clustered" else bc_models.clamped_beam()
    scene = kryflex.scene_from_dict(spec)
    Ms, Ks, G, H = bc_models.single_body_reference(spec)[:4]
    f_dense = dense_flexible_frequencies(np.asarray(Ms), np.asarray(Ks))
    red = reduce_sparse(scene, "block", kf_verify_modes=f_dense.size)
    w = 2 * np.pi * np.ravel(red.result(0, "frf_frequencies_hz"))
    exact = ref.modal_frf(np.asarray(Ms), np.asarray(Ks), np.asarray(G), np.asarray(H), w, scene.damping)
    T = red.frf(0, "full")
    err = np.abs(T - exact).max() / np.abs(exact).max()
    f = np.ravel(red.result(0, "full_frequencies_hz"))
    print("%s: %d of %d modes, frequencies vs dense %.1e, reference response vs dense modal %.1e of the peak"
          % (name, f.size, f_dense.size, np.abs(f / f_dense[:f.size] - 1).max(), err))
    assert f.size == f_dense.size
    assert np.abs(f / f_dense - 1).max() <= 1e-9
    assert err <= 1e-9


@pytest.mark.mpi
@pytest.mark.parametrize("name", ["free_clustered", "clamped"])
def test_block_eigensolve_two_ranks(tmp_path, name):
    """The block path on 2 ranks (its random columns the same on any rank count) against Krylov-Schur on 1."""
    scene, _, options = model(name, tmp_path)
    serial = reduce_sparse(scene, "slepc", **options)
    builder = "free_clustered_beam" if name == "free_clustered" else "clamped_beam"
    extra = [x for k, v in options.items() for x in ("-" + k, str(v))]
    assert_two_ranks_agree(serial, builder, tmp_path / "two.npz", ["-kf_verify_eigen_method", "block"] + extra,
                           "%s: 2 ranks block vs 1 rank Krylov-Schur" % name)


def test_block_eigensolve_with_damping_matrices():
    """Galileo with damping matrices forced through the sparse path: the block path's modes coupled by [Phi_r Phi]^T C
    [Phi_r Phi] against the dense damped direct solve, as the Krylov-Schur path (test_damping.py), and against it."""
    import test_damping as td
    mats = td.damping_matrices()
    damping = {"modal": 0.002, "rayleigh": {"alpha": 0.01, "beta": 0.0}, "structural": 0.003}
    errs = {}
    for method in ("block", "slepc"):
        opts = PETSc.Options()
        opts.setValue("kf_verify_eigen_method", method)
        try:
            _, _, err_red, err_full = td.reduce_and_check(td.galileo_spec(damping, mats), damping, mats,
                                                         verify_dense_max_dofs=0)
        finally:
            opts.delValue("kf_verify_eigen_method")
        errs[method] = err_full
    print("damping matrices, reference vs dense damped direct solve: block %.2e, Krylov-Schur %.2e" % (
        errs["block"], errs["slepc"]))
    assert errs["block"] <= 1e-5


def reduce_logged(scene, log, **options):
    """(reducer, progress text): the scene reduced on the sparse path with the options given, its progress lines
    (printed by the C library on rank 0's stdout) captured in the file log."""
    opts = PETSc.Options()
    values = dict(kf_verify_dense_max_dofs=0, kf_quiet=False, **options)
    for k, v in values.items():
        opts.setValue(k, v)
    fd, saved = sys.stdout.fileno(), os.dup(sys.stdout.fileno())
    try:
        with open(log, "w") as f:
            os.dup2(f.fileno(), fd)
            reducer = kryflex.Reducer(scene, quiet=False, search=False)
            reducer.reduce()
    finally:
        os.dup2(saved, fd)
        os.close(saved)
        opts.setValue("kf_quiet", True)
        for k in values:
            if k != "kf_quiet":
                opts.delValue(k)
    return reducer, log.read_text()


def test_block_eigensolve_falls_back_to_krylov_schur(tmp_path):
    """Capped at one block the block path does not converge: Krylov-Schur takes the configuration, the progress
    line says so, and the reference is Krylov-Schur's."""
    scene, systems, _ = model("frame", tmp_path)
    capped, text = reduce_logged(scene, tmp_path / "progress.txt", kf_verify_eigen_method="block",
                                 kf_verify_eigen_max_blocks=1)
    slepc = reduce_sparse(scene, "slepc")
    # every configuration's reference (the angles and the midpoint) fell back, and only those
    assert text.count("did not converge") == text.count("(Krylov-Schur, shift-and-invert") >= len(systems), text[-2000:]
    assert "Krylov-Schur (SLEPc) instead" in text and "block Krylov of K+ M" not in text
    for c in range(len(systems)):
        f1, f2 = np.ravel(capped.result(c, "full_frequencies_hz")), np.ravel(slepc.result(c, "full_frequencies_hz"))
        assert f1.size == f2.size and np.allclose(f1, f2, rtol=1e-12, atol=0)


def test_block_eigensolve_cap_follows_the_modes_asked(tmp_path):
    """More modes asked than 12 blocks can hold (100 flexible modes of the 360-dof frame, blocks of 7 columns: 12
    blocks and the start hold 91): with the cap's default (sized from the modes asked) every configuration converges
    on the block path, its frequencies dense SciPy's (1e-9), the progress line stating the blocks and the cap; capped
    at 12 blocks they fall back to Krylov-Schur, whose frequencies the block path's are (1e-9)."""
    scene, systems, _ = model("frame", tmp_path)
    nev = 100
    auto, text = reduce_logged(scene, tmp_path / "auto.txt", kf_verify_eigen_method="block", kf_verify_modes=nev)
    capped, text12 = reduce_logged(scene, tmp_path / "capped.txt", kf_verify_eigen_method="block",
                                   kf_verify_modes=nev, kf_verify_eigen_max_blocks=12)
    lines = [l for l in text.splitlines() if "block Krylov of K+ M" in l]
    print("\n".join(lines))
    assert "Krylov-Schur (SLEPc) instead" not in text, text[-2000:]
    assert len(lines) >= len(systems)
    for l in lines:  # blocks used above the old default, within the cap stated
        used, b, cap = (int(x) for x in re.search(r"(\d+) blocks of (\d+) columns, at most (\d+)\)", l).groups())
        assert 12 < used <= cap and b == 7
    assert text12.count("did not converge") == text12.count("(Krylov-Schur, shift-and-invert") >= len(systems)
    assert "(its cap 12)" in text12 and "block Krylov of K+ M" not in text12
    for c, (Ms, Ks) in enumerate(systems):
        f, f12 = np.ravel(auto.result(c, "full_frequencies_hz")), np.ravel(capped.result(c, "full_frequencies_hz"))
        f_dense = dense_flexible_frequencies(np.asarray(Ms), np.asarray(Ks))
        print("configuration %d: %d modes, block vs dense SciPy %.1e, vs Krylov-Schur %.1e" % (
            c, f.size, np.abs(f / f_dense[:f.size] - 1).max(), np.abs(f / f12 - 1).max()))
        assert f.size == f12.size == nev
        assert np.abs(f / f_dense[:nev] - 1).max() <= 1e-9
        assert np.abs(f / f12 - 1).max() <= 1e-9


@pytest.mark.mpi
def test_block_eigensolve_cap_follows_the_modes_asked_two_ranks(tmp_path):
    """The 100 modes above on 2 ranks with the cap's default, the arrays grown from the start block
    (-kf_verify_eigen_first_mb 0; the serial run allocates them once): every configuration on the block path (its
    -info line: the cap sized from the modes asked, 100 returned), the same frequencies and reference response as 1
    rank (1e-9)."""
    from test_sparse_eigensolve import ENV, PROBE
    scene, systems, _ = model("frame", tmp_path)
    serial = reduce_sparse(scene, "block", kf_verify_modes=100)
    path = os.path.join(str(tmp_path), "scene.yaml")
    out = tmp_path / "two.npz"
    p = subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, path, str(out), "-kf_verify_eigen_method",
                        "block", "-kf_verify_modes", "100", "-kf_verify_eigen_first_mb", "0", "-info", ":sys"],
                       env=ENV, capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stdout + p.stderr[-3000:]
    info = re.findall(r"block Krylov, 7 columns per block, cap (\d+) blocks for 100 modes asked, \d+ Ritz pairs, "
                      r"(\d+) returned", p.stdout)
    steps = [int(x) for x in re.findall(r"allocated in (\d+) steps", p.stdout)]
    print(info, steps)
    assert len(info) >= len(systems) and all(int(cap) > 12 and ret == "100" for cap, ret in info), p.stdout[-3000:]
    assert len(steps) == len(info) and min(steps) >= 3
    two = np.load(out)
    for c in range(len(systems)):
        f1, f2 = np.ravel(serial.result(c, "full_frequencies_hz")), two["f%d" % c]
        T1, T2 = common_grid(np.ravel(serial.result(c, "frf_frequencies_hz")), serial.frf(c, "full"),
                             two["w%d" % c], two["T%d" % c])
        print("configuration %d: 2 ranks vs 1, frequencies %.1e, response %.1e of the peak" % (
            c, np.abs(f2 / f1 - 1).max(), np.abs(T2 - T1).max() / np.abs(T1).max()))
        assert f1.size == f2.size == 100 and np.allclose(f2, f1, rtol=1e-9, atol=0)
        assert np.abs(T2 - T1).max() <= 1e-9 * np.abs(T1).max()


BLOCK_INFO = re.compile(r"eigensolve: (\d+) iterations, .*block Krylov, (\d+) columns per block, cap (\d+) blocks .*"
                        r"arrays for (\d+) of the cap's (\d+) columns, allocated in (\d+) steps\)")


def probe_one_rank(path, out, options):
    """(the probe's npz, [(blocks, columns per block, cap, columns allocated, the cap's columns, steps)] from the block
    eigensolve's -info lines): the scene reduced on 1 rank by the sparse probe with the options given"""
    from test_sparse_eigensolve import ENV, PROBE
    p = subprocess.run([sys.executable, PROBE, path, str(out), "-info", ":sys"] + options, env=ENV,
                       capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, p.stdout + p.stderr[-3000:]
    return np.load(out), [tuple(int(x) for x in m) for m in BLOCK_INFO.findall(p.stdout)]


def test_block_eigensolve_arrays_grow_with_the_basis(tmp_path):
    """The block path's arrays (V, M V, K+ M V, the projection) are allocated as its basis grows, at least doubling,
    from the start block on with -kf_verify_eigen_first_mb 0 (the default first allocation, 32 MB, holds the whole
    cap of a model this small). Forced to many blocks (100 modes of the 360-dof frame, blocks of 7 columns: 44
    blocks, the basis filling the system) they grow in several steps and every mode is dense SciPy eigh's (1e-9).
    With a cap far above the blocks used (500 blocks, the modes to the cut) the arrays are those of the blocks used,
    well below the cap's, and the reference, frequencies and response, is the automatic cap's bit for bit, and the
    default first allocation's."""
    scene, systems, _ = model("frame", tmp_path)
    path = os.path.join(str(tmp_path), "scene.yaml")
    words = ["-kf_verify_eigen_method", "block", "-kf_verify_eigen_first_mb", "0"]
    many, info_many = probe_one_rank(path, tmp_path / "many.npz", words + ["-kf_verify_modes", "100"])
    auto, info = probe_one_rank(path, tmp_path / "auto.npz", words)
    far, info_far = probe_one_rank(path, tmp_path / "far.npz", words + ["-kf_verify_eigen_max_blocks", "500"])
    first, info_first = probe_one_rank(path, tmp_path / "first.npz", words[:2])
    print("(blocks, columns per block, cap, columns allocated, the cap's columns, steps)\n100 modes: %s\n"
          "to the cut, automatic cap: %s\nto the cut, cap 500: %s\nto the cut, first allocation 32 MB: %s"
          % (info_many, info, info_far, info_first))
    assert len(info_many) == len(info) == len(info_far) == len(info_first) >= len(systems)
    for blocks, b, cap, ld, capcols, steps in info_many:  # grown from the start block, within the cap
        assert 12 < blocks <= cap and b == 7 and steps >= 3 and (blocks + 1) * b <= 2 * ld and ld <= capcols
    for (blocks, _, cap, ld, capcols, steps), (blocks_far, _, cap_far, ld_far, capcols_far, _) in zip(info, info_far):
        assert blocks == blocks_far < cap < cap_far == 500 and steps >= 2
        assert ld <= capcols and ld_far <= 2 * (blocks + 1) * 7 and 2 * ld_far <= capcols_far  # the blocks used
    for (_, _, _, ld, capcols, steps), (_, _, _, ld_first, _, steps_first) in zip(info, info_first):
        assert ld_first == capcols and steps_first == 1  # the whole cap at once, its pages touched as written
    for c, (Ms, Ks) in enumerate(systems):
        f = many["f%d" % c]
        f_dense = dense_flexible_frequencies(np.asarray(Ms), np.asarray(Ks))
        print("configuration %d: %d modes, vs dense SciPy eigh %.1e"
              % (c, f.size, np.abs(f / f_dense[:f.size] - 1).max()))
        assert f.size == 100 and np.abs(f / f_dense[:f.size] - 1).max() <= 1e-9
        assert auto["f%d" % c].size > 0
        for key in ("f%d", "T%d", "w%d"):
            assert np.array_equal(auto[key % c], far[key % c]) and np.array_equal(auto[key % c], first[key % c])


def test_bad_block_options(tmp_path):
    """A bad method or count is refused before any work, naming the option."""
    scene, _, _ = model("clamped", tmp_path)
    for k, v, msg in (("kf_verify_eigen_method", "lanczos", "kf_verify_eigen_method"),
                      ("kf_verify_eigen_random", -1, "kf_verify_eigen_random"),
                      ("kf_verify_eigen_max_blocks", 0, "kf_verify_eigen_max_blocks"),
                      ("kf_verify_eigen_max_blocks", -2, "kf_verify_eigen_max_blocks"),
                      ("kf_verify_eigen_first_mb", -1, "kf_verify_eigen_first_mb")):
        with pytest.raises(Exception, match=msg):
            reduce_sparse(scene, "block", **{k: v})


@pytest.mark.parametrize("name", ["free_clustered", "clamped"])
def test_block_eigensolve_wide_blocks_deflate_to_dense(tmp_path, name):
    """Blocks wider than the small beams' flexible space can fill (12 random columns): each block is rotated after its
    Gram-Schmidt passes and its dependent columns are dropped by their M-norm before the passes, recovered from the
    passes' coefficients. The space runs out within a few blocks; every flexible mode asked for is dense SciPy's
    (1e-9), and the wide-block reference response is the default block's (1e-9 of the peak)."""
    scene, systems, options = model(name, tmp_path)
    wide = reduce_sparse(scene, "block", kf_verify_eigen_random=12, **options)
    narrow = reduce_sparse(scene, "block", **options)
    Ms, Ks = systems[0]
    f_dense = dense_flexible_frequencies(np.asarray(Ms), np.asarray(Ks))
    fw, fn = np.ravel(wide.result(0, "full_frequencies_hz")), np.ravel(narrow.result(0, "full_frequencies_hz"))
    Tw, Tn = common_grid(np.ravel(wide.result(0, "frf_frequencies_hz")), wide.frf(0, "full"),
                         np.ravel(narrow.result(0, "frf_frequencies_hz")), narrow.frf(0, "full"))
    print("%s: %d modes with 12 random columns, vs dense SciPy %.1e, vs 3 random columns %.1e, response %.1e" % (
        name, fw.size, np.abs(fw / f_dense[:fw.size] - 1).max(), np.abs(fw[:fn.size] / fn - 1).max(),
        np.abs(Tw - Tn).max() / np.abs(Tn).max()))
    assert fw.size == fn.size > 0
    assert np.abs(fw / f_dense[:fw.size] - 1).max() <= 1e-9
    assert np.abs(Tw - Tn).max() <= 1e-9 * np.abs(Tn).max()


@pytest.mark.mpi
def test_block_eigensolve_wide_blocks_two_ranks(tmp_path):
    """The wide blocks above on 2 ranks against 1: the rotation's Gram matrix and the dropped columns the same."""
    scene, _, options = model("clamped", tmp_path)
    serial = reduce_sparse(scene, "block", kf_verify_eigen_random=12, **options)
    assert_two_ranks_agree(serial, "clamped_beam", tmp_path / "two.npz",
                           ["-kf_verify_eigen_method", "block", "-kf_verify_eigen_random", "12"],
                           "clamped, 12 random columns: 2 ranks vs 1")


def massless_model(name, folder):
    """(spec, M, K, G, H, rigid modes) of a model with massless dofs: 'lumped_frame' (bc_models.lumped_frame: lumped
    translational masses, every rotation massless, zero rows of M), 'aircraft' (bc_models.lumped_aircraft written as
    a long-field DMIG punch and read back by kryflex's Nastran reader, as test_reference_truth.py does: massless wing
    tips and fin, masses offset from their nodes, so M is singular beyond its zero diagonal and rounded as exported)
    or 'lumped_aircraft' (the same before the export, as assembled)."""
    import reference_truth_probe as probe
    spec = probe.plate_spec("aircraft", str(folder)) if name == "aircraft" else getattr(bc_models, name)()
    M, K, G, H = bc_models.layout_reference(spec)
    return spec, np.asarray(M), np.asarray(K), np.asarray(G), np.asarray(H), 6


@pytest.mark.parametrize("name", ["lumped_frame", "aircraft"])
def test_block_eigensolve_massless_against_condensed_scipy(tmp_path, name):
    """Every flexible mode asked for (no residual term to approximate): the block path converges (the progress line
    says block Krylov, no fall back), its frequencies are dense SciPy's with M's null space condensed (1e-9) and its
    reference response the condensed modal response with the static flexibility of M's null space (1e-9 of the
    peak). The default run (the modes to the cut) takes the block path too, with dense SciPy's frequencies (1e-9) and
    Krylov-Schur's reference response (1e-9 of the peak)."""
    from test_reference_truth import scipy_frf
    spec, M, K, G, H, nrigid = massless_model(name, tmp_path)
    scene = kryflex.scene_from_dict(spec)
    f_dense = dense_flexible_frequencies(M, K)
    assert np.count_nonzero(np.diag(M) == 0) > 0
    every, text = reduce_logged(scene, tmp_path / "every.txt", kf_verify_eigen_method="block",
                                kf_verify_modes=f_dense.size)
    cut, text_cut = reduce_logged(scene, tmp_path / "cut.txt", kf_verify_eigen_method="block")
    slepc = reduce_sparse(scene, "slepc")
    f = np.ravel(every.result(0, "full_frequencies_hz"))
    w = np.ravel(every.result(0, "frf_frequencies_hz"))
    exact, _ = scipy_frf(M, K, G, H, w, scene.damping, nrigid)
    err = np.abs(every.frf(0, "full") - exact).max() / np.abs(exact).max()
    fc = np.ravel(cut.result(0, "full_frequencies_hz"))
    Tc, Ts = common_grid(np.ravel(cut.result(0, "frf_frequencies_hz")), cut.frf(0, "full"),
                         np.ravel(slepc.result(0, "frf_frequencies_hz")), slepc.frf(0, "full"))
    dT = np.abs(Tc - Ts).max() / np.abs(Ts).max()
    print("%s: %d massless dofs, M's null space %d; every mode: %d of %d, frequencies vs condensed SciPy %.1e, "
          "response %.1e of the peak; to the cut: %d modes, vs SciPy %.1e, response vs Krylov-Schur %.1e"
          % (name, np.count_nonzero(np.diag(M) == 0), len(M) - nrigid - f_dense.size, f.size, f_dense.size,
             np.abs(f / f_dense - 1).max(), err, fc.size, np.abs(fc / f_dense[:fc.size] - 1).max(), dT))
    for t in (text, text_cut):
        assert "block Krylov of K+ M" in t and "Krylov-Schur (SLEPc) instead" not in t, t[-2000:]
    assert f.size == f_dense.size
    assert np.abs(f / f_dense - 1).max() <= 1e-9
    assert err <= 1e-9
    assert 0 < fc.size == np.ravel(slepc.result(0, "full_frequencies_hz")).size
    assert np.abs(fc / f_dense[:fc.size] - 1).max() <= 1e-9
    assert dT <= 1e-9


@pytest.mark.mpi
@pytest.mark.parametrize("builder", ["lumped_frame", "lumped_aircraft"])
def test_block_eigensolve_massless_two_ranks(tmp_path, builder):
    """The block path on the massless models on 2 ranks against 1 (the serial run on the block path, not fallen
    back): the same modes and reference response (1e-9)."""
    spec = massless_model(builder, tmp_path)[0]
    serial, text = reduce_logged(kryflex.scene_from_dict(spec), tmp_path / "one.txt", kf_verify_eigen_method="block")
    assert "block Krylov of K+ M" in text and "Krylov-Schur (SLEPc) instead" not in text, text[-2000:]
    assert_two_ranks_agree(serial, builder, tmp_path / "two.npz", ["-kf_verify_eigen_method", "block"],
                           "%s: 2 ranks vs 1, block path" % builder)


def rigid_offset_model():
    """(spec, M, K, G, H) of bc_models.rigid_offset_frame: the lumped frame with its rigid elements eliminated, M as
    singular as the lumped frame's (45 of 90 dofs in its null space) but with no zero diagonal."""
    spec = bc_models.rigid_offset_frame()
    M, K, G, H = (np.asarray(x) for x in bc_models.layout_reference(spec))
    mu = np.linalg.eigvalsh(M)
    assert np.diag(M).min() > 0 and np.count_nonzero(mu <= 1e-8 * mu.max()) == 45
    return spec, M, K, G, H


def test_block_eigensolve_singular_mass_without_zero_diagonal(tmp_path):
    """A mass singular with no zero diagonal (rigid elements eliminated: M = T^T M T): the block path's start is
    purified as with massless dofs, so it converges to the cut without falling back to Krylov-Schur (it did before:
    not converged in 9 blocks), its frequencies dense SciPy's with M's null space condensed (1e-9), its reference
    response Krylov-Schur's (1e-9 of the peak); the reduction meets its target against SciPy's response."""
    from test_reference_truth import scipy_frf
    spec, M, K, G, H = rigid_offset_model()
    scene = kryflex.scene_from_dict(spec)
    block, text = reduce_logged(scene, tmp_path / "block.txt", kf_verify_eigen_method="block")
    slepc = reduce_sparse(scene, "slepc")
    f_dense = dense_flexible_frequencies(M, K)
    fb = np.ravel(block.result(0, "full_frequencies_hz"))
    Tb, Ts = common_grid(np.ravel(block.result(0, "frf_frequencies_hz")), block.frf(0, "full"),
                         np.ravel(slepc.result(0, "frf_frequencies_hz")), slepc.frf(0, "full"))
    w = np.ravel(block.result(0, "frf_frequencies_hz"))
    exact, _ = scipy_frf(M, K, G, H, w, scene.damping, 6)
    reduced = np.asarray(block.reduce().model.at([]).frf(w)).reshape(exact.shape)
    err = bc_models.hinf_error(exact, reduced)
    print("rigid offset frame: %d modes on the block path, vs condensed SciPy %.1e, response vs Krylov-Schur %.1e of "
          "the peak; reduced model vs SciPy %.1e (target %g)" % (fb.size, np.abs(fb / f_dense[:fb.size] - 1).max(),
                                                                np.abs(Tb - Ts).max() / np.abs(Ts).max(), err,
                                                                spec["accuracy"]))
    assert "block Krylov of K+ M" in text and "Krylov-Schur (SLEPc) instead" not in text, text[-2000:]
    assert 0 < fb.size == np.ravel(slepc.result(0, "full_frequencies_hz")).size
    assert np.abs(fb / f_dense[:fb.size] - 1).max() <= 1e-9
    assert np.abs(Tb - Ts).max() <= 1e-9 * np.abs(Ts).max()
    assert err <= spec["accuracy"]


@pytest.mark.mpi
def test_block_eigensolve_singular_mass_without_zero_diagonal_two_ranks(tmp_path):
    """The same on 2 ranks against 1 (the singularity found by the mass's factor on both): the same modes and
    reference response (1e-9)."""
    spec = rigid_offset_model()[0]
    serial, text = reduce_logged(kryflex.scene_from_dict(spec), tmp_path / "one.txt", kf_verify_eigen_method="block")
    assert "block Krylov of K+ M" in text and "Krylov-Schur (SLEPc) instead" not in text, text[-2000:]
    assert_two_ranks_agree(serial, "rigid_offset_frame", tmp_path / "two.npz", ["-kf_verify_eigen_method", "block"],
                           "rigid offset frame: 2 ranks vs 1, block path")
