"""The peers bench's one-angle scenes (bench.kryflex_spec: angle 0, C = beta K with the bench's beta, the target, the
scene's reduction settings dropped) written as YAML files, so that `kryflex reduce` runs them on 1 and 2 ranks."""
import os, sys, yaml
import numpy as np
ROOT = sys.argv[1]
sys.path.insert(0, os.path.join(ROOT, "benchmarks", "peers"))
import bench
out = sys.argv[2]
for name, path in (("solid", "/tmp/peers57/solid/spacecraft.yaml"), ("galileo", os.path.join(ROOT, "meshes/galileo/galileo.yaml"))):
    scene = bench.ref.load_scene(path)
    beta = bench.elastic_setup(scene, 0.0)[5]
    for t in (1e-2, 1e-3, 1e-4):
        spec = bench.kryflex_spec(path, 0.0, float(beta), t)
        with open(os.path.join(out, "%s_%g.yaml" % (name, t)), "w") as f:
            yaml.safe_dump(spec, f)
    print(name, "beta", beta)
