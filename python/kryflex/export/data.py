"""What a multibody export holds: the model's bodies as floating-frame bodies (bodies.py), its joints, inputs,
outputs and damping; made from a ReducedModel (from_model) or read back from the neutral file (neutral.py)."""
import dataclasses

import numpy as np

from .bodies import ExportError, reduced_body
from .ties import coordinates, export_ties


@dataclasses.dataclass(eq=False)
class MultibodyExport:
    """bodies: FloatingBody per body, in the model's order; joints: dicts (name, type 'revolute'|'fixed', parent,
    child (body indices), parent_interface, child_interface (interface indices), axis (3, parent frame), R0 (3 x 3):
    the child frame's orientation in the parent's at angle 0); revolute joints come first, in the order of the angles.
    inputs, outputs: names; damping: the uniform modal damping ratio the reduction served; scene: the scene's name.
    A trimmed model (reduction.max_frequency): max_frequency_hz, and systems: its trimmed reassembled systems at the
    model's reduction angles (export/systems.py), which the floating-frame bodies cannot carry; a model without joints
    whose bodies do not all float: systems holds its one reassembled system."""
    scene: str
    bodies: list
    joints: list
    inputs: list
    outputs: list
    damping: float
    max_frequency_hz: float = 0.0       # the model's trimming limit (0: none), docs/guide/trimming.md
    systems: list = dataclasses.field(default_factory=list)   # fixed-angle systems (export/systems.py)
    # a model of shared directions: its coordinate ties on the stacked exported coordinates (export/ties.py: the
    # floating bodies' flexible ones, a body without a floating frame its reduced ones), T q = 0; None without ties
    ties: np.ndarray = None

    @property
    def coordinate_sizes(self):
        """Per body the number of its exported coordinates the ties act on (export/ties.py)."""
        return [coordinates(b) for b in self.bodies]

    @property
    def floating(self):
        """True when every body has a floating frame (its 6 rigid motions)."""
        return all(b.floating for b in self.bodies)

    @property
    def revolute(self):
        return [j["name"] for j in self.joints if j["type"] == "revolute"]

    def body_index(self, name):
        names = [b.name for b in self.bodies]
        if name not in names:
            raise ExportError("no body '%s' in the export (bodies: %s)" % (name, ", ".join(names)))
        return names.index(name)


def from_model(model, configurations_deg=None):
    """The MultibodyExport of a kryflex ReducedModel: each body a floating-frame body when it has its 6 rigid motions,
    else as reduced (FloatingBody.floating False); a trimmed model adds its trimmed systems at configurations_deg
    (default: its reduction angles), and a model without joints whose bodies do not all float adds its reassembled
    system (no angle), which Exudyn takes as one ObjectGenericODE2. A model of shared directions carries its
    coordinate ties (export/ties.py), ExportError where one reaches a body's rigid motions."""
    bodies = [reduced_body(name, ifs, **arrays)
              for name, ifs, arrays in zip(model.body_names, model.interfaces, model.bodies)]
    # a model of shared directions: its ties, on the flexible coordinates (export/ties.py)
    D = getattr(model, "ties", None)
    ties = None if D is None else export_ties(D, bodies, model.scene_name)
    joints = []
    for j in model.joints:
        joints.append(dict(name=j["name"], type=j["type"], parent=int(j["parent"]), child=int(j["child"]),
                           parent_interface=int(j["parent_interface"]), child_interface=int(j["child_interface"]),
                           axis=np.asarray(j["axis"], dtype=float), R0=np.asarray(j["R0"], dtype=float)))
    limit = float(model.settings.get("max_frequency_hz") or 0.0)
    systems = []
    if limit > 0:
        from .systems import trimmed_systems
        if configurations_deg is None:
            configurations_deg = [list(np.atleast_1d(c)) for c in model.settings.get("reduction_angles_deg") or []]
        systems = trimmed_systems(model, configurations_deg)
    elif not joints and not all(b.floating for b in bodies):
        from .systems import trimmed_systems
        systems = trimmed_systems(model, [[]])
    return MultibodyExport(scene=model.scene_name, bodies=bodies, joints=joints, inputs=list(model.input_names),
                           outputs=list(model.output_names), damping=float(model.settings.get("damping", 0.0)),
                           max_frequency_hz=limit, systems=systems, ties=ties)
