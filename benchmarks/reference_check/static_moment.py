"""The reported static moment error against a dense NumPy one, on one angle (the peers bench's scenes).

For each target, the scene is reduced as benchmarks/peers/bench.py does (bench.kryflex_spec: one angle, C = beta K),
in this process, and it prints:

- reported: the summary's chosen.static_moment_error (the model's L^0 against kryflex's full-order moments);
- ref-dense: kryflex's full-order L^0 (full_moments, k = 0) against a dense one, ties eliminated two ways:
  bench.full_order (a pivoted QR of the ties) and reference.assemble (an SVD null space), each solved by
  reference.static_moment (double, refined with long-double residuals); dense-dense: the two against each other,
  the dense references' own floor;
- model-dense: the chosen model's L^0 against each dense one: what the model keeps, independently measured;
- the moments' seconds (time_moments), the whole reduction's, the block-solve columns, and this process's CPU seconds.

With --ranks N the reductions run as `mpiexec -n N build/kryflex reduce` on the scene written as YAML instead (the
model and summary.json read back; kryflex's own L^0 and the timings are then not printed).

    PYTHONPATH=python .venv/bin/python benchmarks/reference_check/static_moment.py --scene meshes/galileo/galileo.yaml
    .venv/bin/python meshes/solid/generate.py --refine 0.5 -o /tmp/solid      # the 2,760-dof solid, then
    PYTHONPATH=python mpiexec -n 2 .venv/bin/python benchmarks/reference_check/static_moment.py \
        --scene /tmp/solid/spacecraft.yaml --beta 0.000133 --ranks 2
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import yaml

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "benchmarks", "peers"))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
import bench  # noqa: E402
import reference as ref  # noqa: E402

import kryflex  # noqa: E402


def rel(x, y):
    return float(np.linalg.norm(x - y) / np.linalg.norm(y))


def dense_L0(scene_path, angle):
    """{'qr': L^0 with bench.full_order's ties, 'svd': with reference.assemble's}."""
    scene = ref.load_scene(scene_path)
    M, K, G, H, R = bench.full_order(scene, angle)
    out = {"qr": ref.static_moment(M.toarray(), K.toarray(), G, H, R)}
    Ms, Ks, Gs, Hs = ref.assemble(scene, [angle])
    out["svd"] = ref.static_moment(Ms, Ks, Gs, Hs, ref.geometric_rigid_modes(scene, [angle]))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", required=True)
    ap.add_argument("--angle", type=float, default=0.0)
    ap.add_argument("--beta", type=float, help="C = beta K (default: the peers bench's, zeta at the first mode)")
    ap.add_argument("--targets", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4])
    ap.add_argument("--options", nargs="*", default=[], help="reducer options key=value (-kf_ without the prefix)")
    ap.add_argument("--ranks", type=int, help="reduce with `mpiexec -n RANKS build/kryflex reduce` instead")
    args = ap.parse_args()
    path = os.path.abspath(args.scene)
    beta = args.beta if args.beta is not None else float(bench.elastic_setup(ref.load_scene(path), args.angle)[5])
    dense = dense_L0(path, args.angle)
    print("%s at %g deg, %d rank(s), beta %.3g, %s; dense-dense (qr vs svd ties) %.2e" % (
        args.scene, args.angle, args.ranks or 1, beta, time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        rel(dense["qr"], dense["svd"])), flush=True)
    if args.ranks:
        # mpiexec must not inherit the singleton defaults kryflex's import may have set in this process
        env = {k: v for k, v in os.environ.items() if k not in kryflex._runtime.MPI_SINGLETON_DEFAULTS}
        with tempfile.TemporaryDirectory() as folder:
            for target in args.targets:
                scene = os.path.join(folder, "scene_%g.yaml" % target)
                with open(scene, "w") as f:
                    yaml.safe_dump(bench.kryflex_spec(path, args.angle, beta, target), f, sort_keys=False)
                out = os.path.join(folder, "out_%g" % target)
                subprocess.run(["mpiexec", "-n", str(args.ranks), os.path.join(ROOT, "build", "kryflex"), "reduce",
                                scene, "-o", out, "-quiet"] + ["-kf_%s=%s" % tuple(o.split("=", 1)) for o in args.options],
                               check=True, capture_output=True, env=env)
                with open(os.path.join(out, "summary.json")) as f:
                    reported = max(e for e in json.load(f)["chosen"]["static_moment_error"].values() if e is not None)
                Lm = kryflex.ReducedModel.load(os.path.join(out, "reduced.h5")).at([args.angle]).moments(1)[0]
                print("target %g: reported %.2e; model-dense qr %.2e svd %.2e (%d ranks, kryflex reduce)" % (
                    target, reported, rel(Lm, dense["qr"]), rel(Lm, dense["svd"]), args.ranks), flush=True)
        return
    opts = dict(o.split("=", 1) for o in args.options)
    for target in args.targets:
        c0 = time.process_time()
        reducer = kryflex.Reducer(kryflex.scene_from_dict(bench.kryflex_spec(path, args.angle, beta, target)),
                                  quiet=True, **opts)
        out = reducer.reduce()
        cpu = time.process_time() - c0
        Lf = reducer.moments(0, "full_moments")[0]
        Lm = out.model.at([args.angle]).moments(1)[0]
        reported = max(e for e in out.summary.chosen.static_moment_error.values() if e is not None)

        def res(name):
            return float(np.ravel(reducer.result(-1, name))[0])
        print("target %g: reported %.2e; ref-dense qr %.2e svd %.2e; model-dense qr %.2e svd %.2e; "
              "moments %.3f s of %.2f s, %d solve columns, CPU %.2f s" % (
                  target, reported, rel(Lf, dense["qr"]), rel(Lf, dense["svd"]), rel(Lm, dense["qr"]),
                  rel(Lm, dense["svd"]), res("time_moments"), res("time_whole"), res("solve_columns"), cpu), flush=True)


if __name__ == "__main__":
    main()
