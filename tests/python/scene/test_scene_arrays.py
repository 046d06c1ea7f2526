"""Python scenes take the data wherever a scene file takes a file: body matrices as NumPy /
SciPy / petsc4py, nodes as an (n, 5) array or a list of tuples, input/output vectors as 1-D arrays or petsc4py Vecs,
through the one resolver io/scene.py resolve(). The Galileo scene given as arrays must reduce to the same model as
from its files; bad arrays give the scene's usual one-line errors."""
import copy
import os
import sys

import numpy as np
import pytest
import scipy.io
import scipy.sparse as sp
import yaml
from petsc4py import PETSc

import kryflex
from kryflex.io import scene as scene_io
from kryflex.io.scene_schema import SceneError
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)

HERE = os.path.dirname(os.path.abspath(__file__))
GALILEO = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(HERE))), "meshes", "galileo", "galileo.yaml")
GALILEO_DIR = os.path.dirname(GALILEO)

pytestmark = [pytest.mark.fast, pytest.mark.usefixtures("quiet_library")]   # tests/python/conftest.py


def spec_from_files():
    with open(GALILEO) as f:
        spec = yaml.safe_load(f)
    spec["angles"] = [0, 45]
    return spec


def stator_ry_vector():
    """The stator's output pointA_ry (node 2, ry) as a vector over its dofs, from its nodes file."""
    nodes = np.loadtxt(os.path.join(GALILEO_DIR, "stator_nodes.txt"), ndmin=2)
    offset = int(sum(n[4] for n in nodes[:list(nodes[:, 0]).index(2)]))
    v = np.zeros(int(nodes[:, 4].sum()))
    v[offset + 4] = 1.0
    return v


def petsc_mat(A):
    A = sp.csr_matrix(A)
    M = PETSc.Mat().createAIJ(A.shape, csr=(A.indptr, A.indices, A.data), comm=PETSc.COMM_SELF)
    M.assemble()
    return M


def spec_from_arrays():
    spec = spec_from_files()
    load = lambda name: scipy.io.mmread(os.path.join(GALILEO_DIR, name))  # noqa: E731
    stator, rotor = spec["bodies"]["stator"], spec["bodies"]["rotor"]
    stator["mass"] = load("stator_M.mtx").toarray()                       # NumPy dense
    stator["stiffness"] = sp.csr_matrix(load("stator_K.mtx"))              # SciPy sparse
    stator["nodes"] = np.loadtxt(os.path.join(GALILEO_DIR, "stator_nodes.txt"), ndmin=2)   # (n, 5) array
    rotor["mass"] = petsc_mat(load("rotor_M.mtx"))                         # petsc4py Mat
    rotor["stiffness"] = load("rotor_K.mtx").tocoo()
    rotor["nodes"] = [tuple(r) for r in np.loadtxt(os.path.join(GALILEO_DIR, "rotor_nodes.txt"), ndmin=2).tolist()]
    spec["outputs"]["pointA_ry"] = [{"body": "stator", "vector": stator_ry_vector()}]   # 1-D array
    return spec


def test_arrays_reduce_to_the_same_model_as_files(tmp_path):
    spec = spec_from_files()
    np.savetxt(tmp_path / "ry.txt", stator_ry_vector())
    spec["outputs"]["pointA_ry"] = [{"body": "stator", "vector": str(tmp_path / "ry.txt")}]
    from_files = kryflex.reduce(kryflex.scene_from_dict(spec, base=GALILEO_DIR), quiet=True).model
    from_arrays = kryflex.reduce(kryflex.scene_from_dict(spec_from_arrays()), quiet=True).model
    freqs = np.geomspace(0.01, 10, 50)
    for angle in (0.0, 45.0):
        a, b = from_files.at([angle]), from_arrays.at([angle])
        assert a.dofs == b.dofs
        np.testing.assert_allclose(b.frequencies_hz, a.frequencies_hz, rtol=1e-10)
        np.testing.assert_allclose(b.frf(freqs), a.frf(freqs), rtol=1e-9, atol=1e-12 * np.abs(a.frf(freqs)).max())


def test_vector_as_petsc_vec_and_column_matrix():
    v = stator_ry_vector()
    vec = PETSc.Vec().createWithArray(v.copy(), comm=PETSc.COMM_SELF)
    for given in (vec, v.reshape(-1, 1), sp.csr_matrix(v.reshape(-1, 1)), v.tolist()):
        got = scene_io.resolve("scene", "outputs.x[0].vector", given, None, "vector")
        np.testing.assert_array_equal(got, v)


def test_resolver_reads_files_and_data_alike(tmp_path):
    modes = np.arange(12.0).reshape(6, 2)
    np.save(tmp_path / "modes.npy", modes)
    np.savetxt(tmp_path / "modes.txt", modes)
    scipy.io.mmwrite(str(tmp_path / "modes.mtx"), modes)
    for given in ("modes.npy", "modes.txt", "modes.mtx", modes, modes.tolist(), sp.csr_matrix(modes),
                  petsc_mat(modes)):
        got = scene_io.resolve("scene", "bodies.b.rigid_modes", given, str(tmp_path), "dense")
        np.testing.assert_array_equal(got, modes)


@pytest.mark.parametrize("bad, message", [
    (np.zeros(5), r"outputs.pointA_ry\[0\].vector \(array\): 5 entries, but body 'stator' has \d+ dofs"),
    ("nan", r"outputs.pointA_ry\[0\].vector: the array holds non-finite values"),
    (np.zeros((3, 4)), r"outputs.pointA_ry\[0\].vector: the array has shape \(3, 4\); give a vector"),
    ({"a": 1}, r"outputs.pointA_ry\[0\].vector: \{.*\} is neither a file name nor a vector"),
    (["x", "y"], r"outputs.pointA_ry\[0\].vector: list is not numeric data"),
])
def test_bad_vector_data_is_a_clear_error(bad, message):
    spec = spec_from_arrays()
    if isinstance(bad, str) and bad == "nan":
        bad = stator_ry_vector()
        bad[1] = np.nan
    spec["outputs"]["pointA_ry"][0]["vector"] = bad
    with pytest.raises(SceneError, match=message) as info:
        kryflex.scene_from_dict(copy.copy(spec))
    assert "not found" not in str(info.value) and "\n" not in str(info.value)


PROBE = """
import json, sys
import numpy as np
sys.path.insert(0, %r)
import kryflex
from petsc4py import PETSc
PETSc.Options().setValue("kf_quiet", True)
import test_scene_arrays as t
model = kryflex.reduce(kryflex.scene_from_dict(t.spec_from_arrays()), quiet=True).model
out = {str(a): model.at([a]).frequencies_hz.tolist() for a in (0.0, 45.0)}
if PETSc.COMM_WORLD.getRank() == 0:
    print("RESULT " + json.dumps(out))
"""


@pytest.mark.mpi
def test_arrays_on_two_ranks_match_serial():
    import json
    import subprocess
    import sys
    env = run_env.ENV
    proc = subprocess.run(["mpiexec", "-n", "2", sys.executable, "-c", PROBE % HERE], env=env, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (line,) = [x for x in proc.stdout.splitlines() if x.startswith("RESULT ")]
    parallel = json.loads(line[len("RESULT "):])
    serial = kryflex.reduce(kryflex.scene_from_dict(spec_from_arrays()), quiet=True).model
    for angle in (0.0, 45.0):
        np.testing.assert_allclose(parallel[str(angle)], serial.at([angle]).frequencies_hz, rtol=1e-9)
