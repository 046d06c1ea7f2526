"""Runs `kryflex ARGS` (the kryflex on PYTHONPATH) with wall and CPU clocks around its Python stages, wrapped in
place; prints them to stderr, and to $STAGES as JSON (fixed_costs.py reads it).

    PYTHONPATH=python .venv/bin/python benchmarks/proof_cost/stages.py reduce SCENE -o OUT [options]"""
import atexit, json, os, sys, time
T0w, T0c = time.perf_counter(), time.process_time()
rows = []
def _last():
    w, c = clock()
    print("atexit (last): wall %.2f cpu %.2f" % (w, c), file=sys.stderr)
atexit.register(_last)
def clock():
    return time.perf_counter() - T0w, time.process_time() - T0c
def wrap(owner, name, label):
    fn = getattr(owner, name)
    def inner(*a, **k):
        w0, c0 = clock()
        try:
            return fn(*a, **k)
        finally:
            w1, c1 = clock()
            rows.append((label, w0, w1 - w0, c1 - c0))
    setattr(owner, name, inner)
w_imp0, c_imp0 = clock()
import kryflex.cli.main as cm
w_imp, c_imp = clock()
rows.append(("import kryflex.cli.main", w_imp0, w_imp - w_imp0, c_imp - c_imp0))
w_i0, c_i0 = clock()
import kryflex, kryflex.io.scene as sc, kryflex.cli.reduce as cr, kryflex.cli.common as cc, kryflex.reducer as rd
import kryflex.results as rs, kryflex.api as api, kryflex.io.files as fl
w_i1, c_i1 = clock(); rows.append(("import (harness: scene, reducer, api)", w_i0, w_i1 - w_i0, c_i1 - c_i0))
wrap(kryflex, "init", "init (PETSc/SLEPc)")
wrap(sc, "load_scene", "load_scene")
wrap(cr, "model_check", "model_check")
wrap(cc, "checked_reducer", "checked_reducer")
wrap(rd.Reducer, "reduce", "Reducer.reduce (all)")
wrap(rs.Summary, "from_json", "Summary.from_json")
wrap(rs.Summary, "dumps", "Summary.dumps")
wrap(api.ReducedModel, "save", "ReducedModel.save")
wrap(fl.Staging, "commit", "Staging.commit")
wrap(cr, "append_check_section", "append_check_section")
# lazily imported modules: patch them when first imported
import importlib, builtins
_orig_import = builtins.__import__
patched = set()
def late():
    m = sys.modules
    if "kryflex.report.summary" in m and "bs" not in patched and hasattr(m["kryflex.report.summary"], "build_summary"):
        patched.add("bs"); wrap(m["kryflex.report.summary"], "build_summary", "build_summary")
    if "kryflex.report.writer" in m and "wr" not in patched and hasattr(m["kryflex.report.writer"], "write_unverified") and hasattr(m.get("kryflex.report"), "write_unverified"):
        patched.add("wr"); w = m["kryflex.report.writer"]
        for n in ("_render_plots", "render_markdown", "validate_summary", "plot_file_names"):
            if hasattr(w, n): wrap(w, n, "report." + n)
        wrap(w, "write_report", "write_report (all)"); wrap(w, "write_unverified", "write_unverified (all)")
        r = m["kryflex.report"]; r.write_report = w.write_report; r.write_unverified = w.write_unverified
    if "kryflex.report.plots" in m and "pl" not in patched and hasattr(m["kryflex.report.plots"], "save_figure"):
        patched.add("pl"); pl = m["kryflex.report.plots"]
        # the PNGs encoded in this process (helpers' not counted): figure_png_bytes before plots had its own encoder
        wrap(pl, "_encode_png" if hasattr(pl, "_encode_png") else "figure_png_bytes", "  png encoded here (each)")
    if "kryflex.report.writer" in m and "bg" not in patched and hasattr(m["kryflex.report.writer"], "PendingReport"):
        patched.add("bg"); pr = m["kryflex.report.writer"].PendingReport
        wrap(pr, "__init__", "report begun (text written, helpers given work)"); wrap(pr, "finish", "report finished (figures)")
def imp(name, *a, **k):
    w0, c0 = clock()
    mod = _orig_import(name, *a, **k)
    late()
    return mod
builtins.__import__ = imp
def report():
    w, c = clock()
    agg = {}
    for label, start, dw, dc in rows:
        a = agg.setdefault(label, [start, 0.0, 0.0, 0])
        a[1] += dw; a[2] += dc; a[3] += 1
    print("\nstage                               start     wall      cpu   calls", file=sys.stderr)
    for label, (start, dw, dc, n) in sorted(agg.items(), key=lambda kv: kv[1][0]):
        print("%-32s %8.2f %8.2f %8.2f %5d" % (label, start, dw, dc, n), file=sys.stderr)
    print("%-32s %8.2f %8.2f %8.2f" % ("main returned (before exit)", w, w, c), file=sys.stderr)
    if os.environ.get("STAGES"):
        json.dump(dict(rows=rows, end=[w, c]), open(os.environ["STAGES"], "w"))
sys.argv = ["kryflex"] + sys.argv[1:]
try:
    code = cm.main()
finally:
    report()
sys.exit(code)
