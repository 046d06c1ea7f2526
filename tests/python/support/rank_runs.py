"""A Python script run under mpiexec on 1 and on 2 ranks, its results read back for comparison: shared by the
2-rank tests that compare a parallel result with the serial one (reducer/test_damped_check.py,
reducer/test_direct_check_bodywise.py)."""
import json
import subprocess
import sys


def results_on_ranks(script, folder, env, ranks=(1, 2), timeout=300):
    """Writes `script` (Python source) to folder/two.py and runs it with `mpiexec -n N` for each N in `ranks`; each run
    must exit 0 and print one line `RESULT <json>` (from rank 0). Returns the decoded results, one per N."""
    path = folder / "two.py"
    path.write_text(script)
    results = []
    for n in ranks:
        p = subprocess.run(["mpiexec", "-n", str(n), sys.executable, str(path)], env=env, capture_output=True,
                           text=True, timeout=timeout)
        assert p.returncode == 0, p.stderr[-2000:]
        line = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")][0]
        results.append(json.loads(line[7:]))
    return results
