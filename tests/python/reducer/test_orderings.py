"""Nested dissection through Debian's SCOTCH/PT-SCOTCH build of MUMPS, and auto's choice of the flexible solve.

On the 13,513-dof solid pair (meshes/solid --refine 1), one angle, verification off:
- the kryflex command runs the SCOTCH build: -kf_ordering scotch orders by SCOTCH on 1 and 2 ranks, -kf_ordering
  ptscotch runs PT-SCOTCH's parallel analysis on 2 ranks, and auto (MUMPS' own choice) is SCOTCH for this matrix;
- the reduced model is the same whichever ordering factored the stiffness (PORD, SCOTCH on 1 and 2 ranks, PT-SCOTCH):
  the same sizes, reduced frequencies and FRF error to rounding; and the same to the last bit when run again;
- -kf_ordering_tries analyses several SCOTCH seeds and keeps the factor with the fewest flops on the busiest rank,
  and -kf_scotch_seed orders with the seed it found at once;
- with the plain build (KRYFLEX_MUMPS=plain, or petsc4py imported before kryflex) -kf_ordering scotch says that MUMPS
  chose another ordering, and the reduction completes with the same model;
- -kf_flex_solver auto (the default) takes the monolithic solve for one configuration and the body-wise one for a
  reduction that visits several (here with -kf_bodywise_min_dofs lowered to the scene's size).
"""
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
KRYFLEX_CMD = run_env.KRYFLEX
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
ONE_ANGLE = ("-scene.angles", "30", "-kf_verify", "false")
SAME_FREQ = 1e-7     # reduced frequencies, relative: the orderings' factors differ by rounding (residuals ~1e-9)
SAME_ERROR = 1e-6    # the estimated FRF error, relative


@pytest.fixture(scope="module")
def solid(tmp_path_factory):
    out = tmp_path_factory.mktemp("orderings") / "solid"
    subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "solid", "generate.py"), "--refine", "1.0",
                    "-o", str(out)], check=True, capture_output=True, env=ENV)
    return str(out / "spacecraft.yaml")


def reduce_cli(scene, ranks, out, *opts, env=None):
    cmd = [KRYFLEX_CMD, "reduce", scene, "-o", str(out), *opts]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, capture_output=True, text=True, env=env or ENV, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    with open(os.path.join(out, "summary.json")) as f:
        return p.stdout + p.stderr, json.load(f)


def orderings(log):
    return re.findall(r"MUMPS analysis: (.+?) ordering", log)


@pytest.fixture(scope="module")
def runs(solid, tmp_path_factory):
    base = tmp_path_factory.mktemp("runs")
    return {"pord": reduce_cli(solid, 1, base / "pord", *ONE_ANGLE, "-kf_ordering", "pord"),
            "auto1": reduce_cli(solid, 1, base / "auto1", *ONE_ANGLE),
            "auto2": reduce_cli(solid, 2, base / "auto2", *ONE_ANGLE),
            "scotch1": reduce_cli(solid, 1, base / "scotch1", *ONE_ANGLE, "-kf_ordering", "scotch"),
            "scotch1_again": reduce_cli(solid, 1, base / "scotch1_again", *ONE_ANGLE, "-kf_ordering", "scotch"),
            "ptscotch": reduce_cli(solid, 2, base / "ptscotch", *ONE_ANGLE, "-kf_ordering", "ptscotch")}


def same_model(a, b):
    ra, rb = a["reduced"], b["reduced"]
    assert ra["dofs_per_body"] == rb["dofs_per_body"]
    fa, fb = np.array(ra["frequencies_hz"]["30"], float), np.array(rb["frequencies_hz"]["30"], float)
    np.testing.assert_allclose(fb, fa, rtol=SAME_FREQ)   # the flexible frequencies of the reassembled model
    assert abs(b["error_max"] - a["error_max"]) <= SAME_ERROR * a["error_max"]


@pytest.mark.mpi
def test_orderings_applied(runs):
    assert orderings(runs["pord"][0]) == ["pord"], runs["pord"][0]
    assert orderings(runs["scotch1"][0]) == ["scotch"], runs["scotch1"][0]
    assert orderings(runs["ptscotch"][0]) == ["ptscotch (parallel analysis)"], runs["ptscotch"][0]
    # auto: MUMPS' own choice, which the SCOTCH build makes SCOTCH here (the plain build chose PORD)
    assert orderings(runs["auto1"][0]) == ["scotch"], runs["auto1"][0]
    assert orderings(runs["auto2"][0]) == ["scotch"], runs["auto2"][0]


@pytest.mark.mpi
def test_scotch_ordering_is_repeatable(runs):
    """SCOTCH on one thread with a fixed seed: the same reduction twice gives the same model to the last bit (its
    threads had ordered the same matrix differently from run to run)"""
    a, b = runs["scotch1"][1], runs["scotch1_again"][1]
    assert a["reduced"]["frequencies_hz"] == b["reduced"]["frequencies_hz"]
    assert a["error_max"] == b["error_max"]


@pytest.mark.mpi
@pytest.mark.parametrize("name", ["auto1", "auto2", "ptscotch"])
def test_same_model_whatever_the_ordering(runs, name):
    same_model(runs["pord"][1], runs[name][1])


