"""Multibody export (kryflex export, kryflex.export): the reduced solid bodies of the bus/rotor spacecraft (3-dof hex8
nodes, RBE2 interface nodes, a revolute joint) built in Exudyn as ObjectFFRFreducedOrder bodies from the neutral file,
whose linearized frequencies must equal kryflex's reassembled ones at 0, 30 and 60 deg; the neutral file checked
against the full-order matrices with NumPy alone; the command's refusals."""
import json
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
from run_env import run  # noqa: E402  (in run_env.COMMAND_ENV: oversubscribed, for mpiexec -n 2 on a small machine)
ROOT = run_env.ROOT
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
KRYFLEX = run_env.KRYFLEX
ANGLES = (0.0, 30.0, 60.0)
MATCH = 1e-6            # the frequencies must agree to this (relative): the export adds no approximation
ZERO = 1e-12            # |lambda| <= ZERO * max |lambda|: a rigid-body or mechanism mode

exudyn = pytest.importorskip("exudyn", reason="Exudyn comes with the project's .venv (scripts/setup)")
from exudyn_checks import exudyn_frequencies, linear_parts, output_jacobian, step_response_errors  # noqa: E402



@pytest.fixture(scope="module")
def solid(tmp_path_factory):
    """The solid pair at refine 0.25 (1,308 dofs) and its multi-angle reduced model with the whole basis (64 flexible
    system modes: enough to test the export beyond the first few)."""
    out = tmp_path_factory.mktemp("solid")
    r = run([sys.executable, os.path.join(ROOT, "meshes", "solid", "generate.py"), "--refine", "0.25", "-o", str(out)])
    assert r.returncode == 0, r.stderr
    red = out / "red"
    r = run([KRYFLEX, "reduce", str(out / "spacecraft.yaml"), "-o", str(red), "-quiet", "-scene.reduction.method",
             "multi-angle", "-kf_search", "0", "-kf_verify", "0"])
    assert r.returncode == 0, r.stdout + r.stderr
    return out, red / "reduced.h5"


@pytest.fixture(scope="module")
def neutral(solid, tmp_path_factory):
    out = tmp_path_factory.mktemp("export") / "spacecraft.npz"
    r = run([KRYFLEX, "export", str(solid[1]), "-o", str(out), "--format", "exudyn", "--angle", "0", "--angle", "30",
             "--angle", "60", "--json"])
    assert r.returncode == 0, r.stdout + r.stderr
    return out, json.loads(r.stdout)


def test_exudyn_matches_reassembly_at_0_30_60(solid, neutral):
    """The exported solid bodies built in Exudyn (from the neutral file) have kryflex's
    reassembled flexible frequencies at 0, 30 and 60 deg to 1e-6, and 6 rigid + 1 mechanism zero modes."""
    import kryflex
    from kryflex.export.exudyn import build_mbs
    model = kryflex.ReducedModel.load(str(solid[1]))
    seen = []
    for a in ANGLES:
        ref = model.at([a])
        SC, mbs, handles = build_mbs(str(neutral[0]), [a])
        assert set(handles["bodies"]) == {"bus", "rotor"} and set(handles["joints"]) == {"spin_bearing"}
        f, nzero = exudyn_frequencies(mbs)
        assert nzero == 7 == ref.rigid_modes.shape[1]
        assert len(f) == len(ref.frequencies_hz) == 64
        err = np.max(np.abs(f - ref.frequencies_hz) / ref.frequencies_hz)
        assert err <= MATCH, (a, err)
        seen.append(f[:5])
    # the configurations differ (the check is not passing by comparing one system with itself)
    assert np.abs(seen[0] - seen[2]).max() > 1e-3 * seen[0][0]
    # the command made the same comparison and reported it
    checks = neutral[1]["check"]
    assert [c["angles_deg"] for c in checks] == [[a] for a in ANGLES]
    assert all(c["max_rel_diff"] <= MATCH and c["exudyn_zero"] == 7 and c["kryflex_rigid"] == 7 for c in checks)


