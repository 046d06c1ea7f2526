"""Fixtures shared by the Python test modules."""
import pytest

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


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a test that takes more than 30 s")
    config.addinivalue_line("markers", "mpi: a test that runs on 2 MPI ranks")
