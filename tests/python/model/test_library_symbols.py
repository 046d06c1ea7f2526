"""The C library exports the reducer object's API: a C or Fortran finite-element code links it without Python."""
import os
import re
import shutil
import subprocess

import pytest

pytestmark = pytest.mark.fast   # the fast tier (tests/README.md)

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
LIBRARY = os.path.join(ROOT, "build", "libkryflex.so")
HEADER = os.path.join(ROOT, "src", "include", "kryflex.h")


@pytest.mark.skipif(shutil.which("nm") is None, reason="nm (binutils) not installed")
def test_every_function_of_the_public_header_is_exported():
    declared = set(re.findall(r"PETSC_EXTERN\s+PetscErrorCode\s+(KF\w+)\s*\(", open(HEADER).read()))
    assert {"KFReducerCreate", "KFReducerSetFromOptions", "KFReducerSolve", "KFReducerGetReducedModel",
            "KFReducedModelSave", "KFReducedModelReassemble"} <= declared
    out = subprocess.run(["nm", "-D", "--defined-only", LIBRARY], capture_output=True, text=True, check=True).stdout
    exported = {line.split()[-1] for line in out.splitlines() if line.split()[-2:-1] == ["T"]}
    assert sorted(declared - exported) == []
