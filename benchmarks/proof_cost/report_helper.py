"""The report of one summary.json written with the figures' helper process off and forced on (report/helper.py),
alternating: this process's CPU, the helper's CPU, the wall; the files compared byte for byte. On an idle machine the
report's wall is about the larger of the two CPU figures.

    .venv/bin/python benchmarks/proof_cost/report_helper.py OUTDIR_OF_A_DEFAULT_RUN [repeats]"""
import os, resource, sys, time, shutil, tempfile
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "python"))
from kryflex.results import Summary
from kryflex.report import write_report
s = Summary.load(sys.argv[1])
reps = int(sys.argv[2]) if len(sys.argv) > 2 else 2
files = {}
for rep in range(reps):
    for mode in ("0", "1"):
        os.environ["KRYFLEX_REPORT_HELPER"] = mode
        out = os.path.join(tempfile.gettempdir(), "kryflex_report_helper_%s" % mode)
        shutil.rmtree(out, ignore_errors=True)
        c0, k0, w0 = time.process_time(), resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
        write_report(s, out)
        c1, k1, w1 = time.process_time(), resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
        kid = (k1.ru_utime - k0.ru_utime) + (k1.ru_stime - k0.ru_stime)
        print("helper %s: this process cpu %.2f, helper cpu %.2f, wall %.2f, load %.1f" % (mode, c1 - c0, kid, w1 - w0, os.getloadavg()[0]), flush=True)
        files[mode] = {n: open(os.path.join(out, n), "rb").read() for n in os.listdir(out)}
print("identical files:", files["0"] == files["1"], len(files["0"]))
