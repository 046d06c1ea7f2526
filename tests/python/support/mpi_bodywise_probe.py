#!/usr/bin/python3
"""The body-wise flexible solve against the monolithic one at each given configuration, on any number of ranks (a
helper of test_bodywise.py).

    mpiexec -n 2 /usr/bin/python3 tests/python/support/mpi_bodywise_probe.py SCENE OUT.json --angles "0;45;210"

Per configuration (degrees, ';' between configurations, ',' between a configuration's joints) and per variant
(the default held dofs; -kf_held_cond_max 1, which sends the monolithic solve to its pivoted-QR held dofs and the
body-wise one to its own choice among the interface unknowns; a shift): the largest entry of K+ G body-wise minus
monolithic relative to the largest of K+ G (all ranks' rows), the output-side product H K+ G of each (independent of
how the ranks number the system dofs, so serial and parallel runs compare), and which implementation ran. Then the
sparse factorization counts of a system visited at every configuration by one kind of solver only. Rank 0 writes
OUT.json."""
import argparse
import json

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--angles", required=True)
    ap.add_argument("--shift", type=float, default=1.0)
    args = ap.parse_args()

    import kryflex
    from kryflex import _core
    from petsc4py import PETSc
    comm = PETSc.COMM_WORLD.tompi4py()
    opts = PETSc.Options()
    opts.setValue("kf_quiet", True)
    # both solves refined (-kf_refine_rtol 0, every solve, as without the residual rule): the comparison is of the
    # operators K+, not of one unrefined solve's rounding (the pivoted held dofs leave 1e-9 there)
    opts.setValue("kf_refine_rtol", 0)
    configs = [[float(a) for a in c.split(",")] for c in args.angles.split(";")]

    scene = kryflex.load_scene(args.scene)
    system = _core.CSystem(scene.cscene)

    def solve(kind, shift=None):
        s = _core.FlexSolver(system, shift=shift, type=kind)
        _, _, G, Ht = system.matrices()
        X = s.apply(G)
        x, h = X.getDenseArray(), Ht.getDenseArray()
        HX = comm.allreduce(h.T @ x)
        return s.type, x.copy(), HX, s.stats()["held"]

    def relmax(a, b):
        num = comm.allreduce(float(np.abs(a - b).max()) if a.size else 0.0, op=max_op)
        den = comm.allreduce(float(np.abs(b).max()) if b.size else 0.0, op=max_op)
        return num / den

    from mpi4py import MPI
    max_op = MPI.MAX
    result = {"ranks": comm.Get_size(), "configurations": {}}
    variants = {"held": ({}, None), "pivoted": ({"kf_held_cond_max": "1"}, None), "shift": ({}, args.shift)}
    for cfg in configs:
        system.set_angles(scene.angles_rad(cfg))
        out = {}
        for name, (extra, shift) in variants.items():
            for k, v in extra.items():
                opts.setValue(k, v)
            try:
                tm, xm, hm, nhm = solve("monolithic", shift)
                tb, xb, hb, nhb = solve("bodywise", shift)
            finally:
                for k in extra:
                    opts.delValue(k)
            out[name] = {"types": [tm, tb], "held": [nhm, nhb], "rel_diff": relmax(xb, xm),
                         "HKG_monolithic": hm.tolist(), "HKG_bodywise": hb.tolist()}
        result["configurations"][",".join("%g" % a for a in cfg)] = out

    counts = {}
    for kind in ("monolithic", "bodywise"):
        sysk = _core.CSystem(scene.cscene)
        for cfg in configs:
            sysk.set_angles(scene.angles_rad(cfg))
            s = _core.FlexSolver(sysk, type=kind)
            s.setup()
            del s
        counts[kind] = sysk.factor_count()
    result["factor_counts"] = counts
    result["bodies"] = scene.info["bodies"]
    if comm.Get_rank() == 0:
        with open(args.out, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
