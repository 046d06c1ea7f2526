"""Where the tests find the repository and its programs, and the environment their subprocesses (kryflex, mpiexec,
python probes) run in.

ROOT      the repository (this file is tests/python/support/run_env.py).
PACKAGE   ROOT/python, the kryflex package's folder.
PYTHON    the interpreter running the tests: probes and examples run under the same virtual environment.
KRYFLEX   the kryflex command as CMake builds it (ROOT/build/kryflex).
PYTHONPATH  PACKAGE first, then the caller's PYTHONPATH (if any): a child imports this tree's kryflex, not an
          installed one, and still finds what the caller added (a sitecustomize, pytest's helpers).

BASE_ENV  the caller's environment with
          OMPI_ALLOW_RUN_AS_ROOT, OMPI_ALLOW_RUN_AS_ROOT_CONFIRM = 1: containers and CI run as root, and Open MPI's
              mpiexec refuses to start as root without both;
          OPENBLAS_NUM_THREADS = 1: the MPI ranks (or the test process and its child) already fill the machine's
              cores; BLAS threads on top would oversubscribe them and make timings and rounding order vary.
ENV       BASE_ENV and OMPI_MCA_rmaps_base_oversubscribe = 1: mpiexec -n 2 (or more) must start on a machine with
          fewer free slots than ranks (2 cores shared with other jobs), where Open MPI would otherwise refuse.
          PYTHONPATH is left as the caller's: a module that needs the package adds PYTHONPATH=PACKAGE (the package
          alone) or PYTHONPATH=PYTHONPATH (the package first, then the caller's). A module that runs mpiexec takes ENV
          (its ranks must start on a 1-core machine too); one that runs single processes only may keep BASE_ENV
          (reducer/test_settings_table.py, scene/test_nastran_import.py), where oversubscription changes nothing.

A module makes its own from these, e.g. ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE, MPLBACKEND="Agg")
(MPLBACKEND=Agg: a child that plots draws no window). Copy before changing: these dicts are shared by every module.

COMMAND_ENV  that example: ENV with the package alone on PYTHONPATH and MPLBACKEND=Agg, run()'s default.
run(cmd)     the command to its end, its output captured as text (a CompletedProcess), in COMMAND_ENV unless env=.
on_ranks(n, cmd)  cmd's command line on n MPI ranks: under mpiexec -n n, or cmd itself when n is 1.

The environment is read once, when this module is first imported: tests/python/conftest.py imports it before
kryflex, whose import puts Open MPI singleton defaults (OMPI_MCA_pml, OMPI_MCA_ess_singleton_isolated,
kryflex._runtime.MPI_SINGLETON_DEFAULTS) into the test process's environment until PETSc starts; a child, mpiexec
among them, does not inherit them.
"""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
PACKAGE = os.path.join(ROOT, "python")
PYTHON = sys.executable
KRYFLEX = os.path.join(ROOT, "build", "kryflex")
PYTHONPATH = os.pathsep.join(filter(None, [PACKAGE, os.environ.get("PYTHONPATH")]))

BASE_ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1")
ENV = dict(BASE_ENV, OMPI_MCA_rmaps_base_oversubscribe="1")
COMMAND_ENV = dict(ENV, PYTHONPATH=PACKAGE, MPLBACKEND="Agg")


def run(cmd, env=COMMAND_ENV, timeout=600, **kw):
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout, **kw)


def on_ranks(n, cmd):
    return (["mpiexec", "-n", str(n)] if n > 1 else []) + list(cmd)
