"""Where every second of one `kryflex reduce` goes: a table whose rows sum to the process's wall time.

    .venv/bin/python benchmarks/proof_cost/account.py SCENE [--tree TREE] [--work DIR] [-- kryflex reduce options]

Python's part is timed by the arrival of the progress lines (each stamped by the C library's clock, which starts
with it; the offset of the first line gives the start-up before it); the C solve's part by summary.json's stage
seconds (timings_s, performance), whose remainder inside KFReducerSolve is printed as its own row. CPU seconds
(user + sys of the process and its children: the report's figure helpers included) are printed beside.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench import ROOT, first, stamps  # noqa: E402


def arrivals(cmd, env):
    """(wall, CPU, [(arrival s since launch, line)]) of one run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    got = [(time.perf_counter() - t0, line.rstrip("\n")) for line in proc.stdout]
    proc.wait()
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode:
        sys.exit("kryflex reduce exited %d:\n%s" % (proc.returncode, "\n".join(t for _, t in got[-40:])))
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), got


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--tree", default=ROOT, help="the kryflex tree whose build/kryflex runs (default: this one)")
    ap.add_argument("--work", default="/tmp/account")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    args = ap.parse_args(argv[:cut])
    args.extra = argv[cut + 1:]       # kryflex reduce's own options
    out = os.path.join(args.work, "out")
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    cmd = [os.path.join(args.tree, "build", "kryflex"), "reduce", args.scene, "-o", out] + args.extra
    load = os.getloadavg()[0]
    wall, cpu, got = arrivals(cmd, env)
    text = "\n".join(t for _, t in got)
    lines = stamps(text)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    perf, st = s.get("performance") or {}, s.get("timings_s") or {}

    def at(prefix):     # arrival of the first line with this text after its stamp
        return next(a for a, t in got if t.split("] ", 1)[-1].startswith(prefix))
    offset = got[0][0] - lines[0][0]              # launch -> the C library's clock at 0 (Python, imports, init)
    t_check = at("rigid-body and mechanism modes")             # the model check's rigid modes: the scene is loaded
    t_scene = at("scene '")                                   # KFReducerSolve's first line
    t_done = at("timings (s): basis")                         # its last
    t_write = at("writing the results")
    whole = perf.get("whole_s", 0.0)
    solve_rows = [("  assembly and rigid modes (per configuration)", st.get("assembly", 0.0)),
                  ("  factorization", perf.get("factorization_s", 0.0)),
                  ("  block solves", perf.get("solves_s", 0.0)),
                  ("  Krylov basis less its solves (orthogonalization, body bases)",
                   st.get("krylov", 0.0) - perf.get("solves_s", 0.0)),
                  ("  projection, search, compression (search %.2f s)" % (perf.get("search_s") or 0.0),
                   st.get("projection", 0.0))]
    solve_rows += [("  %s" % k, v) for k, v in st.items() if k not in ("assembly", "factorization", "krylov", "projection")]
    rows = [("start-up: Python, imports, the libraries' init (launch -> the C clock's 0)", offset),
            ("scene loading, the model check's assembly and rigid modes (-> its rigid-modes line)", t_check - offset),
            ("the model check's rest, the reducer's set-up (-> KFReducerSolve's first line)", t_scene - t_check),
            ("KFReducerSolve, its first to last line (whole_s %.2f)" % whole, t_done - t_scene)]
    if perf.get("certificate_count_s"):
        solve_rows.append(("    (in 'other': the certificate's mode count %.2f s)" % perf["certificate_count_s"], 0.0))
    rows += solve_rows
    rows.append(("  outside its stages (lines apart less the stages' sum)", (t_done - t_scene) - sum(v for _, v in solve_rows)))
    rows += [("after the solve: summary, verdict (-> 'writing the results')", t_write - t_done),
             ("writing: report, reduced.h5, summary.json, the process's exit", wall - t_write)]
    top = [v for n, v in rows if not n.startswith("  ")]
    print("kryflex reduce %s %s (tree %s), %s UTC, load average %.1f at the start, %.1f at the end" % (
        args.scene, " ".join(args.extra), args.tree, time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime()), load,
        os.getloadavg()[0]))
    print("verdict %s, error %s, %s system dofs" % (s.get("verdict_kind"), s.get("error_max"),
                                                   (s.get("full") or {}).get("system_dofs")))
    print("%-100s %8s" % ("row", "wall s"))
    for n, v in rows:
        print("%-100s %8.2f" % (n, v))
    print("%-100s %8.2f" % ("sum of the top rows", sum(top)))
    print("%-100s %8.2f  (CPU %.2f s, process and children)" % ("wall", wall, cpu))


if __name__ == "__main__":
    main()
