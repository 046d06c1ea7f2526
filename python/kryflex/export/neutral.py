"""The neutral multibody file (docs/guide/export.md): one NumPy .npz archive, every array named, read with
numpy.load alone. Written atomically (a temporary file beside the target, renamed when complete)."""
import io
import os

import numpy as np

from .bodies import ExportError, FloatingBody
from .data import MultibodyExport
from .systems import SYSTEM_ARRAYS

FORMAT = "kryflex-multibody"
VERSION = 1
NEUTRAL_SUFFIX = ".npz"

# per-body arrays, in the order the manual lists them: the reduced body's own, then its floating-frame fields (only
# for a body with its 6 rigid motions: body<i>/floating 1; a body without them has floating 0 and missing_rigid)
REDUCED_ARRAYS = ("M", "K", "G", "H", "iface")
FRAME_ARRAYS = ("rigid_coords", "modes", "mass_flex", "stiffness_flex", "mass", "center_of_mass", "inertia",
                "interface_positions", "interface_modes", "input_rigid", "input_flex", "output_rigid", "output_flex")
BODY_ARRAYS = REDUCED_ARRAYS + FRAME_ARRAYS
# per-body arrays a file of an earlier kryflex may lack (read as zeros): the viscous damping matrix and F^T C F
OPTIONAL_BODY_ARRAYS = ("C", "damping_flex")
# the FloatingBody attribute of a file array named otherwise (the file's C, as in the FE convention, is the damping)
ATTRIBUTES = {"C": "damping_matrix"}


def _strings(values):
    return np.array(list(values), dtype=np.str_) if len(values) else np.zeros(0, dtype="<U1")


def arrays(data):
    """The neutral file's arrays (name -> array) of a MultibodyExport."""
    out = dict(format=np.array(FORMAT), version=np.array(VERSION), scene=np.array(data.scene),
               inputs=_strings(data.inputs), outputs=_strings(data.outputs), damping_ratio=np.array(data.damping),
               body_names=_strings([b.name for b in data.bodies]))
    J = data.joints
    out.update(joint_names=_strings([j["name"] for j in J]), joint_type=_strings([j["type"] for j in J]),
               joint_parent=np.array([j["parent"] for j in J], dtype=np.int64),
               joint_child=np.array([j["child"] for j in J], dtype=np.int64),
               joint_parent_interface=np.array([j["parent_interface"] for j in J], dtype=np.int64),
               joint_child_interface=np.array([j["child_interface"] for j in J], dtype=np.int64),
               joint_axis=np.array([j["axis"] for j in J], dtype=float).reshape(len(J), 3),
               joint_R0=np.array([j["R0"] for j in J], dtype=float).reshape(len(J), 3, 3))
    # a trimmed model: its limit and fixed-angle trimmed systems (readers of the bodies alone may ignore them)
    out["max_frequency_hz"] = np.array(float(data.max_frequency_hz))
    out["nsystems"] = np.array(len(data.systems), dtype=np.int64)
    for i, sysd in enumerate(data.systems):
        for key in SYSTEM_ARRAYS:
            out["system%d/%s" % (i, key)] = np.asarray(sysd[key], dtype=float)
    # a model of shared directions: its coordinate ties on the stacked exported coordinates (rows: ties; columns: per
    # body its flexible coordinates when it floats, else its reduced ones; 0 rows without ties)
    ncoord = sum(data.coordinate_sizes)
    out["ties"] = np.zeros((0, ncoord)) if data.ties is None else np.asarray(data.ties, dtype=float)
    for i, b in enumerate(data.bodies):
        out["body%d/interface_names" % i] = _strings(b.interfaces)
        out["body%d/floating" % i] = np.array(int(b.floating), dtype=np.int64)
        out["body%d/missing_rigid" % i] = _strings(b.missing_rigid)
        keys = BODY_ARRAYS + OPTIONAL_BODY_ARRAYS if b.floating else REDUCED_ARRAYS + ("C",)
        for key in keys:
            out["body%d/%s" % (i, key)] = np.asarray(getattr(b, ATTRIBUTES.get(key, key)), dtype=float)
    return out


