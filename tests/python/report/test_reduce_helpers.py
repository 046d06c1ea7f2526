"""kryflex reduce with its report's helper processes (started with the run, report/helper.py) writes the figures a run
without them writes, pixel for pixel (the PNGs' bytes too: the same encoder on the same data), serially and on 2
ranks, and leaves no helper running. The embedded Galileo scene at two angles (its paper section's figure included)."""
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
KRYFLEX = run_env.KRYFLEX
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
ENV = dict(run_env.ENV, MPLBACKEND="Agg")

pytestmark = pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built (cmake --build build)")


def reduce(out, helpers, ranks=1):
    cmd = [KRYFLEX, "reduce", GALILEO, "-o", str(out), "-quiet", "-scene.angles", "0,30"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, env=dict(ENV, KRYFLEX_REPORT_HELPER=helpers), capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert "Traceback" not in p.stderr
    return {name: (out / name).read_bytes() for name in os.listdir(out) if name.endswith(".png")}


def helpers_running():
    ps = subprocess.run(["ps", "-eo", "pid,args"], capture_output=True, text=True).stdout
    return [line for line in ps.splitlines() if "kryflex.report.helper" in line and ROOT in line]


@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
def test_helpers_started_with_the_run_draw_the_same_figures(tmp_path, ranks):
    alone = reduce(tmp_path / "alone", "0", ranks)
    helped = reduce(tmp_path / "helped", "1", ranks)
    assert len(alone) >= 6 and "paper_fig3.png" in alone
    assert sorted(helped) == sorted(alone)
    assert [name for name in alone if helped[name] != alone[name]] == []
    for name in ("bode_overview.png", "frf_error.png"):      # and they are pictures, not empty files
        assert np.asarray(Image.open(tmp_path / "helped" / name)).std() > 0
    assert helpers_running() == []
