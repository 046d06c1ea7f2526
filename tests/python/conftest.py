"""Fixtures shared by the Python test modules, and the helpers' folder (support/) on sys.path for every module."""
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "support"))

import run_env  # noqa: E402,F401  (before kryflex: the subprocesses' environment is the caller's, see run_env)
import kryflex  # noqa: F401  (first: the tests see the MUMPS the kryflex command uses, whoever imports petsc4py)


@pytest.fixture(scope="module")
def quiet_library():
    """In-process flexible solves print progress lines unless -kf_quiet: silence them for a module."""
    from petsc4py import PETSc
    opts = PETSc.Options()
    was = opts.hasName("kf_quiet")
    opts.setValue("kf_quiet", True)
    yield
    if not was:
        opts.delValue("kf_quiet")


def reassembled(model, angles_deg):
    """model.at(angles_deg) as the tuple the tests compare: (M, K, B, C, constraint rank, sigma ratio, rigid modes)."""
    s = model.at(angles_deg)
    return s.M, s.K, s.B, s.C, s.constraint_rank, s.sigma_ratio, s.rigid_modes

