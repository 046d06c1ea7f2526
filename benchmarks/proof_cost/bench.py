"""What the proof costs: `kryflex reduce` with its verdict measured against the full order (search, full-order
verification, report and plots) beside the bare reduction (`-kf_verify false`: the error only estimated, no plots),
side by side in one run, on the solid spacecraft of meshes/solid.

    .venv/bin/python benchmarks/proof_cost/bench.py [--refine 0.5 1.55] [--repeat 1] [--work DIR] [--whole-check]
        [--direct-check] [--block-eigen] [--slepc-eigen] [--mode-count] [--certified] [--other TREE [--bare-only]]

For each size the two runs alternate (bare first), --repeat times. Printed per run: the wall and CPU seconds of the
process, the reduction's factorization and block solves (summary.json's performance), the model check, the
verification split (eigensolves, direct solves, the rest), the search, the report and plots, and the ratio the goal
is stated in: default wall / (factorization + block solves of the bare run), and the direct check's numerical
factorizations (its progress line), and how many angles and midpoints the check iterated from the reference (steps,
fallbacks: summary.json). The default's eigensolves are the block Krylov path's: their blocks per configuration and columns per block
are printed. --slepc-eigen adds a run of the default with SLEPc's Krylov-Schur (-kf_verify_eigen_method slepc) and
the two's ratio. --mode-count adds a run of the default with the eigensolves certified by inertia counts
(-kf_verify_count true: one LDL^T of K_S - sigma M_S per configuration) and prints each count's seconds beside the
eigensolve's per configuration, and whether the two runs' models are the same bit for bit. --block-eigen adds a run of the default with the eigensolves by SLEPc's subspace iteration
(K+ applied to blocks) and prints both runs' K+ applications, columns and seconds per column. --direct-check adds a run of the default with the check solved by factorizations
(-kf_verify_check_method direct, the method before the iterative one) and the two checks' ratio. --whole-check adds a third run, the default with the direct check factoring the
whole system per angle and frequency (-kf_verify_check_bodywise false), and the two checks' ratio. The machine is shared: read the ratios
of runs taken together, and the CPU seconds beside the wall. --other TREE runs that tree's build (e.g. /work/main)
and this one's alternately, bare then default, and prints each beside the other with its ratios (--bare-only: the bare runs alone, and whether the two trees'
reduced models are the same bit for bit). --certified adds the certified estimate (-kf_verify auto with
-kf_verify_certified_min_dofs 0: the estimate, its mode counts at every configuration, measured only where they
differ) and prints its count's seconds, wall / (factorization + solves of the bare run) and wall / (its own
factorizations, the count's included, + solves). The runs are labelled by what they are: "bare" (-kf_verify false),
"measured" (-kf_verify true) and "certified"; the default (-kf_verify auto) is the measured run below
-kf_verify_certified_min_dofs (50,000) system dofs and the certified one from there, which each size's heading says.
With --other the second run of each tree is the default itself (no -kf_verify given), labelled by the verdict it
gave. The report's seconds run from the arrival of its progress line to the process's end (run()). Every heading
prints the load average.
"""
import argparse
import json
import os
import re
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
STAMP = re.compile(r"^\[kryflex\s+([0-9.]+) s\] (.*)$")
# -info :eps, one line per sparse eigensolve (src/verify/eigen.c)
# the block Krylov eigensolve's progress line, one per configuration (src/verify/eigen.c), and its fall back
BLOCK_LINE = re.compile(r"block Krylov of K\+ M with the flexible solver's factor: (\d+) blocks of (\d+) columns(?:, at most \d+)?\)")
BLOCK_FALLBACK = "the block Krylov space did not converge"
# the mode count's progress line, one per configuration (src/reducer/reference.c)
COUNT_LINE = re.compile(r"mode count \(inertia of K_S - sigma M_S\): (\d+) flexible modes below ([0-9.e+-]+) Hz, the "
                        r"eigensolve found (\d+) \(([0-9.e+-]+) s, (?:body-wise|monolithic)\)")
EIGEN_INFO = re.compile(r"kryflex verification eigensolve: (\d+) iterations, (\d+) K\+ applications, (\d+) columns, "
                        r"([0-9.e+-]+) s in the factor's solves")


