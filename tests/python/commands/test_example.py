"""python/examples/two_body_scene.py as a user runs it: serial and under mpiexec -n 2, into a fresh folder.

Its outputs are checked against what it printed, against each other (HDF5 and .npz, 1 and 2 ranks), and
against an independent dense reference: the example's own matrices written to files and assembled by
tests/python/support/reference.py (constraint null space by SVD, paper eq. 21-22), with moments from plain dense solves.
"""
import importlib.util
import os
import re
import subprocess
import sys

import numpy as np
import pytest
import scipy.io
import scipy.linalg as sl
import scipy.sparse as sp
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
EXAMPLE = os.path.join(ROOT, "python", "examples", "two_body_scene.py")
PYTHON = run_env.PYTHON
sys.path.insert(0, SUPPORT)
import reference as ref  # noqa: E402
from conftest import reassembled  # noqa: E402

ENV = dict(run_env.ENV, PYTHONPATH=run_env.PYTHONPATH)
NFREQ_PRINTED = 6


def run_example(outdir, ranks, *extra):
    cmd = [PYTHON, EXAMPLE, str(outdir), *extra]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    proc = subprocess.run(cmd, env=ENV, cwd=str(outdir.parent), capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, "the example failed (%d ranks):\n%s\n%s" % (ranks, proc.stdout, proc.stderr)
    return proc.stdout


def printed_frequencies(stdout):
    """{angle: the lowest flexible frequencies the example printed}"""
    found = re.findall(r"^reduced frequencies at (\S+) deg \(Hz\): (.*)$", stdout, re.M)
    return {float(a): np.array(v.split(), dtype=float) for a, v in found}


def printed_moments(stdout):
    """(angle, array (k, outputs)) of the moments the example printed for one input."""
    angle = float(re.search(r"^moments at (\S+) deg", stdout, re.M).group(1))
    rows = re.findall(r"^  L\^(\d+) = (.*)$", stdout, re.M)
    return angle, np.array([r[1].split() for r in sorted(rows, key=lambda r: int(r[0]))], dtype=float)


def load_example_module():
    spec = importlib.util.spec_from_file_location("two_body_scene", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


# ------------------------------------------------------------------ an independent reference with exact rigid modes

def node_table(scene, body):
    """Rows (id, x, y, z, ndof) of a body's nodes file, '#' comments skipped."""
    rows = []
    with open(os.path.join(scene.here, scene.raw["bodies"][body.name]["nodes"])) as f:
        for line in f:
            fields = line.split("#", 1)[0].split()
            if fields:
                rows.append([float(v) for v in fields])
    return np.array(rows)


def body_rigid_motions(scene, body):
    """The 6 rigid motions of a body from its node coordinates: translations, then rotations about x, y, z
    through the origin (u = w x X, theta = w on 6-dof nodes)."""
    R = np.zeros((body.n, 6))
    for nid, x, y, z, _ in node_table(scene, body):
        d, X = body.first_dof[int(nid)], np.array([x, y, z])
        for m in range(3):
            R[d + m, m] = 1.0
            R[d:d + 3, 3 + m] = np.cross(np.eye(3)[m], X)
            if body.ndof[int(nid)] == 6:
                R[d + 3 + m, 3 + m] = 1.0
    return R


def rigid_mode_moments(scene, angles_deg, nmom):
    """Moments L^k = H (K+ M)^k K+ G of the full-order scene (reference.py's assembly), with K+ from dense solves
    on K + M Phi Phi^T M, Phi the exact rigid-body and mechanism modes: rigid motions of the bodies that satisfy the
    joint constraints. (An eigendecomposition would blur the rigid subspace into the softest mode and cost several
    digits when the eigenvalues span 1e8.) Also returns the number of rigid/mechanism modes found."""
    Rb = sl.block_diag(*[body_rigid_motions(scene, b) for b in scene.bodies])
    C = ref.constraint_matrix(scene, angles_deg)
    P = ref.null_space_svd(C)
    Ms, Ks, Gs, Hs = ref.assemble(scene, angles_deg)
    Phi = P.T @ (Rb @ sl.null_space(C @ Rb)) if C.shape[0] else Rb
    assert np.linalg.norm(Ks @ Phi) <= 1e-12 * np.linalg.norm(Ks) * np.linalg.norm(Phi), "rigid motions strain K"
    Phi = Phi @ np.linalg.inv(np.linalg.cholesky(Phi.T @ Ms @ Phi)).T     # M-orthonormal
    Q = np.eye(len(Ms)) - Phi @ (Phi.T @ Ms)
    lu = sl.lu_factor(Ks + Ms @ Phi @ Phi.T @ Ms)
    X = Q @ sl.lu_solve(lu, Q.T @ Gs)
    L = []
    for _ in range(nmom):
        L.append(Hs @ X)
        X = Q @ sl.lu_solve(lu, Q.T @ (Ms @ X))
    return np.array(L), Phi.shape[1], (Ms, Ks)


def stiffness_spread(model, angle):
    """kappa = lambda_max / lambda_1 (lowest flexible) of the reassembled reduced model: what rounding is
    amplified by in its eigenvalues and in its moments."""
    Mh, Kh = reassembled(model, [angle])[:2]
    lam = sl.eigh(Kh, Mh, eigvals_only=True)
    return lam[-1] / lam[model.nrigid]


def normwise_errors(L_ref, L):
    return np.array([np.linalg.norm(L_ref[k] - L[k]) / np.linalg.norm(L_ref[k]) for k in range(len(L_ref))])


def write_scene_files(spec, folder):
    """The example's in-memory scene as files (Matrix Market, 17 digits; nodes; YAML in the same key order)."""
    from petsc4py import PETSc
    os.makedirs(folder, exist_ok=True)
    spec = dict(spec, bodies={name: dict(b) for name, b in spec["bodies"].items()})
    for name, body in spec["bodies"].items():
        for key in ("mass", "stiffness"):
            A = body[key]
            if isinstance(A, PETSc.Mat):
                indptr, indices, data = A.getValuesCSR()
                A = sp.csr_matrix((data, indices, indptr), shape=A.getSize())
            scipy.io.mmwrite(os.path.join(folder, "%s_%s.mtx" % (name, key)), sp.csr_matrix(A), precision=17)
            body[key] = "%s_%s.mtx" % (name, key)
        np.savetxt(os.path.join(folder, name + "_nodes.txt"), body["nodes"], fmt="%d %.17g %.17g %.17g %d")
        body["nodes"] = name + "_nodes.txt"
    path = os.path.join(folder, "scene.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(spec, f, sort_keys=False)      # keep the order of bodies, inputs and outputs
    return path


# ------------------------------------------------------------------ fixtures: one serial and one 2-rank run

@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("example") / "serial_out"
    return out, run_example(out, 1)


@pytest.fixture(scope="module")
def parallel(tmp_path_factory):
    out = tmp_path_factory.mktemp("example") / "mpi_out"
    return out, run_example(out, 2, "-quiet")


@pytest.fixture(scope="module")
def example_reference(tmp_path_factory):
    """The example's scene written to files and loaded by the dense reference; the angles it reduces at."""
    mod = load_example_module()
    path = write_scene_files(mod.build_scene_spec(), str(tmp_path_factory.mktemp("example_scene")))
    return ref.load_scene(path), mod.ANGLES_OF_INTEREST, mod.OTHER_ANGLES


# ------------------------------------------------------------------ tests

def test_example_writes_model_files_and_bode_plot(serial):
    out, stdout = serial
    for name in ("two_body.h5", "two_body.npz", "bode.png"):
        assert os.path.getsize(out / name) > 1000, name
    with open(out / "bode.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert not [f for f in os.listdir(out) if f.startswith(".kryflex-")], "temporary files left behind"
    # progress lines (not -quiet) and the summary
    assert "[kryflex" in stdout and "wrote %s" % out in stdout


def test_saved_models_reload_to_the_printed_numbers(serial):
    import kryflex
    out, stdout = serial
    freqs = printed_frequencies(stdout)
    angle, L_printed = printed_moments(stdout)
    assert len(freqs) >= 5 and angle in freqs
    h5 = kryflex.ReducedModel.load(str(out / "two_body.h5"))
    for model in (h5,):
        for a, f in freqs.items():
            # Printed with 12 digits, but recomputed here (arrays in another memory order take other BLAS
            # paths): a dense eigensolve carries ~eps lambda_max of rounding, relative eps kappa for the lowest mode.
            rtol = 10 * np.finfo(float).eps * stiffness_spread(model, a)
            np.testing.assert_allclose(model.at([a]).frequencies_hz[:NFREQ_PRINTED], f, rtol=rtol, err_msg="%g deg" % a)
        # moments by solves: rounding ~ eps kappa per application of K+
        L = model.at([angle]).moments(L_printed.shape[0])[:, :, 0]
        rtol = 10 * np.finfo(float).eps * stiffness_spread(model, angle)
        for k in range(len(L)):
            assert np.linalg.norm(L[k] - L_printed[k]) <= (k + 1) * rtol * np.linalg.norm(L[k]), k
    # the NumPy export holds the same arrays and names, bit for bit
    with np.load(str(out / "two_body.npz")) as npz:
        assert list(npz["inputs"]) == h5.input_names and list(npz["outputs"]) == h5.output_names
        assert list(npz["revolute_joints"]) == h5.revolute
        for name, b1 in zip(h5.body_names, h5.bodies):
            for key in b1:
                np.testing.assert_array_equal(b1[key], npz["%s__%s" % (name, key)])


def test_reduced_model_matches_the_independent_reference(serial, example_reference):
    """The example asks for the multi-angle method: 8 moments matched at every angle of interest. The reference
    solves carry rounding ~ cond(K_reg) eps ~ 1e-9 (the model spans 0.78 Hz to kHz), hence 1e-7."""
    import kryflex
    out, stdout = serial
    scene, angles, _ = example_reference
    model = kryflex.ReducedModel.load(str(out / "two_body.h5"))
    assert model.settings["method"] == "multi-angle"
    freqs = printed_frequencies(stdout)
    for a in angles:
        L_ref, nrigid, (Ms, Ks) = rigid_mode_moments(scene, [a], 8)
        assert nrigid == 7 == model.nrigid                 # 6 free-floating + 1 hinge
        err = normwise_errors(L_ref, model.at([a]).moments(8))
        assert err.max() < 1e-7, "%g deg: moment errors %s" % (a, err)
        # the lowest flexible modes (dense eigensolve of the full order): the reduced model keeps them
        lam = sl.eigh(Ks, Ms, eigvals_only=True)
        full = np.sqrt(lam[nrigid:nrigid + NFREQ_PRINTED]) / (2 * np.pi)
        np.testing.assert_allclose(freqs[a], full, rtol=1e-6, err_msg="%g deg" % a)


@pytest.mark.mpi
def test_two_ranks_give_the_serial_model(serial, parallel):
    import kryflex
    (out1, stdout1), (out2, stdout2) = serial, parallel
    f1, f2 = printed_frequencies(stdout1), printed_frequencies(stdout2)
    assert f1.keys() == f2.keys()
    # The reduced basis is built with the sums in another order: Ritz values move by a few 1e-9 (observed).
    for a in f1:
        np.testing.assert_allclose(f2[a], f1[a], rtol=1e-7, err_msg="%g deg" % a)
    m1 = kryflex.ReducedModel.load(str(out1 / "two_body.h5"))
    m2 = kryflex.ReducedModel.load(str(out2 / "two_body.h5"))
    assert m1.sizes == m2.sizes
    for a in (0.0, 45.0, 90.0):
        assert normwise_errors(m1.at([a]).moments(6), m2.at([a]).moments(6)).max() < 1e-7, a
    # printed once, not once per rank; -quiet silences the progress lines only
    assert stdout2.count("wrote %s" % out2) == 1 and stdout2.count("scene 'bus_and_boom'") == 1
    assert "[kryflex" not in stdout2
    with open(out2 / "bode.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
