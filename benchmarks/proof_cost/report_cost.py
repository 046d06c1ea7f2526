"""The report of one summary.json written by two trees side by side (another checkout, e.g. main, and this one), each
in a fresh Python (the cost kryflex reduce pays: matplotlib's import included), alternating:

- alone:   KRYFLEX_REPORT_HELPER=0, every figure drawn by the process itself;
- on call: KRYFLEX_REPORT_HELPER=1, write_report starting its helper when called (both trees);
- ahead:   the helpers started first (report.helper.start_helpers, as kryflex reduce does when the run starts: told
           the band and the configurations where the tree's start_helpers takes them, so that they prepare their
           figures) and left to load matplotlib, then write_report timed (the reduction's time is not counted).

Printed per run: write_report's wall, this process's CPU and the helpers' CPU; then the PNGs' pixels (decoded) compared
with the same tree's alone run and the files both trees write with the other tree's alone run, summary.json and
report.md byte for byte. --modes: some of the three modes only. Run on an idle machine for the wall
figures; on a shared one read the CPU columns.

    .venv/bin/python benchmarks/proof_cost/report_cost.py OUTDIR_OF_A_DEFAULT_RUN --against /work/main [--repeat 3]
"""
import argparse, json, os, shutil, subprocess, sys, tempfile, time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

CHILD = r"""
import json, os, resource, sys, time
w0 = time.perf_counter()
from kryflex.results import Summary
from kryflex import report
s = Summary.load(sys.argv[1])
if sys.argv[3] == "ahead":
    import inspect
    from kryflex.report.helper import start_helpers, _ahead
    if "prepare" in inspect.signature(start_helpers).parameters:
        spec = {"band_hz": s.band_hz, "configurations": len(s.frf)}
        try:                # the pairs' names, where the tree's report draws them in one figure (kryflex reduce's spec)
            from kryflex.report.formatting import MAX_PAIRS_PER_FIGURE, pair_name
            pairs = [pair_name(o, i) for o in s.outputs for i in s.inputs]
            spec["pairs"] = pairs if len(pairs) <= MAX_PAIRS_PER_FIGURE else []
        except ImportError:
            pass
        start_helpers(prepare=spec)
    else:
        start_helpers()
    time.sleep(float(sys.argv[4]))          # the reduction's time, during which the helpers load matplotlib
def before():      # the helpers' CPU so far (their start and preparation), from /proc: not the report's
    if sys.argv[3] != "ahead":
        return 0.0
    ticks = 0
    for h in _ahead:
        with open("/proc/%d/stat" % h.proc.pid) as f:
            fields = f.read().rsplit(")", 1)[1].split()
        ticks += int(fields[11]) + int(fields[12])
    return ticks / os.sysconf("SC_CLK_TCK")
ahead_cpu = before()
k0 = resource.getrusage(resource.RUSAGE_CHILDREN)
c0, t0 = time.process_time(), time.perf_counter()
report.write_report(s, sys.argv[2])
c1, t1 = time.process_time(), time.perf_counter()
k1 = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps(dict(wall=t1 - t0, cpu=c1 - c0, helpers=(k1.ru_utime - k0.ru_utime) + (k1.ru_stime - k0.ru_stime),
                      ahead=ahead_cpu, whole_cpu=time.process_time())))
"""


def run(tree, summary_dir, out, mode, settle):
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg", PYTHONPATH=os.path.join(tree, "python"),
               KRYFLEX_REPORT_HELPER="0" if mode == "alone" else "1")
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    p = subprocess.run([os.path.join(tree, ".venv", "bin", "python"), "-c", CHILD, summary_dir, out, mode, str(settle)],
                       env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode:
        sys.exit("%s %s failed: %s" % (tree, mode, p.stderr[-2000:]))
    r = json.loads(p.stdout.strip().splitlines()[-1])
    r["process_wall"] = time.perf_counter() - t0
    return r


def contents(folder):
    """{file: its pixels (PNG, decoded) or bytes (summary.json, report.md)}."""
    import numpy as np
    from PIL import Image
    return {n: np.asarray(Image.open(os.path.join(folder, n))).tobytes() if n.endswith(".png")
            else open(os.path.join(folder, n), "rb").read() for n in os.listdir(folder)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("summary", help="the output folder of a default kryflex reduce (its summary.json)")
    ap.add_argument("--against", required=True, help="the other checkout's root (its python/ and .venv)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--settle", type=float, default=3.0, help="seconds the helpers started ahead get to load")
    ap.add_argument("--work", default=os.path.join(tempfile.gettempdir(), "kryflex_report_cost"))
    ap.add_argument("--modes", default="alone,on call,ahead", help="comma-separated, of: alone, on call, ahead")
    args = ap.parse_args()
    modes = tuple(m.strip() for m in args.modes.split(","))
    if "alone" not in modes:
        modes = ("alone",) + modes          # the reference of the comparisons
    trees = [("against", os.path.abspath(args.against), modes), ("this", ROOT, modes)]
    print("report of %s, %s UTC, load average %s" % (args.summary, time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
                                                    " ".join("%.1f" % x for x in os.getloadavg())), flush=True)
    print("%-8s %-8s %8s %8s %8s %8s %8s   load" % ("tree", "mode", "wall", "cpu", "helpers", "of it", "cpu sum"))
    print("(helpers: their whole CPU; of it: before write_report was called, their start and preparation while the "
          "reduction would run; cpu sum: the report's own, this process's and the helpers' less that)")
    best = {}
    for rep in range(args.repeat):
        for name, tree, modes in trees:
            for mode in modes:
                out = os.path.join(args.work, "%s_%s" % (name, mode.replace(" ", "_")))
                r = run(tree, args.summary, out, mode, args.settle)
                key = (name, mode)
                best[key] = min(best.get(key, r["wall"]), r["wall"])
                print("%-8s %-8s %8.2f %8.2f %8.2f %8.2f %8.2f   %.1f" % (name, mode, r["wall"], r["cpu"], r["helpers"],
                      r["ahead"], r["cpu"] + r["helpers"] - r["ahead"], os.getloadavg()[0]), flush=True)
    ref = contents(os.path.join(args.work, "against_alone"))
    for name, _, modes in trees:
        own = contents(os.path.join(args.work, "%s_alone" % name))
        for mode in modes:
            folder = os.path.join(args.work, "%s_%s" % (name, mode.replace(" ", "_")))
            got = contents(folder)
            same = sorted(got) == sorted(own) and all(got[n] == own[n] for n in own)
            common = sorted(set(got) & set(ref))
            differ = [n for n in common if got[n] != ref[n]]
            size = sum(os.path.getsize(os.path.join(folder, n)) for n in got if n.endswith(".png"))
            print("%-8s %-8s best wall %.2f s (%.2f of against alone); %d files (%d PNGs, %.2f MB), the same as its "
                  "tree's alone run: %s; of the %d files the against tree writes too, differing: %s" % (
                      name, mode, best[(name, mode)], best[(name, mode)] / best[("against", "alone")], len(got),
                      sum(n.endswith(".png") for n in got), size / 1e6, same, len(common), differ or "none"))


if __name__ == "__main__":
    main()
