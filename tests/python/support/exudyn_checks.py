"""Checks of an exported model in Exudyn (tests/python/export): its linearized frequencies (exudyn_frequencies), its
linear parts at the initial state (linear_parts), and its step response against the reduced model's own
(step_response_errors): Exudyn's nonlinear time integration (generalized-alpha, 2,000 steps over T = 0.2 s) of a small step on each input, against the
undamped response by modal superposition, y(T) = sum_i H phi_i phi_i^T G u g_i(T): g = T^2/2 for rigid/mechanism
modes, (1 - cos w T) / w^2 for flexible ones, 1 / w^2 above 500 Hz (the integrator damps those oscillations; their
mean is the static deflection)."""
import numpy as np

ZERO = 1e-12            # |lambda| <= ZERO * max |lambda|: a rigid-body or mechanism mode
T = 0.2


def step_response_errors(model, neutral_path, angle_deg):
    """{input name: max |y_exudyn - y_modal| / max |y_modal|} at T over the outputs, the model (a ReducedModel) at
    angle_deg, its export read from neutral_path."""
    import exudyn
    from kryflex.export.exudyn import build_mbs, output_values, set_input
    ref = model.at([angle_deg])
    lam, Phi = ref.eigenvalues, ref.modes
    w = np.sqrt(np.abs(lam))
    rigid = np.abs(lam) <= ZERO * np.abs(lam).max()
    g = np.where(rigid, T ** 2 / 2, (1 - np.cos(w * T)) / np.where(rigid, 1.0, np.abs(lam)))
    high = w / (2 * np.pi) > 500
    g[high] = 1 / lam[high]
    errors = {}
    for k, name in enumerate(model.input_names):
        SC, mbs, h = build_mbs(str(neutral_path), [angle_deg])
        set_input(mbs, h, name, 1.0)
        ss = exudyn.SimulationSettings()
        ss.timeIntegration.numberOfSteps = 2000
        ss.timeIntegration.endTime = T
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.write = False
        mbs.SolveDynamic(ss)
        y = np.array([output_values(mbs, h)[n] for n in model.output_names])
        yref = ((ref.C @ Phi) * (Phi.T @ ref.B[:, k])) @ g
        errors[name] = np.abs(y - yref).max() / np.abs(yref).max()
    return errors


def exudyn_frequencies(mbs):
    """Linearized undamped frequencies of an assembled Exudyn system (constraints by Exudyn's null-space projection):
    (flexible ones in Hz, number of zero modes)."""
    lam, _ = mbs.ComputeODE2Eigenvalues(useAbsoluteValues=False)
    lam = np.sort(np.real(lam))
    zero = np.abs(lam) <= ZERO * np.abs(lam).max()
    assert np.all(lam[~zero] > 0)
    return np.sqrt(lam[~zero]) / (2 * np.pi), int(zero.sum())


def linear_parts(mbs):
    """Exudyn's own linearization at the initial state: mass matrix, stiffness (minus the Jacobian of the ODE2
    right-hand side), constraint Jacobian (ODE2 coordinates x constraints) and the ODE2 right-hand side (the loads)."""
    import exudyn
    ss = exudyn.SimulationSettings()
    ss.solution.file.write = False          # no solution/ folder in the working directory
    ss.solution.file.writeInitialValues = False
    sol = exudyn.MainSolverImplicitSecondOrder()
    sol.InitializeSolver(mbs, ss)
    n = sol.GetODE2size()
    sol.ComputeMassMatrix(mbs)
    M = sol.GetSystemMassMatrix().copy()
    sol.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=-1, scalarFactor_ODE2_t=0, scalarFactor_ODE1=0)
    sol.ComputeJacobianAE(mbs, scalarFactor_ODE2=1.0, scalarFactor_ODE2_t=0.0, scalarFactor_ODE1=0.0,
                          velocityLevel=False)
    J = sol.GetSystemJacobian().copy()
    sol.ComputeODE2RHS(mbs)
    rhs = sol.GetSystemResidual()[:n].copy()
    sol.FinalizeSolver(mbs, ss)
    return M, J[:n, :n], J[:n, n:], rhs


def output_jacobian(mbs, h, output_names):
    """d y / d q of the export's outputs (output_values) at the initial coordinates, by central differences (step 1e-6);
    the coordinates are restored."""
    import exudyn
    from kryflex.export.exudyn import output_values
    q0 = mbs.systemData.GetODE2Coordinates()
    Hy, eps = np.zeros((len(output_names), len(q0))), 1e-6
    for i in range(len(q0)):
        for sign in (1.0, -1.0):
            q = q0.copy()
            q[i] += sign * eps
            mbs.systemData.SetODE2Coordinates(q, exudyn.ConfigurationType.Current)
            y = output_values(mbs, h)
            Hy[:, i] += sign * np.array([y[n] for n in output_names]) / (2 * eps)
    mbs.systemData.SetODE2Coordinates(q0, exudyn.ConfigurationType.Current)
    return Hy
