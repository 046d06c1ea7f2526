"""Never hang, never lose a result, never accept nonsense: the table-driven bad-input suite.

Every case (tests/python/support/bad_inputs/*_cases.py) breaks one thing in a fresh copy of meshes/galileo (or on the command
line, or in the environment) and runs the kryflex command on it, alone and under `mpiexec -n 2`, with a timeout.
It checks what every refusal must do (the exit codes of the manual's "Troubleshooting and exit codes"), not
whatever today's code happens to do:
- the documented exit code (2 input, 3 numeric, 4 output, 5 model file, 6 target missed, 130, 143);
- `kryflex: error: <message>` on stderr exactly once, also under 2 ranks; never a traceback;
- the message names the entry path / file and the offending value, and says what to do;
- no partial output: OUT absent before -> absent after; OUT holding an earlier result -> byte-identical, nothing new
  (no staging folder, no .tmp); input files untouched, nothing new beside them;
- no hang: a timeout fails the case as a hang;
- scene and file cases: kryflex.load_scene raises kryflex.SceneError with the same content (in-process, serial only,
  and only when the command neither crashed nor hung); model cases: kryflex.ReducedModel.load raises ModelFileError.
Good variants (class file, names good_*) must be accepted: exit 0, no error line.

Cases per class (test ids: class-case-npRANKS; `pytest -k scene-` runs one class):
    scene 108, file 51 (8 of them good variants), model 21, cli 27, env 9, mpi 6, target 2:
    224 cases, 442 runs (mpi cases run only under 2 ranks)
(test_suite_size prints the counts and checks there are at least 150.)

Run time: the cases run two at a time in the background in the order pytest runs them (BAD_INPUTS_WORKERS=1: one
at a time, inside each test), sharing one real reduction of Galileo (the earlier result copied into OUT).
"""
import collections
import os
import shutil
from concurrent.futures import ThreadPoolExecutor

import pytest

from bad_inputs import edits
from bad_inputs.cli_cases import CASES as CLI_CASES
from bad_inputs.env_cases import ENV_CASES, MPI_CASES, TARGET_CASES
from bad_inputs.file_cases import CASES as FILE_CASES
from bad_inputs.harness import (COMMAND, ENV, GALILEO_DIR, Ctx, check_api, check_outcome, fresh_copy, run_case)
from bad_inputs.model_cases import CASES as MODEL_CASES
from bad_inputs.scene_cases import CASES as SCENE_CASES

import kryflex

ALL = SCENE_CASES + FILE_CASES + MODEL_CASES + CLI_CASES + ENV_CASES + MPI_CASES + TARGET_CASES
PARAMS = [pytest.param(case, ranks, id=case.id(ranks), marks=[pytest.mark.mpi] if ranks > 1 else [])
          for case in ALL for ranks in case.ranks]
WORKERS = int(os.environ.get("BAD_INPUTS_WORKERS", "2"))

pytestmark = pytest.mark.skipif(not os.path.exists(COMMAND), reason="build/kryflex not built (./scripts/setup)")


def counts():
    return collections.Counter(c.cls for c in ALL)


# ------------------------------------------------------------------ shared: the earlier good result, the runner

@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return str(tmp_path_factory.mktemp("bad_inputs"))


@pytest.fixture(scope="module")
def cache(base):
    """One real `kryflex reduce` of meshes/galileo (with --npz): the earlier good result every 'earlier' OUT starts
    as, and the good reduced.h5 the model cases break."""
    import subprocess
    out = os.path.join(base, "earlier-result")
    p = subprocess.run([COMMAND, "reduce", os.path.join(GALILEO_DIR, "galileo.yaml"), "-o", out, "--npz", "-quiet"],
                       env=ENV, capture_output=True, text=True, timeout=300)
    assert p.returncode == 0 and os.path.isfile(os.path.join(out, "reduced.h5")), \
        "the good reduction the suite starts from failed: exit %d\n%s" % (p.returncode, p.stderr[-2000:])
    return out


class Runner:
    """Runs the cases WORKERS at a time, in the order the tests ask for them, ahead of the tests."""

    def __init__(self, base, cache, workers):
        self.base, self.cache = base, cache
        self.pool = ThreadPoolExecutor(max_workers=workers) if workers > 1 else None
        self.futures = {}

    def submit(self, case, ranks):
        key = case.id(ranks)
        if self.pool is not None and key not in self.futures:
            self.futures[key] = self.pool.submit(run_case, case, ranks, self.base, self.cache)

    def result(self, case, ranks):
        key = case.id(ranks)
        if self.pool is None:
            return run_case(case, ranks, self.base, self.cache)
        self.submit(case, ranks)
        return self.futures.pop(key).result()

    def close(self):
        if self.pool is not None:
            self.pool.shutdown(wait=True, cancel_futures=True)


@pytest.fixture(scope="module")
def runner(request, base, cache):
    r = Runner(base, cache, WORKERS)
    for item in request.session.items:          # the selected tests of this module, in their order
        spec = getattr(item, "callspec", None)
        if item.module is not None and item.module.__name__ == __name__ and spec and "case" in spec.params:
            r.submit(spec.params["case"], spec.params["ranks"])
    yield r
    r.close()


# ------------------------------------------------------------------ the suite

@pytest.mark.parametrize("case, ranks", PARAMS)
def test_case(case, ranks, runner):
    ctx, outcome = runner.result(case, ranks)
    problems = []
    try:
        check_outcome(case, ctx, outcome)
    except AssertionError as e:
        problems.append(str(e))
    crashed = outcome.hang or (outcome.returncode is not None and outcome.returncode < 0 and case.kind != "signal")
    if case.api and ranks == 1:
        if crashed:
            problems.append("in-process check skipped: the command %s" % ("hung" if outcome.hang else
                                                                          "died (signal %d)" % -outcome.returncode))
        else:
            try:
                check_api(case, ctx)
            except AssertionError as e:
                problems.append("python api: %s" % e)
    if not os.environ.get("BAD_INPUTS_KEEP"):
        shutil.rmtree(ctx.dir, ignore_errors=True)
    if problems:
        pytest.fail("\n".join(problems), pytrace=False)


def test_suite_size():
    """At least 150 cases, every class represented, ids unique."""
    n = counts()
    print("bad-input cases per class: %s; total %d, runs %d" % (dict(n), len(ALL), len(PARAMS)))
    assert len(ALL) >= 150, dict(n)
    assert set(n) == {"scene", "file", "model", "cli", "env", "mpi", "target"}
    assert len({p.id for p in PARAMS}) == len(PARAMS), "duplicate case names"


def test_indefinite_stiffness_refused_at_factorization(tmp_path):
    """A negative eigenvalue behind a positive diagonal is found only by the MUMPS factorization (negative pivots):
    load_scene accepts it, kryflex.reduce raises kryflex.Error (the command side is file-indefinite_behind_...)."""
    folder = str(tmp_path / "scene")
    fresh_copy(folder)
    ctx = Ctx(folder, str(tmp_path / "out"), "")
    edits.negative_eigenvalue(ctx)
    scene = kryflex.load_scene(ctx.scene)
    with pytest.raises(kryflex.Error) as err:
        kryflex.reduce(scene, quiet=True)
    assert "indefinite" in str(err.value).lower() or "negative" in str(err.value).lower(), str(err.value)
