"""Galileo reduced with one reducer keyword at two values, at each of two targets, beside its independent dense
reference: the module-scoped fixtures reducer/test_compress.py (compress) and reducer/test_static_exact.py
(static_exact) share, and the same reduction run on 2 MPI ranks for comparison with the serial one.

A test module makes its fixtures by assigning what the factories return to module names:

    both = galileo_pairs.pair_fixture("compress", (False, True))      # {False: result, True: result, "target": t}
    dense = galileo_pairs.dense_fixture("compress_dense")             # accuracy_scenes.DenseReference of Galileo
"""
import os
import subprocess
import sys

import numpy as np
import pytest
import yaml

import kryflex

import accuracy_scenes as acc

SUPPORT = os.path.dirname(os.path.abspath(__file__))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
PROBE = os.path.join(SUPPORT, "mpi_reducer_probe.py")
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PYTHONPATH)
TARGETS = (1e-3, 1e-4)


def galileo_settings():
    """Galileo's configurations of interest ([[angle]] each), band (Hz) and modal damping ratio, from its scene file."""
    with open(GALILEO) as f:
        raw = yaml.safe_load(f)
    return [[float(a)] for a in raw["angles"]], raw["band"], float(raw["damping"])


def reduce_galileo(accuracy, **keyword):
    """kryflex.reduce on Galileo at accuracy, quiet, with the reducer keyword(s) given."""
    return kryflex.reduce(kryflex.load_scene(GALILEO), quiet=True, accuracy=accuracy, **keyword)


def static_rounding(model, angles):
    """The relative rounding to expect in a reduced model's static moment L^0 at angles: machine epsilon times the
    condition of its flexible stiffness in the mass norm, (f_max / f_min)^2 over its flexible frequencies (Galileo's
    stiff reduced K: 3.5e7 to 4.0e7, so 7.7e-9 to 9.0e-9). Runs on 1 and 2 ranks sum in another order and so differ
    by up to this much (measured 2.0e-10 and 1.2e-9 at 1e-3 on an AMD EPYC, 2.05e-10 before on another machine)."""
    f = model.at(angles).frequencies_hz
    f = f[f > 1e-6 * f.max()]      # the rigid and mechanism modes, at 0 up to rounding, have no static compliance
    return np.finfo(float).eps * (f.max() / f.min()) ** 2


def static_moments(a, b, dense, angles):
    """The static moment L^0 of models a and b at angles and of the dense full order (its flexible modal sum), and
    how far a's is from b's (relative)."""
    La, Lb = a.at(angles).moments(1)[0], b.at(angles).moments(1)[0]
    full = dense.at(angles)
    f = ~full.rigid
    Lf = (full.hp[:, f] / full.lam[f]) @ full.pg[f]
    return La, Lb, Lf, np.linalg.norm(La - Lb) / np.linalg.norm(Lb)


def pair_fixture(keyword, values, targets=TARGETS, name="both"):
    """A module-scoped fixture, parametrized by target (ids "%g"): Galileo reduced with keyword=value for each value
    (in the order given), as {value: reduction, "target": target}."""
    @pytest.fixture(scope="module", params=targets, ids=lambda t: "%g" % t, name=name)
    def pair(request):
        out = {v: reduce_galileo(request.param, **{keyword: v}) for v in values}
        out["target"] = request.param
        return out
    return pair


def dense_fixture(folder, name="dense"):
    """A module-scoped fixture: Galileo's dense full-order reference (accuracy_scenes.DenseReference) cached in a
    temporary folder named after folder."""
    @pytest.fixture(scope="module", name=name)
    def dense(tmp_path_factory):
        return acc.DenseReference(GALILEO, str(tmp_path_factory.mktemp(folder)))
    return dense


def on_two_ranks(scene, folder, *options):
    """The scene reduced by kryflex.Reducer on 2 MPI ranks with the -kf_ options given (mpi_reducer_probe.py); the
    model it saved under folder, loaded."""
    path = os.path.join(str(folder), "m.h5")
    subprocess.run(["mpiexec", "-n", "2", sys.executable, PROBE, scene, path, os.path.join(str(folder), "s.json")]
                   + list(options), env=ENV, check=True, timeout=600, capture_output=True)
    return kryflex.ReducedModel.load(path)