def test_joint_is_what_ties_the_bodies(solid, neutral):
    """Without its joint the two bodies float apart: 12 zero modes and each body's own free-free frequencies. So the
    match above comes from the joint reproducing kryflex's interface ties, not from the bodies alone."""
    from kryflex.export import read_neutral
    from kryflex.export.exudyn import build_mbs
    # no algebraic equations once the joint is off: rotation parameters without the Euler-parameter constraint
    SC, mbs, h = build_mbs(str(neutral[0]), [30.0], assemble=False, rotation="RotationRotationVector")
    mbs.SetObjectParameter(h["joints"]["spin_bearing"], "activeConnector", False)
    mbs.Assemble()
    lam, _ = mbs.ComputeODE2Eigenvalues(useAbsoluteValues=False, ignoreAlgebraicEquations=True)
    lam = np.sort(np.real(lam))
    zero = np.abs(lam) <= ZERO * np.abs(lam).max()
    assert zero.sum() == 12
    data = read_neutral(str(neutral[0]))
    own = np.sort(np.concatenate([b.frequencies_hz for b in data.bodies]))
    assert np.allclose(np.sqrt(lam[~zero]) / (2 * np.pi), own, rtol=1e-8)


def test_inputs_and_outputs_match_kryflex_frf(solid, neutral):
    """The inputs' loads (set_input) and the outputs (output_values) of the Exudyn system give kryflex's undamped
    frequency response at 30 deg: H_y (K - w^2 M)^-1 f on the null space of Exudyn's constraint Jacobian, f from
    Exudyn's right-hand side with the input on, H_y by central differences of output_values."""
    import kryflex
    from scipy.linalg import null_space

    from kryflex.export.exudyn import build_mbs, output_values, set_input
    model = kryflex.ReducedModel.load(str(solid[1]))
    ref = model.at([30.0])
    freqs = np.array([0.5, 3.0, 12.0])            # between resonances, below and in the band
    T = ref.frf(freqs, damping=0.0)               # (frequencies, outputs, inputs)
    SC, mbs, h = build_mbs(str(neutral[0]), [30.0])
    M, K, C, rhs0 = linear_parts(mbs)
    assert np.abs(rhs0).max() == 0.0              # at rest, inputs off: no load
    N = null_space(C.T)
    Hy = output_jacobian(mbs, h, model.output_names)
    assert output_values(mbs, h) == {n: 0.0 for n in model.output_names}
    for k, name in enumerate(model.input_names):
        set_input(mbs, h, name, 1.0)
        f = linear_parts(mbs)[3] - rhs0
        set_input(mbs, h, name, 0.0)
        assert np.abs(f).max() > 0
        for iw, w in enumerate(2 * np.pi * freqs):
            y = Hy @ N @ np.linalg.solve(N.T @ (K - w ** 2 * M) @ N, N.T @ f)
            err = np.abs(y - T[iw, :, k].real).max() / np.abs(T[iw, :, k]).max()
            assert err <= 1e-7, (name, freqs[iw], err)


def test_time_simulation_follows_kryflex_step_response(solid, neutral):
    """Exudyn's nonlinear time integration of a small step input agrees with kryflex's undamped step response at
    30 deg by modal superposition (support/exudyn_checks.py). Small input: rotations ~1e-5 rad, so the nonlinear
    kinematics add ~1e-5 relative. Measured: 2e-5 (bearing_torque), 6e-6 (tip_force)."""
    import kryflex
    model = kryflex.ReducedModel.load(str(solid[1]))
    for name, err in step_response_errors(model, neutral[0], 30.0).items():
        assert err <= 1e-3, (name, err)


def test_joint_angles_follow_the_spin(neutral):
    """joint_angles: the configured angle at build; after 1 s of a 100 N m bearing torque, the angle has changed by the
    bodies' relative frame rotation about the axis (z here), to the small elastic rotation at the bearing."""
    from kryflex.export.exudyn import build_mbs, frame_motion, joint_angles, set_input
    SC, mbs, h = build_mbs(str(neutral[0]), [30.0])
    assert joint_angles(mbs, h) == pytest.approx({"spin_bearing": 30.0}, abs=1e-12)
    set_input(mbs, h, "bearing_torque", 100.0)
    ss = exudyn.SimulationSettings()
    ss.timeIntegration.numberOfSteps = 500
    ss.timeIntegration.endTime = 1.0
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    mbs.SolveDynamic(ss)
    turn = joint_angles(mbs, h)["spin_bearing"] - 30.0
    rb, _ = frame_motion(mbs, h, "bus")
    rr, _ = frame_motion(mbs, h, "rotor")
    assert abs(turn) > 1.0                                   # degrees: a real spin, not round-off
    assert turn == pytest.approx(np.degrees(rr[5] - rb[5]), rel=1e-2)


