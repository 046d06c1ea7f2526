"""The slewing study (docs/guide/slewing.md): the articulated structure integrated in time while its joint angles move, the
full-order model against a reduced one along the same angle history, and the error of the output histories
against the slew rate.

    bodies.py      SlewBodies: M, K, G, H, interface rows, rigid motions in the bodies' own coordinates (full or
                   reduced), and the joint ties D(alpha) = T(alpha) I of the reassembly
    profiles.py    Profile: slew (rest to rest) and spin-up angle histories and their drive torque
    integrator.py  Integrator: Newmark (trapezoidal) with the ties on the positions, one factorization per run
    study.py       SlewStudy: the sweep over slew rates, the error measure, the adequacy limit, the step check
    output.py      slew.csv, slew.md, slew.png, slew_histories.png
    exudyn_check.py  Exudyn: the same linear equations (exudyn_history), and the reduced bodies as nonlinear
                   floating-frame bodies against the full model along Exudyn's angle history (ffrf_comparison)

The command is `kryflex slew SCENE -o OUTDIR` (cli/slew.py); benchmarks/slew/bench-slew runs it on Galileo and a frame scene.
"""
