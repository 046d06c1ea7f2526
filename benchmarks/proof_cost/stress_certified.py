"""The certified estimate (-kf_verify auto, threshold 0 dofs) on meshes/stress.py's scenes at 1e-2/1e-3/1e-4: its
verdict kind, the counts, its error beside the plain estimate's and the dense NumPy truth (test_stress_scenes.py's
measure), and whether it passes falsely. Add verify_certified_min_accuracy=1e-5 below to see the certificate at
1e-4 (the default measures there).

    .venv/bin/python benchmarks/proof_cost/stress_certified.py [OUT]
"""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path[:0] = [os.path.join(ROOT, "tests/python/support"), os.path.join(ROOT, "tests/python/reducer")]
import kryflex
from test_stress_scenes import VARIANTS, dense_error
out = sys.argv[1] if len(sys.argv) > 1 else "/tmp/stress_certified"
if not os.path.exists(os.path.join(out, VARIANTS[0], "scene.yaml")):
    subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "stress.py"), "--out", out], check=True, capture_output=True)
print("%-14s %7s %-9s %-9s %11s %11s %11s %s" % ("variant", "acc", "kind", "counts", "error", "plain est.", "dense", "verdict"))
for v in VARIANTS:
    path = os.path.join(out, v, "scene.yaml")
    for acc in (1e-2, 1e-3, 1e-4):
        try:
            red = kryflex.reduce(kryflex.load_scene(path), quiet=True, accuracy=acc, verify="auto", verify_certified_min_dofs=0,
                                 verify_certified_min_accuracy=1e-5)
            plain = kryflex.reduce(kryflex.load_scene(path), quiet=True, accuracy=acc, verify=False)
        except Exception as e:
            print("%-14s %7g error %s" % (v, acc, str(e)[:150])); continue
        s = red.summary.verdict
        c = s.certificate or {}
        truth = dense_error(path, red.model)
        fc, rc = c.get("full_counts", []), c.get("rich_counts", [])
        counts = "%d/%d" % (min(fc), min(rc)) if fc else "-"
        false_pass = s.target_met and truth > 1.02 * acc
        print("%-14s %7g %-9s %-9s %11.4g %11.4g %11.4g %s%s" % (v, acc, s.verdict_kind, counts, s.error_max,
              plain.summary.verdict.error_max, truth, "pass" if s.target_met else "miss", "  FALSE PASS" if false_pass else ""), flush=True)
