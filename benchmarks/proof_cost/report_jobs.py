"""The report's figure jobs (figures.figure_jobs) in one process, their figures prepared as the helpers prepare them
(plots.prepared_figures, every kind): CPU seconds per job. Run with either tree's PYTHONPATH and python:

    PYTHONPATH=TREE/python TREE/.venv/bin/python benchmarks/proof_cost/report_jobs.py OUTDIR/summary.json NAME
"""
import sys, time, inspect
from kryflex.results import Summary
from kryflex.report.figures import figure_jobs, plot_file_names
from kryflex.report import plots
s = Summary.load(sys.argv[1])
names = plot_file_names(s)
kw = {}
if "pairs" in inspect.signature(plots.prepared_figures).parameters:
    from kryflex.report.formatting import pair_name
    kw["pairs"] = [pair_name(o, i) for o in s.outputs for i in s.inputs]
t = time.process_time(); prep = plots.prepared_figures(s.band_hz, len(s.frf), **kw); p = time.process_time() - t
jobs = figure_jobs(s, names, prep)
tot = 0; n = 0; rows = []
for w, job, kind in jobs:
    t = time.process_time(); k = sum(1 for _ in job()); d = time.process_time() - t
    tot += d; n += k; rows.append("%s %d %.3f" % (kind, k, d))
print("%s: prepared %.2f s; %d figures %.3f s CPU  [%s]" % (sys.argv[2], p, n, tot, "; ".join(rows)))