def test_modal_damping_damps_each_body_mode(neutral):
    """build_mbs(modal_damping=zeta): with the joint off, every body's flexible mode has damping ratio zeta in Exudyn's
    complex eigenvalues."""
    from kryflex.export import read_neutral
    from kryflex.export.exudyn import build_mbs
    SC, mbs, h = build_mbs(str(neutral[0]), [0.0], assemble=False, modal_damping=0.02,
                           rotation="RotationRotationVector")
    mbs.SetObjectParameter(h["joints"]["spin_bearing"], "activeConnector", False)
    mbs.Assemble()
    ev, _ = mbs.ComputeODE2Eigenvalues(computeComplexEigenvalues=True, useAbsoluteValues=False,
                                       ignoreAlgebraicEquations=True)
    ev = ev[np.imag(ev) > 1.0]          # the flexible modes, one of each conjugate pair
    zeta = -np.real(ev) / np.abs(ev)
    data = read_neutral(str(neutral[0]))
    assert len(ev) == sum(b.nflex for b in data.bodies)
    assert np.allclose(zeta, 0.02, rtol=1e-6)
    with pytest.raises(Exception, match="modal_damping"):
        build_mbs(str(neutral[0]), [0.0], modal_damping=-1)


def _load_petsc_dense(path):
    from petsc4py import PETSc
    viewer = PETSc.Viewer().createBinary(str(path), "r", comm=PETSc.COMM_SELF)
    A = PETSc.Mat().create(PETSc.COMM_SELF)
    A.setType("aij")
    A.load(viewer)
    viewer.destroy()
    return A.convert("dense").getDenseArray().copy()


def _rigid_modes(nodes_file):
    """Rigid motions (n x 6: translations, rotations about the origin) from a kryflex nodes file (id x y z ndof)."""
    rows = []
    for line in open(nodes_file):
        if line.startswith("#") or not line.strip():
            continue
        _, x, y, z, nd = line.split()
        x = np.array([float(x), float(y), float(z)])
        for c in range(int(nd)):
            r = np.zeros(6)
            if c < 3:
                r[c] = 1.0
                for k in range(3):
                    w = np.eye(3)[k]
                    r[3 + k] = np.cross(w, x)[c]
            else:
                r[c] = 1.0
            rows.append(r)
    return np.array(rows)


def test_neutral_file_reads_with_numpy_and_matches_full_order(solid, neutral):
    """The neutral file with numpy.load alone: every documented array, the flexible modes M-orthonormal and M-orthogonal
    to the rigid motions, and the mass properties equal to the full-order body's (its M and its node coordinates)."""
    out, _ = solid
    with np.load(str(neutral[0]), allow_pickle=False) as z:
        assert str(z["format"]) == "kryflex-multibody" and int(z["version"]) == 1
        assert list(z["body_names"]) == ["bus", "rotor"] and list(z["joint_names"]) == ["spin_bearing"]
        assert list(z["inputs"]) == ["bearing_torque", "tip_force"]
        assert float(z["damping_ratio"]) == pytest.approx(0.0025)
        for i, name in enumerate(z["body_names"]):
            M, K, R, F = (z["body%d/%s" % (i, k)] for k in ("M", "K", "rigid_coords", "modes"))
            v = M.shape[0]
            assert R.shape == (v, 6) and F.shape == (v, v - 6)
            assert np.allclose(F.T @ M @ F, np.eye(v - 6), atol=1e-10)
            assert np.abs(R.T @ M @ F).max() <= 1e-8 * np.sqrt(np.abs(R.T @ M @ R).max())
            Kf = z["body%d/stiffness_flex" % i]
            assert np.allclose(Kf, np.diag(np.diag(Kf)), atol=1e-9 * np.abs(Kf).max())
            # independent reference: Phi^T M Phi of the full-order body from its matrix file and node coordinates
            Mfull = _load_petsc_dense(out / ("%s_M.petsc" % name))
            Phi = _rigid_modes(out / ("%s_nodes.txt" % name))
            Mr = Phi.T @ Mfull @ Phi
            m = Mr[0, 0]
            assert float(z["body%d/mass" % i]) == pytest.approx(m, rel=1e-10)
            c = np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]]) / m       # first moments: row i, column k is m (e_k x c)_i
            assert np.allclose(z["body%d/center_of_mass" % i], c, atol=1e-9 * (1 + np.abs(c).max()))
            assert np.allclose(z["body%d/inertia" % i], Mr[3:, 3:], rtol=1e-9, atol=1e-9 * np.abs(Mr[3:, 3:]).max())
            # the bearing RBE2 node sits at the origin of both bodies (meshes/solid/README.md)
            assert list(z["body%d/interface_names" % i]) == ["bearing"]
            assert np.abs(z["body%d/interface_positions" % i]).max() < 1e-9


