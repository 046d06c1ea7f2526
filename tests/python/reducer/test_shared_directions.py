"""Shared directions (-kf_shared_directions, src/reducer/ties.c, the ties of src/dense/reassemble.c): each kept system
vector costs one direction of the system, not one per body. The bodies keep their bases; their stacked coordinates are
tied to span[R C] (the bodies' rigid motions and the kept vectors' body coordinates) by angle-independent rows D_s the
model stores and every reassembly appends to the joints' ties.

Checked on the solid bus/rotor pair (2,760 dofs, one angle) against an independent dense NumPy/SciPy reference built
from the bodies' own mass and stiffness files, the joints' constraints and the model's maps and ties:
(a) at the reduction angle and (b) at another angle, the reassembled tied model is the Galerkin projection of the full
order on the conforming subspace blkdiag(Psi_b) null([D_joints(angle) Psi; D_s]) (eigenvalues and transfer function),
its eigenvalues are upper bounds of the full order's (Cauchy interlacing) and its rigid modes are exact;
(c) the ties survive a save/load round trip; (d) the search with the option meets the elastic target with fewer system
dofs than without, and 2 MPI ranks choose the same model; (e) the static moment L^0 is the full order's at the
reduction angle (1e-10). With the option off a model has no ties.
"""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import accuracy_scenes as acc  # noqa: E402
import reference as ref  # noqa: E402

PROBE = os.path.join(SUPPORT, "mpi_reducer_probe.py")
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PYTHONPATH)
TARGET = 1e-3
ANGLE = 0.0           # the reduction angle
OTHER = 40.0          # an angle the basis was not built at
SAME_EIG = 1e-10      # tied model against the NumPy Galerkin projection: eigenvalues, relative to the largest
                      # (measured 1.5e-12; the split model 4e-15)
SAME_FRF = 1e-8       # and transfer function, relative to its largest entry (measured ~1e-11)
INTERLACE = 1e-7      # lam_k(model) >= lam_k(full) to this (relative): at the reduction angle the lowest modes are
                      # matched to rounding (measured -6.5e-9), and the dense full order's eigenvalues are only known to
                      # eps lam_max / lam_k (reference.py); at 40 deg every gap is positive (>= 4.6e-7)
STATIC = 1e-10        # L^0 against the full order's at the reduction angle (relative)
RIGID = 1e-9          # the full order's rigid modes outside the tied subspace (relative)

pytestmark = pytest.mark.usefixtures("quiet_library")


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    base = acc.solid_base(str(tmp_path_factory.mktemp("solid")))
    return acc.write_variant(base, str(tmp_path_factory.mktemp("tied") / "one.yaml"), accuracy=TARGET,
                             angles=[[ANGLE]], band=acc.SOLID_BAND)


@pytest.fixture(scope="module")
def runs(scene):
    return {sd: kryflex.reduce(kryflex.load_scene(scene), quiet=True, shared_directions=sd) for sd in (False, True)}


@pytest.fixture(scope="module")
def full(scene):
    s = ref.load_scene(scene)
    return s, ref.assemble(s, [ANGLE]), ref.assemble(s, [OTHER])


def tied_subspace(s, model, angle):
    """The tied model's subspace in the full order's coordinates at this angle (ref.assemble's: x = P y), from the
    maps, the joints' full constraints and the model's ties alone."""
    Q = sl.block_diag(*model.maps)                        # stacked body dofs x body coordinates
    C = ref.constraint_matrix(s, [angle])
    N = ref.null_space_svd(np.vstack([C @ Q, model.ties]), rtol=1e-9)
    P = ref.null_space_svd(C)
    return P.T @ (Q @ N)


def transfer(M, K, G, H, w):
    return np.array([H @ np.linalg.solve(K - x * x * M, G) for x in w])


