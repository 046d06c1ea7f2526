"""CPU seconds of one reduction (the scene's own settings, the default -kf_shared_directions auto and -kf_compress),
with whichever kryflex PYTHONPATH gives; run alternately with this branch's and main's _core:
    PYTHONPATH=<python dir> python cpu_side_by_side.py SCENE TARGET
prints the CPU seconds of the reduction (with its helper processes), its time_compress, the system dofs and whether the compression tied."""
import resource, sys, time
import numpy as np
import kryflex
scene, target = sys.argv[1], float(sys.argv[2])
cfg = [list(c) for c in kryflex.load_scene(scene).configurations]
def cpu_now():     # this process and its finished children (the reduction's helper processes)
    return time.process_time() + resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime \
        + resource.getrusage(resource.RUSAGE_CHILDREN).ru_stime


c0 = cpu_now()
r = kryflex.Reducer(kryflex.load_scene(scene), quiet=True, accuracy=target)
out = r.reduce()
cpu = cpu_now() - c0
res = lambda n: float(np.ravel(r.result(-1, n))[0]) if n in r.result_names(-1) else float("nan")
print("%s %g: CPU %.2f s, time_compress %.2f s, system dofs %d, compressed_tied %s, kryflex %s"
      % (scene, target, cpu, res("time_compress"), max(out.model.at(a).dofs for a in cfg), res("compressed_tied"),
         kryflex.__file__), flush=True)
