"""The fixed costs of kryflex reduce (everything but the factorization, the block solves and the verification), two
trees side by side in one run: another checkout (--against, e.g. main) and this one, each the bare run
(-kf_verify false) and the default run of the solid of meshes/solid, alternating, under stages.py (the wall and CPU
seconds of each Python stage: imports, scene loading, model check, the reduction, the summary, the report and its
figures, the model file), with bench.py's figures from the progress lines and summary.json.

    .venv/bin/python benchmarks/proof_cost/fixed_costs.py --against /work/main [--refine 1.55] [--repeat 1] [--work DIR]

Each tree runs on its own python/ and .venv. Read the CPU seconds on a shared machine: the wall ones follow its load.
"""
import argparse, json, os, re, resource, subprocess, sys, time
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench
ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--against", required=True, help="the other checkout's root (its python/ and .venv)")
ap.add_argument("--refine", type=float, default=1.55)
ap.add_argument("--repeat", type=int, default=1)
ap.add_argument("--work", default=os.path.join(bench.ROOT, "out", "fixed_costs"))
ARGS = ap.parse_args()
TREES = {"against": os.path.abspath(ARGS.against), "this": bench.ROOT}
WORK = ARGS.work
os.makedirs(WORK, exist_ok=True)
SCENE = bench.scene_of(ARGS.refine, WORK)

def run(tree, kind, rep):
    root = TREES[tree]
    out = os.path.join(WORK, "%s_%s_%d" % (tree, kind, rep))
    st = out + ".stages.json"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg", PYTHONPATH=os.path.join(root, "python"), STAGES=st)
    cmd = [os.path.join(root, ".venv/bin/python"), os.path.join(HERE, "stages.py"), "reduce", SCENE, "-o", out] + \
          (["-kf_verify", "false"] if kind == "bare" else [])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    open(out + ".log", "w").write(p.stdout + p.stderr)
    if p.returncode:
        sys.exit("%s %s exited %d: %s" % (tree, kind, p.returncode, p.stderr[-2000:]))
    lines = bench.stamps(p.stdout)
    s = json.load(open(os.path.join(out, "summary.json")))
    perf = s.get("performance") or {}
    t_check0, t_scene = bench.first(lines, "rigid-body and mechanism modes"), bench.first(lines, "scene '")
    t_write = bench.first(lines, "writing the results")
    t_search = bench.first(lines, "searching the smallest")
    stages = json.load(open(st))
    agg = {}
    for label, start, dw, dc in stages["rows"]:
        a = agg.setdefault(label, [0.0, 0.0]); a[0] += dw; a[1] += dc
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return dict(wall=wall, cpu=cpu, f=perf.get("factorization_s", 0), s=perf.get("solves_s", 0),
                whole=perf.get("whole_s"), search=perf.get("search_s"),
                check=(t_scene - t_check0), report=wall - t_write, error=s.get("error_max"),
                main_returned=stages["end"], exit_wall=wall - stages["end"][0], stages=agg,
                timings=s.get("timings_s"), eig=perf.get("reference_eigensolve_s"), direct=perf.get("reference_check_s"))

reps = ARGS.repeat
res = []
print("side by side, %s UTC, load average %s" % (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), " ".join("%.1f" % x for x in os.getloadavg())), flush=True)
for rep in range(reps):
    for tree in ("against", "this"):
        for kind in ("bare", "default"):
            r = run(tree, kind, rep)
            r.update(tree=tree, kind=kind, rep=rep, load=os.getloadavg()[0])
            res.append(r)
            print("%-7s %-8s wall %7.2f cpu %7.2f  f+s %5.2f  check %5.2f  search %5s  report %6.2f (%4.1f %%)  exit %5.2f  "
                  "error %.10g  load %.1f" % (tree, kind, r["wall"], r["cpu"], r["f"] + r["s"], r["check"],
                  "%.2f" % r["search"] if r["search"] is not None else "-", r["report"], 100 * r["report"] / r["wall"],
                  r["exit_wall"], r["error"], r["load"]), flush=True)
            print("        stages (wall/cpu): " + "; ".join("%s %.2f/%.2f" % (k, v[0], v[1]) for k, v in r["stages"].items()),
                  flush=True)
json.dump(res, open(os.path.join(WORK, "side.json"), "w"), indent=1)