@pytest.fixture(scope="module")
def oblique(tmp_path_factory):
    """Galileo (beams, 6-dof nodes) with its joint axis made oblique, [1, 2, 3], and the child frame turned (orientation
    R0 = 53.1 deg about y), so that the joint frames and placements the export builds are tested off the coordinate
    axes: its reduced model and its export checked at 0, 60, 137.5 deg."""
    import shutil
    out = tmp_path_factory.mktemp("oblique")
    gal = os.path.join(ROOT, "meshes", "galileo")
    for name in os.listdir(gal):
        if name.endswith((".mtx", "_nodes.txt")):
            shutil.copy(os.path.join(gal, name), out)
    text = open(os.path.join(gal, "galileo.yaml")).read()
    assert "axis: [0, 0, 1]" in text
    (out / "oblique.yaml").write_text(text.replace("axis: [0, 0, 1]", "axis: [1, 2, 3], orientation: [[0.6, 0, 0.8], "
                                                                      "[0, 1, 0], [-0.8, 0, 0.6]]"))
    r = run([KRYFLEX, "reduce", str(out / "oblique.yaml"), "-o", str(out / "red"), "-quiet", "-kf_verify", "0"])
    assert r.returncode == 0, r.stdout + r.stderr
    r = run([KRYFLEX, "export", str(out / "red" / "reduced.h5"), "-o", str(out / "g.npz"), "--format", "exudyn",
             "--angle", "0", "--angle", "60", "--angle", "137.5", "--json"])
    assert r.returncode == 0, r.stdout + r.stderr
    return out / "red" / "reduced.h5", out / "g.npz", json.loads(r.stdout)


def test_beam_bodies_export_too(oblique):
    """Bodies with rotational dofs (Galileo's beams) go the same route: the reduced mass already holds their rotary
    inertia, and their interface rows their rotations."""
    checks = oblique[2]["check"]
    for c in checks:
        assert c["max_rel_diff"] <= MATCH and c["exudyn_zero"] == 7 and len(c["exudyn_hz"]) >= 3
    assert abs(checks[0]["exudyn_hz"][-1] - checks[1]["exudyn_hz"][-1]) > 1e-3 * checks[0]["exudyn_hz"][-1]


