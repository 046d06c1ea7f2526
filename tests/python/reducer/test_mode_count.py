"""The count of the full order's flexible modes below a frequency without an eigensolve (src/verify/mode_count.c:
the negative pivots of MUMPS' LDL^T of K_S - (2 pi f)^2 M_S, Sylvester's law of inertia, less the rigid modes),
against dense SciPy eigenvalues of the assembled full order (M_S's null space condensed statically, the low modes
resolved by shift-and-invert as in the assembly tests): Galileo at two angles, the solid spacecraft at refine 0.5,
a clamped beam (no rigid modes), a free-free beam with clustered bending frequencies, a frame whose rotations are
massless, a plate with a singular lumped mass (offset masses, M singular beyond its zero diagonal). The counts are
taken half-way below the first mode, just below and just above modes (1e-6 in frequency, far above the reference's
own error), between the two closest modes of a cluster and above every finite mode; on 1 and 2 ranks. As the
verification's certificate (-kf_verify_count): the count recorded per configuration against SciPy's, the reference and
the model unchanged by it, and a block eigensolve that misses modes (its start block never reaches them) solved
again by Krylov-Schur."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sl

import kryflex
from kryflex import _core

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import accuracy_scenes  # noqa: E402
import bc_models  # noqa: E402
from mpi_assembly_probe import accurate_eigenvalues, zero_split  # noqa: E402

pytestmark = [pytest.mark.usefixtures("quiet_library")]

PROBE = os.path.join(SUPPORT, "mode_count_probe.py")
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
# taken at import, before this process initializes MPI (its singleton's variables would confuse mpiexec)
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PYTHONPATH)
REL = 1e-6                      # just below / just above a mode, relative in frequency


def dense(A):
    """A petsc4py Mat gathered on this (single) rank as a NumPy array."""
    return A.convert("dense").getDenseArray().copy() if not A.getType().endswith("dense") else A.getDenseArray().copy()


def reference_frequencies(M, K):
    """(every finite flexible frequency in Hz ascending, rigid count) of (K, M) by SciPy: M's null space (eigenvalues
    of M at most 1e-8 of its largest) condensed statically, then the condensed pencil's eigenvalues with its low
    ones resolved by shift-and-invert (accurate_eigenvalues)."""
    M, K = 0.5 * (M + M.T), 0.5 * (K + K.T)
    mu, U = np.linalg.eigh(M)
    null = mu <= 1e-8 * mu.max()
    Z, Y = U[:, null], U[:, ~null]
    T = Y - Z @ np.linalg.solve(Z.T @ K @ Z, Z.T @ K @ Y) if null.any() else Y
    Kc, Mc = T.T @ K @ T, T.T @ M @ T
    lam = accurate_eigenvalues(0.5 * (Kc + Kc.T), 0.5 * (Mc + Mc.T))
    nzero = zero_split(lam)[0]
    return np.sqrt(np.sort(lam)[nzero:]) / (2 * np.pi), nzero


def probe_frequencies(f):
    """Frequencies (Hz) at which to count: half the first mode; just below and above the first, a middle and the
    last mode; the geometric midpoint of the closest pair of distinct modes (a cluster); above every mode."""
    out = [0.5 * f[0]]
    for k in sorted({0, 1, len(f) // 2, len(f) - 1}):
        out += [f[k] * (1 - REL), f[k] * (1 + REL)]
    gaps = f[1:] / f[:-1] - 1
    distinct = np.flatnonzero(gaps > 1e3 * REL)
    k = distinct[np.argmin(gaps[distinct])]
    out.append(np.sqrt(f[k] * f[k + 1]))
    out.append(1.5 * f[-1])
    return np.array(out)


def scene_and_angles(name, tmp_path_factory):
    """(scene object, scene argument of the probe, angles in degrees)"""
    if name.startswith("galileo"):
        angle = {"galileo0": 0.0, "galileo45": 52.5}[name]
        return kryflex.load_scene(accuracy_scenes.GALILEO), accuracy_scenes.GALILEO, [angle]
    if name == "solid":
        path = accuracy_scenes.solid_base(str(tmp_path_factory.mktemp("solid")))
        return kryflex.load_scene(path), path, [45.0]
    return kryflex.scene_from_dict(getattr(bc_models, name)()), "bc:" + name, []


NAMES = ["galileo0", "galileo45", "solid", "clamped_beam", "free_clustered_beam", "lumped_frame", "lumped_plate"]


@pytest.fixture(scope="module", params=NAMES)
def case(request, tmp_path_factory):
    """(name, probe scene argument, angles, reference frequencies, frequencies probed, counts by kryflex on 1 rank)"""
    name = request.param
    scene, arg, angles = scene_and_angles(name, tmp_path_factory)
    system = _core.CSystem(scene.cscene)
    system.set_angles(np.radians(angles))
    Ms, Ks, _, _ = system.matrices()
    f, nzero = reference_frequencies(dense(Ms), dense(Ks))
    Phi, _ = system.rigid_modes()
    assert nzero == Phi.getSize()[1], (name, nzero)   # the geometric rigid modes are K's null space
    probes = probe_frequencies(f)
    counts = [system.count_modes_below(q) for q in probes]
    return name, arg, angles, f, probes, counts


def test_count_matches_dense_eigenvalues(case):
    """Every count equals the number of SciPy's flexible frequencies below it, at every probe."""
    name, _, _, f, probes, counts = case
    expected = [int(np.sum(f < q)) for q in probes]
    assert counts == expected, (name, list(zip(probes, counts, expected)))
    assert expected[0] == 0 and expected[-1] == len(f)        # the probes span nothing to everything
    assert any(e - c == 1 for c, e in zip(expected[1::2], expected[2::2]))  # a mode falls between a pair of probes


