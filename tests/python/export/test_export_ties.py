"""Export of a model of shared directions (-kf_shared_directions true): the solid bus/rotor pair at refine 0.5, one
angle, whose bodies' coordinates obey coordinate ties D_s besides the joints. The neutral file carries the ties on the
bodies' flexible coordinates (export/ties.py), and the Exudyn system holds them as ObjectConnectorCoordinateVector
constraints. Checked against independent inputs: the Exudyn system's linearized frequencies and frequency response
equal kryflex's reassembly and a NumPy reassembly from the model's own arrays (bodies' K, M, the joints' rows at the
angle, D_s; null space by SVD) to 1e-6, at the reduction angle and at another; without its ties the same Exudyn
system fails that check (the test is sensitive to them)."""
import json
import os
import sys

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.spatial.transform import Rotation

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
from run_env import run  # noqa: E402  (in run_env.COMMAND_ENV: oversubscribed, for mpiexec -n 2 on a small machine)
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "support"))
import accuracy_scenes as acc  # noqa: E402

KRYFLEX = run_env.KRYFLEX
MATCH = 1e-6            # frequencies, relative (measured ~1e-10)
FRF_MATCH = 1e-7        # frequency response, relative to the largest entry per input (measured: see the test)
ZERO = 1e-12            # |lambda| <= ZERO * max |lambda|: a rigid-body or mechanism mode
ANGLES = (0.0, 40.0)    # the reduction angle, and one the basis was not built at

exudyn = pytest.importorskip("exudyn", reason="Exudyn comes with the project's .venv (scripts/setup)")
from exudyn_checks import exudyn_frequencies, linear_parts, output_jacobian, step_response_errors  # noqa: E402



@pytest.fixture(scope="module")
def tied(tmp_path_factory):
    """The tied model (reduced.h5) and its export (neutral .npz through --format exudyn, the command's JSON)."""
    base = acc.solid_base(str(tmp_path_factory.mktemp("solid")))
    out = tmp_path_factory.mktemp("tied")
    scene = acc.write_variant(base, str(out / "one.yaml"), accuracy=1e-3, angles=[[0.0]], band=acc.SOLID_BAND)
    r = run([KRYFLEX, "reduce", scene, "-o", str(out / "red"), "-quiet", "-kf_shared_directions", "true",
             "-kf_verify", "0"])
    assert r.returncode == 0, r.stdout + r.stderr
    model = out / "red" / "reduced.h5"
    r = run([KRYFLEX, "export", str(model), "-o", str(out / "tied.npz"), "--format", "exudyn", "--angle", "0",
             "--angle", "40", "--json"])
    assert r.returncode == 0, r.stdout + r.stderr
    return model, out / "tied.npz", json.loads(r.stdout)


def numpy_reassembly(model, angle, ties=None):
    """Independent reference from the model's own arrays: blkdiag(M_b), blkdiag(K_b), the joints' rows on the interface
    rows at this angle (translations equal; rotations across the axis equal) and the ties D_s, null space by SVD:
    (M, K, G, H, N) with the tied model's coordinates phi = N y."""
    bodies = model.bodies
    off = np.concatenate([[0], np.cumsum(model.sizes)])
    rows = []
    for j in model.joints:
        k = np.asarray(j["axis"], float) / np.linalg.norm(j["axis"])
        R = Rotation.from_rotvec(np.radians(angle) * k).as_matrix() @ np.asarray(j["R0"], float)
        E = sl.null_space(k[None, :]).T
        p, c = int(j["parent"]), int(j["child"])
        ip = bodies[p]["iface"][6 * int(j["parent_interface"]):][:6]
        ic = bodies[c]["iface"][6 * int(j["child_interface"]):][:6]
        for sel, T in ((slice(0, 3), np.eye(3)), (slice(3, 6), E)):
            D = np.zeros((T.shape[0], off[-1]))
            D[:, off[p]:off[p + 1]] = T @ ip[sel]
            D[:, off[c]:off[c + 1]] = -T @ R @ ic[sel]
            rows.append(D)
    rows.append(np.asarray(model.ties if ties is None else ties))
    N = sl.null_space(np.vstack(rows), rcond=1e-10)
    M = sl.block_diag(*[b["M"] for b in bodies])
    K = sl.block_diag(*[b["K"] for b in bodies])
    G = np.vstack([b["G"] for b in bodies])
    H = np.hstack([b["H"] for b in bodies])
    return M, K, G, H, N