def _dense_reassembly_hz(data, angles_deg):
    """Independent reference (NumPy/SciPy, docs/guide/export.md): the flexible frequencies of the export's
    reduced bodies tied at the given angles, D(alpha) on the interface rows, its null space by SVD."""
    from scipy.linalg import eigh, null_space
    from scipy.spatial.transform import Rotation
    sizes = [b.M.shape[0] for b in data.bodies]
    off = np.concatenate([[0], np.cumsum(sizes)])
    rows, irev = [], 0
    for j in data.joints:
        k = np.asarray(j["axis"], float) / np.linalg.norm(j["axis"])
        if j["type"] == "revolute":
            R = Rotation.from_rotvec(np.radians(angles_deg[irev]) * k).as_matrix() @ j["R0"]
            irev += 1
            E = null_space(k[None, :]).T                      # two unit vectors across the axis
        else:
            R, E = np.asarray(j["R0"]), np.eye(3)
        P, C = data.bodies[j["parent"]], data.bodies[j["child"]]
        ip, ic = P.iface[6 * j["parent_interface"]:][:6], C.iface[6 * j["child_interface"]:][:6]
        for sel, T in ((slice(0, 3), np.eye(3)), (slice(3, 6), E)):
            D = np.zeros((T.shape[0], off[-1]))
            D[:, off[j["parent"]]:off[j["parent"] + 1]] = T @ ip[sel]
            D[:, off[j["child"]]:off[j["child"] + 1]] = -T @ R @ ic[sel]
            rows.append(D)
    N = null_space(np.vstack(rows), rcond=1e-10)
    Mb = np.zeros((off[-1], off[-1]))
    Kb = np.zeros_like(Mb)
    for b, body in enumerate(data.bodies):
        Mb[off[b]:off[b + 1], off[b]:off[b + 1]] = body.M
        Kb[off[b]:off[b + 1], off[b]:off[b + 1]] = body.K
    lam = eigh(N.T @ Kb @ N, N.T @ Mb @ N, eigvals_only=True)
    nzero = 6 + len(data.revolute)           # a free tree of bodies: 6 rigid + one mechanism per revolute joint
    assert np.abs(lam[:nzero]).max() <= 1e-6 * lam[nzero]
    return np.sqrt(lam[nzero:]) / (2 * np.pi)


def test_rigid_only_body_becomes_an_exudyn_rigid_body(oblique):
    """A body reduced to its 6 rigid motions (no flexible coordinate) becomes an ObjectRigidBody with MarkerBodyRigid
    joints. The reference is the dense reassembly written here; it also agrees with kryflex's C reassembly."""
    import kryflex
    from kryflex.export import floating_body, read_neutral
    from kryflex.export.exudyn import build_mbs
    data = read_neutral(str(oblique[1]))
    model = kryflex.ReducedModel.load(str(oblique[0]))
    for a in (0.0, 60.0):
        ref = _dense_reassembly_hz(data, [a])
        assert np.allclose(ref, model.at([a]).frequencies_hz, rtol=1e-7)
    stator = data.bodies[0]
    R = stator.rigid_coords
    M6 = R.T @ stator.M @ R
    data.bodies[0] = floating_body(stator.name, stator.interfaces, M6, np.zeros((6, 6)), R.T @ stator.G,
                                   stator.H @ R, stator.iface @ R, M6)
    assert data.bodies[0].nflex == 0
    for a in (0.0, 60.0, 137.5):
        ref = _dense_reassembly_hz(data, [a])
        SC, mbs, h = build_mbs(data, [a])
        f, nzero = exudyn_frequencies(mbs)
        assert nzero == 7 and len(f) == len(ref)
        assert np.max(np.abs(f - ref) / ref) <= MATCH, a


@pytest.mark.parametrize("rotation", ["RotationEulerParameters", "RotationRotationVector", "RotationRxyz"])
def test_child_frame_turned_90_deg_about_y(oblique, rotation):
    """A joint whose R0 turns the child frame 90 deg about y (Tait-Bryan angles' singular pitch): the default Euler
    parameters and rotation vectors still match the dense reassembly; Rxyz is offered but cannot (documented)."""
    from kryflex.export import read_neutral
    from kryflex.export.exudyn import build_mbs
    data = read_neutral(str(oblique[1]))
    data.joints[0]["R0"] = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    ref = _dense_reassembly_hz(data, [0.0])
    SC, mbs, h = build_mbs(data, [0.0], rotation=rotation)
    try:
        f, nzero = exudyn_frequencies(mbs)
        ok = nzero == 7 and len(f) == len(ref) and np.max(np.abs(f - ref) / ref) <= MATCH
    except (AssertionError, ValueError, np.linalg.LinAlgError):
        ok = False
    assert ok == (rotation != "RotationRxyz")


@pytest.mark.mpi
def test_two_ranks_write_the_same_export(solid, neutral, tmp_path):
    out = tmp_path / "two.npz"
    r = run(["mpiexec", "-n", "2", KRYFLEX, "export", str(solid[1]), "-o", str(out), "--format", "exudyn", "--angle",
             "30"])
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.count("kryflex: exported") == 1
    with np.load(str(out)) as a, np.load(str(neutral[0])) as b:
        assert sorted(a.files) == sorted(b.files)
        for k in a.files:
            assert np.array_equal(a[k], b[k]), k
    assert os.listdir(tmp_path) == ["two.npz"]


