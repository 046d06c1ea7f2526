"""Out-of-core factorization (-kf_ooc true, -kf_ooc_dir): the same reduced model as in core, and the factor's folder
removed after the run, whether it succeeded or failed, on 1 and 2 ranks."""
import os
import subprocess

import numpy as np
import pytest

import kryflex
from solid_runs import reduce_solid, solid_scene

import run_env  # support/run_env.py: the repository's paths, the subprocesses' environment
KRYFLEX = run_env.KRYFLEX
ENV = dict(run_env.ENV)   # a copy: MUMPS_OOC_TMPDIR is taken out below
ENV.pop("MUMPS_OOC_TMPDIR", None)
EXIT_NUMERIC = 3

pytestmark = pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built (scripts/setup)")


@pytest.fixture(scope="module")
def solid14k(tmp_path_factory):
    """The 13,513-dof solid pair: MUMPS writes its factor to disk out of core (13 MB in core against 32 MB)."""
    return solid_scene(tmp_path_factory, "solid14k", 1, ENV)


def _reduce(scene, out, ranks, *options):
    return reduce_solid(scene, out, ranks, *options, env=ENV)


def _leftovers(folder):
    """What a run left in a folder besides its results: hidden entries (staging and out-of-core folders)."""
    return sorted(n for n in os.listdir(folder) if n.startswith(".")) if os.path.isdir(folder) else []


@pytest.mark.slow
@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
def test_out_of_core_gives_the_in_core_model(solid14k, tmp_path, ranks):
    """-kf_ooc true, factors under -kf_ooc_dir: the reduced model's frequencies and frequency response equal the
    in-core run's to 1e-10; the folder holds nothing after the run, and the output no hidden folder."""
    parent = tmp_path / "scratch"
    parent.mkdir()
    p = _reduce(solid14k, tmp_path / "ooc", ranks, "-kf_ooc", "true", "-kf_ooc_dir", str(parent))
    assert p.returncode == 0, p.stderr
    log = p.stdout + p.stderr
    assert "out-of-core factors in %s/.kryflex-ooc-" % parent in log
    assert "MUMPS analysis:" in log and ", out-of-core," in log
    assert os.listdir(parent) == []
    assert _leftovers(tmp_path / "ooc") == []
    q = _reduce(solid14k, tmp_path / "incore", ranks, "-kf_ooc", "false")
    assert q.returncode == 0, q.stderr
    assert "out-of-core" not in q.stdout + q.stderr
    a, b = (kryflex.ReducedModel.load(str(tmp_path / d / "reduced.h5")).at([30.0]) for d in ("ooc", "incore"))
    assert a.K.shape == b.K.shape
    # out of core, MUMPS sums in another order: 1 rank agreed to 1e-10, 2 ranks to 3.7e-10 (the 1.9 kHz mode)
    np.testing.assert_allclose(a.frequencies_hz, b.frequencies_hz, rtol=1e-9, atol=0)
    f = np.linspace(0.05, 15, 60)
    Ha, Hb = a.frf(f), b.frf(f)
    # per input/output pair, against that pair's peak: the measure of the reduction's accuracy
    err = np.abs(Ha - Hb).max(axis=0) / np.abs(Hb).max(axis=0)
    assert err.max() <= 1e-10, err


@pytest.mark.slow
@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
def test_out_of_core_folder_removed_after_a_failure(solid14k, tmp_path, ranks):
    """A factorization that fails after the folder is made (MUMPS' workspace capped at 1 MB, -mat_mumps_icntl_23):
    exit 3 with MUMPS' failure named; nothing left, neither under -kf_ooc_dir nor in the output folder (the default
    parent: the output's staging folder)."""
    parent = tmp_path / "scratch"
    parent.mkdir()
    p = _reduce(solid14k, tmp_path / "given", ranks, "-kf_ooc", "true", "-kf_ooc_dir", str(parent),
                "-mat_mumps_icntl_23", "1")
    assert p.returncode == EXIT_NUMERIC, p.stderr
    assert "out-of-core factors in" in p.stdout + p.stderr
    assert "MUMPS could not factor" in p.stderr and "Traceback" not in p.stderr
    assert os.listdir(parent) == []
    (tmp_path / "staged").mkdir()
    p = _reduce(solid14k, tmp_path / "staged", ranks, "-kf_ooc", "true", "-mat_mumps_icntl_23", "1")
    assert p.returncode == EXIT_NUMERIC, p.stderr
    assert "out-of-core factors in %s/.kryflex-" % (tmp_path / "staged") in p.stdout + p.stderr
    assert os.listdir(tmp_path / "staged") == []


