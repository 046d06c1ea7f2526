"""The reported static moment error measures the model, not the reference's rounding (src/reducer/full_moments.c).

The summary's chosen.static_moment_error compares the model's L^0 with kryflex's full-order L^0, which is now
solved with refinement to the factor's floor (also where the other moments come from the Krylov basis). Checked on
Galileo at one angle as the peers bench runs it (C = beta K; its 28-dof Krylov space exhausted, the basis deflated:
the moments solved), and with 10 moments (the basis whole: L^0 solved, the rest from the basis), against a dense
NumPy L^0 of the same ties (benchmarks/peers/bench.full_order, reference.static_moment: double, long-double
residuals), on 1 and 2 ranks:

- kryflex's reference L^0 is the dense one to 1e-12 (6e-14 measured; 1e-10 with the block solves unrefined);
- the reported error and the dense error of the model's L^0 agree within a factor 2 (1.9e-12 and 2.0e-12
  measured; 1.07e-10 reported against 2.0e-12 before), both within the 1e-10 promised.

With the moments solved unrefined the "solved" case fails (reference 1.1e-10 from the dense one on 1 rank, 3.0e-11 on
2); the "basis" one passed before too (the basis's L^0 was accurate there), and stays as a check of that path.
"""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "support"))
import run_env  # noqa: E402
sys.path.insert(0, os.path.join(run_env.ROOT, "benchmarks", "peers"))
import bench  # noqa: E402
import reference as ref  # noqa: E402

GALILEO = os.path.join(run_env.ROOT, "meshes", "galileo", "galileo.yaml")
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PYTHONPATH, MPLBACKEND="Agg")
ANGLE = 0.0
PROMISE = 1e-10      # the static moment "exact": relative Frobenius, as static_gain_error
REFERENCE_RTOL = 1e-12
AGREE = 2.0          # reported / dense, either way

pytestmark = pytest.mark.usefixtures("quiet_library")

PROBE = r"""
import json, sys, numpy as np, kryflex
spec = json.loads(sys.argv[1])
r = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True)
out = r.reduce()
res = {"reported": max(e for e in out.summary.chosen.static_moment_error.values() if e is not None),
       "reference": r.moments(0, "full_moments")[0].tolist(),
       "model": out.model.at([spec["angles"][0]]).moments(1)[0].tolist()}
from mpi4py import MPI
if MPI.COMM_WORLD.rank == 0:
    print("RESULT " + json.dumps(res))
"""


def rel(x, y):
    return float(np.linalg.norm(np.asarray(x) - y) / np.linalg.norm(y))


@pytest.fixture(scope="module")
def dense():
    """Galileo's L^0 at ANGLE, dense, and the bench's beta."""
    scene = ref.load_scene(GALILEO)
    M, K, G, H, R = bench.full_order(scene, ANGLE)
    beta = float(bench.elastic_setup(scene, ANGLE)[5])
    return ref.static_moment(M.toarray(), K.toarray(), G, H, R), beta


def spec(beta, moments):
    s = bench.kryflex_spec(GALILEO, ANGLE, beta, 1e-2)
    if moments:
        s["reduction"] = {"moments_max": moments}
    return s


def run(s, ranks, tmp_path):
    if ranks == 1:
        r = kryflex.Reducer(kryflex.scene_from_dict(s), quiet=True)
        out = r.reduce()
        return {"reported": max(e for e in out.summary.chosen.static_moment_error.values() if e is not None),
                "reference": r.moments(0, "full_moments")[0], "model": out.model.at([ANGLE]).moments(1)[0]}
    probe = tmp_path / "probe.py"
    probe.write_text(PROBE)
    p = subprocess.run(["mpiexec", "-n", str(ranks), run_env.PYTHON, str(probe), json.dumps(s)], env=ENV,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    return json.loads([x for x in p.stdout.splitlines() if x.startswith("RESULT ")][0][7:])


@pytest.mark.parametrize("ranks", [pytest.param(1, marks=pytest.mark.fast), pytest.param(2, marks=pytest.mark.mpi)])
@pytest.mark.parametrize("moments", [None, 10], ids=["solved", "basis"])
def test_reported_static_error_is_the_dense_one(dense, moments, ranks, tmp_path):
    L0, beta = dense
    got = run(spec(beta, moments), ranks, tmp_path)
    reference, model = rel(got["reference"], L0), rel(got["model"], L0)
    print("%d rank(s), %s: reference vs dense %.2e, reported %.2e, model vs dense %.2e"
          % (ranks, moments, reference, got["reported"], model))
    assert reference <= REFERENCE_RTOL
    assert got["reported"] <= PROMISE and model <= PROMISE
    assert 1 / AGREE <= got["reported"] / model <= AGREE
