"""Several angles of interest, kryflex's compression of tied models (the compressed tied model competing under auto):
kryflex's own models under the bench's spec (compression on, -kf_shared_directions auto; each with the static response
exact and with -kf_static_exact 0), measured by the bench's independent elastic error at every angle of interest and
midpoint (multiangle.py's set-up, run as it is), beside the CPU seconds of the whole reduction and of its compression.
    python tiedcompress.py --scene SCENE [--targets 1e-2 1e-3 1e-4]
"""
import os, sys, time
HERE = os.path.dirname(os.path.abspath(__file__))
MULTI = os.path.join(HERE, "..", "2026-12-01m", "multiangle.py")
sys.argv += ["--kryflex-only"]
__file__ = MULTI    # multiangle.py finds tied.py beside it
exec(compile(open(MULTI).read().split("\nimport kryflex\n")[0], MULTI, "exec"))    # its set-up and independent()
import numpy as np
import kryflex
for target in args.targets:
    for label, opts in (("static exact", {}), ("static_exact 0", {"static_exact": "0"})):
        spec = B.kryflex_spec(path, angles[0], beta, target)
        spec["angles"] = list(angles)
        c0 = time.process_time()
        reducer = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, **opts)
        out = reducer.reduce()
        cpu = time.process_time() - c0
        model = out.model
        worst, el, s_ = independent(model)
        res = lambda n: float(np.ravel(reducer.result(-1, n))[0]) if n in reducer.result_names(-1) else float("nan")
        print("kryflex target %g %-14s: bodies %s, ties %s, %d elastic states (%d system dofs), compressed %s %d -> %d, "
              "independent worst error %.2g, kryflex's %.2g, %s, CPU %.2f s (compression %.2f s wall), whole %.2f s"
              % (target, label, model.sizes, None if model.ties is None else model.ties.shape[0], 2 * max(el),
                 max(el) + s_.rigid_modes.shape[1], "tied" if res("compressed_tied") == 1 else "body-wise",
                 res("compressed_from_dofs"), res("compressed_to_dofs"), worst, out.summary.verdict.error_max,
                 out.summary.chosen.method, cpu, res("time_compress"), out.summary.performance.whole_s), flush=True)