def scene_of(refine, work):
    """The solid spacecraft at this refinement (generated once into work)."""
    out = os.path.join(work, "solid_%s" % refine)
    path = os.path.join(out, "spacecraft.yaml")
    if not os.path.exists(path):
        subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "meshes", "solid", "generate.py"), "--refine",
                        str(refine), "-o", out], check=True, stdout=subprocess.DEVNULL)
    return path


def stamps(log):
    """(seconds, text) of the progress lines."""
    return [(float(m.group(1)), m.group(2)) for m in map(STAMP.match, log.splitlines()) if m]


def first(lines, prefix):
    return next((t for t, text in lines if text.startswith(prefix)), None)


def run(scene, out, extra, root=ROOT):
    """One kryflex reduce (of the tree root): its figures from the clock, the progress lines and summary.json. The
    report's time runs from the moment its line ("writing the results") arrives to the process's end: the lines'
    stamps start when the C library does, about half a second after the process (Python and its imports), so the wall
    less the line's stamp counted that half second as the report's too (this bench did before 2026-11-29p; it is
    printed beside, as report_stamp)."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    cmd = [os.path.join(root, "build", "kryflex"), "reduce", scene, "-o", out] + extra
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    # the progress lines are flushed as written (PetscPrintf): read as they come, each line's arrival timed
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    text, t_write_seen = [], None
    for line in proc.stdout:
        if t_write_seen is None and "] writing the results" in line:
            t_write_seen = time.perf_counter()
        text.append(line)
    proc.wait()
    wall = time.perf_counter() - t0
    proc.stdout = "".join(text)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode:
        sys.exit("kryflex reduce exited %d:\n%s" % (proc.returncode, proc.stdout[-3000:]))
    lines = stamps(proc.stdout)
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    perf = s.get("performance") or {}
    t_check0, t_scene = first(lines, "rigid-body and mechanism modes"), first(lines, "scene '")
    t_write = first(lines, "writing the results")
    nfact = re.search(r"reference checks: .*?, (\d+) numerical factorizations", proc.stdout)
    return dict(wall=wall, cpu=(after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
                factorization=perf.get("factorization_s", 0.0), solves=perf.get("solves_s", 0.0),
                whole=perf.get("whole_s", 0.0), verification=(s.get("timings_s") or {}).get("verification eigensolve", 0.0),
                eigensolve=perf.get("reference_eigensolve_s"), check=perf.get("reference_check_s"),
                search=perf.get("search_s"), count=perf.get("reference_count_s"),
                certificate_count=perf.get("certificate_count_s"), kind=s.get("verdict_kind"),
                count_helper=perf.get("certificate_count_helper_s"),
                count_helper_rss=perf.get("certificate_count_helper_rss_mb"),
                certificate=s.get("certificate"),
                counts=[(int(a), float(b), int(c), float(d)) for a, b, c, d in COUNT_LINE.findall(proc.stdout)],
                count_kind="body-wise" if "s, body-wise)" in proc.stdout else "monolithic",
                model_check=(t_scene - t_check0) if t_check0 is not None and t_scene is not None else None,
                report=(t0 + wall - t_write_seen) if t_write_seen is not None else None,
                report_stamp=(wall - t_write) if t_write is not None else None,
                check_factorizations=int(nfact.group(1)) if nfact else None,
                iterated=((s.get("reference_check") or {}).get("iterative_points"),
                          (s.get("reference_check") or {}).get("iterative_steps_max"),
                          (s.get("reference_check") or {}).get("fallbacks")),
                error=s.get("error_max"), estimated=s.get("error_estimated"), dofs=(s.get("full") or {}).get("system_dofs"),
                eigen_info=[(int(a), int(b), int(c), float(d)) for a, b, c, d in EIGEN_INFO.findall(proc.stdout)],
                blocks=[(int(a), int(b)) for a, b in BLOCK_LINE.findall(proc.stdout)],
                fallbacks=proc.stdout.count(BLOCK_FALLBACK))


def helper_text(r):
    """' (waited; the helper process's own 4.98 s beside the run, peak RSS 602 MB)' where the count helper counted
    (kryflex/count_helper.py; its CPU is in the run's, the helper being the run's child)."""
    if r.get("count_helper") is None:
        return ""
    return " (waited; the helper process's own %.2f s beside the run, peak RSS %.0f MB)" % (
        r["count_helper"], r["count_helper_rss"] or float("nan"))


def show_blocks(name, r):
    """The block Krylov eigensolves of a run: blocks per configuration, columns per block, fall backs to SLEPc."""
    b = r["blocks"]
    if not b and not r["fallbacks"]:
        return
    print("%-19s %d eigensolves by block Krylov: blocks per eigensolve %s, columns per block %s, %d block solves "
          "(%d columns); %d fell back to Krylov-Schur; eigensolves %.2f s" % (
              name, len(b), ",".join(str(x[0]) for x in b), ",".join(sorted({str(x[1]) for x in b})),
              sum(x[0] + 1 for x in b), sum((x[0] + 1) * x[1] for x in b), r["fallbacks"], r["eigensolve"]))


def show_eigen(name, r):
    """The K+ work of a run's sparse eigensolves (-info :eps): iterations, applications, columns, the factor's seconds."""
    e = r["eigen_info"]
    if not e:
        return
    its, calls, cols, sec = (sum(x[i] for x in e) for i in range(4))
    print("%-19s %d eigensolves: %d iterations, %d K+ applications, %d columns, factor's solves %.2f s (%.4f s per "
          "column, %.3f s per application); eigensolves %.2f s, of which outside the factor's solves %.2f s" % (
              name, len(e), its, calls, cols, sec, sec / cols, sec / calls, r["eigensolve"], r["eigensolve"] - sec))


def default_kind(dofs):
    """Which run the default (-kf_verify auto) is at this many system dofs: certified from
    -kf_verify_certified_min_dofs (the settings table's default) on, measured below (targets tighter than
    -kf_verify_certified_min_accuracy are measured at any size; the bench's 0.05 is not)."""
    sys.path.insert(0, os.path.join(ROOT, "python"))
    from kryflex import settings
    least = int(settings.row("-kf_verify_certified_min_dofs")["default"])
    return "certified" if dofs is not None and dofs >= least else "measured", least


def kind_of(r):
    """A run's label by its verdict: measured, certified, or estimated (summary.json's verdict_kind)."""
    return {"measured": "measured", "certified": "certified"}.get(r["kind"], r["kind"] or "estimated")


def load():
    return " ".join("%.1f" % x for x in os.getloadavg())


def fmt(x):
    return "%8.2f" % x if isinstance(x, (int, float)) else "%8s" % "-"


def show(name, r, denom):
    print("%-19s %s %s %s %s %s %s %s %s %s %s  ratio %5.2f  error %s%s" % (
        name, fmt(r["wall"]), fmt(r["cpu"]), fmt(r["factorization"]), fmt(r["solves"]), fmt(r["model_check"]),
        fmt(r["verification"]), fmt(r["eigensolve"]), fmt(r["check"]), fmt(r["search"]), fmt(r["report"]),
        r["wall"] / denom, "%.4g%s" % (r["error"], " (est.)" if r["estimated"] else "") if r["error"] is not None else "-",
        "  check factorizations %d" % r["check_factorizations"] if r["check_factorizations"] is not None else "")
        + ("  iterated points %s (steps <= %s, fallbacks %s)" % r["iterated"] if r["iterated"][0] else ""))


def compare_trees(scene, refine, rep, args):
    """One repeat of --other: that tree's bare and default runs, then this tree's (the order alternating between
    repeats), each tree's ratio to its own bare run, and the report's share of each default wall."""
    trees = [("other", os.path.abspath(args.other)), ("this", ROOT)]
    if rep % 2:
        trees.reverse()
    got = {}
    for name, root in trees:
        bare = run(scene, os.path.join(args.work, "bare_%s_%s" % (name, refine)), ["-kf_verify", "false"], root)
        full = None if args.bare_only else run(scene, os.path.join(args.work, "default_%s_%s" % (name, refine)), [], root)
        got[name] = (bare, full)
    if args.bare_only:
        compare_bare(got, trees, refine, rep, args)
        return
    dofs = got["this"][1]["dofs"]
    print("\nrefine %s (%s dofs), run %d (%s first), load average %s; the default (-kf_verify auto) at this size: "
          "%s" % (refine, dofs, rep + 1, trees[0][0], load(), default_kind(dofs)[0]))
    print("%-19s %8s %8s %8s %8s %8s %8s %8s %8s %8s %8s" % ("run", "wall", "cpu", "factor", "solves", "check",
                                                             "verify", "eigen", "direct", "search", "report"))
    for name, _ in trees:
        bare, full = got[name]
        denom = bare["factorization"] + bare["solves"]
        show("%s bare" % name, bare, denom)
        show("%s %s" % (name, kind_of(full)), full, denom)
        print("%s: default (%s) / bare wall %.2f, CPU %.2f; CPU / wall %.2f; count %s s%s; report and plots %.2f s = "
              "%.1f %% of the default wall (by the line's stamp, as before: %.2f s, %.1f %%)" % (
                  name, kind_of(full), full["wall"] / bare["wall"], full["cpu"] / bare["cpu"],
                  full["cpu"] / full["wall"], "%.2f" % full["certificate_count"]
                  if full["certificate_count"] is not None else "-", helper_text(full), full["report"],
                  100 * full["report"] / full["wall"], full["report_stamp"], 100 * full["report_stamp"] / full["wall"]))
    print("this / other: default wall %.3f, default CPU %.3f, report %.3f" % (
        got["this"][1]["wall"] / got["other"][1]["wall"], got["this"][1]["cpu"] / got["other"][1]["cpu"],
        got["this"][1]["report"] / got["other"][1]["report"]))


def compare_bare(got, trees, refine, rep, args):
    """--bare-only with --other: the two trees' bare runs, their ratios, CPU seconds, and whether the reduced models
    are the same (summary.json's sizes and errors, reduced.h5's arrays bit for bit)."""
    print("\nrefine %s (%s dofs), run %d (%s first), load average %s" % (
        refine, got["this"][0]["dofs"], rep + 1, trees[0][0], load()))
    print("%-19s %8s %8s %8s %8s %8s %8s %8s %8s %8s %8s" % ("run", "wall", "cpu", "factor", "solves", "check",
                                                             "verify", "eigen", "direct", "search", "report"))
    for name, _ in trees:
        bare = got[name][0]
        show("%s bare" % name, bare, bare["factorization"] + bare["solves"])
    this, other = got["this"][0], got["other"][0]
    print("this / other: bare wall %.3f, bare CPU %.3f; outside factorization + solves: wall %.2f / %.2f s; "
          "reduced.h5 %s" % (this["wall"] / other["wall"], this["cpu"] / other["cpu"],
                             this["wall"] - this["factorization"] - this["solves"],
                             other["wall"] - other["factorization"] - other["solves"],
                             "identical" if same_model(os.path.join(args.work, "bare_this_%s" % refine),
                                                       os.path.join(args.work, "bare_other_%s" % refine))
                             else "DIFFERENT"))


def same_model(a, b):
    """Whether two output folders' reduced.h5 hold the same datasets, bit for bit, and summary.json the same error."""
    import h5py
    import numpy as np
    with open(os.path.join(a, "summary.json")) as f, open(os.path.join(b, "summary.json")) as g:
        if json.load(f).get("error_max") != json.load(g).get("error_max"):
            return False
    with h5py.File(os.path.join(a, "reduced.h5"), "r") as fa, h5py.File(os.path.join(b, "reduced.h5"), "r") as fb:
        na, nb = [], []
        fa.visit(na.append)
        fb.visit(nb.append)
        if sorted(na) != sorted(nb):
            return False
        for n in na:
            if isinstance(fa[n], h5py.Dataset):
                x, y = np.asarray(fa[n][()]), np.asarray(fb[n][()])
                if x.dtype != y.dtype or x.shape != y.shape:
                    return False
                if x.dtype == object:     # names: their values (the array's bytes are pointers)
                    if x.tolist() != y.tolist():
                        return False
                elif x.tobytes() != y.tobytes():
                    return False
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--refine", type=float, nargs="+", default=[0.5], help="meshes/solid refinements (1.55: 57k dofs)")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--whole-check", action="store_true",
                    help="a third run: the default with the direct check factoring the whole system per angle and "
                         "frequency (-kf_verify_check_bodywise false), beside the body-wise one")
    ap.add_argument("--direct-check", action="store_true",
                    help="a run of the default with the check solved by factorizations (-kf_verify_check_method "
                         "direct), beside the iterative one")
    ap.add_argument("--block-eigen", action="store_true",
                    help="a run of the default with the eigensolves by subspace iteration, K+ applied to blocks "
                         "(-kf_verify_eps_type subspace), beside Krylov-Schur's single vectors; both with -info :eps "
                         "for their K+ applications and columns")
    ap.add_argument("--slepc-eigen", action="store_true",
                    help="a run of the default with SLEPc's Krylov-Schur eigensolves (-kf_verify_eigen_method slepc, "
                         "the method before the block Krylov one), beside the block path, and the two's ratio")
    ap.add_argument("--mode-count", action="store_true",
                    help="a run of the default with its eigensolves certified by inertia counts (-kf_verify_count "
                         "true), beside the default: each count's seconds against the eigensolve's per configuration")
    ap.add_argument("--certified", action="store_true",
                    help="a run of the certified estimate (-kf_verify auto, the threshold at 0 dofs) beside bare and "
                         "measured: its mode count's seconds and its two ratios")
    ap.add_argument("--bare-only", action="store_true",
                    help="with --other: the bare runs alone (-kf_verify false), each tree's beside the other's, and "
                         "whether their reduced models are the same bit for bit")
    ap.add_argument("--work", default=os.path.join(ROOT, "out", "proof_cost"))
    ap.add_argument("--other", metavar="TREE",
                    help="another kryflex tree (its build/kryflex) run alternately with this one, bare and default, "
                         "in each repeat: the two builds timed side by side (e.g. --other /work/main)")
    args = ap.parse_args()
    if args.bare_only and not args.other:
        ap.error("--bare-only compares two trees: give --other TREE")
    os.makedirs(args.work, exist_ok=True)
    print("proof cost, %s UTC, load average %s" % (time.strftime("%Y-%m-%d %H:%M", time.gmtime()), load()))
    print("seconds: wall, CPU (user + sys), factorization, block solves, model check, verification (eigensolves, "
          "direct solves), search, report and plots; ratio = wall / (factorization + solves of the bare run)")
    for refine in args.refine:
        scene = scene_of(refine, args.work)
        for rep in range(args.repeat):
            if args.other:
                compare_trees(scene, refine, rep, args)
                continue
            bare = run(scene, os.path.join(args.work, "bare_%s" % refine), ["-kf_verify", "false"])
            info = ["-info", ":eps"] if args.block_eigen else []
            full = run(scene, os.path.join(args.work, "measured_%s" % refine), info + ["-kf_verify", "true"])
            cert = run(scene, os.path.join(args.work, "certified_%s" % refine),
                       ["-kf_verify", "auto", "-kf_verify_certified_min_dofs", "0"]) if args.certified else None
            block = run(scene, os.path.join(args.work, "block_%s" % refine),
                        info + ["-kf_verify_eigen_method", "slepc", "-kf_verify_eps_type", "subspace"]) \
                if args.block_eigen else None
            slepc = run(scene, os.path.join(args.work, "slepc_%s" % refine), ["-kf_verify_eigen_method", "slepc"]) \
                if args.slepc_eigen else None
            whole = run(scene, os.path.join(args.work, "whole_%s" % refine), ["-kf_verify_check_bodywise", "false"]) \
                if args.whole_check else None
            direct = run(scene, os.path.join(args.work, "direct_%s" % refine), ["-kf_verify_check_method", "direct"]) \
                if args.direct_check else None
            counted = run(scene, os.path.join(args.work, "count_%s" % refine), ["-kf_verify_count", "true"]) \
                if args.mode_count else None
            denom = bare["factorization"] + bare["solves"]
            print("\nrefine %s (%s dofs), run %d, load average %s; bare factorization + solves %.2f s; the default "
                  "(-kf_verify auto) at this size: the %s run (certified from %d system dofs)" % (
                      refine, full["dofs"], rep + 1, load(), denom, default_kind(full["dofs"])[0],
                      default_kind(full["dofs"])[1]))
            print("%-19s %8s %8s %8s %8s %8s %8s %8s %8s %8s %8s" % ("run", "wall", "cpu", "factor", "solves", "check",
                                                                "verify", "eigen", "direct", "search", "report"))
            show("bare", bare, denom)
            show("measured", full, denom)
            show_blocks("measured", full)
            if cert:
                show("certified", cert, denom)
                own = cert["factorization"] + (cert["certificate_count"] or 0) + cert["solves"]
                c = cert["certificate"] or {}
                print("certified: verdict %s; counts %s flexible modes below %s Hz (full order / richest candidate "
                      "per configuration); count %.2f s%s; wall / (bare factorization + solves) %.2f; wall / (own "
                      "factorizations + count + solves = %.2f s) %.2f; CPU %.2f; wall / measured %.2f; error %.12g "
                      "(bare %.12g, measured %.12g)" % (
                          cert["kind"], ",".join("%d/%d" % (a, b) for a, b in zip(c.get("full_counts", []),
                                                                                 c.get("rich_counts", []))),
                          c.get("below_hz"), cert["certificate_count"] or 0, helper_text(cert), cert["wall"] / denom, own,
                          cert["wall"] / own, cert["cpu"], cert["wall"] / full["wall"], cert["error"], bare["error"],
                          full["error"]))
            if slepc:
                show("slepc", slepc, denom)
                print("eigensolves, block Krylov (measured) / Krylov-Schur: %.2f s / %.2f s = %.2f; measured wall / "
                      "Krylov-Schur's: %.2f; errors %.12g and %.12g" % (
                          full["eigensolve"], slepc["eigensolve"], full["eigensolve"] / slepc["eigensolve"],
                          full["wall"] / slepc["wall"], full["error"], slepc["error"]))
            if block:
                show("block", block, denom)
                show_eigen("measured", full)
                show_eigen("block", block)
                print("eigensolves, block / Krylov-Schur: %.2f s / %.2f s = %.2f" % (
                    block["eigensolve"], full["eigensolve"], block["eigensolve"] / full["eigensolve"]))
            if whole:
                show("whole", whole, denom)
                print("direct solves, body-wise / whole-system: %.2f (%s against %s factorizations)" % (
                    full["check"] / whole["check"], full["check_factorizations"], whole["check_factorizations"]))
            if counted:
                show("count", counted, denom)
                n = len(counted["counts"])
                print("count: %d configurations counted %s (modes below the cut, inertia / eigensolve); counts %.2f s "
                      "(%s s each; %s) against eigensolves %.2f s (%.2f s per configuration): %.2f; measured wall with / "
                      "without %.3f, CPU %.3f; models %s" % (
                          n, ",".join("%d/%d" % (c[0], c[2]) for c in counted["counts"]), counted["count"] or 0,
                          ",".join("%.2f" % c[3] for c in counted["counts"]), counted["count_kind"], counted["eigensolve"],
                          counted["eigensolve"] / max(n, 1), (counted["count"] or 0) / counted["eigensolve"],
                          counted["wall"] / full["wall"], counted["cpu"] / full["cpu"],
                          "identical" if same_model(os.path.join(args.work, "measured_%s" % refine),
                                                    os.path.join(args.work, "count_%s" % refine)) else "DIFFERENT"))
            if direct:
                show("direct", direct, denom)
                print("reference check, iterative / direct: %.2f s / %.2f s = %.2f; measured wall, iterative / direct: %.2f" % (
                    full["check"], direct["check"], full["check"] / direct["check"], full["wall"] / direct["wall"]))
            print("measured / bare: wall %.2f, CPU %.2f; report and plots %.1f %% of the measured wall" % (
                full["wall"] / bare["wall"], full["cpu"] / bare["cpu"], 100 * (full["report"] or 0) / full["wall"]))


if __name__ == "__main__":
    main()
