"""The certificate's mode count beside the reduction (python/kryflex/count_helper.py, src/reducer/certify.c): kryflex
reduce on one process starts a helper process that counts while the reduction runs, and the solve takes its counts.
Checked on the 2,760-dof solid, body-wise, certified from 0 dofs: the helper's counts are the in-process count's and a
dense SciPy count's, the verdict and reduced.h5 the in-process run's bit for bit; a helper that exits non-zero, is
killed or writes other configurations leaves the count in-process (the same verdict and model, exit 0, no traceback);
2 ranks count in-process, as 1 rank does."""
import json
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest
import scipy.linalg

import kryflex
from kryflex import _core

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from test_certified_verdict import evaluation_angles, solid  # noqa: E402,F401  (solid: the module's fixture)
from test_mode_count import ENV, ROOT, dense  # noqa: E402

OPTIONS = ["-kf_verify_certified_min_dofs", "0", "-kf_flex_solver", "bodywise"]


def run(scene, out, helper, child_code=None, ranks=1):
    """kryflex reduce with the count helper on (1) or off (0); child_code: what the helper runs instead of the count
    (count_helper.CHILD_CODE set in the command's process). Returns (the process, summary.json)."""
    code = "import sys; from kryflex.__main__ import _end, main; "
    if child_code is not None:
        code += "import kryflex.count_helper as c; c.CHILD_CODE = %r; " % child_code
    code += "_end(main(sys.argv[1:]))"
    cmd = [sys.executable, "-c", code, "reduce", scene, "-o", str(out)] + OPTIONS
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=ROOT,
                       env=dict(ENV, KRYFLEX_COUNT_HELPER=str(helper)))
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "Traceback" not in r.stdout + r.stderr
    return r, json.load(open(os.path.join(out, "summary.json")))


def scipy_count(path, angle, below_hz):
    """The full order's flexible modes below below_hz at one configuration (degrees), by SciPy's dense generalized
    eigenvalues below the cut alone (the solid's consistent mass is positive definite): those above 1e-6 of the
    cut's omega^2 (the rigid and mechanism modes sit at rounding's 1e-6 rad^2/s^2)."""
    system = _core.CSystem(kryflex.load_scene(path).cscene)
    system.set_angles(np.radians([angle]))
    Ms, Ks, _, _ = system.matrices()
    M, K, w2 = dense(Ms), dense(Ks), (2 * np.pi * below_hz) ** 2
    lam = scipy.linalg.eigh(0.5 * (K + K.T), 0.5 * (M + M.T), eigvals_only=True, subset_by_value=(-np.inf, w2))
    return int(np.sum(lam > 1e-6 * w2))


def datasets(path):
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
    return out


def same_model(a, b):
    da, db = datasets(os.path.join(a, "reduced.h5")), datasets(os.path.join(b, "reduced.h5"))
    assert sorted(da) == sorted(db) and da
    for name in da:
        x, y = np.asarray(da[name]), np.asarray(db[name])
        if x.dtype.kind == "O":      # names (variable-length strings)
            assert x.tolist() == y.tolist(), name
        else:
            assert x.shape == y.shape and x.tobytes() == y.tobytes(), name


def without_source(certificate):
    return {k: v for k, v in certificate.items() if k != "count_source"}


@pytest.fixture(scope="module")
def in_process(solid, tmp_path_factory):
    out = tmp_path_factory.mktemp("count_in_process") / "out"
    r, s = run(solid, out, 0)
    assert s["certificate"]["count_source"] == "in-process"
    assert "K - w^2 M at" in r.stdout and "helper" not in r.stdout
    return str(out), s


def test_the_helpers_counts_are_the_in_process_counts_and_scipys(solid, in_process, tmp_path):
    out = tmp_path / "out"
    r, s = run(solid, out, 1)
    ref_out, ref = in_process
    c = s["certificate"]
    assert c["count_source"] == "helper" and c["certified"]
    assert "counted at 7 configurations by the helper process" in r.stdout
    assert "K - w^2 M at" not in r.stdout       # nothing factored for the count here
    assert without_source(c) == without_source(ref["certificate"])
    # a midpoint (dense eigenvalues: seconds each; the in-process count is SciPy's at every configuration,
    # test_certified_verdict.py)
    angle = evaluation_angles(kryflex.load_scene(solid))[5]
    assert c["full_counts"][5] == scipy_count(solid, angle, c["below_hz"]) > 0
    for key in ("verdict_kind", "error_max", "target_met"):
        assert s[key] == ref[key], key
    same_model(str(out), ref_out)
    p = s["performance"]
    assert p["certificate_count_helper_s"] > 0 and p["certificate_count_helper_rss_mb"] > 0
    assert p["certificate_count_s"] >= 0
    assert not os.path.exists(out / "count_helper.log")      # kept only when the helper failed


@pytest.mark.parametrize("child, says", [
    ("import sys; sys.exit(3)", "it wrote no counts"),
    ("import os, signal; os.kill(os.getpid(), signal.SIGKILL)", "it wrote no counts"),
    ("import os, sys; os.write(int(sys.argv[1]), b'kfcount1 2 1 0.1\\n0 7 6 1\\n1 7 6 1\\nend\\n')",
     "it counted other configurations"),
])
def test_a_helper_that_fails_leaves_the_count_in_process(solid, in_process, tmp_path, child, says):
    out = tmp_path / "out"
    r, s = run(solid, out, 1, child_code=child)
    ref_out, ref = in_process
    assert "the helper process's counts are not used (%s): counting here" % says in r.stdout
    assert "K - w^2 M at" in r.stdout
    assert s["certificate"] == ref["certificate"] and s["certificate"]["count_source"] == "in-process"
    assert s["error_max"] == ref["error_max"] and s["verdict_kind"] == ref["verdict_kind"] == "certified"
    assert s["performance"].get("certificate_count_helper_s") is None
    same_model(str(out), ref_out)


def test_two_ranks_count_in_process_as_one_rank_does(solid, in_process, tmp_path):
    r, s = run(solid, tmp_path / "out", 1, ranks=2)
    c = s["certificate"]
    assert c["count_source"] == "in-process" and "helper" not in r.stdout
    assert c["full_counts"] == in_process[1]["certificate"]["full_counts"]
