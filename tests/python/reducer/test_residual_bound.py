"""The first residual of a block solve decided in double where its rounding bound allows (src/solve/flex_solver.c,
KFFlexSolverResidualBelow; the bound itself is checked against quadruple-precision sums in
tests/c/test_extended_product.c).

On the stiff stress scene spread-1e-5 (a rotor 1e-5 as stiff) the double product K_S X is mostly rounding: its blocks
must go on to the double-double residual (and be refined where that is above -kf_refine_rtol: 116 of 276 blocks, as
before), and a solver whose blocks stay undecided stops trying after 4. On Galileo every block is decided in double.
A block decided in double has its double residual plus its bound within the threshold.
"""
import json
import os
import re
import subprocess
import sys

import pytest

import run_env  # support/run_env.py: the repository's paths, the subprocesses' environment

LINE = re.compile(r"first residual ([0-9.e+-]+) in double, its rounding bound ([0-9.e+-]+) \(relative\): "
                  r"(below -kf_refine_rtol|measured in double-double)")
RTOL = 1e-6  # -kf_refine_rtol's default


def reduce_with_info(scene, out):
    p = subprocess.run([sys.executable, "-m", "kryflex", "reduce", scene, "-o", out, "-kf_verify", "false", "-info"],
                       env=run_env.COMMAND_ENV, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr
    with open(os.path.join(out, "summary.json")) as f:
        lines = [(float(r), float(b), what.startswith("below")) for r, b, what in LINE.findall(p.stdout + p.stderr)]
        return lines, json.load(f)["performance"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("residual_bound"))
    subprocess.run([sys.executable, os.path.join(run_env.ROOT, "meshes", "stress.py"), "--out", out], check=True,
                   capture_output=True, timeout=120)
    return {"stiff": reduce_with_info(os.path.join(out, "spread-1e-5", "scene.yaml"), os.path.join(out, "stiff")),
            "galileo": reduce_with_info(os.path.join(run_env.ROOT, "meshes", "galileo", "galileo.yaml"),
                                        os.path.join(out, "galileo"))}


def test_stiff_blocks_go_on_to_double_double(runs):
    lines, perf = runs["stiff"]
    assert lines and not any(below for _, _, below in lines)
    assert all(r + b > RTOL * 0.999 for r, b, _ in lines)  # the figures printed to 4 digits
    assert len(lines) < perf["solve_calls"]  # the solvers stopped trying
    # the residuals above the threshold were seen: those blocks were refined, the ones left above it are counted
    assert perf["refinement_solves"] > 0
    assert perf["residual_final_max"] <= RTOL or perf["blocks_unconverged"] > 0


def test_well_conditioned_blocks_are_decided_in_double(runs):
    lines, perf = runs["galileo"]
    assert lines and all(below for _, _, below in lines)
    assert all(r + b <= RTOL * 1.001 for r, b, _ in lines)
    assert perf["residual_first_max"] == pytest.approx(max(r for r, _, _ in lines), rel=1e-3)
