"""The block Gram-Schmidt of the Krylov basis (src/krylov/block_arnoldi.c: row-chunked block products, two passes on
the kept M-products, each chain's next block from the basis's coordinates and the chain's complement) against a dense
NumPy reference on small models, serially and on 2 ranks: chains of equal and of very different lengths (the panels'
29 input blocks beside 1 output block; more output blocks than input ones), and an output collocated with an input,
whose chain lies in the input chain's space (every output column deflates in the basis, not in its own chain).

tests/python/support/krylov_dense_probe.py builds kryflex's basis and, with NumPy alone, the reference: K+ from a
dense pseudo-inverse, each chain by block Arnoldi with full re-orthogonalization, the chains' union M-orthonormalized
with the same deflation tolerance. The two spans must agree (largest principal angle) and so must the reduced model
(the eigenvalues of the projected K, M pair); kryflex's basis must be M-orthonormal and free of rigid content to
rounding.

The limits: the reference's K+ (a dense pseudo-inverse) and kryflex's (a sparse LDL^T with held dofs) each carry
about eps cond(K) ~ 1e-8 of relative error on these beam models, and the basis spans what they produce over 10
blocks: 1e-6 on the angle and 1e-7 on the eigenvalues leave a margin of 30x over the measured 2-4e-8 (2e-8 on the
eigenvalues where two columns deflate), and fail at once on a basis that misses a direction (sine ~1) or projects
with the wrong products.

Run (from the repository root): PYTHONPATH=python .venv/bin/python -m pytest -q tests/python/reducer/test_krylov_dense_reference.py
"""
import json
import os
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
PROBE = os.path.join(os.path.dirname(HERE), "support", "krylov_dense_probe.py")
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402
from rank_runs import probe_on_ranks  # noqa: E402

EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def free_scene(tmp_path_factory):
    """3 free bodies on two revolute joints (rigid and mechanism modes), 3 inputs and 2 outputs: two chains"""
    return frames.write_random_scene(str(tmp_path_factory.mktemp("dense_ref")), 600, nbodies=3, ninputs=3,
                                     noutputs=2, seed=7)


@pytest.fixture(scope="module")
def collocated_scene(free_scene, tmp_path_factory):
    """the free scene with a third output equal to its first input: that output's Krylov chain is the input chain's"""
    import yaml
    with open(free_scene) as f:
        scene = yaml.safe_load(f)
    scene["outputs"]["at_in0"] = [dict(e) for e in scene["inputs"]["in0"]]
    d = str(tmp_path_factory.mktemp("collocated"))
    base = os.path.dirname(free_scene)
    for body in scene["bodies"].values():
        for key in ("mass", "stiffness", "nodes"):
            if key in body and not os.path.isabs(body[key]):
                body[key] = os.path.join(base, body[key])
    path = os.path.join(d, "scene.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(scene, f)
    return path


def probe(scene, out, nranks, blocks=(8, 2)):
    probe_on_ranks([sys.executable, PROBE, scene, out, "--input-blocks", str(blocks[0]), "--output-blocks",
                    str(blocks[1])], nranks, dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE), cwd=ROOT)
    with open(out) as f:
        return json.load(f)


def check(r, nranks):
    print(r)
    assert r["ranks"] == nranks
    assert r["size"] == r["reference_size"] and r["size"] > 0
    assert r["orthonormality"] <= 20 * EPS and r["rigid_content"] <= 20 * EPS
    assert r["largest_sine"] <= 1e-6
    assert r["eigenvalues_rel"] <= 1e-7


@pytest.mark.parametrize("which", ["free", "clamped"])
def test_basis_spans_the_dense_reference(which, free_scene, tmp_path):
    r = probe(free_scene if which == "free" else "bc:clamped", str(tmp_path / "serial.json"), 1)
    check(r, 1)
    if which == "clamped":
        assert r["rigid_content"] == 0.0 and r["deflated"] > 0   # no rigid modes; the short beam's chains deflate


@pytest.mark.mpi
@pytest.mark.parametrize("which", ["free", "clamped"])
def test_basis_spans_the_dense_reference_on_two_ranks(which, free_scene, tmp_path):
    serial = probe(free_scene if which == "free" else "bc:clamped", str(tmp_path / "serial.json"), 1)
    r = probe(free_scene if which == "free" else "bc:clamped", str(tmp_path / "np2.json"), 2)
    check(r, 2)
    assert (r["size"], r["deflated"]) == (serial["size"], serial["deflated"])


# (input blocks, output blocks): the panels' shape (the output chain ends after its first block; the input chain's
# complement holds only the output columns), and the reverse (the output chain's complement grows with the input
# chain until that one ends)
SHAPES = {"long_input": (12, 1), "long_output": (2, 6)}


@pytest.mark.parametrize("shape", sorted(SHAPES))
def test_chains_of_different_lengths_span_the_dense_reference(shape, free_scene, tmp_path):
    check(probe(free_scene, str(tmp_path / "serial.json"), 1, SHAPES[shape]), 1)


def test_output_collocated_with_an_input_spans_the_dense_reference(collocated_scene, tmp_path):
    r = probe(collocated_scene, str(tmp_path / "serial.json"), 1)
    check(r, 1)
    assert r["deflated"] == 2   # one column of each output block: the collocated output's lies in the input chain


@pytest.mark.mpi
@pytest.mark.parametrize("case", ["long_input", "long_output", "collocated"])
def test_uneven_and_collocated_chains_on_two_ranks(case, free_scene, collocated_scene, tmp_path):
    scene, blocks = (collocated_scene, (8, 2)) if case == "collocated" else (free_scene, SHAPES[case])
    serial = probe(scene, str(tmp_path / "serial.json"), 1, blocks)
    r = probe(scene, str(tmp_path / "np2.json"), 2, blocks)
    check(r, 2)
    assert (r["size"], r["deflated"]) == (serial["size"], serial["deflated"])
