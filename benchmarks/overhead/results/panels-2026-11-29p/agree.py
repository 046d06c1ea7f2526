"""run main and this tree on 1 and 2 ranks on one scene, print the FRF distances between the four models"""
import importlib.machinery, importlib.util, os, subprocess, sys, itertools
ROOT = "/work/wt/panels"
loader = importlib.machinery.SourceFileLoader("bo", ROOT + "/benchmarks/overhead/bench-overhead")
spec = importlib.util.spec_from_loader("bo", loader); bo = importlib.util.module_from_spec(spec); loader.exec_module(bo)
scene, angle, out = sys.argv[1], sys.argv[2], sys.argv[3]
extra = sys.argv[4:]
env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OPENBLAS_NUM_THREADS="1", OMPI_MCA_rmaps_base_oversubscribe="1")
models = {}
for label, build in (("main", "/work/main/build"), ("new", ROOT + "/build")):
    for n in (1, 2):
        d = os.path.join(out, "%s-np%d" % (label, n))
        cmd = [build + "/kryflex", "reduce", scene, "-o", d, "-scene.angles", angle, "-kf_verify", "false"] + extra
        if n > 1: cmd = ["mpiexec", "-n", str(n)] + cmd
        if os.path.exists(os.path.join(d, "reduced.h5")):
            models["%s-np%d" % (label, n)] = os.path.join(d, "reduced.h5"); continue
        p = subprocess.run(cmd, capture_output=True, text=True, env=env)
        assert p.returncode == 0, p.stderr[-2000:]
        models["%s-np%d" % (label, n)] = os.path.join(d, "reduced.h5")
ang = eval(angle)[0][0] if angle.startswith("[[") else float(angle.split(",")[0])
import time
for a, b in [("new-np1", "main-np1"), ("new-np2", "main-np2"), ("new-np2", "new-np1"), ("main-np2", "main-np1")]:
    print("%s vs %s: FRF %.2g" % (a, b, bo.frf_distance(models[a], models[b], ang)))