def check_galerkin(s, model, system, angle):
    Ms, Ks, Gs, Hs = system
    V = tied_subspace(s, model, angle)
    Mr, Kr = V.T @ Ms @ V, V.T @ Ks @ V
    rs = model.at([angle], trimmed=False)
    assert rs.dofs == V.shape[1]
    lam_ref = sl.eigh(Kr, Mr, eigvals_only=True)
    lam = np.sort(rs.eigenvalues)
    top = lam_ref.max()
    err = np.max(np.abs(lam - lam_ref)) / top
    # the band's resonances (5.96 .. 11.8 Hz) lie between these: off resonance, both systems invertible
    w = 2 * np.pi * np.array([3.1, 8.3, 14.7])
    T_ref = transfer(Mr, Kr, V.T @ Gs, Hs @ V, w)
    T = transfer(rs.M, rs.K, rs.B, rs.C, w)
    ferr = np.max(np.abs(T - T_ref)) / np.max(np.abs(T_ref))
    # Cauchy interlacing: a Galerkin model's k-th eigenvalue bounds the full order's from above
    lam_full = sl.eigh(Ks, Ms, eigvals_only=True, subset_by_index=[0, len(lam) - 1])
    nr = rs.rigid_modes.shape[1]
    above = np.min((lam[nr:] - lam_full[nr:]) / lam[nr:])
    # the full order's rigid modes (from geometry, in ref.assemble's coordinates) lie in the tied subspace
    R = ref.geometric_rigid_modes(s, [angle])
    Qv, _ = np.linalg.qr(V)
    res = np.linalg.norm(R - Qv @ (Qv.T @ R)) / np.linalg.norm(R)
    print("angle %g: %d dofs (ties %d), eigenvalues %.2e, FRF %.2e from the NumPy projection; (lam - lam_full)/lam "
          ">= %.2e; %d rigid modes, residual %.2e" % (angle, rs.dofs, model.ties.shape[0], err, ferr, above, nr, res))
    assert err <= SAME_EIG
    assert ferr <= SAME_FRF
    assert above >= -INTERLACE
    assert nr == 7
    assert res <= RIGID


def test_the_model_records_it(runs):
    assert runs[False].model.ties is None
    assert "shared_directions" not in runs[False].model.settings
    assert runs[True].model.ties is not None
    assert runs[True].model.settings["shared_directions"] is True


def test_galerkin_at_the_reduction_angle(runs, full):
    s, at_angle, _ = full
    check_galerkin(s, runs[True].model, at_angle, ANGLE)


def test_galerkin_and_conforming_at_another_angle(runs, full):
    s, _, other = full
    check_galerkin(s, runs[True].model, other, OTHER)


def test_static_moment_exact_at_the_reduction_angle(runs, full):
    s, (Ms, Ks, Gs, Hs), _ = full
    # the rigid modes from geometry (independent of the model), M-orthonormalized
    R = ref.geometric_rigid_modes(s, [ANGLE])
    R = R @ np.linalg.inv(np.linalg.cholesky(R.T @ Ms @ R)).T
    Ge = Gs - Ms @ R @ (R.T @ Gs)
    x = np.linalg.solve(Ks + Ms @ R @ R.T @ Ms, Ge)
    x -= R @ (R.T @ (Ms @ x))
    L0 = Hs @ x
    L0r = runs[True].model.at([ANGLE]).moments(1)[0]
    err = np.linalg.norm(L0r - L0) / np.linalg.norm(L0)
    print("L^0 of the tied model against the full order: %.2e" % err)
    assert err <= STATIC


def test_save_load_keeps_the_ties(runs, tmp_path):
    m = runs[True].model
    path = str(tmp_path / "tied.h5")
    m.save(path)
    back = kryflex.ReducedModel.load(path)
    assert np.array_equal(back.ties, m.ties)
    assert np.allclose(back.at([OTHER]).frequencies_hz, m.at([OTHER]).frequencies_hz, rtol=1e-12, atol=0)
    m0 = runs[False].model
    m0.save(str(tmp_path / "split.h5"))
    assert kryflex.ReducedModel.load(str(tmp_path / "split.h5")).ties is None