def test_two_ranks_agree(case, tmp_path):
    """The counts on 2 ranks (the inertia of the distributed factor: ICNTL(13) = 1) are the serial ones."""
    name, arg, angles, _, probes, counts = case
    out = tmp_path / "counts.json"
    r = subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, arg, ",".join("%r" % a for a in angles),
                        ",".join("%.17g" % q for q in probes), str(out)], capture_output=True, text=True, timeout=600,
                       cwd=ROOT, env=ENV)
    assert r.returncode == 0, r.stderr[-3000:]
    got = json.load(open(out))
    assert got["ranks"] == 2 and got["counts"] == counts, (name, got, counts)


def test_bad_frequency_is_a_clear_error():
    """A frequency that is not a positive number is refused by name."""
    system = _core.CSystem(kryflex.scene_from_dict(bc_models.clamped_beam()).cscene)
    system.set_angles(np.zeros(0))
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="positive number of Hz"):
            system.count_modes_below(bad)


# ---------------------------------------------------------------- the certificate of the verification's eigensolve

def z_only_clustered_beam():
    """The clamped beam with equal section inertias (bending pairs in y and z) read and loaded in z only: with no random
    start columns (-kf_verify_eigen_random 0) the block eigensolve's space never leaves the xz plane, so it misses
    every y-bending mode below the cut, and nothing in its stop can tell."""
    from test_sparse_eigensolve import clustered_beam
    spec = clustered_beam()
    spec["inputs"] = {k: v for k, v in spec["inputs"].items() if all(d["dof"] == "uz" for d in v)}
    spec["outputs"] = {k: v for k, v in spec["outputs"].items() if all(d["dof"] == "uz" for d in v)}
    assert spec["inputs"] and spec["outputs"]
    return spec


@pytest.mark.parametrize("method", ["block", "slepc"])
@pytest.mark.parametrize("name", ["clamped_beam", "lumped_frame", "free_clustered_beam", "rigid_offset_frame"])
def test_verification_count_recorded(name, method):
    """-kf_verify_count on the sparse path: the count recorded (full_order_mode_count) is SciPy's number of flexible
    modes below the cut, the eigensolve's modes below it are as many, and the reference and the model's error are
    the same as without the count, bit for bit."""
    from test_sparse_eigensolve import reduce_sparse
    spec = getattr(bc_models, name)()
    on = reduce_sparse(kryflex.scene_from_dict(spec), kf_verify_count=True, kf_verify_eigen_method=method)
    off = reduce_sparse(kryflex.scene_from_dict(spec), kf_verify_eigen_method=method)
    count, below = int(on.result(0, "full_order_mode_count")[0]), float(on.result(0, "full_order_mode_count_below_hz")[0])
    Ms, Ks = bc_models.single_body_reference(spec)[:2]
    f, _ = reference_frequencies(np.asarray(Ms), np.asarray(Ks))
    assert below == pytest.approx(3 * spec["band"][1])              # -kf_verify_cover x the band's top
    assert count == int(np.sum(f < below)) > 0
    assert int(np.sum(np.ravel(on.result(0, "full_frequencies_hz")) < below)) == count
    for key in ("full_frequencies_hz", "frf_full_re", "frf_reduced_re"):
        assert np.array_equal(on.result(0, key), off.result(0, key)), key
    assert "full_order_mode_count" not in off.result_names(0)       # off by default: nothing counted


