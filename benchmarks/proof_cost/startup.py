"""The fixed start-up and exit of `kryflex reduce` alone: the command run on a scene file that does not exist, so it
starts Python, imports what a reduction imports up to the scene's loading, starts MPI, PETSc and SLEPc, refuses the
scene (exit 2) and ends; two trees alternated, CPU seconds (user + sys) and wall per run, and their medians.

    .venv/bin/python benchmarks/proof_cost/startup.py [--other /work/main] [--repeat 10]
"""
import argparse
import os
import resource
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench import ROOT  # noqa: E402


def one(tree, work):
    """(wall, CPU) of one refused run of tree's kryflex."""
    cmd = [os.path.join(tree, "build", "kryflex"), "reduce", os.path.join(work, "no-such-scene.yaml"),
           "-o", os.path.join(work, "out")]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 2 or "no-such-scene.yaml" not in proc.stderr:
        sys.exit("%s: expected the scene refused (exit 2), got %d:\n%s" % (tree, proc.returncode, proc.stderr))
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--other", default="/work/main", help="the tree compared with this one")
    ap.add_argument("--repeat", type=int, default=10)
    ap.add_argument("--work", default="/tmp/startup")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    trees = [("other", args.other), ("this", ROOT)]
    got = {name: [] for name, _ in trees}
    print("kryflex reduce start-up and exit, %s UTC, load average %s" % (
        time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime()), " ".join("%.1f" % x for x in os.getloadavg())))
    for i in range(args.repeat):
        for name, tree in (trees if i % 2 == 0 else trees[::-1]):
            wall, cpu = one(tree, args.work)
            got[name].append((wall, cpu))
            print("run %2d %-5s (%s)  wall %.3f  CPU %.3f" % (i + 1, name, tree, wall, cpu))
    for name, tree in trees:
        print("median %-5s (%s)  wall %.3f  CPU %.3f" % (name, tree, statistics.median(w for w, _ in got[name]),
                                                        statistics.median(c for _, c in got[name])))
    print("load average %s" % " ".join("%.1f" % x for x in os.getloadavg()))


if __name__ == "__main__":
    main()
