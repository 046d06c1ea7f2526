"""The time integrator checked by Exudyn: the same linear time-varying equations of a SlewBodies (bodies.py)

    M z'' + C z' + K z + D(alpha(t))^T lambda = G u(t),      D(alpha(t)) z = 0

built in Exudyn from its generic items (a NodeGenericODE2 with the bodies' coordinates, an ObjectGenericODE2 with
M, K, C and the drive as its force user function, an ObjectConnectorCoordinateVector to the ground whose constraint
and Jacobian user functions are D(alpha(t)) z and D(alpha(t))) and integrated by Exudyn's own solver (generalized-
alpha, index 3, fixed step), so that the check shares the equations, not the integration, with integrator.py: with
spectral radius 1 Exudyn's rule is the trapezoidal one, so at the same step the histories must agree to round-off
(tests/python/slew/test_slew.py; `kryflex slew --exudyn-check` reports it for the fastest slew). Exudyn models the
slewing structure this way because the study's model is linear time-varying by design (docs/guide/slewing.md).

    t, y = exudyn_history(bodies, profile, t_end, h, damping_beta)

The second check is physical: the REDUCED bodies as Exudyn floating-frame bodies
(kryflex.export.exudyn.build_mbs, ObjectFFRFreducedOrder: the nonlinear terms the linear time-varying study leaves
out) slewed by the bearing torque, against integrator.py's full and reduced bodies along the angle history Exudyn
produced (`kryflex slew --exudyn-ffrf`, benchmarks/slew-exudyn/bench-slew-exudyn, tests/python/slew/test_slew_exudyn.py):

    r = ffrf_comparison(study, periods)      # r["exudyn_vs_full"], r["reduced_vs_full"], r["exudyn_vs_reduced"]
"""
import numpy as np
import scipy.sparse

SPARSE_FROM = 300   # above this many coordinates Exudyn gets sparse matrices and its sparse solver


def exudyn_history(bodies, profile, t_end, h, damping_beta=0.0, spectral_radius=1.0):
    """The outputs y = H z at every step of Exudyn's generalized-alpha solution from rest: (t, y)."""
    import exudyn as exu
    from exudyn.itemInterface import (MarkerNodeCoordinates, NodeGenericODE2, NodePointGround,
                                      ObjectConnectorCoordinateVector, ObjectGenericODE2, SensorNode)
    b = bodies
    n = b.dofs
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n, initialCoordinates=[0.0] * n,
                                       initialCoordinates_t=[0.0] * n, numberOfODE2Coordinates=n))
    g1 = b.G.sum(axis=1)

    def force(mbs_, t, item, q, q_t):
        return g1 * float(profile.torque(t))
    sparse = n > SPARSE_FROM

    def matrix(A):
        """Dense for small bodies, else Exudyn's sparse container (triplets, without zeros)."""
        if not sparse:
            return np.asarray(A.toarray() if hasattr(A, "toarray") else A)
        A = scipy.sparse.coo_matrix(A)
        keep = A.data != 0
        mc = exu.MatrixContainer()
        mc.SetWithSparseMatrixCSR(A.shape[0], A.shape[1],
                                  np.column_stack([A.row[keep], A.col[keep], A.data[keep]]).astype(float))
        return mc
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=matrix(b.M), stiffnessMatrix=matrix(b.K),
                                    dampingMatrix=matrix(damping_beta * b.K), forceUserFunction=force))
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    m_body = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=node))
    m_ground = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=ground))

    def ties(t):
        return b.ties(profile.angles(np.atleast_1d(t))[0])

    def constraint(mbs_, t, item, q, q_t, velocity_level):
        qb = np.asarray(q)[:n]
        return ties(t) @ (np.asarray(q_t)[:n] if velocity_level else qb)

    def jacobian(mbs_, t, item, q, q_t, velocity_level):
        return ties(t)                       # (Exudyn takes this one dense only)
    if b.nties:
        mbs.AddObject(ObjectConnectorCoordinateVector(markerNumbers=[m_body, m_ground],
                                                      scalingMarker0=np.zeros((b.nties, 1)),
                                                      constraintUserFunction=constraint,
                                                      jacobianUserFunction=jacobian))
    sensor = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                      outputVariableType=exu.OutputVariableType.Coordinates))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    if sparse:
        settings.linearSolverType = exu.LinearSolverType.EigenSparse
    settings.timeIntegration.numberOfSteps = int(np.ceil(t_end / h - 1e-9))
    settings.timeIntegration.endTime = settings.timeIntegration.numberOfSteps * h
    settings.timeIntegration.generalizedAlpha.spectralRadius = spectral_radius
    settings.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    settings.timeIntegration.newton.useModifiedNewton = False
    settings.timeIntegration.adaptiveStep = False        # the fixed step h of the comparison
    settings.timeIntegration.newton.relativeTolerance = 1e-7   # linear equations: one Newton step solves them
    settings.timeIntegration.newton.absoluteTolerance = 1e-10 * max(1.0, float(np.abs(g1).max()))
    settings.timeIntegration.verboseMode = 0
    settings.timeIntegration.newton.maxIterations = 5
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = 0.5 * h     # every step recorded (a period of h skips some)
    settings.show.computationTime = False
    settings.show.statistics = False
    exu.SolveDynamic(mbs, settings)
    data = np.asarray(mbs.GetSensorStoredData(sensor))
    _, first = np.unique(np.round(data[:, 0] / h).astype(int), return_index=True)   # one row per step
    data = data[first]
    return data[:, 0], data[:, 1:1 + n] @ b.H.T


