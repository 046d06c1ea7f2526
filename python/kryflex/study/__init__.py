"""The speed-accuracy study of a scene (docs/guide/accuracy.md): every reduction method swept over its size parameter and
measured against ONE full-order reference, on the C reducer and the C error measures.

    from kryflex.study import Study
    study = Study(scene, cmax=30)                 # which methods, which C features are there
    study.run_reference()                         # one verified reduction: the grid and full responses per angle
    for row in study.sweep(): ...                 # one row per reduction run (sweep.py)
    write_csv(rows, path); accuracy_figures(...)  # output.py
    check = EstimatorCheck(scene).run()           # the search's error estimator against the truth (estimator.py)
    estimator_output.write_csv(check.rows, ...)   # estimator.csv, estimate_vs_truth.png, its study.md section

Orchestration only: the reductions, the reassembled responses, the errors and the Hankel singular values come from
the C library through the binding (kryflex._core); this package chooses the runs, times them and lays the numbers
out. `kryflex study` (cli/study.py) is the command; benchmarks/accuracy/bench-accuracy runs it on Galileo and the stress scenes
(meshes/stress.py) and builds the failure table (failures.py); benchmarks/estimator/bench-estimator runs the estimator check on
Galileo and a 5k-dof frame and tabulates it (estimator_table.py).
"""
from .sweep import CSV_FIELDS, METHODS, Study  # noqa: F401
