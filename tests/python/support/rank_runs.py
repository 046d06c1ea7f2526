"""Python scripts run on 1 and on 2 ranks: results_on_ranks (a script's results read back for comparison: the 2-rank
tests that compare a parallel result with the serial one) and probe_on_ranks (a probe that writes its results to a
file, on the ranks a test asks for)."""
import json
import subprocess
import sys

from run_env import on_ranks, run


def results_on_ranks(script, folder, env, ranks=(1, 2), timeout=300, args=()):
    """Writes `script` (Python source) to folder/two.py and runs it (with the arguments args) with `mpiexec -n N` for
    each N in `ranks`; each run must exit 0 and print one line `RESULT <json>` (from rank 0). Returns the decoded
    results, one per N."""
    path = folder / "two.py"
    path.write_text(script)
    results = []
    for n in ranks:
        p = subprocess.run(["mpiexec", "-n", str(n), sys.executable, str(path), *map(str, args)], env=env, capture_output=True,
                           text=True, timeout=timeout)
        assert p.returncode == 0, p.stderr[-2000:]
        line = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")][0]
        results.append(json.loads(line[7:]))
    return results


def probe_on_ranks(cmd, ranks, env, timeout=300, **kw):
    """cmd (a probe's command line: sys.executable, the probe, its arguments) on `ranks` ranks (under mpiexec above
    1), which must exit 0: the finished process (what the probe wrote is the test's to read)."""
    p = run(on_ranks(ranks, cmd), env=env, timeout=timeout, **kw)
    assert p.returncode == 0, "%s failed:\n%s\n%s" % (" ".join(cmd), p.stdout[-2000:], p.stderr[-2000:])
    return p
