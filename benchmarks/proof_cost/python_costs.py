"""The Python side's own per-run costs that grow with the model, two trees side by side: reading the bodies' nodes
files (kryflex.io.scene._read_nodes, with the node table's checks), checking summary.json's values
(report.schema._check_json_types) and writing its text (Summary.dumps), each timed in CPU seconds in a fresh process
of each tree, the trees alternating, and the results' digests compared (the same node tables, the same text).

    .venv/bin/python benchmarks/proof_cost/python_costs.py --against /work/main --scene DIR/spacecraft.yaml \
        --summary OUT/summary.json [--rounds 5] [--repeat 5]

--summary: a 57k bare run's summary.json (its FRF blocks: 449 frequencies x 3 x 2 per configuration).
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

CHILD = r"""
import hashlib, json, os, sys, time
import yaml
from kryflex.io import scene as S
from kryflex.results import Summary
from kryflex.report.schema import _check_json_types
scene, summary, repeat = sys.argv[1], sys.argv[2], int(sys.argv[3])
base = os.path.dirname(os.path.abspath(scene))
bodies = yaml.safe_load(open(scene))["bodies"]
files = [b["nodes"] for b in (bodies.values() if isinstance(bodies, dict) else bodies)]
s = Summary.load(summary)
d = s.to_json()
best = {"nodes": 1e9, "check": 1e9, "dumps": 1e9}
for _ in range(repeat):
    t = time.process_time()
    tables = [S._read_nodes("scene", "nodes", f, base) for f in files]
    best["nodes"] = min(best["nodes"], time.process_time() - t)
    t = time.process_time()
    _check_json_types(d, ())
    best["check"] = min(best["check"], time.process_time() - t)
    t = time.process_time()
    text = s.dumps()
    best["dumps"] = min(best["dumps"], time.process_time() - t)
h = hashlib.sha256()
for tb in tables:
    for a in (tb[0], tb[1], tb[2], tb.comps):
        h.update(a.tobytes())
best["nodes_digest"] = h.hexdigest()[:16]
best["text_digest"] = hashlib.sha256(text.encode()).hexdigest()[:16]
print(json.dumps(best))
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", required=True, help="the other checkout's root (its python/)")
    ap.add_argument("--scene", required=True)
    ap.add_argument("--summary", required=True)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=5, help="timings per process (the least is kept)")
    args = ap.parse_args()
    trees = [("against", os.path.abspath(args.against)), ("this", ROOT)]
    got = {name: [] for name, _ in trees}
    print("python costs, load average %s" % " ".join("%.1f" % x for x in os.getloadavg()))
    for r in range(args.rounds):
        for name, root in (trees if r % 2 == 0 else trees[::-1]):
            env = dict(os.environ, PYTHONPATH=os.path.join(root, "python"), OPENBLAS_NUM_THREADS="1")
            out = subprocess.run([sys.executable, "-c", CHILD, args.scene, args.summary, str(args.repeat)], env=env,
                                 check=True, stdout=subprocess.PIPE, text=True).stdout
            x = json.loads(out.strip().splitlines()[-1])
            got[name].append(x)
            print("round %d %-7s nodes %.4f  check %.4f  dumps %.4f  (CPU s)  nodes %s  text %s"
                  % (r + 1, name, x["nodes"], x["check"], x["dumps"], x["nodes_digest"], x["text_digest"]), flush=True)
    med = lambda v: sorted(v)[len(v) // 2]  # noqa: E731
    for key in ("nodes", "check", "dumps"):
        a, t = med([x[key] for x in got["against"]]), med([x[key] for x in got["this"]])
        print("median %-6s against %.4f  this %.4f  (%.2fx, %.3f s less)" % (key, a, t, t / a, a - t))
    same = all(x["nodes_digest"] == got["against"][0]["nodes_digest"] and
               x["text_digest"] == got["against"][0]["text_digest"] for v in got.values() for x in v)
    print("the same node tables and summary.json text in every run: %s" % same)
    print("load average %s" % " ".join("%.1f" % x for x in os.getloadavg()))


if __name__ == "__main__":
    main()
