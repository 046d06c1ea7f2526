"""Galileo at its 6 angles of interest (meshes/galileo/galileo.yaml as it is): kryflex's search split without and with
compression, and with shared directions (compression skipped). Per run: the bodies' sizes, the ties, the largest
reassembled system dofs over the angles, kryflex's verified elastic error and the method chosen.
Run from the worktree: .venv/bin/python benchmarks/peers/results/2026-11-30t/galileo_angles.py TARGET"""
import sys, time
import kryflex

GALILEO = "meshes/galileo/galileo.yaml"
acc = float(sys.argv[1])
cfg = [list(c) for c in kryflex.load_scene(GALILEO).configurations]    # degrees, one list per configuration
for sd, comp in ((False, False), (False, True), (True, False)):
    t = time.time()
    out = kryflex.reduce(kryflex.load_scene(GALILEO), quiet=True, accuracy=acc, shared_directions=sd, compress=comp)
    m = out.model
    dofs = max(m.at(a).dofs for a in cfg)
    print("target %g shared_directions %-5s compress %-5s: bodies %s, ties %s, system dofs %d (%d elastic states), "
          "error %.3g, met %s, %s, %.1f s" % (acc, sd, comp, m.sizes, 0 if m.ties is None else m.ties.shape[0], dofs,
                                             2 * (dofs - 7), out.summary.verdict.error_max,
                                             out.summary.verdict.target_met, out.summary.chosen.method,
                                             time.time() - t))
