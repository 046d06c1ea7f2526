#!/usr/bin/python3
"""One lumped-mass model of bc_models (the plate lumped_plate at two sizes, the stick aircraft lumped_aircraft),
exported as a DMIG punch (nastran_model.write_punch), read back by kryflex's Nastran reader and reduced by
kryflex.Reducer on the ranks it runs on:

    mpiexec -n 2 .venv/bin/python tests/python/reference_truth_probe.py small|large|aircraft OUT.npz [PETSc options]

Writes (rank 0) the body as read (M, K), the reference response on its grid, the reduced model's response there, and
the results of the direct-solve check. A kryflex error prints 'error: <message>' on rank 0 and exits 3."""
import os
import sys
import tempfile
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

SIZES = {"small": ((5, 3), (0.5, 200.0)), "large": ((15, 14), (0.5, 20.0))}


def model_spec(size):
    """The scene as written by bc_models (before export)."""
    import bc_models
    if size == "aircraft":
        return bc_models.lumped_aircraft(band=(0.5, 20.0))
    (nx, ny), band = SIZES[size]
    return bc_models.lumped_plate(nx, ny, band=band)


def plate_spec(size, folder):
    """The model's scene with its body read back from the punch it was written to (rounded as exported)."""
    import nastran_model as nm
    from kryflex.io import dmig

    spec = model_spec(size)
    body = next(iter(spec["bodies"].values()))
    pch, bdf = nm.write_punch(folder, body["stiffness"], body["mass"], body["nodes"])
    with warnings.catch_warnings():      # MAAX leaves the massless dofs' zero columns out, as Nastran does
        warnings.simplefilter("ignore")
        M, K, nodes, _ = dmig.nastran_body(pch, [bdf])
    body.update(mass=M.toarray(), stiffness=K.toarray(), nodes=[list(n) for n in nodes])
    return spec


def main():
    size, out = sys.argv[1:3]
    import kryflex
    kryflex.init(sys.argv[:1] + sys.argv[3:])
    from petsc4py import PETSc

    comm = PETSc.COMM_WORLD
    rank = comm.getRank()
    folder = comm.tompi4py().bcast(tempfile.mkdtemp() if rank == 0 else None) if comm.getSize() > 1 else tempfile.mkdtemp()
    spec = plate_spec(size, folder) if rank == 0 else None
    if comm.getSize() > 1:
        spec = comm.tompi4py().bcast(spec)
    try:
        reducer = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True)
        reduction = reducer.reduce()
    except kryflex.Error as e:
        if rank == 0:
            print("error: %s" % e, flush=True)
        sys.exit(3)
    f = np.ravel(reducer.result(0, "frf_frequencies_hz"))
    Tred = reduction.model.at([]).frf(f)
    if rank == 0:
        body = next(iter(spec["bodies"].values()))
        np.savez(out, M=body["mass"], K=body["stiffness"], f=f, Tfull=reducer.frf(0, "full"), Tred=Tred,
                 check=reducer.result(-1, "reference_check_error"), error_max=reducer.result(-1, "error_max"),
                 check_f=reducer.result(0, "reference_check_frequencies_hz"),
                 check_truth=reducer.result(0, "reference_check_truth_re") + 1j * reducer.result(0, "reference_check_truth_im"),
                 check_iterated=reducer.result(-1, "reference_check_iterative_points"),
                 target_met=reducer.result(-1, "target_met"), accuracy=spec["accuracy"], zeta=spec["damping"],
                 band=spec["band"])


if __name__ == "__main__":
    main()