def write_neutral(data, path):
    """Writes the MultibodyExport to path (.npz): complete or not at all."""
    from ..io.files import atomic_path
    path = os.fspath(path)
    if not path.lower().endswith(NEUTRAL_SUFFIX):
        raise ExportError("%s: the neutral export is a NumPy archive: give a file name ending in .npz" % path)
    buf = io.BytesIO()          # built in memory first: a failing write leaves no half-closed archive behind
    np.savez(buf, **arrays(data))
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(buf.getbuffer())
    return path


def read_neutral(path):
    """A MultibodyExport from a neutral file (checked: format, version, every array present)."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ExportError("%s: neutral export file not found" % path)
    try:
        z = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as e:
        raise ExportError("%s: not a NumPy .npz archive (%s)" % (path, e)) from None
    with z:
        if "format" not in z.files or str(z["format"]) != FORMAT:
            raise ExportError("%s: not a kryflex multibody export (no format '%s'): write one with 'kryflex export'"
                              % (path, FORMAT))
        if int(z["version"]) != VERSION:
            raise ExportError("%s: export version %d, this kryflex reads version %d: export the model again"
                              % (path, int(z["version"]), VERSION))
        try:
            bodies = []
            for i, name in enumerate(z["body_names"]):
                # files before bodies without a floating frame have no 'floating': every body floats there
                floating = bool(int(z["body%d/floating" % i])) if "body%d/floating" % i in z.files else True
                kw = {key: z["body%d/%s" % (i, key)] for key in (BODY_ARRAYS if floating else REDUCED_ARRAYS)}
                kw.update({ATTRIBUTES.get(key, key): z["body%d/%s" % (i, key)] for key in OPTIONAL_BODY_ARRAYS
                           if "body%d/%s" % (i, key) in z.files})
                if floating:
                    kw["mass"] = float(kw["mass"])
                else:
                    kw.pop("damping_flex", None)
                    kw.update(floating=False, missing_rigid=tuple(str(s) for s in z["body%d/missing_rigid" % i]))
                bodies.append(FloatingBody(name=str(name), interfaces=[str(s) for s in z["body%d/interface_names" % i]],
                                           **kw))
            joints = [dict(name=str(n), type=str(t), parent=int(p), child=int(c), parent_interface=int(pi),
                           child_interface=int(ci), axis=ax, R0=R0)
                      for n, t, p, c, pi, ci, ax, R0 in zip(z["joint_names"], z["joint_type"], z["joint_parent"],
                                                             z["joint_child"], z["joint_parent_interface"],
                                                             z["joint_child_interface"], z["joint_axis"], z["joint_R0"])]
            nsys = int(z["nsystems"]) if "nsystems" in z.files else 0     # files before trimming have none
            systems = [{key: z["system%d/%s" % (i, key)] for key in SYSTEM_ARRAYS} for i in range(nsys)]
            # files before shared directions have no 'ties'; an empty one: none
            ties = z["ties"] if "ties" in z.files and z["ties"].shape[0] else None
            data = MultibodyExport(scene=str(z["scene"]), bodies=bodies, joints=joints,
                                   inputs=[str(s) for s in z["inputs"]], outputs=[str(s) for s in z["outputs"]],
                                   damping=float(z["damping_ratio"]),
                                   max_frequency_hz=float(z["max_frequency_hz"]) if "max_frequency_hz" in z.files
                                   else 0.0, systems=systems, ties=ties)
            if ties is not None and ties.shape[1] != sum(data.coordinate_sizes):
                raise ExportError("%s: its ties have %d columns, its bodies %d exported coordinates: export the model "
                                  "again" % (path, ties.shape[1], sum(data.coordinate_sizes)))
            return data
        except KeyError as e:
            raise ExportError("%s: incomplete kryflex multibody export: %s is missing; export the model again"
                              % (path, e)) from None
