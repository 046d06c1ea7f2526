"""Boundary conditions, massless dofs and dof layouts (docs/guide/boundary-conditions.md): clamped, sprung, grounded-articulated, lumped-mass
(massless rotations), plate (c345 nodes) and scalar-point models reduce to their stated accuracy,
checked against dense NumPy/SciPy references written in bc_models.py (not against kryflex's own report), on 1 and 2
ranks; the rigid and mechanism modes are derived (and the reduced systems carry them); bad conditions fail with a
message naming them, on every rank, without hanging."""
import os
import subprocess
import sys

import numpy as np
import pytest

import bc_models

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
PROBE = os.path.join(SUPPORT, "bc_probe.py")
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)
TIMEOUT = 240

# the rigid and mechanism modes each case must have (free beam on uz springs at both ends: ux, uy, rx, rz)
EXPECTED_RIGID = {"clamped": 0, "sprung": 4, "grounded": 2, "lumped": 6, "plate": 3, "spoints": 6, "plate_supported": 0}


def probe(case, ranks, tmp_path):
    out = tmp_path / ("%s_%d.npz" % (case, ranks))
    cmd = [sys.executable, PROBE, case, str(out)]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=TIMEOUT)
    return p, out


def reference(case, spec, angle):
    if case == "grounded":
        Ms, Ks, Gs, Hs = bc_models.grounded_arm_reference(spec, angle)
    elif case in ("plate", "spoints", "plate_supported"):
        Ms, Ks, Gs, Hs = bc_models.layout_reference(spec)
    else:
        Ms, Ks, Gs, Hs = bc_models.single_body_reference(spec)
    return Ms, Ks, Gs, Hs


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("bc")
    done = {}
    for case in bc_models.CASES:
        for ranks in (1, 2):
            p, out = probe(case, ranks, tmp)
            assert p.returncode == 0, "%s on %d ranks failed:\n%s\n%s" % (case, ranks, p.stdout, p.stderr[-3000:])
            done[case, ranks] = dict(np.load(out))
    return done


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
@pytest.mark.parametrize("case", list(bc_models.CASES))
def test_reduced_frf_meets_accuracy_against_dense_reference(runs, case, ranks):
    spec = bc_models.CASES[case]()
    r = runs[case, ranks]
    for k, angle in enumerate(r["angles"]):
        Ms, Ks, Gs, Hs = reference(case, spec, angle)
        R = bc_models.rigid_null(Ks)
        assert R.shape[1] == EXPECTED_RIGID[case]            # the reference agrees with what the case must have
        if case == "lumped":   # massless rotations: the reference condenses them
            Tf = bc_models.condensed_frf(Ms, Ks, Gs, Hs, r["f"])
        else:
            Tf = bc_models.modal_frf(Ms, Ks, Gs, Hs, r["f"], rigid=R)
        err = bc_models.hinf_error(Tf, r["T"][k])
        assert err <= spec["accuracy"], "%s at %s deg: FRF error %.3g against the dense reference > %g" % (
            case, angle, err, spec["accuracy"])


@pytest.mark.mpi
@pytest.mark.parametrize("case", list(bc_models.CASES))
def test_rigid_count_is_derived(runs, case):
    for ranks in (1, 2):
        r = runs[case, ranks]
        assert int(r["rigid_modes"].ravel()[0]) == EXPECTED_RIGID[case]
        assert (r["nrigid"] == EXPECTED_RIGID[case]).all(), r["nrigid"]


@pytest.mark.mpi
@pytest.mark.parametrize("case", list(bc_models.CASES))
def test_two_ranks_agree_with_one(runs, case):
    T1, T2 = runs[case, 1]["T"], runs[case, 2]["T"]
    if T1.shape == T2.shape:
        assert np.abs(T1 - T2).max() <= 1e-6 * np.abs(T1).max()
    else:   # a different basis size is allowed only if both meet the target (checked above)
        pytest.skip("the two runs chose different model sizes %s and %s" % (runs[case, 1]["sizes"], runs[case, 2]["sizes"]))