@pytest.mark.parametrize("args, code, words", [
    (["missing.h5", "-o", "x.npz"], 5, "reduced-model file not found"),
    (["@model", "-o", "x.npz", "--format", "fmu"], 2, "--format fmu: unknown export format: use neutral or exudyn"),
    (["@model", "-o", "x.h5"], 2, "give a file name ending in .npz"),
    (["@model", "-o", "x.npz", "--angle", "30"], 2, "--angle is for --format exudyn"),
    (["@model", "-o", "x.npz", "--format", "exudyn", "--angle", "30,40"], 2, "give 1 angle(s), got 2"),
    (["@model", "-o", "nofolder/x.npz"], 4, "is not an existing folder"),
    (["@model"], 2, "missing"),
    (["@model", "-o", "x.npz", "--scene", os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")], 5,
     "was reduced from scene 'spacecraft_solid_r0.25', not from this scene 'galileo'"),
])
def test_bad_input_is_refused_cleanly(solid, tmp_path, args, code, words):
    args = [str(solid[1]) if a == "@model" else a for a in args]
    r = run([KRYFLEX, "export", *args], cwd=str(tmp_path))
    assert r.returncode == code, r.stdout + r.stderr
    assert words in r.stderr and "Traceback" not in r.stderr
    assert os.listdir(tmp_path) == []          # nothing written, no temporary left


@pytest.mark.mpi
def test_two_ranks_refuse_together(solid, tmp_path):
    """Under mpiexec -n 2 a refusal is agreed: one message, the documented code on every rank, no hang."""
    r = run(["mpiexec", "-n", "2", KRYFLEX, "export", str(solid[1]), "-o", str(tmp_path / "x.npz"), "--format", "exudyn",
             "--angle", "30,40"])
    assert r.returncode == 2 and r.stderr.count("kryflex: error:") == 1 and "give 1 angle(s), got 2" in r.stderr
    r = run(["mpiexec", "-n", "2", KRYFLEX, "export", str(tmp_path / "none.h5"), "-o", str(tmp_path / "x.npz")])
    assert r.returncode == 5 and r.stderr.count("kryflex: error:") == 1
    assert os.listdir(tmp_path) == []


def test_not_a_model_file_is_refused(tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_text("not hdf5")
    r = run([KRYFLEX, "export", str(bad), "-o", str(tmp_path / "x.npz")])
    assert r.returncode == 5 and "not a readable kryflex reduced model" in r.stderr and "Traceback" not in r.stderr
    assert sorted(os.listdir(tmp_path)) == ["bad.h5"]


def test_bodies_that_cannot_float_are_refused():
    """A body without rigid-body rows (older models, clamped bodies) or whose basis lacks its rigid motions: an
    ExportError naming the body (kryflex export: exit 5)."""
    from kryflex.export import ExportError, floating_body
    rng = np.random.default_rng(1)
    v = 8
    A = rng.standard_normal((v, v))
    M, K = A @ A.T + v * np.eye(v), A.T @ A
    G, H, iface = np.zeros((v, 1)), np.zeros((1, v)), rng.standard_normal((6, v))
    with pytest.raises(ExportError, match="body 'arm': the reduced model holds no rigid-body rows"):
        floating_body("arm", ["hub"], M, K, G, H, iface, None)
    # rigid rows that do not move the interface node rigidly: not a floating body's rigid motions
    with pytest.raises(ExportError, match="body 'arm'"):
        floating_body("arm", ["hub"], M, K, G, H, iface, rng.standard_normal((v, 6)))


def test_read_neutral_refuses_other_files(tmp_path):
    from kryflex.export import ExportError, read_neutral
    other = tmp_path / "other.npz"
    np.savez(other, a=np.zeros(3))
    with pytest.raises(ExportError, match="not a kryflex multibody export"):
        read_neutral(str(other))
    with pytest.raises(ExportError, match="not found"):
        read_neutral(str(tmp_path / "none.npz"))