TRIED = re.compile(r"SCOTCH orderings of (\d+) seeds tried in [0-9.]+ s \(-kf_ordering_tries\), flops on the busiest rank "
                   r"([0-9.e+, -]+): seed (\d+) kept \(-kf_scotch_seed (\d+) orders so at once\)")


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
def test_ordering_tries_keep_the_fewest_flops(solid, runs, tmp_path, ranks):
    """-kf_ordering_tries 3: SCOTCH orderings of seeds 1, 3, 5 analysed, the factor with the fewest flops on the
    busiest rank kept; the reduced model is the same as with PORD's factor to rounding. -kf_scotch_seed with the
    seed the line names orders so at once (no tries): the same flops, and on one rank the same model to the last bit
    (on 2 ranks MUMPS' dynamic scheduling of a front's slaves may round differently from run to run). Without the
    options: one ordering (seed 1), no line."""
    log, summary = reduce_cli(solid, ranks, tmp_path / "tries", *ONE_ANGLE, "-kf_ordering_tries", "3")
    m = TRIED.search(log)
    assert m and m.group(1) == "3", log
    flops = [float(x) for x in m.group(2).split(",")]
    assert len(flops) == 3 and all(f > 0 for f in flops), log
    best = min(range(3), key=lambda i: (flops[i], i))        # ties keep the earlier seed
    assert int(m.group(3)) == int(m.group(4)) == [1, 3, 5][best], log
    assert orderings(log) == ["scotch"], log
    same_model(runs["pord"][1], summary)
    log2, again = reduce_cli(solid, ranks, tmp_path / "again", *ONE_ANGLE, "-kf_scotch_seed", m.group(4))
    assert not TRIED.search(log2), log2
    if ranks == 1:
        assert again["reduced"]["frequencies_hz"] == summary["reduced"]["frequencies_hz"]
        assert again["error_max"] == summary["error_max"]
    else:
        same_model(summary, again)
    for name in ("auto1", "auto2", "scotch1"):
        assert not TRIED.search(runs[name][0]), runs[name][0]


@pytest.mark.parametrize("option,value,message", [
    ("-kf_ordering_tries", "0", "0 is outside [1, inf); give an integer in [1, inf)"),
    ("-kf_scotch_seed", "0", "0 is outside [1, inf); give an integer in [1, inf)")])
def test_ordering_options_bad_value_is_refused(solid, tmp_path, option, value, message):
    p = subprocess.run([KRYFLEX_CMD, "reduce", solid, "-o", str(tmp_path / "bad"), *ONE_ANGLE, option, value],
                       capture_output=True, text=True, env=ENV, timeout=600)
    assert p.returncode == 2, p.stdout + p.stderr            # a bad option value, refused before the analysis
    assert "kryflex: error: %s %s: " % (option, value) in p.stderr and message in p.stderr, p.stderr
    assert "MUMPS analysis" not in p.stdout and "Traceback" not in p.stderr and not (tmp_path / "bad").exists()


@pytest.mark.mpi
def test_plain_mumps_falls_back(solid, runs, tmp_path):
    env = dict(ENV, KRYFLEX_MUMPS="plain")
    log, summary = reduce_cli(solid, 1, tmp_path / "plain", *ONE_ANGLE, "-kf_ordering", "scotch", env=env)
    assert "the MUMPS in use has no SCOTCH" in log and "libmumps-ptscotch-5.5" in log, log
    assert orderings(log) and orderings(log)[0] != "scotch", log
    same_model(runs["pord"][1], summary)


@pytest.mark.mpi
def test_auto_flex_solver_by_configurations(solid, runs, tmp_path):
    # one angle: monolithic (the runs above); two angles of interest: the system is visited at several configurations
    assert "body-wise" not in runs["auto1"][0]
    log, summary = reduce_cli(solid, 1, tmp_path / "two", "-scene.angles", "0,60", "-kf_verify", "false",
                              "-kf_bodywise_min_dofs", "10000")
    assert "flexible solve: body-wise" in log and "0 body factorizations now" in log, log   # the second reuses them
    assert summary["target_met"], log
    log, _ = reduce_cli(solid, 1, tmp_path / "small", "-scene.angles", "0,60", "-kf_verify", "false")
    assert "body-wise" not in log, log        # below the default -kf_bodywise_min_dofs (20,000)


def test_petsc4py_first_keeps_plain_mumps_and_says_so(solid, tmp_path):
    """A script that imports petsc4py before kryflex: PETSc bound to its plain MUMPS at load, so no SCOTCH; the
    progress line says why, and the reduction completes."""
    script = tmp_path / "script.py"
    script.write_text("import sys\nfrom petsc4py import PETSc\nimport kryflex\n"
                      "scene = kryflex.load_scene(sys.argv[1])\n"
                      "kryflex.Reducer(scene, search=False, verify=False, ordering='scotch').reduce()\n")
    p = subprocess.run([sys.executable, str(script), solid], capture_output=True, text=True, env=ENV, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    log = p.stdout + p.stderr
    assert "-kf_ordering scotch: the MUMPS in use has no SCOTCH" in log and "import kryflex before petsc4py" in log
    assert "scotch ordering" not in log, log