def test_search_meets_the_target_with_fewer_system_dofs(runs):
    split, tied = runs[False], runs[True]
    n_split, n_tied = split.model.at([ANGLE]).dofs, tied.model.at([ANGLE]).dofs
    print("system dofs at %g deg: %d split (bodies %s), %d tied (bodies %s, %d ties); errors %.3g, %.3g"
          % (ANGLE, n_split, split.model.sizes, n_tied, tied.model.sizes, tied.model.ties.shape[0],
             split.summary.verdict.error_max, tied.summary.verdict.error_max))
    assert tied.summary.verdict.target_met and tied.summary.verdict.error_max <= TARGET
    assert n_tied < n_split        # measured 16 against 19


@pytest.mark.mpi
def test_two_ranks_choose_the_same_tied_model(runs, scene, tmp_path):
    path = str(tmp_path / "m.h5")
    subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, scene, path, str(tmp_path / "s.json"),
                    "-kf_shared_directions", "true"], env=ENV, check=True, timeout=600, capture_output=True)
    two, one = kryflex.ReducedModel.load(path), runs[True].model
    assert two.sizes == one.sizes and two.ties.shape == one.ties.shape
    f1, f2 = one.at([OTHER]).frequencies_hz, two.at([OTHER]).frequencies_hz
    assert np.allclose(f1, f2, rtol=1e-8, atol=0)


def test_a_tied_model_is_compressed_tied(runs):
    # compression keeps the ties: one SVD of the stacked coordinates, the model tied to the leading directions
    # (test_tied_compress.py checks it against NumPy)
    ch, model = runs[True].summary.chosen, runs[True].model
    assert ch.compressed_tied is True
    assert ch.compressed_to_dofs == sum(model.sizes) - model.ties.shape[0] <= ch.compressed_from_dofs


def test_export_carries_the_ties(runs, tmp_path):
    """The tied model exports body by body with its ties (tests/python/export/test_export_ties.py checks the export
    against the reassembly); the command in both formats: exit 0, no traceback."""
    from kryflex.export import from_model
    data = from_model(runs[True].model)
    assert data.ties.shape == (runs[True].model.ties.shape[0], sum(data.coordinate_sizes))
    path = str(tmp_path / "tied.h5")
    runs[True].model.save(path)
    for fmt in ("neutral", "exudyn"):
        p = subprocess.run([sys.executable, "-m", "kryflex", "export", path, "-o", str(tmp_path / ("x_%s.npz" % fmt)),
                            "--format", fmt], env=ENV, cwd=ROOT, capture_output=True, text=True, timeout=300)
        print(fmt, p.returncode, p.stdout.strip().splitlines()[-1:])
        assert p.returncode == 0, p.stderr
        assert "Traceback" not in p.stderr
    assert from_model(runs[False].model).ties is None      # the split model exports as before


def test_a_file_with_ties_of_the_wrong_shape_is_refused(runs, tmp_path):
    import h5py
    path = str(tmp_path / "bad.h5")
    runs[True].model.save(path)
    with h5py.File(path, "r+") as f:
        D = f["ties"][()]
        del f["ties"]
        f["ties"] = D[:, :-1]                      # one body coordinate short
    with pytest.raises(kryflex.ModelFileError, match="ties"):
        kryflex.ReducedModel.load(path)


def test_the_scene_key_sets_it(tmp_path):
    galileo = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
    path = acc.write_variant(galileo, str(tmp_path / "g.yaml"), accuracy=1e-3, angles=[[0.0]],
                             reduction={"shared_directions": True})
    m = kryflex.reduce(kryflex.load_scene(path), quiet=True).model
    assert m.settings.get("shared_directions") is True and m.ties is not None
    bad = acc.write_variant(galileo, str(tmp_path / "bad.yaml"), reduction={"shared_directions": "maybe"})
    with pytest.raises(kryflex.SceneError, match="shared_directions"):
        kryflex.load_scene(bad)


