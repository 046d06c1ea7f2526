"""A scene at its angles of interest (argument 2, default meshes/galileo/galileo.yaml: Galileo as it is): kryflex's search by
-kf_shared_directions: default (its default, false), split (false), tied (true) and auto (both measured, the smaller
kept). Per run: the bodies' sizes, the ties, the largest reassembled system dofs over the angles, kryflex's verified
elastic error and the method chosen.
Run from the worktree: .venv/bin/python benchmarks/peers/results/2026-11-30tied/galileo_angles.py TARGET [SCENE]  (SCENE: e.g. the solid of meshes/solid/generate.py --refine 0.5, angles 0/30/60/90)"""
import sys, time
import kryflex

GALILEO = sys.argv[2] if len(sys.argv) > 2 else "meshes/galileo/galileo.yaml"
acc = float(sys.argv[1])
cfg = [list(c) for c in kryflex.load_scene(GALILEO).configurations]    # degrees, one list per configuration
for label, opts in (("default", {}), ("split", {"shared_directions": False}), ("tied", {"shared_directions": True}),
                    ("auto", {"shared_directions": "auto"})):
    t = time.time()
    out = kryflex.reduce(kryflex.load_scene(GALILEO), quiet=True, accuracy=acc, **opts)
    m = out.model
    dofs = max(m.at(a).dofs for a in cfg)
    print("target %g %-7s: bodies %s, ties %s, system dofs %d (%d elastic states), error %.3g, met %s, %s, %.1f s"
          % (acc, label, m.sizes, 0 if m.ties is None else m.ties.shape[0], dofs, 2 * (dofs - 7),
             out.summary.verdict.error_max, out.summary.verdict.target_met, out.summary.chosen.method,
             time.time() - t), flush=True)
