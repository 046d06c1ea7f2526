"""The trimmed reduced systems of a model for multibody and time-domain codes (docs/guide/trimming.md).

A model reduced with reduction.max_frequency is trimmed per configuration: at each angle its reassembled system keeps
the modes up to the limit (modal coordinates: M = I, K = diag(lambda)) and carries the trimmed modes' static share
as a feedthrough D (y = C x + D u). The floating-frame bodies of the export (bodies.py) cannot carry that per-angle
trimming, so the export adds these fixed-angle systems beside them:

    systems = trimmed_systems(model, [[0.0], [60.0]])     # one dict per configuration
    SC, mbs, sensor = system_mbs(systems[0], torque)      # an Exudyn system of one of them (ObjectGenericODE2)
"""
import numpy as np

SYSTEM_ARRAYS = ("angles_deg", "M", "K", "B", "C", "D", "frequencies_hz")


def trimmed_systems(model, configurations_deg):
    """Per configuration (degrees, one angle per revolute joint; [] without revolute joints) the model's reassembled
    system as it trims it: a dict of SYSTEM_ARRAYS (D zero when nothing was trimmed there), damping_matrix (or None)
    rigid_modes (their count) and rigid_level (exudyn.rigid_level: the energy of the rigid modes, with its margin)."""
    from .exudyn import rigid_level
    out = []
    for angles in configurations_deg:
        s = model.at(angles)
        D = s.feedthrough if s.feedthrough is not None else np.zeros((s.C.shape[0], s.B.shape[1]))
        out.append(dict(angles_deg=np.asarray(s.angles_deg, float), M=s.M, K=s.K, B=s.B, C=s.C, D=np.asarray(D),
                        frequencies_hz=np.asarray(s.frequencies_hz, float), damping_matrix=s.damping_matrix,
                        trimmed=int(s.trimmed), rigid_modes=0 if s.rigid_modes is None else int(s.rigid_modes.shape[1]),
                        rigid_level=rigid_level(s.M, s.K, s.rigid_modes)))
    return out


def system_mbs(system, torque, damping_matrix=None):
    """An Exudyn system of one fixed-angle system (a trimmed_systems dict): one NodeGenericODE2 with its coordinates,
    an ObjectGenericODE2 with M, K (and the damping matrix given, else the system's, else none), every input driven
    by torque(t). Returns (SystemContainer, mbs, sensor of the coordinates); the outputs are C q + D u."""
    import exudyn as exu
    from exudyn.itemInterface import NodeGenericODE2, ObjectGenericODE2, SensorNode
    n = system["M"].shape[0]
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n, initialCoordinates=[0.0] * n,
                                       initialCoordinates_t=[0.0] * n, numberOfODE2Coordinates=n))
    g1 = np.asarray(system["B"], float).sum(axis=1)

    def force(mbs_, t, item, q, q_t):
        return g1 * float(torque(t))
    C = damping_matrix if damping_matrix is not None else system.get("damping_matrix")
    kw = dict(dampingMatrix=np.asarray(C, float)) if C is not None else {}
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=np.asarray(system["M"], float),
                                    stiffnessMatrix=np.asarray(system["K"], float), forceUserFunction=force, **kw))
    sensor = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                      outputVariableType=exu.OutputVariableType.Coordinates))
    mbs.Assemble()
    return SC, mbs, sensor