def test_auto_by_default_the_scene_key_false_and_the_command_line_over_it(tmp_path):
    """Galileo at one angle, 1e-3: a scene without the key reduces as auto does; the key false gives the split model
    although the option's default is auto; the option in PETSc's database (the command line) overrides the key."""
    from kryflex.reducer import kf_options
    galileo = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
    plain = acc.write_variant(galileo, str(tmp_path / "g.yaml"), accuracy=1e-3, angles=[[0.0]])
    split = acc.write_variant(galileo, str(tmp_path / "s.yaml"), accuracy=1e-3, angles=[[0.0]],
                              reduction={"shared_directions": False})
    model = {sd: kryflex.reduce(kryflex.load_scene(plain), quiet=True, shared_directions=sd).model
             for sd in (False, "auto")}
    default = kryflex.reduce(kryflex.load_scene(plain), quiet=True).model
    keyed = kryflex.reduce(kryflex.load_scene(split), quiet=True).model
    with kf_options({"shared_directions": "auto"}):
        overridden = kryflex.reduce(kryflex.load_scene(split), quiet=True).model
    print("split %s, auto %s (ties %s), default %s, key false %s, key false under -kf_shared_directions auto %s"
          % (model[False].sizes, model["auto"].sizes, model["auto"].ties is not None, default.sizes, keyed.sizes,
             overridden.sizes))
    assert model["auto"].ties is not None      # the tied model wins at one angle, so the cases differ
    assert default.sizes == model["auto"].sizes and default.ties is not None
    assert default.settings.get("shared_directions") is True
    assert keyed.sizes == model[False].sizes and keyed.ties is None
    assert overridden.sizes == model["auto"].sizes and overridden.ties is not None


# -kf_shared_directions auto: the search measures every candidate size split and tied and keeps the model with fewer
# reassembled system dofs that meets the target (split on a tie, and split when its compressed model is no larger)

GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
GALILEO_REDUCTION = {"moments": 10, "output_blocks": 1, "importance": "h2", "keep_threshold": 0.1,
                     "reduction_angle": "auto"}      # the scene's own settings
GALILEO_TARGET = 1e-4


@pytest.fixture(scope="module")
def auto_run(scene):
    return kryflex.reduce(kryflex.load_scene(scene), quiet=True, shared_directions="auto")


@pytest.fixture(scope="module")
def galileo_angles(tmp_path_factory):
    work = tmp_path_factory.mktemp("galileo")
    path = acc.write_variant(GALILEO, str(work / "g.yaml"), accuracy=GALILEO_TARGET, reduction=GALILEO_REDUCTION)
    runs = {sd: kryflex.reduce(kryflex.load_scene(path), quiet=True, shared_directions=sd)
            for sd in (False, True, "auto")}
    return path, acc.DenseReference(path, str(work / "dense")), runs


def test_auto_keeps_the_tied_model_where_it_is_smaller(runs, auto_run, scene, full, tmp_path):
    import elastic_measure as em
    split, tied = runs[False].model, runs[True].model
    m = auto_run.model
    configs = [[ANGLE]]
    n = {k: em.system_dofs(x, configs) for k, x in (("split", split), ("tied", tied), ("auto", m))}
    print("system dofs at %g deg: %s" % (ANGLE, n))
    assert n["tied"] < n["split"]
    assert m.ties is not None and m.settings.get("shared_directions") is True
    assert m.sizes == tied.sizes and m.ties.shape == tied.ties.shape and n["auto"] == n["tied"]
    s, _, other = full
    check_galerkin(s, m, other, OTHER)                 # the NumPy Galerkin projection on its tied subspace
    dense = acc.DenseReference(scene, str(tmp_path / "dense"))
    el, _ = em.errors(m, dense, configs, acc.SOLID_BAND, float(s.raw["damping"]))
    print("auto: dense elastic error %.3g (kryflex's %.3g)" % (el, auto_run.summary.verdict.error_max))
    assert el <= TARGET and auto_run.summary.verdict.target_met
    assert auto_run.summary.chosen.compressed_tied is True     # the tied model compressed across its bodies


