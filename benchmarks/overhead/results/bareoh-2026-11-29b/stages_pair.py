"""The bare run's stages (benchmarks/proof_cost/stages.py: wall and CPU seconds of each Python stage) for two trees,
alternating, and the process's own wall and CPU (rusage of the child: user + sys).

    .venv/bin/python benchmarks/overhead/results/bareoh-2026-11-29b/stages_pair.py SCENE OTHER_TREE REPEAT WORK
"""
import json, os, resource, subprocess, sys, time
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(HERE))))
STAGES = os.path.join(ROOT, "benchmarks", "proof_cost", "stages.py")
scene, other, repeat, work = sys.argv[1], os.path.abspath(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
trees = [("main", other), ("this", ROOT)]
os.makedirs(work, exist_ok=True)
rows = {}
print("bare run stages, %s UTC, load %s" % (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), os.getloadavg()))
for rep in range(repeat):
    for name, root in (trees if rep % 2 == 0 else trees[::-1]):
        out = os.path.join(work, "%s_%d" % (name, rep))
        st = out + ".json"
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg", PYTHONPATH=os.path.join(root, "python"),
                   STAGES=st)
        b = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        p = subprocess.run([os.path.join(root, ".venv/bin/python"), STAGES, "reduce", scene, "-o", out, "-kf_verify",
                            "false"], env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        a = resource.getrusage(resource.RUSAGE_CHILDREN)
        assert p.returncode == 0, p.stderr[-2000:]
        d = json.load(open(st))
        agg = {}
        for label, start, dw, dc in d["rows"]:
            w, c = agg.get(label, (0, 0))
            agg[label] = (w + dw, c + dc)
        agg["main returned"] = tuple(d["end"])
        agg["process (rusage)"] = (wall, (a.ru_utime - b.ru_utime) + (a.ru_stime - b.ru_stime))
        agg["process less main returned"] = (wall - d["end"][0], agg["process (rusage)"][1] - d["end"][1])
        perf = json.load(open(os.path.join(out, "summary.json"))).get("performance") or {}
        agg["factorization + solves (C)"] = (perf.get("factorization_s", 0) + perf.get("solves_s", 0), float("nan"))
        rows.setdefault(name, []).append(agg)
        print("%s run %d: wall %.2f cpu %.2f, load %.1f" % (name, rep + 1, wall, agg["process (rusage)"][1], os.getloadavg()[0]), flush=True)
labels = [k for k in rows["this"][0]]
print("\n%-40s %s" % ("stage: wall / cpu s", "  ".join("%-13s" % ("%s #%d" % (n, i + 1)) for i in range(repeat) for n in ("main", "this"))))
for k in labels:
    cells = []
    for i in range(repeat):
        for n in ("main", "this"):
            w, c = rows[n][i].get(k, (float("nan"), float("nan")))
            cells.append("%5.2f / %5.2f" % (w, c))
    print("%-40s %s" % (k, "  ".join(cells)))
