"""The time integrator checked by Exudyn: the same linear time-varying equations of a SlewBodies (bodies.py)

    M z'' + C z' + K z + D(alpha(t))^T lambda = G u(t),      D(alpha(t)) z = 0

built in Exudyn from its generic items (a NodeGenericODE2 with the bodies' coordinates, an ObjectGenericODE2 with
M, K, C and the drive as its force user function, an ObjectConnectorCoordinateVector to the ground whose constraint
and Jacobian user functions are D(alpha(t)) z and D(alpha(t))) and integrated by Exudyn's own solver (generalized-
alpha, index 3, fixed step), so that the check shares the equations, not the integration, with integrator.py: with
spectral radius 1 Exudyn's rule is the trapezoidal one, so at the same step the histories must agree to round-off
(tests/python/test_slew.py; `kryflex slew --exudyn-check` reports it for the fastest slew). Exudyn models the
slewing structure this way because the study's model is linear time-varying by design (README: slewing); a
floating-frame (ObjectFFRFreducedOrder) model would add the nonlinear terms the study leaves out of both models.

    t, y = exudyn_history(bodies, profile, t_end, h, damping_beta)
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
