"""The failure table of the stress study (which scenes a method cannot reduce, and why), from the study.csv of each stress scene and the exit of
`kryflex reduce` on it (benchmarks/accuracy/bench-accuracy runs both):

    /usr/bin/python3 -m kryflex.study.failures NAME=STUDY_DIR:EXIT_CODE:REASON_FILE ... > failure-table.md

Per scene and method: the best error reached, at what size, how the method failed (error > 1, spurious near-zero
mode, lost moments, a non-zero exit), and what kryflex's default did: the exit code of `kryflex reduce` with the
scene as it is, the reason it printed, and the default model's error and size measured by the study."""
import math
import os
import sys

from .output import read_csv
from .sweep import LABELS, METHODS


def scene_rows(name, study_dir, reduce_exit, reason):
    rows = read_csv(os.path.join(study_dir, "study.csv"))
    accuracy = _accuracy(study_dir)
    out = []
    for method in METHODS:
        mine = [r for r in rows if r["method"] == method]
        if not mine:
            continue
        measured = [r for r in mine if not math.isnan(r["error_hinf"])]
        best = min(measured, key=lambda r: (r["error_hinf"], r["system_dofs"])) if measured else None
        kinds = []
        for r in mine:
            for f in (r.get("failure") or "").split("; "):
                if not f:
                    continue
                kind = f.split(" (")[0].split(":")[0]
                param = r["parameter"]
                for k in kinds:
                    if k[0] == kind:
                        k[1].append(param)
                        break
                else:
                    kinds.append((kind, [param]))
            if r.get("note", "").startswith("skipped"):
                kinds.append(("not run", [r["note"]]))
        failure = "; ".join("%s at %s %s" % (kind, _param_name(method), _ranges(params)) if kind != "not run"
                            else params[0] for kind, params in kinds) or "none"
        if method == "kryflex":
            r = mine[0]
            failure = ("`kryflex reduce` exit %s%s; the same defaults measured by the study: %s" % (
                reduce_exit, " (%s)" % reason if reason else "",
                "error %s at %s system dofs%s" % (_g(r["error_hinf"]), _i(r["system_dofs"]),
                                                  ", " + r["failure"] if r.get("failure") else "")
                if not math.isnan(r["error_hinf"]) else (r.get("failure") or "no model").split(":")[0]))
        met = best is not None and best["error_hinf"] <= accuracy
        out.append("| %s | %s | %s | %s | %s | %s |" % (
            name, LABELS[method], _g(best["error_hinf"]) if best else "n/a",
            ("%s (%s %s)" % (_i(best["system_dofs"]), _param_name(method), best["parameter"]) if method != "kryflex"
             else _i(best["system_dofs"])) if best else "",
            "yes" if met else "no", failure))
    return out


def _accuracy(study_dir):
    """The scene accuracy study.md states."""
    try:
        with open(os.path.join(study_dir, "study.md")) as f:
            for line in f:
                if "Scene accuracy:" in line:
                    return float(line.rsplit("Scene accuracy:", 1)[1].strip().rstrip("."))
    except (OSError, ValueError):
        pass
    return math.nan


def _param_name(method):
    return {"eigen-static": "cover", "eigen-plain": "cover", "kryflex": ""}.get(method, "c =")


def _ranges(params):
    """'20-22, 25' for ['20', '21', '22', '25'] (integers), the list as it is otherwise."""
    try:
        nums = [int(p) for p in params]
    except ValueError:
        return ", ".join(params)
    out, start, prev = [], nums[0], nums[0]
    for n in nums[1:] + [None]:
        if n is not None and n == prev + 1:
            prev = n
            continue
        out.append("%d" % start if start == prev else "%d-%d" % (start, prev))
        if n is not None:
            start = prev = n
    return ", ".join(out)


def _g(x):
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else "%.3g" % x


def _i(x):
    try:
        return "%d" % int(float(x))
    except (TypeError, ValueError):
        return str(x)


def main(argv):
    lines = ["| scene | method | best error | at system dofs (parameter) | meets the scene's accuracy | failure modes "
             "/ what kryflex's default did |", "|---|---|---|---|---|---|"]
    for spec in argv:
        name, rest = spec.split("=", 1)
        study_dir, code, reason_file = rest.rsplit(":", 2)
        reason = ""
        if reason_file and os.path.isfile(reason_file):
            with open(reason_file) as f:
                errs = [l.strip() for l in f if l.strip().startswith("kryflex: ")]
            reason = errs[-1][len("kryflex: "):] if errs else ""
        lines += scene_rows(name, study_dir, code, reason.replace("|", "/"))
    print("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1:])