def numpy_frequencies(model, angle, ties=None):
    M, K, _, _, N = numpy_reassembly(model, angle, ties)
    lam = sl.eigh(N.T @ K @ N, N.T @ M @ N, eigvals_only=True)
    nzero = int(np.sum(np.abs(lam) <= 1e-9 * lam.max()))
    return np.sqrt(lam[nzero:]) / (2 * np.pi), nzero


def test_neutral_file_carries_the_ties(tied):
    """The file's 'ties' (read with NumPy alone) are the model's D_s in the exported coordinates: for each body
    phi_b = R_b r_b + F_b q_b, D_s blkdiag([R_b F_b]) is zero on the frames' r and the file's ties on the q."""
    import kryflex
    from kryflex.export import load, read_neutral
    model = kryflex.ReducedModel.load(str(tied[0]))
    D = model.ties
    assert D is not None and D.shape[0] > 0
    with np.load(str(tied[1])) as z:
        T = z["ties"]
        off = np.concatenate([[0], np.cumsum(model.sizes)])
        cols, col = [], 0
        for b in range(len(model.sizes)):
            R, F = z["body%d/rigid_coords" % b], z["body%d/modes" % b]
            Db = D[:, off[b]:off[b + 1]]
            assert np.abs(Db @ R).max() <= 1e-10 * np.abs(R).max()
            cols.append(Db @ F)
            col += F.shape[1]
        assert T.shape == (D.shape[0], col)
        assert np.allclose(T, np.hstack(cols), rtol=0, atol=1e-12)
    # read back: the same ties, and the same as an export made in memory
    assert np.array_equal(read_neutral(str(tied[1])).ties, T)
    assert np.array_equal(load(model).ties, T)
    # the command says how many it wrote
    assert tied[2]["coordinate_ties"] == D.shape[0]


def test_exudyn_matches_the_tied_reassembly(tied):
    """The Exudyn system (from the neutral file) has the tied model's flexible frequencies at 0 and 40 deg: kryflex's
    reassembly and the NumPy one agree, and Exudyn agrees with both to 1e-6; 6 rigid + 1 mechanism zero modes.
    The command made the same check and reported it."""
    import kryflex
    from kryflex.export.exudyn import build_mbs
    model = kryflex.ReducedModel.load(str(tied[0]))
    for a in ANGLES:
        ref = model.at([a]).frequencies_hz
        npf, npzero = numpy_frequencies(model, a)
        assert npzero == 7 and len(npf) == len(ref)
        assert np.max(np.abs(npf - ref) / ref) <= 1e-8, a
        SC, mbs, h = build_mbs(str(tied[1]), [a])
        assert len(h["ties"]) == 1          # two bodies: one connector between their modal nodes
        f, nzero = exudyn_frequencies(mbs)
        assert nzero == 7 and len(f) == len(npf)
        err = np.max(np.abs(f - npf) / npf)
        print("%g deg: %d flexible modes, Exudyn vs NumPy %.2e" % (a, len(f), err))
        assert err <= MATCH, (a, err)
    for c in tied[2]["check"]:
        assert c["max_rel_diff"] <= MATCH and c["exudyn_zero"] == 7


def test_without_its_ties_the_export_differs(tied):
    """The same Exudyn system with the ties dropped has the untied bodies' extra freedom: more flexible modes, and
    the ones it has differ from the tied model's, so the check above is sensitive to the ties."""
    import kryflex
    from kryflex.export import read_neutral
    from kryflex.export.exudyn import build_mbs
    model = kryflex.ReducedModel.load(str(tied[0]))
    data = read_neutral(str(tied[1]))
    data.ties = None
    ref = model.at([0.0]).frequencies_hz
    SC, mbs, h = build_mbs(data, [0.0])
    assert h["ties"] == []
    f, nzero = exudyn_frequencies(mbs)
    assert nzero == 7 and len(f) == len(ref) + model.ties.shape[0]
    # the lowest len(ref) of the untied system are (Cauchy) at or below the tied ones, and some clearly below
    assert np.max(np.abs(f[:len(ref)] - ref) / ref) > 100 * MATCH