def test_auto_keeps_the_split_search_model_compressed_tied(galileo_angles):
    """Galileo's own settings at 6 angles: the search's split model wins over its tied one (23 against 25 system
    dofs, the tied one cannot be compressed: its reassembly misses the spin mode), and that split model compressed
    across its bodies (tied) has fewer system dofs than compressed body by body (the model -kf_shared_directions
    false returns)."""
    import elastic_measure as em
    path, dense, runs = galileo_angles
    raw = dense.scene.raw
    configs = [[float(a)] for a in raw["angles"]]
    n = {sd: em.system_dofs(r.model, configs) for sd, r in runs.items()}
    print("Galileo, 6 angles, %g: system dofs %s" % (GALILEO_TARGET, n))
    assert n[False] < n[True]                          # measured 23 against 25
    m, ch = runs["auto"].model, runs["auto"].summary.chosen
    assert n["auto"] < n[False]                        # measured 21
    assert ch.compressed_tied is True and m.ties is not None
    assert ch.compressed_to_dofs == sum(m.sizes) - m.ties.shape[0] < ch.compressed_from_dofs
    el, _ = em.errors(m, dense, configs, raw["band"], float(raw["damping"]))
    print("auto: dense elastic error %.3g (kryflex's %.3g)" % (el, runs["auto"].summary.verdict.error_max))
    assert el <= GALILEO_TARGET and runs["auto"].summary.verdict.target_met
    from kryflex.export import from_model
    assert from_model(m).ties.shape[0] == m.ties.shape[0]      # a tied model exports with its ties


@pytest.mark.mpi
def test_two_ranks_choose_the_same_model_under_auto(auto_run, scene, tmp_path):
    path = str(tmp_path / "m.h5")
    subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, scene, path, str(tmp_path / "s.json"),
                    "-kf_shared_directions", "auto"], env=ENV, check=True, timeout=600, capture_output=True)
    two, one = kryflex.ReducedModel.load(path), auto_run.model
    assert two.sizes == one.sizes and two.ties is not None and two.ties.shape == one.ties.shape
    assert np.allclose(one.at([OTHER]).frequencies_hz, two.at([OTHER]).frequencies_hz, rtol=1e-8, atol=0)


def test_a_bad_option_value_is_a_clear_error(tmp_path):
    r = subprocess.run([sys.executable, "-m", "kryflex", "reduce", GALILEO, "-o", str(tmp_path / "out"),
                        "-kf_shared_directions", "sometimes"], capture_output=True, text=True, timeout=300, cwd=ROOT,
                       env=ENV)
    assert r.returncode == 2, r.stdout[-2000:] + r.stderr[-2000:]
    assert "-kf_shared_directions sometimes: give auto, true or false" in r.stderr
    assert "Traceback" not in r.stderr + r.stdout


def test_the_scene_key_takes_auto(galileo_angles, tmp_path):
    path = acc.write_variant(GALILEO, str(tmp_path / "a.yaml"), accuracy=GALILEO_TARGET,
                             reduction=dict(GALILEO_REDUCTION, shared_directions="auto"))
    m = kryflex.reduce(kryflex.load_scene(path), quiet=True).model
    auto = galileo_angles[2]["auto"].model
    assert m.sizes == auto.sizes and m.ties.shape == auto.ties.shape
    bad = acc.write_variant(GALILEO, str(tmp_path / "bad.yaml"), reduction={"shared_directions": "sometimes"})
    with pytest.raises(kryflex.SceneError, match="shared_directions.*auto, true or false"):
        kryflex.load_scene(bad)