# ---------------------------------------------------------------------------------------------------------------------
# The reduced bodies in Exudyn's nonlinear floating-frame formulation, driven by the bearing torque: a physical check beside the linear one

class RecordedProfile:
    """An angle history sampled at times t (radians per revolute joint, linear interpolation between samples) with a
    drive torque function: what Integrator.run needs (angles(t), torque(t)) to follow an angle history that a
    multibody code produced."""

    def __init__(self, t, angles_rad, torque):
        self.t, self.alpha = np.asarray(t, float), np.asarray(angles_rad, float).reshape(len(t), -1)
        self._torque = torque

    def angles(self, t):
        t = np.atleast_1d(np.asarray(t, float))
        return np.stack([np.interp(t, self.t, a) for a in self.alpha.T], axis=-1)

    def torque(self, t):
        return self._torque(t)


def _peak_torque(data, profile):
    """The drive torque's peak (N m) that slews two rigid bodies of the model's inertias about the (first) revolute
    axis by the profile's amplitude: tau = J_eff alpha'' with J_eff = J_p J_c / (J_p + J_c) about the joint's axis and
    alpha'' = A u / int int u (u: the unit-peak torque shape; for the cycloidal slew int int u = T^2 / 2 pi). Only a
    scale: the angle the multibody system then turns by is read from it, not assumed."""
    j = next(j for j in data.joints if j["type"] == "revolute")
    k = np.asarray(j["axis"], float) / np.linalg.norm(j["axis"])
    kc = np.asarray(j["R0"], float).T @ k
    Jp = k @ data.bodies[j["parent"]].inertia @ k
    Jc = kc @ data.bodies[j["child"]].inertia @ kc
    T = profile.T
    return float(Jp * Jc / (Jp + Jc) * np.max(np.abs(profile.amplitude)) * 2 * np.pi / T ** 2)


def ffrf_history(model, inputs, profile, t_end, h, torque_peak=None):
    """The reduced model `model` in Exudyn (kryflex.export.exudyn.build_mbs: one ObjectFFRFreducedOrder per body,
    nonlinear floating frames, GenericJoints), at the profile's first angles, from rest, undamped, driven by
    torque_peak * profile.torque(t) on the given inputs (default peak: _peak_torque), integrated by Exudyn's
    generalized-alpha solver (spectral radius 1: no numerical damping, as the Newmark rule of integrator.py) with the
    fixed step h. Returns dict: t (steps), alpha (radians, per revolute joint: the angle Exudyn's joint turned to,
    joint_angles), z (steps x reduced coordinates: the state in the reduced bodies' own coordinates, see below),
    torque_peak, frame_offset (the largest frame rotation relative to its reference, radians: elastic-small when the
    references follow the joint's turn).

    z: per body z_b = R_b r_b + F_b q_b (the reduced body's coordinates, export/bodies.py), q_b Exudyn's flexible
    coordinates and r_b the body frame's motion (translation, rotation vector) relative to a reference that carries
    the large motion: the first body's own current frame, and each other body placed from it by the joints at the
    current angles (export.exudyn.placements). The first body's r is zero: z then differs from the bodies' motion by
    a rigid motion of the whole structure (to first order), which the elastic outputs take out."""
    import exudyn as exu
    from exudyn.itemInterface import SensorNode, SensorObject
    from exudyn.rigidBodyUtilities import RotationMatrix2RotationVector

    from ..export.exudyn import build_mbs, placements, set_input
    alpha0 = np.degrees(profile.angles(0.0)[0])
    SC, mbs, hd = build_mbs(model, alpha0, assemble=False)
    data = hd["export"]
    tau = _peak_torque(data, profile) if torque_peak is None else float(torque_peak)
    OV = exu.OutputVariableType
    sensors = []
    for body in data.bodies:
        b = hd["bodies"][body.name]
        s = [mbs.AddSensor(SensorNode(nodeNumber=b["rigid_node"], storeInternal=True, outputVariableType=ov))
             for ov in (OV.Position, OV.RotationMatrix)]
        if b["modal_node"] is not None:
            s.append(mbs.AddSensor(SensorNode(nodeNumber=b["modal_node"], storeInternal=True,
                                              outputVariableType=OV.Coordinates)))
        sensors.append(s)
    revolute = [j for j in data.joints if j["type"] == "revolute"]
    turn = [mbs.AddSensor(SensorObject(objectNumber=hd["joints"][j["name"]], storeInternal=True,
                                       outputVariableType=OV.Rotation)) for j in revolute]

    def pre_step(mbs_, t):                 # t: the end of the step about to be computed
        u = tau * float(profile.torque(t))
        for name in inputs:
            set_input(mbs_, hd, name, u)
        return True
    mbs.SetPreStepUserFunction(pre_step)
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(np.ceil(t_end / h - 1e-9))
    settings.timeIntegration.endTime = settings.timeIntegration.numberOfSteps * h
    settings.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    settings.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    settings.timeIntegration.adaptiveStep = False
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = 0.5 * h     # every step recorded (a period of h skips some)
    exu.SolveDynamic(mbs, settings)

    def stored(s):
        d = np.asarray(mbs.GetSensorStoredData(s))
        _, first = np.unique(np.round(d[:, 0] / h).astype(int), return_index=True)
        return d[first]
    t = stored(turn[0])[:, 0]
    alpha = np.radians(alpha0)[None, :] + np.stack([stored(s)[:, 3] for s in turn], axis=1)
    rec = [[stored(s)[:, 1:] for s in ss] for ss in sensors]
    z = np.zeros((len(t), sum(b.M.shape[0] for b in data.bodies)))
    offset = 0.0
    for n in range(len(t)):
        place, _ = placements(data, np.degrees(alpha[n]))
        p0, A0 = rec[0][0][n], rec[0][1][n].reshape(3, 3)
        col = 0
        for b, (body, (pb, Ab)) in enumerate(zip(data.bodies, place)):
            pr, Ar = p0 + A0 @ pb, A0 @ Ab           # the body's reference: the first body's frame, then the joints
            p, A = rec[b][0][n], rec[b][1][n].reshape(3, 3)
            r = np.concatenate([Ar.T @ (p - pr), np.asarray(RotationMatrix2RotationVector(Ar.T @ A))])
            offset = max(offset, float(np.abs(r[3:]).max()))
            zb = body.rigid_coords @ r
            if body.nflex:
                zb = zb + body.modes @ rec[b][2][n]
            z[n, col:col + len(zb)] = zb
            col += len(zb)
    return dict(t=t, alpha=alpha, z=z, torque_peak=tau, frame_offset=offset)


