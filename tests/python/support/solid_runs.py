"""The generated solid spacecraft (meshes/solid/generate.py) and `kryflex reduce` runs on it, shared by the
out-of-core and memory-limit tests (reducer/test_ooc.py, reducer/test_solver_work.py)."""
import os
import subprocess
import sys

from run_env import KRYFLEX, ROOT, on_ranks


def solid_scene(tmp_path_factory, name, refine, env):
    """The solid pair generated at mesh refinement `refine` in a fresh folder: the path of its scene file."""
    out = tmp_path_factory.mktemp(name)
    r = subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "solid", "generate.py"), "--refine", str(refine),
                        "-o", str(out)], env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return os.path.join(out, "spacecraft.yaml")


def reduce_solid(scene, out, ranks, *options, env):
    """`kryflex reduce` at 30 degrees without verification, on `ranks` ranks (mpiexec above 1): the finished process."""
    cmd = on_ranks(ranks, [KRYFLEX, "reduce", scene, "-o", str(out), "-kf_verify", "false", "-scene.angles", "30",
                           "-kf_error_agreement_timeout", "5", *options])
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600)