def test_frequency_response_through_the_export(tied):
    """The inputs' loads and the outputs of the tied Exudyn system at 40 deg give the undamped frequency response of
    the NumPy reassembly H N (N^T (K - w^2 M) N)^-1 N^T G (and kryflex's), off resonance, to 1e-7."""
    import kryflex
    from kryflex.export.exudyn import build_mbs, output_values, set_input
    model = kryflex.ReducedModel.load(str(tied[0]))
    a = 40.0
    freqs = np.array([0.5, 3.0, 8.3, 14.7])
    Mn, Kn, Gn, Hn, N0 = numpy_reassembly(model, a)
    Tn = np.array([Hn @ N0 @ np.linalg.solve(N0.T @ (Kn - w * w * Mn) @ N0, N0.T @ Gn) for w in 2 * np.pi * freqs])
    Tk = model.at([a]).frf(freqs, damping=0.0)
    kerr = np.abs(Tk - Tn).max() / np.abs(Tn).max()       # measured 2.4e-8 (at 0.5 Hz, the rigid motions' share)
    assert kerr <= FRF_MATCH
    SC, mbs, h = build_mbs(str(tied[1]), [a])
    M, K, C, rhs0 = linear_parts(mbs)
    N = sl.null_space(C.T)
    Hy = output_jacobian(mbs, h, model.output_names)
    worst = 0.0
    for k, name in enumerate(model.input_names):
        set_input(mbs, h, name, 1.0)
        f = linear_parts(mbs)[3] - rhs0
        set_input(mbs, h, name, 0.0)
        for iw, w in enumerate(2 * np.pi * freqs):
            y = Hy @ N @ np.linalg.solve(N.T @ (K - w ** 2 * M) @ N, N.T @ f)
            worst = max(worst, np.abs(y - Tn[iw, :, k]).max() / np.abs(Tn[iw, :, k]).max())
    print("FRF through the export vs NumPy: %.2e (kryflex vs NumPy %.2e)" % (worst, kerr))
    assert worst <= FRF_MATCH


def test_time_simulation_follows_the_tied_step_response(tied):
    """Exudyn's nonlinear time integration of a small step input, with the ties as constraints, follows the tied
    model's undamped step response at 40 deg by modal superposition (support/exudyn_checks.py, as test_export.py's for
    the split model)."""
    import kryflex
    model = kryflex.ReducedModel.load(str(tied[0]))
    for name, err in step_response_errors(model, tied[1], 40.0).items():
        print("step response, %s: %.2e" % (name, err))
        assert err <= 1e-3, (name, err)


def test_rows_on_three_bodies_go_through_gathered_coordinates(tied, monkeypatch):
    """Rows that a pair connector cannot hold act on an ObjectGenericODE2 gathering the bodies' modal nodes: forced
    here for every tie, the system keeps the tied frequencies."""
    import kryflex
    from kryflex.export import ties as kt
    from kryflex.export.exudyn import build_mbs
    model = kryflex.ReducedModel.load(str(tied[0]))
    monkeypatch.setattr(kt, "split_ties", lambda T, sizes: ([], np.asarray(T)))
    SC, mbs, h = build_mbs(str(tied[1]), [40.0])
    f, nzero = exudyn_frequencies(mbs)
    ref, _ = numpy_frequencies(model, 40.0)
    assert nzero == 7 and len(f) == len(ref) and np.max(np.abs(f - ref) / ref) <= MATCH