def ffrf_comparison(study, periods):
    """The physical check for a small scene: the reduced bodies in Exudyn's nonlinear floating-frame formulation
    (ffrf_history), driven by the slew's torque of duration periods * P1, against kryflex's linear time-varying
    integrator (integrator.py) of the FULL-order bodies and of the reduced bodies along the angle history Exudyn
    produced, at the same step and without damping. Errors as the study's (per output max_t |y_a - y_b| / max_t
    |y_full|, the largest over outputs) of the elastic outputs (rigid-body and mechanism modes at alpha(t) taken out):
    exudyn_vs_full (the reduced bodies in the multibody code against the full model), reduced_vs_full (the reduction
    alone, same linear equations) and exudyn_vs_reduced (what the nonlinear formulation adds: centrifugal and
    Coriolis terms, finite rotations, and the export's neglected second-order inertia terms)."""
    from .integrator import Integrator
    duration = periods * study.P1
    h = study.step(duration)
    t_end = duration + study.settle_periods * study.P1
    prof = study.profile(duration)
    ex = ffrf_history(study.model, study.inputs, prof, t_end, h)
    tau = ex["torque_peak"]
    rec = RecordedProfile(ex["t"], ex["alpha"], lambda t: tau * prof.torque(t))
    red_int = Integrator(study.reduced, h, 0.0)
    e_exu = np.array([red_int.elastic_outputs(z, a) for z, a in zip(ex["z"], ex["alpha"])])
    runs = {}
    for label, bodies in (("full", study.full), ("reduced", study.reduced)):
        t, _, e = Integrator(bodies, h, 0.0).run(rec, ex["t"][-1])
        if len(t) != len(ex["t"]) or not np.allclose(t, ex["t"]):
            raise RuntimeError("Exudyn recorded %d steps, the integrator %d" % (len(ex["t"]), len(t)))
        runs[label] = e
    scale = np.maximum(np.abs(runs["full"]).max(axis=0), np.finfo(float).tiny)

    def err(a, b):
        return float((np.abs(a - b).max(axis=0) / scale).max())
    amp = np.degrees(ex["alpha"][-1] - ex["alpha"][0])
    rate = np.degrees(np.abs(np.diff(ex["alpha"], axis=0)).max() / h)
    return dict(periods=periods, duration_s=duration, step_s=h, torque_peak=tau, frame_offset=ex["frame_offset"], turn_deg=float(np.max(np.abs(amp))),
                peak_rate_deg_s=float(rate), exudyn_vs_full=err(e_exu, runs["full"]),
                reduced_vs_full=err(runs["reduced"], runs["full"]), exudyn_vs_reduced=err(e_exu, runs["reduced"]),
                t=ex["t"], alpha=ex["alpha"], exudyn=e_exu, full=runs["full"], reduced=runs["reduced"])
