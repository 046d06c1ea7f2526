"""The dense reference with M definite, this build against another (--other: a build directory, e.g. main's): Galileo
and the stress scenes of meshes/stress.py at one accuracy, on 1 and 2 ranks. Per case and build: the exit code,
the measured error, the reduced dofs (per body), and the direct-solve check's worst disagreement (summary.json).

    .venv/bin/python benchmarks/reference_check/dense_refine.py --other /tmp/spread/main/build --accuracy 1e-3
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
VARIANTS = ["damping-heavy", "damping-light", "far-angle", "light-mass", "many-moments", "mimo-8x8", "repeated",
            "spread-1e-5", "spread-1e5"]
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")


def run(build, scene, accuracy, ranks, out):
    cmd = [os.path.join(build, "kryflex"), "reduce", scene, "-o", out, "-scene.accuracy", str(accuracy), "-quiet"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    proc = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=600)
    row = {"exit": proc.returncode}
    path = os.path.join(out, "summary.json")
    if os.path.exists(path):
        with open(path) as f:
            d = json.load(f)
        row.update(error=d.get("error_max"), dofs="+".join(str(v) for v in d["reduced"]["dofs_per_body"].values()),
                   check=(d.get("reference_check") or {}).get("error"))
    return row


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--other", required=True, help="the other build directory (its kryflex binary)")
    p.add_argument("--accuracy", type=float, default=1e-3)
    a = p.parse_args()
    tmp = tempfile.mkdtemp(prefix="dense_refine_")
    subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "stress.py"), "--out", tmp], check=True,
                   capture_output=True, timeout=300)
    scenes = [("galileo", os.path.join(ROOT, "meshes", "galileo", "galileo.yaml"))]
    scenes += [(v, os.path.join(tmp, v, "scene.yaml")) for v in VARIANTS]
    builds = [("this", os.path.join(ROOT, "build")), ("other", a.other)]
    print("| scene | ranks | build | exit | error | reduced dofs | check disagreement |")
    print("|---|---|---|---|---|---|---|")
    for name, scene in scenes:
        for ranks in (1, 2):
            for label, build in builds:
                r = run(build, scene, a.accuracy, ranks, os.path.join(tmp, "%s-%d-%s" % (name, ranks, label)))
                fmt = lambda x: "%.6g" % x if isinstance(x, float) else str(x)
                print("| %s | %d | %s | %d | %s | %s | %s |" % (name, ranks, label, r["exit"], fmt(r.get("error")),
                                                          r.get("dofs", ""), fmt(r.get("check"))), flush=True)


if __name__ == "__main__":
    main()
