"""The time domain's damping (python/kryflex/slew/damping.py): with the angle held, the frequency domain's damping model.

Against references written here from the scene's files (reference.py, SciPy): the modal operator damps each flexible
mode of each model by 2 zeta_k omega_k and no other (the modes those of the dense system, the rigid-body and
mechanism modes undamped); the Newmark histories under modal and Rayleigh damping match the exact solution (matrix
exponential) of the assembled system damped the frequency domain's way, with second-order convergence; and the
held-angle elastic error of `kryflex slew`'s baseline stays within the scene's accuracy on Galileo at 0.05, 1e-2 and
1e-3 and on the solid (slow).
"""
import os
import sys

import numpy as np
import pytest
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
sys.path.insert(0, SUPPORT)
import accuracy_scenes as acs  # noqa: E402
import reference as ref  # noqa: E402


@pytest.fixture(scope="module")
def galileo(quiet_library):
    import kryflex
    scene = kryflex.load_scene(GALILEO)
    model = kryflex.Reducer(scene, quiet=True).reduce().model
    return scene, model


def dense_damping(angle, zeta, alpha=0.0, beta=0.0):
    """(Ms, Ks, Gs, Hs, Cs) of Galileo at angle (null-space coordinates), Cs = Ms Phi diag(2 zeta w) Phi^T Ms on the
    flexible modes (rigid ones from geometry) + alpha Ms + beta Ks."""
    scene = ref.load_scene(GALILEO)
    Ms, Ks, Gs, Hs = ref.assemble(scene, [angle])
    modal = acs.modal_data(Ms, Ks, Gs, Hs, rigid_modes=ref.geometric_rigid_modes(scene, [angle]))
    R = ref.geometric_rigid_modes(scene, [angle])
    Q = R @ np.linalg.inv(sl.cholesky(R.T @ Ms @ R))
    Z = sl.null_space((Ms @ Q).T)
    lam, y = sl.eigh(Z.T @ Ks @ Z, Z.T @ Ms @ Z)
    Phi = Z @ y
    assert np.allclose(np.sqrt(lam) / (2 * np.pi), modal.flexible_hz, rtol=1e-10)
    Cs = Ms @ Phi @ np.diag(2 * zeta * np.sqrt(lam)) @ Phi.T @ Ms + alpha * Ms + beta * Ks
    return Ms, Ks, Gs, Hs, Cs


def exact_history(Ms, Ks, Gs, Hs, Cs, duration, t):
    """y(t) of M q'' + C q' + K q = G sin(2 pi t / duration) on [0, duration], 0 after, from rest: the matrix
    exponential of the state-space system with the sine's oscillator (test_slew.py's reference, any C)."""
    n = Ms.shape[0]
    Minv = np.linalg.inv(Ms)
    w = 2 * np.pi / duration
    A = np.zeros((2 * n + 2, 2 * n + 2))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -Minv @ Ks
    A[n:2 * n, n:2 * n] = -Minv @ Cs
    A[n:2 * n, 2 * n] = Minv @ Gs.sum(axis=1)
    A[2 * n, 2 * n + 1], A[2 * n + 1, 2 * n] = w, -w
    step = sl.expm(A * (t[1] - t[0]))
    x = np.zeros(2 * n + 2)
    x[2 * n + 1] = 1.0
    ys = []
    for tk in t:
        if tk >= duration - 1e-12:
            x[2 * n:] = 0.0
        ys.append(Hs @ x[:n])
        x = step @ x
    return np.array(ys)


def test_modal_operator_damps_each_mode_by_its_ratio(galileo):
    """Each model at 30 deg: Phi^T C Phi = diag(2 zeta_k omega_k) on its own flexible modes (bands taken per mode),
    C annihilates its rigid-body and mechanism modes; the full order's modes are the dense system's, the reduced
    model's its own frequencies."""
    from kryflex.slew.bodies import SlewBodies
    from kryflex.slew.damping import structure_modes, time_damping
    scene, model = galileo
    bands = [[0.5, 0.01], [3.0, 0.002], [1e4, 0.03]]
    a = np.radians([30.0])
    dense = acs.modal_data(*ref.assemble(ref.load_scene(GALILEO), [30.0]),
                           rigid_modes=ref.geometric_rigid_modes(ref.load_scene(GALILEO), [30.0]))
    for bodies, freqs in ((SlewBodies.from_scene(scene), dense.flexible_hz),
                          (SlewBodies.from_model(model), model.at([30.0]).frequencies_hz)):
        C = time_damping(bodies, a, {"modal": bands}).toarray()
        lam, Phi = structure_modes(bodies, a)
        f = np.sqrt(lam) / (2 * np.pi)
        assert np.allclose(f, freqs, rtol=1e-8)
        zeta = np.array([next((z for fm, z in bands if fk <= fm), bands[-1][1]) for fk in f])
        CPhi = Phi.T @ C @ Phi
        assert np.allclose(CPhi, np.diag(2 * zeta * 2 * np.pi * f), rtol=1e-9, atol=1e-9 * np.abs(CPhi).max())
        R = np.asarray(bodies.rigid_modes(a))
        assert np.abs(C @ R).max() <= 1e-10 * np.abs(C).max() * np.abs(R).max()


