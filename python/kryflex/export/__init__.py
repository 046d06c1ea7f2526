"""Export of reduced models to multibody codes.

    from kryflex import export
    data = export.load("out/reduced.h5")                   # a MultibodyExport (from a model file, a neutral file or
                                                           # a ReducedModel)
    export.write_neutral(data, "spacecraft.kfmb.npz")      # the documented neutral format (docs/guide/export.md), NumPy only
    SC, mbs, handles = export.exudyn.build_mbs(data, [30.0])   # an Exudyn system at 30 deg, assembled

Modules, one job each:
    bodies.py   one reduced body as a floating-frame body (rigid frame + flexible modes, mass properties, interfaces)
    data.py     the whole export (bodies, joints, inputs, outputs, damping) from a ReducedModel
    neutral.py  the neutral file: write (atomic) and read, without kryflex on the reading side
    ties.py     a model of shared directions: its coordinate ties on the exported (flexible) coordinates
    exudyn.py   the Exudyn system: ObjectFFRFreducedOrder per body, joints, ties, loads for inputs, outputs
"""
import os

from .bodies import ExportError, FloatingBody, floating_body
from .data import MultibodyExport, from_model
from .neutral import NEUTRAL_SUFFIX, read_neutral, write_neutral

__all__ = ["ExportError", "FloatingBody", "MultibodyExport", "floating_body", "from_model", "load", "read_neutral",
           "write_neutral", "NEUTRAL_SUFFIX"]


def load(source):
    """A MultibodyExport from a ReducedModel, a MultibodyExport, a reduced-model file (.h5) or a neutral file (.npz)."""
    if isinstance(source, MultibodyExport):
        return source
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        if path.lower().endswith(".npz"):
            return read_neutral(path)
        from ..api import ReducedModel
        return from_model(ReducedModel.load(path))
    if hasattr(source, "bodies") and hasattr(source, "joints") and hasattr(source, "body_names"):
        return from_model(source)
    raise ExportError("cannot export a %s: give a ReducedModel, a reduced-model file (.h5) or a neutral export (.npz)"
                      % type(source).__name__)
