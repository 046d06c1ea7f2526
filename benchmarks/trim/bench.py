"""Trimming bench (docs/guide/trimming.md): each scene reduced by its own fixed recipe (its reduction section,
search off) without and with reduction.max_frequency: 3. The runs are side by side in one process, so the ratios
hold even when the machine is loaded.

Per scene and setting it prints:
- the reduction's time and its FRF error (target met or not);
- the highest reduced frequency (max over the angles of interest) and the stable explicit step 2 / omega_max;
- kryflex slew: the reduced model's run time over NSLEW slews, and their error against one full-order run;
- Exudyn: the reassembled reduced system at the slew's first angle (export/systems.py, ObjectGenericODE2) under
  Exudyn's explicit RK44 at 0.9 x its stable step, with its run time, steps and difference from the untrimmed run.

    PYTHONPATH=python OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1 \\
        .venv/bin/python benchmarks/trim/bench.py [--scenes galileo,solid] [--out DIR]
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
LIMITS = (None, 3)
SLEW_PERIODS = (4.0, 1.0)        # slew durations in first flexible periods
EXUDYN_END = 1.0                 # s of explicit simulation
PULSE = 0.25                     # s: the drive torque sin^2 pulse


def solid_scene(folder):
    path = os.path.join(folder, "spacecraft.yaml")
    if not os.path.exists(path):
        sys.path.insert(0, os.path.join(ROOT, "meshes", "solid"))
        import generate
        from petsc4py import PETSc
        path = generate.write_spacecraft(folder, refine=0.5, comm=PETSc.COMM_SELF)
    return path


def torque(t):
    t = np.asarray(t, float)
    return np.where(t < PULSE, np.sin(np.pi * np.clip(t, 0, PULSE) / PULSE) ** 2, 0.0)


def exudyn_explicit(system, h, t_end):
    """(seconds, steps, t, y) of Exudyn's RK44 on the fixed-angle system at step h; y = C q + D u."""
    import exudyn as exu
    from kryflex.export.systems import system_mbs
    SC, mbs, sensor = system_mbs(system, lambda t: float(torque(t)), damping_matrix=np.zeros_like(system["M"]))
    s = exu.SimulationSettings()
    steps = int(np.ceil(t_end / h))
    s.timeIntegration.numberOfSteps = steps
    s.timeIntegration.endTime = steps * h
    s.timeIntegration.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.writePeriod = t_end / 200
    s.show.computationTime = False
    s.show.statistics = False
    t0 = time.perf_counter()
    exu.SolveDynamic(mbs, s, solverType=exu.DynamicSolverType.RK44)
    seconds = time.perf_counter() - t0
    data = np.asarray(mbs.GetSensorStoredData(sensor))
    q = data[:, 1:]
    y = q @ np.asarray(system["C"]).T + np.outer(torque(data[:, 0]), np.asarray(system["D"]).sum(axis=1))
    return seconds, steps, data[:, 0], y


def run_scene(name, path):
    import kryflex
    from kryflex.export.systems import trimmed_systems
    from kryflex.slew.study import SlewStudy
    rows, ref, full_runs = [], None, {}
    for limit in LIMITS:
        scene = kryflex.load_scene(path)
        scene.reduction["search"] = False
        scene.reduction["max_frequency"] = limit
        t0 = time.perf_counter()
        result = kryflex.Reducer(scene, quiet=True).reduce()
        reduce_s = time.perf_counter() - t0
        model, s = result.model, result.summary
        trim = s["reduced"]["trimming"]
        study = SlewStudy(scene, model, nrates=2)
        slew_s, slew_err = 0.0, 0.0
        for p in SLEW_PERIODS:
            duration = p * study.P1
            if p not in full_runs:
                full_runs[p] = study.simulate(study.full, duration)
            t1 = time.perf_counter()
            red = study.simulate(study.reduced, duration)
            slew_s += time.perf_counter() - t1
            elastic, total = study.errors(full_runs[p], red)
            slew_err = max(slew_err, float(max(elastic.max(), total.max())))
        system = trimmed_systems(model, [list(study.alpha0_deg)])[0]
        top = float(system["frequencies_hz"].max())
        h = 0.9 / (np.pi * top)
        ex_s, ex_steps, te, ye = exudyn_explicit(system, h, EXUDYN_END)
        if ref is None:
            ref = (te, ye)
            diff = 0.0
        else:
            yi = np.stack([np.interp(ref[0], te, ye[:, o]) for o in range(ye.shape[1])], axis=1)
            diff = float(np.abs(yi - ref[1]).max() / max(np.abs(ref[1]).max(), 1e-300))
        rows.append(dict(scene=name, limit="none" if limit is None else str(limit), reduce_s=reduce_s,
                         error=s["error_max"], met=s["target_met"], top=trim["top_frequency_hz_max"],
                         step=trim["explicit_step_s_min"], slew_s=slew_s, slew_err=slew_err,
                         slew_step=study.step(SLEW_PERIODS[-1] * study.P1), exudyn_s=ex_s, exudyn_steps=ex_steps,
                         exudyn_h=h, exudyn_diff=diff))
    return rows


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--scenes", default="galileo,solid")
    p.add_argument("--out", default=None, help="folder for the generated solid scene (default: a temporary one)")
    args = p.parse_args()
    folder = args.out or tempfile.mkdtemp(prefix="kryflex-trim-")
    scenes = {"galileo": lambda: GALILEO, "solid": lambda: solid_scene(os.path.join(folder, "solid"))}
    rows = []
    for name in args.scenes.split(","):
        rows += run_scene(name, scenes[name]())
    head = ("| scene | max_frequency | reduce (s) | FRF error | target met | highest reduced (Hz) | explicit step (s) | "
            "slew reduced runs (s) | slew error | Exudyn RK44 step (s) | Exudyn steps | Exudyn (s) | Exudyn vs untrimmed |")
    print(head)
    print("|" + "|".join(["---"] * (head.count("|") - 1)) + "|")
    for r in rows:
        print("| %s | %s | %.2f | %.3g | %s | %.4g | %.3g | %.2f | %.3g | %.3g | %d | %.3f | %.2g |" % (
            r["scene"], r["limit"], r["reduce_s"], r["error"], r["met"], r["top"], r["step"], r["slew_s"],
            r["slew_err"], r["exudyn_h"], r["exudyn_steps"], r["exudyn_s"], r["exudyn_diff"]))
    print()
    for name in dict.fromkeys(r["scene"] for r in rows):
        a, b = [r for r in rows if r["scene"] == name]
        print("%s: explicit step x%.0f, Exudyn run time /%.1f, slew reduced run time ratio (trimmed / untrimmed) %.2f"
              % (name, b["step"] / a["step"], a["exudyn_s"] / max(b["exudyn_s"], 1e-9),
                 b["slew_s"] / max(a["slew_s"], 1e-9)))


if __name__ == "__main__":
    main()