def test_missed_modes_are_found_again():
    """The block eigensolve that misses the y-bending modes (z-only inputs and outputs, no random columns) passes
    silently without the count (its reference lacks SciPy's y modes); with -kf_verify_count the count finds the miss
    and the configuration is solved again by Krylov-Schur, whose reference then holds every mode SciPy has below the
    cut, to 1e-9."""
    from test_sparse_eigensolve import reduce_sparse
    spec = z_only_clustered_beam()
    opts = dict(kf_verify_eigen_method="block", kf_verify_eigen_random=0)
    silent = reduce_sparse(kryflex.scene_from_dict(spec), **opts)
    Ms, Ks = bc_models.single_body_reference(spec)[:2]
    f, _ = reference_frequencies(np.asarray(Ms), np.asarray(Ks))
    cut = 3 * spec["band"][1]
    expected = f[f < cut]
    found = np.ravel(silent.result(0, "full_frequencies_hz"))
    assert np.sum(found < cut) < expected.size                       # the miss the count is for
    certified = reduce_sparse(kryflex.scene_from_dict(spec), kf_verify_count=True, **opts)
    assert int(certified.result(0, "full_order_mode_count")[0]) == expected.size
    got = np.ravel(certified.result(0, "full_frequencies_hz"))
    got = got[got < cut]
    assert got.size == expected.size and np.abs(got / expected - 1).max() < 1e-9, (got, expected)


def test_bodywise_count_on_the_solid(tmp_path_factory):
    """On the solid spacecraft (two bodies, a revolute joint: the body-wise split applies) the verification's count is
    Haynsworth's: the bodies' interiors of K_b - sigma M_b factored once, the interface problem per configuration. At
    every angle of interest and midpoint it equals the whole system's LDL^T count (-kf_verify_count_bodywise false),
    and at 45 deg SciPy's count of the assembled full order below the cut; the model is the same bit for bit."""
    from petsc4py import PETSc
    path = accuracy_scenes.solid_base(str(tmp_path_factory.mktemp("solid_count")))
    runs = {}
    for bodywise in (True, False):
        opts = PETSc.Options()
        values = dict(kf_verify_count=True, kf_verify_count_bodywise=bodywise)
        for k, v in values.items():
            opts.setValue(k, v)
        try:
            reducer = kryflex.Reducer(kryflex.load_scene(path), quiet=True, search=False)
            reducer.reduce()
        finally:
            for k in values:
                opts.delValue(k)
        runs[bodywise] = reducer
    scene = kryflex.load_scene(path)
    angles = [float(np.ravel(a)[0]) for a in scene.configurations]
    counts = {bw: [int(r.result(c, "full_order_mode_count")[0]) for c in range(len(angles))] for bw, r in runs.items()}
    assert counts[True] == counts[False] and min(counts[True]) > 0, counts
    below = float(runs[True].result(0, "full_order_mode_count_below_hz")[0])
    system = _core.CSystem(scene.cscene)
    k = angles.index(45.0) if 45.0 in angles else 0
    system.set_angles(np.radians([angles[k]]))
    Ms, Ks, _, _ = system.matrices()
    f, _ = reference_frequencies(dense(Ms), dense(Ks))
    assert counts[True][k] == int(np.sum(f < below))
    assert np.array_equal(runs[True].result(0, "frf_reduced_re"), runs[False].result(0, "frf_reduced_re"))


def test_bodywise_count_two_ranks(tmp_path_factory, tmp_path):
    """`kryflex reduce -kf_verify_count true` on 2 ranks (the bodies spread over the ranks, each body's negative pivots
    counted on its owner and summed): summary.json's full.mode_count at every angle is the serial whole-system count
    of the same configuration below the same cut."""
    path = accuracy_scenes.solid_base(str(tmp_path_factory.mktemp("solid_count2")))
    out = tmp_path / "out"
    r = subprocess.run(["mpiexec", "-n", "2", sys.executable, "-m", "kryflex", "reduce", path, "-o", str(out),
                        "-kf_verify_count", "true"], capture_output=True, text=True, timeout=600, cwd=ROOT, env=ENV)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "s, body-wise)" in r.stdout
    counted = json.load(open(out / "summary.json"))["full"]["mode_count"]
    scene = kryflex.load_scene(path)
    system = _core.CSystem(scene.cscene)
    assert len(counted) == len(scene.configurations)
    for angles in scene.configurations:
        label = scene.label([float(a) for a in np.atleast_1d(angles)])
        system.set_angles(np.radians(np.atleast_1d(angles)))
        got = counted[label]
        assert got["count"] == system.count_modes_below(got["below_hz"]) > 0, (label, got)