@pytest.mark.parametrize("damping", [{"modal": 0.02}, {"modal": 0.01, "rayleigh": {"alpha": 0.01, "beta": 1e-4}}])
def test_held_angle_history_is_the_frequency_domains_model(galileo, damping):
    """The full bodies held at 30 deg under the operator: the exact history of the dense system damped the same way,
    second order in the step; stiffness-proportional damping with the same ratio at f1 is far from it."""
    from kryflex.slew.bodies import SlewBodies
    from kryflex.slew.damping import time_damping
    from kryflex.slew.integrator import Integrator
    from kryflex.slew.profiles import Profile
    scene, _ = galileo
    full = SlewBodies.from_scene(scene)
    ray = damping.get("rayleigh", {})
    Ms, Ks, Gs, Hs, Cs = dense_damping(30.0, damping["modal"], ray.get("alpha", 0.0), ray.get("beta", 0.0))
    op = time_damping(full, np.radians([30.0]), damping)
    profile = Profile("slew", 1.5, [0.0], [np.radians(30.0)])
    errs = []
    for h in (0.01, 0.005):
        t, y, _ = Integrator(full, h, damping=op).run(profile, 3.0)
        y_ref = exact_history(Ms, Ks, Gs, Hs, Cs, 1.5, t)
        errs.append(np.abs(y - y_ref).max() / np.abs(y_ref).max())
    f1 = float(np.sqrt(sl.eigh(Ks, Ms, eigvals_only=True)[7]) / (2 * np.pi))
    t, y_beta, _ = Integrator(full, 0.005, 2 * damping["modal"] / (2 * np.pi * f1)).run(profile, 3.0)
    other = np.abs(y_beta - y_ref).max() / np.abs(y_ref).max()
    print("%s: Newmark vs exact %.2e (h 10 ms), %.2e (5 ms); beta K instead: %.2e" % (damping, errs[0], errs[1], other))
    assert errs[1] < 2e-3                         # measured 6.0e-4 (modal), 9.4e-4 (with Rayleigh) at h = 5 ms
    assert 3.0 < errs[0] / errs[1] < 5.0
    assert other > 10 * errs[1]                   # measured 0.21, 0.17


def held_angle_error(scene, model):
    from kryflex.slew.study import SlewStudy
    study = SlewStudy(scene, model, periods_max=20.0, periods_min=0.1, nrates=2)
    row = study.baseline()
    return row["elastic_error"], row["total_error"], study


@pytest.mark.parametrize("accuracy", [0.05, 1e-2, 1e-3])
def test_held_angle_error_within_accuracy_galileo(accuracy, tmp_path, quiet_library):
    import kryflex
    path = acs.write_variant(GALILEO, str(tmp_path / "galileo.yaml"), accuracy=accuracy)
    scene = kryflex.load_scene(path)
    model = kryflex.Reducer(scene, quiet=True).reduce().model
    elastic, total, study = held_angle_error(scene, model)
    print("Galileo at %g: held-angle elastic %.3e, total %.3e" % (accuracy, elastic, total))
    assert not study.notes
    assert elastic <= accuracy and total <= accuracy


@pytest.mark.slow
def test_held_angle_error_within_accuracy_solid(tmp_path, quiet_library):
    """The solid of meshes/solid (refine 0.5, 2,760 dofs) at its own accuracy 0.05."""
    import kryflex
    base = acs.solid_base(str(tmp_path / "solid"))
    scene = kryflex.load_scene(base)
    model = kryflex.Reducer(scene, quiet=True).reduce().model
    elastic, total, _ = held_angle_error(scene, model)
    print("solid at %g: held-angle elastic %.3e, total %.3e" % (scene.accuracy, elastic, total))
    assert elastic <= scene.accuracy and total <= scene.accuracy
