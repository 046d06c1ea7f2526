"""Fixtures shared by the Python test modules."""
import pytest


@pytest.fixture(scope="module")
def quiet_library():
    """In-process flexible solves print progress lines unless -kryflex_quiet: silence them for a module."""
    from petsc4py import PETSc
    opts = PETSc.Options()
    was = opts.hasName("kryflex_quiet")
    opts.setValue("kryflex_quiet", True)
    yield
    if not was:
        opts.delValue("kryflex_quiet")
