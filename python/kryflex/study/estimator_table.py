"""The estimator's figures across scenes (benchmarks/estimator/bench-estimator), from the estimator.csv and study.md of each
`kryflex study` run:

    /usr/bin/python3 -m kryflex.study.estimator_table NAME=STUDY_DIR ... > summary.md

Per scene: full system dofs, accuracy, candidates joined (with both errors exact), the median and the farthest-from-1
ratio estimate / true (all, and where pass or fail is decided), false passes, false fails, and both searches'
choices with their true error and estimate."""
import os
import re
import sys

from .estimator import DECISION_BAND, figures
from .estimator_output import CSV_NAME, read_csv
from .failures import _accuracy
from .output import _g

HEADER = ("| scene | system dofs | accuracy | candidates (exact) | ratio est/true: median | farthest from 1 | "
          "true >= accuracy/%g: n, median | farthest from 1 | false passes | false fails | chosen (full order): "
          "reduced dofs, true, estimate | chosen (estimator): reduced dofs, true, estimate |" % DECISION_BAND)


def scene_row(name, study_dir):
    rows = read_csv(os.path.join(study_dir, CSV_NAME))
    accuracy = _accuracy(study_dir)
    f = figures(rows, accuracy)
    return "| %s | %s | %g | %d (%d) | %s | %s | %d, %s | %s | %d | %d | %s | %s |" % (
        name, _system_dofs(study_dir), accuracy, f["joined"], f["exact"], _g(f["median_ratio"]), _ratio(f["worst"]),
        f["near"], _g(f["near_median_ratio"]), _ratio(f["near_worst"]), len(f["false_passes"]),
        len(f["false_fails"]), _chosen(rows, "chosen_full_order"), _chosen(rows, "chosen_estimator"))


def _system_dofs(study_dir):
    """The full system dofs study.md states."""
    try:
        with open(os.path.join(study_dir, "study.md")) as f:
            m = re.search(r"\((\d+) system dofs", f.read())
        return m.group(1) if m else "?"
    except OSError:
        return "?"


def _ratio(row):
    return "n/a" if row is None else "%s (true %s)" % (_g(row["ratio"]), _g(row["true_error"]))


def _chosen(rows, flag):
    mine = [r for r in rows if r[flag]]
    if not mine:
        return "not tried by the other search (see its .md)"
    r = mine[0]
    return "%d, %s%s, %s%s" % (r["reduced_dofs"], ">= " if r["true_lower_bound"] else "", _g(r["true_error"]),
                               ">= " if r["estimate_lower_bound"] else "", _g(r["estimated_error"]))


def main(argv):
    if not argv or any("=" not in a for a in argv):
        sys.exit("usage: python3 -m kryflex.study.estimator_table NAME=STUDY_DIR ... (a folder `kryflex study` wrote "
                 "with its estimator check: %s and study.md)" % CSV_NAME)
    lines = [HEADER, "|" + "---|" * HEADER.count(" |")]
    for spec in argv:
        name, study_dir = spec.split("=", 1)
        if not os.path.isfile(os.path.join(study_dir, CSV_NAME)):
            sys.exit("%s: no %s in %s (the study ran with --no-estimator, or its check was not made: see its "
                     "study.md)" % (name, CSV_NAME, study_dir))
        lines.append(scene_row(name, study_dir))
    print("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1:])
