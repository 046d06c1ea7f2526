"""kryflex: Krylov reduction of articulated multi-flexible-body structures (A. Y. Lee's methodology).

    import kryflex
    scene = kryflex.load_scene("meshes/galileo/galileo.yaml")
    model = kryflex.Reducer(scene).reduce().model            # reduced bodies (a ReducedModel)
    system = model.at([60.0])                               # the reduced system at 60 deg (a ReducedSystem)

kryflex.reduce(scene) does the same in one call and returns the same Reduction (model, summary, both models).

Importing kryflex starts nothing: PETSc and SLEPc start on first use, or from kryflex.init(argv) with a command
line's PETSc options (the kryflex command does that). It only loads Debian's SCOTCH build of MUMPS where installed, so
that PETSc, loaded after it, can order by nested dissection: import kryflex before petsc4py (docs/guide/large-models.md, "Nested
dissection"), and, in a process not started by mpirun, sets Open MPI's singleton defaults until PETSc has started
(kryflex._runtime.MPI_SINGLETON_DEFAULTS: no daemon, no fabric probe). Runs under mpirun with mpi4py.

The package, in the order data flows through it:
    io/        scenes (YAML, in-memory matrices), body files, Nastran DMIG, Matrix Market, converters
    _core      the binding of the C library (src/include/kryflex.h) on petsc4py and slepc4py
    reducer    Reducer (the C KFReducer: the whole reduction policy and its verification), Reduction, reduce
    api        ReducedModel, ReducedSystem: the results of a reduction, computed in C
    results    Summary: the results of a reduction as typed objects, what summary.json holds
    report/    the summary of a reduction from the C results, report.md, summary.json and plots
    export/    the reduced bodies for multibody codes: the neutral file, the Exudyn system
    cli/       the kryflex command: reduce, reassemble, info, study, export, convert
"""
import importlib

from ._runtime import init, load_mumps_with_orderings, mpi_singleton_defaults

load_mumps_with_orderings()
mpi_singleton_defaults()

__version__ = "0.1.0"

# public name -> the module that defines it; imported on first access
_PUBLIC = {
    "Error": "._core",
    "Interrupted": "._core",
    "ModelFileError": ".api",
    "ReducedModel": ".api",
    "ReducedSystem": ".api",
    "Reducer": ".reducer",
    "Reduction": ".reducer",
    "reduce": ".reducer",
    "Scene": ".io.scene",
    "SceneError": ".io.scene",
    "load_scene": ".io.scene",
    "check_scene": ".check",
    "scene_from_dict": ".io.scene",
    "Summary": ".results",
}
__all__ = ["init", "__version__"] + list(_PUBLIC)


def __getattr__(name):
    if name not in _PUBLIC:
        raise AttributeError("module 'kryflex' has no attribute %r" % name)
    init()
    value = getattr(importlib.import_module(_PUBLIC[name], __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_PUBLIC))