def test_rows_on_one_body_hold_too(tied):
    """A tie on one body's own flexible coordinates (added here: the bus's first flexible mode held, d = (M F e_0)^T
    on its reduced coordinates, so that d R = 0 and d F = e_0^T) gets a connector on that body alone; the system keeps
    the NumPy reassembly's frequencies with [D_s; d]."""
    import kryflex
    from kryflex.export import from_model
    from kryflex.export.exudyn import build_mbs
    model = kryflex.ReducedModel.load(str(tied[0]))
    data = from_model(model)
    bus = data.bodies[0]
    d = np.zeros((1, sum(model.sizes)))
    d[0, :model.sizes[0]] = (bus.M @ bus.modes[:, 0])
    D = np.vstack([model.ties, d])
    data.ties = np.vstack([data.ties, np.eye(1, data.ties.shape[1])])
    SC, mbs, h = build_mbs(data, [40.0])
    from kryflex.export.ties import split_ties
    groups = [b for b, _ in split_ties(data.ties, data.coordinate_sizes)[0]]
    # the bus's own row, and (the pair's rows then fixing a combination of the rotor's) the rotor's own and the pair's
    assert groups == [(0,), (1,), (0, 1)] and len(h["ties"]) == 3
    f, nzero = exudyn_frequencies(mbs)
    ref, rzero = numpy_frequencies(model, 40.0, D)
    assert rzero == nzero == 7 and len(f) == len(ref) == len(model.at([40.0]).frequencies_hz) - 1
    assert np.max(np.abs(f - ref) / ref) <= MATCH


def test_split_ties_keeps_the_row_space():
    """split_ties on a synthetic 3-body T: rows on one body, on pairs, and one on all three; each group's rows vanish
    outside its bodies, and the groups with the rest span T's rows exactly."""
    from kryflex.export.ties import split_ties
    rng = np.random.default_rng(3)
    sizes = [3, 4, 2]
    off = np.concatenate([[0], np.cumsum(sizes)])

    def row(bodies):
        r = np.zeros(off[-1])
        for b in bodies:
            r[off[b]:off[b + 1]] = rng.standard_normal(sizes[b])
        return r
    T = np.array([row([0]), row([0, 1]), row([1, 2]), row([0, 1, 2])])
    T = rng.standard_normal((4, 4)) @ T                   # mixed: every row of T touches all three bodies
    groups, rest = split_ties(T, sizes)
    for bodies, rows in groups:
        outside = np.ones(off[-1], bool)
        for b in bodies:
            outside[off[b]:off[b + 1]] = False
        assert np.abs(rows[:, outside]).max(initial=0.0) == 0.0
    assert [len(b) for b, _ in groups] == [1, 2, 2] and rest is not None and rest.shape[0] == 1
    allrows = np.vstack([r for _, r in groups] + [rest])
    assert np.linalg.matrix_rank(allrows) == 4 and np.linalg.matrix_rank(np.vstack([allrows, T])) == 4


def test_a_tie_on_the_rigid_motions_is_refused(tied):
    """Ties that move a body's rigid motions cannot act on its flexible coordinates alone: an ExportError naming the
    tie, the body and the motion (kryflex export: exit 5), not a wrong export."""
    import kryflex
    from kryflex.export import ExportError, read_neutral
    from kryflex.export.ties import export_ties
    model = kryflex.ReducedModel.load(str(tied[0]))
    data = read_neutral(str(tied[1]))
    D = np.array(model.ties)
    R = data.bodies[1].rigid_coords
    D[2, model.sizes[0]:] += 1e-4 * R[:, 4] / np.linalg.norm(R[:, 4])
    with pytest.raises(ExportError, match="coordinate tie 2 moves the rigid motion ry of body 'rotor'.*"
                                          "-kf_shared_directions false"):
        export_ties(D, data.bodies, data.scene)


@pytest.mark.mpi
def test_two_ranks_write_the_same_tied_export(tied, tmp_path):
    out = tmp_path / "two.npz"
    r = run(["mpiexec", "-n", "2", KRYFLEX, "export", str(tied[0]), "-o", str(out), "--format", "exudyn", "--angle",
             "0", "--angle", "40"])
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.count("kryflex: exported") == 1
    assert r.stdout.count("coordinate ties between the bodies' flexible coordinates") == 1
    with np.load(str(out)) as a, np.load(str(tied[1])) as b:
        assert sorted(a.files) == sorted(b.files) and a["ties"].shape[0] > 0
        for k in a.files:
            assert np.array_equal(a[k], b[k]), k