BAD = {
    "unknown_node": "node 99",
    "missing_component": "node 1 of body 'beam' has no component rx (it is c123)",
    "oblique_ground_axis": "is not one of its coordinate axes",
    "tied_clamp": "tied to the parent body by joint 'elbow'",
    "undeclared_support": "most at body 'beam', node 1, component uz",
    "clamped_output": "output 'z' acts on body 'beam', node 1, component 2 (0-5: ux..rz), which is clamped",
    "plate_ux_output": "node 1 of body 'beam' has 3 dofs (c345), so no 'ux'",
    "plate_interface": "node 2 has 3 dofs (c345); interface nodes need 6",
    "scalar_as_ux": "node 101 of body 'beam' has 1 dofs (a scalar point), so no 'uz'",
}


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
@pytest.mark.parametrize("case", list(BAD))
def test_bad_boundary_conditions_fail_clearly(tmp_path, case, ranks):
    p, out = probe(case, ranks, tmp_path)
    assert p.returncode == 2, p.stdout + p.stderr[-2000:]
    assert BAD[case] in p.stdout, p.stdout
    assert "Traceback" not in p.stderr
    assert not out.exists()


def test_massless_dofs_verified_by_condensation():
    """The verification of a model with massless rotations condenses them (no LAPACK sygvd failure) and says so."""
    p = subprocess.run([sys.executable, "-c", "import sys; sys.path.insert(0, %r); import kryflex, bc_models; "
                        "kryflex.Reducer(kryflex.scene_from_dict(bc_models.lumped_frame()), quiet=False).reduce()" % SUPPORT],
                       env=ENV, capture_output=True, text=True, timeout=TIMEOUT)
    assert p.returncode == 0, p.stderr[-2000:]
    assert "massless dofs condensed" in p.stdout + p.stderr


def test_dof_without_mass_or_stiffness_is_named():
    import kryflex
    spec = bc_models.lumped_frame()
    K = spec["bodies"]["beam"]["stiffness"].copy()
    K[9, :] = 0        # node 2, rx: no stiffness and (lumped) no mass
    K[:, 9] = 0
    spec["bodies"]["beam"]["stiffness"] = K
    with pytest.raises(kryflex.SceneError, match=r"node 2, component rx .*neither mass nor stiffness"):
        kryflex.scene_from_dict(spec)


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
def test_massless_dofs_sparse_verification(tmp_path, ranks):
    """The sparse verification (shift-and-invert) takes the semi-definite M as it is: the same accuracy."""
    out = tmp_path / "ls.npz"
    cmd = [sys.executable, PROBE, "lumped", str(out), "-kf_verify_dense_max_dofs", "0"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=TIMEOUT)
    assert p.returncode == 0, p.stdout + p.stderr[-2000:]
    r = dict(np.load(out))
    spec = bc_models.lumped_frame()
    Tf = bc_models.condensed_frf(*bc_models.single_body_reference(spec), r["f"])
    assert bc_models.hinf_error(Tf, r["T"][0]) <= spec["accuracy"]


def test_reduced_system_takes_rigid_modes_from_geometry():
    """Item 5: the reassembled system's first r modes are the geometric rigid modes (eigenvalue exactly 0, same span
    as rigid_modes, M-orthonormal), not the lowest eigenvectors of the reduced pencil; its FRF is then the dense
    reference's (checked above) and its rigid part equals H Phi_r Phi_r^T G / (-w^2) from rigid_modes alone."""
    import kryflex
    spec = bc_models.sprung_beam()
    model = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True).reduce().model
    s = model.at([])
    R = s.rigid_modes
    r = R.shape[1]
    assert r == EXPECTED_RIGID["sprung"]
    assert np.all(s.eigenvalues[:r] == 0)
    P = s.modes[:, :r]
    assert np.allclose(P.T @ s.M @ P, np.eye(r), atol=1e-12)
    # the same span: R = P (P^T M R)
    assert np.abs(R - P @ (P.T @ s.M @ R)).max() <= 1e-10 * np.abs(R).max()
    # the rigid part of the response at a frequency far below the flexible ones: -H Phi_r Phi_r^T G / w^2
    w = 2 * np.pi * 1e-4
    Rm = R @ np.linalg.inv(np.linalg.cholesky(R.T @ s.M @ R)).T
    T = s.frf([1e-4])[0]
    Trig = -(s.C @ Rm) @ (Rm.T @ s.B) / w**2
    assert np.abs(T - Trig).max() <= 1e-6 * np.abs(Trig).max()
