"""MPI's start in a process not started by mpirun (kryflex._runtime.MPI_SINGLETON_DEFAULTS): Open MPI's singleton
without its daemon and without the fabric probe, only until PETSc has started (a program the process starts does not
inherit them), only where mpirun did not start the process, and never over a value the user set."""
import json
import os
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
NAMES = ("OMPI_MCA_pml", "OMPI_MCA_ess_singleton_isolated")
PROBE = r"""
import json, os, subprocess, sys
names = %r
import kryflex
before = {n: os.environ.get(n) for n in names}
kryflex.init()
from mpi4py import MPI
after = {n: os.environ.get(n) for n in names}
# the daemon a default singleton starts is this process's child (orted)
children = subprocess.run(["ps", "-o", "comm=", "--ppid", str(os.getpid())], capture_output=True, text=True).stdout.split()
out = dict(before=before, after=after, size=MPI.COMM_WORLD.Get_size(), rank=MPI.COMM_WORLD.Get_rank(),
           orted="orted" in children)
sys.stdout.write(json.dumps(out) + "\n")
""" % (NAMES,)


def env(**extra):
    e = {k: v for k, v in run_env.ENV.items()
         if k not in NAMES and not k.startswith(("OMPI_COMM_WORLD", "PMIX_", "PMI_"))}
    e.update(PYTHONPATH=run_env.PACKAGE)
    e.update(extra)
    return e


def probe(cmd, **extra):
    out = subprocess.run(cmd + [sys.executable, "-c", PROBE], env=env(**extra), capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    return [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]


def test_singleton_without_daemon_until_started():
    (got,) = probe([])
    assert got["before"] == {"OMPI_MCA_pml": "ob1", "OMPI_MCA_ess_singleton_isolated": "1"}
    assert got["after"] == {n: None for n in NAMES}     # taken out again once MPI has read them
    assert got["size"] == 1 and not got["orted"]


def test_user_value_wins():
    (got,) = probe([], OMPI_MCA_ess_singleton_isolated="0")
    assert got["before"] == {"OMPI_MCA_pml": "ob1", "OMPI_MCA_ess_singleton_isolated": "0"}
    assert got["after"] == {"OMPI_MCA_pml": None, "OMPI_MCA_ess_singleton_isolated": "0"}   # the user's stays
    assert got["orted"]    # Open MPI's default singleton: its daemon, as the user asked


@pytest.mark.mpi
def test_under_mpirun_nothing_set():
    got = probe(["mpiexec", "-n", "2"])
    assert sorted(g["rank"] for g in got) == [0, 1]
    for g in got:
        assert g["before"] == {n: None for n in NAMES} and g["size"] == 2