@pytest.mark.fast
def test_out_of_core_folder_that_cannot_be_made(solid14k, tmp_path):
    """-kf_ooc_dir naming no folder: exit 3, the message names the folder and the fixes, no traceback."""
    missing = tmp_path / "no" / "such"
    p = _reduce(solid14k, tmp_path / "out", 1, "-kf_ooc", "true", "-kf_ooc_dir", str(missing))
    assert p.returncode == EXIT_NUMERIC, p.stderr
    assert str(missing) in p.stderr and "-kf_ooc_dir" in p.stderr and "-kf_ooc false" in p.stderr
    assert "Traceback" not in p.stderr
    assert not (tmp_path / "out").exists()


@pytest.fixture(scope="module")
def solid57k(tmp_path_factory):
    """The 57,031-dof solid pair: large enough that MUMPS' block low-rank estimate is below its full-rank one."""
    return solid_scene(tmp_path_factory, "solid57k", 1.55, ENV)


@pytest.mark.slow
def test_auto_takes_block_low_rank_between_its_estimate_and_full_rank(solid57k, tmp_path):
    """-kf_ooc auto with the plain MUMPS build (KRYFLEX_MUMPS=plain: block low-rank is not tried with the SCOTCH
    build): at a memory limit between MUMPS' block low-rank and full-rank in-core estimates (read off the refusal at a
    tiny limit), the factorization is block low-rank in core, or, when its factors compress worse than MUMPS
    assumed, out of core after a clean failure; either way the in-core model (measured: frequencies 1.6e-8, the
    in-band response 3.7e-12 apart at -kf_blr 1e-8)."""
    import re
    env = dict(ENV, KRYFLEX_MUMPS="plain")

    def run(out, *options):
        return subprocess.run([KRYFLEX, "reduce", solid57k, "-o", str(out), "-kf_verify", "false", "-scene.angles",
                               "30", *options], env=env, capture_output=True, text=True, timeout=600)
    p = run(tmp_path / "refused", "-kf_memory_limit_mb", "1e-3")
    assert p.returncode == EXIT_NUMERIC, p.stderr
    m = re.search(r"full rank would need ([0-9.e+]+) MB on one node and block low-rank \(-kf_blr 1e-08\) ([0-9.e+]+) MB",
                  p.stdout + p.stderr)
    assert m, p.stdout + p.stderr
    full, blr = float(m.group(1)), float(m.group(2))
    assert blr < full
    p = run(tmp_path / "auto", "-kf_memory_limit_mb", str(full - 0.25 * (full - blr)))
    assert p.returncode == 0, p.stderr
    log = p.stdout + p.stderr
    assert "block low-rank (-kf_blr 1e-08), MUMPS' estimate" in log
    assert ", block low-rank, estimate" in log or "factoring out of core, full rank" in log
    q = run(tmp_path / "incore", "-kf_ooc", "false")
    assert q.returncode == 0, q.stderr
    a, b = (kryflex.ReducedModel.load(str(tmp_path / d / "reduced.h5")).at([30.0]) for d in ("auto", "incore"))
    np.testing.assert_allclose(a.frequencies_hz, b.frequencies_hz, rtol=1e-6, atol=0)
    f = np.linspace(0.05, 15, 60)
    Ha, Hb = a.frf(f), b.frf(f)
    assert (np.abs(Ha - Hb).max(axis=0) / np.abs(Hb).max(axis=0)).max() <= 1e-8
