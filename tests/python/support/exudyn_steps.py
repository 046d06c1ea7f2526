"""An exported model's step response in Exudyn against the reduced model's own (tests/python/export): Exudyn's
nonlinear time integration (generalized-alpha, 2,000 steps over T = 0.2 s) of a small step on each input, against the
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
