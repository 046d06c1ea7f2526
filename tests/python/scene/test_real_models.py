"""Real models, one item at a time: the model check's findings (each one provoked, its numbers recomputed here with
dense NumPy/SciPy), kryflex check serial against 2 ranks, convert MODEL.mat (what it writes, checked against the .mat
file; what it refuses, in one line, nothing written), reassemble/export/info on single structures and their refusals,
the damping defaults. The end-to-end path of docs/guide/real-models.md is test_real_models_guide.py."""
import json
import importlib.util
import os
import re
import subprocess
import sys

import numpy as np
import pytest
import scipy.io
import scipy.linalg as sl
import scipy.sparse as sp

import kryflex

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
EXAMPLE = os.path.join(ROOT, "examples", "single_structure")
KRYFLEX = run_env.KRYFLEX
ENV = dict(run_env.ENV, MPLBACKEND="Agg", PYTHONPATH=run_env.PACKAGE)
# the example's own model builders, loaded from their file: other tests import meshes' generate.py under the same
# module name, which the import system would hand back instead
_spec = importlib.util.spec_from_file_location("single_structure_generate", os.path.join(EXAMPLE, "generate.py"))
generate = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(generate)

needs_cli = pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built")


def run(args, cwd=None, ranks=1):
    cmd = (["mpiexec", "-n", str(ranks)] if ranks > 1 else []) + [KRYFLEX] + args
    p = subprocess.run(cmd, cwd=cwd, env=ENV, capture_output=True, text=True, timeout=240)
    assert "Traceback" not in p.stdout + p.stderr, p.stderr
    return p


def one_error(p):
    lines = [line for line in p.stderr.splitlines() if line.startswith("kryflex: error:")]
    assert len(lines) == 1, p.stderr
    return lines[0]


# ------------------------------------------------------------------ the model check, in process

def plate_spec(K=None, M=None, **extra):
    K0, M0, nodes = generate.plate()
    spec = {"name": "plate", "bodies": {"plate": {"mass": M0 if M is None else M, "stiffness": K0 if K is None else K,
                                                  "nodes": [list(r) for r in nodes]}},
            "inputs": {"f": [{"body": "plate", "node": 20, "dof": "uz"}]},
            "outputs": {"z": [{"body": "plate", "node": 1, "dof": "uz"}]}, "band": [0.5, 100.0], "accuracy": 0.01}
    spec.update(extra)
    return spec


def plate_rigid(nodes):
    """The plate's rigid modes on (uz, rx, ry) per node: uz = 1; rotation about x (uz = y, rx = 1); about y
    (uz = -x, ry = 1)."""
    Phi = np.zeros((3 * len(nodes), 3))
    for i, r in enumerate(nodes):
        x, y = r[1], r[2]
        Phi[3 * i] = [1.0, y, -x]
        Phi[3 * i + 1, 1] = 1.0
        Phi[3 * i + 2, 2] = 1.0
    return Phi


def check(spec):
    return kryflex.check_scene(kryflex.scene_from_dict(spec, quiet=True))


def rayleigh_hz(K, M, Phi):
    lam = sl.eigh(Phi.T @ K @ Phi, Phi.T @ M @ Phi, eigvals_only=True)
    return np.sort(np.sign(lam) * np.sqrt(np.abs(lam)) / (2 * np.pi))


def test_check_exact_plate_has_no_findings():
    K, M, nodes = generate.plate()
    facts, findings = check(plate_spec())
    assert findings == []
    assert facts["rigid_modes"] == 3 and facts["stiffness_null"] == 3 and facts["mass_rank"] == len(K)
    w = sl.eigh(K, M, eigvals_only=True)
    f = np.sqrt(w[3:]) / (2 * np.pi)
    assert abs(facts["first_flexible_hz"] / f[0] - 1) < 1e-8
    assert facts["verification_modes"] == int(np.sum(f <= 300.0))
    ws = np.linalg.eigvalsh(K)          # the condition of K itself on its flexible part
    assert abs(facts["stiffness_condition"] / (ws[-1] / ws[3]) - 1) < 1e-6


def test_check_rounded_stiffness_reports_rigid_energy_in_hz():
    """K rounded to 8 significant digits (as a Nastran punch writes it): the Rayleigh frequencies of the geometric
    rigid modes, computed here, are reported, with the fix."""
    K, M, nodes = generate.plate()
    K8 = np.vectorize(lambda x: float("%.7e" % x))(K)
    facts, findings = check(plate_spec(K=K8))
    ref = rayleigh_hz(K8, M, plate_rigid(nodes))
    np.testing.assert_allclose(sorted(facts["rigid_hz"]), ref, rtol=1e-3, atol=1e-9)
    assert np.abs(ref).max() > 1e-4 * facts["first_flexible_hz"]
    texts = [f.text() for f in findings]
    assert len(texts) == 1 and "Rayleigh frequencies" in texts[0] and "Hz" in texts[0]
    assert "P^T K P" in texts[0] and "full precision" in texts[0]
    assert facts["stiffness_null"] == 3           # the rounded rigid modes still count as null pivots


def test_check_symmetry_defect_and_factorization_pivots():
    """The symmetry defect ||K - K^T||_F / ||K||_F, computed here, of a stiffness whose two triangles differ: at 1e-12
    (round-off of an export) check reports it among the body's facts and finds nothing; at 1e-9 the scene reader
    refuses the matrix itself, naming the measured defect and the fix (so a defect check would report never reaches
    a reduction). The MUMPS pivot counts of the free plate are its 3 rigid modes (null pivots) and no negative one
    (a fact, no finding)."""
    K, M, nodes = generate.plate()
    E = np.triu(np.random.default_rng(1).standard_normal(K.shape), 1) * (K != 0)
    for level in (1e-12, 1e-9):
        Ka = K + level * np.abs(K).max() * E
        want = np.linalg.norm(Ka - Ka.T) / np.linalg.norm(Ka)
        if level < 1e-10:
            facts, findings = check(plate_spec(K=Ka))
            assert np.isclose(facts["bodies"][0]["asymmetry"]["K"], want, rtol=1e-6) and findings == []
        else:
            with pytest.raises(kryflex.SceneError, match="not symmetric: .* = %.5e" % want):
                check(plate_spec(K=Ka))
    facts, findings = check(plate_spec())
    assert facts["factor_null_pivots"] == 3 and facts["factor_negative_pivots"] == 0 and findings == []


def test_check_massless_dofs_and_singular_mass():
    K, M, nodes = generate.plate()
    Mz = M.copy()
    rot = [3 * i + c for i in range(len(nodes)) for c in (1, 2)]      # no rotary inertia
    Mz[rot, :] = 0.0
    Mz[:, rot] = 0.0
    facts, findings = check(plate_spec(M=Mz))
    note = [f for f in findings if "massless dofs" in f.what]
    assert len(note) == 1 and note[0].severity == "note" and "%d massless" % len(rot) in note[0].what
    assert facts["mass_zero_diagonal"] == len(rot)
    assert facts["mass_rank"] == np.linalg.matrix_rank(Mz)
    # singular beyond the zero diagonal: a lumped mass matrix where two uz dofs share one mass (a rank-one block)
    Ms = np.diag(np.diag(M))
    Ms[np.ix_([0, 3], [0, 3])] = M[0, 0]
    facts, findings = check(plate_spec(M=Ms))
    assert facts["mass_rank"] == np.linalg.matrix_rank(Ms) == len(M) - 1
    assert any("M is singular beyond its zero diagonal" in f.what for f in findings)


def flexible_mode(K, M, k=3):
    w, V = sl.eigh(K, M)
    return w[k], V[:, k]


def test_check_mechanism_and_indefinite_stiffness():
    """A flexible mode's energy removed (a mechanism the geometry does not know) or reversed (indefinite): the rigid
    modes still satisfy K Phi = 0, so only the check's spectrum sees them."""
    K, M, nodes = generate.plate()
    lam, v = flexible_mode(K, M)
    Mv = M @ v
    facts, findings = check(plate_spec(K=K - lam * np.outer(Mv, Mv)))
    assert facts["stiffness_null"] == 4
    assert any("4 near-zero eigenvalues" in f.what and "3 rigid" in f.what for f in findings)
    K2 = K - 2 * lam * np.outer(Mv, Mv)
    facts, findings = check(plate_spec(K=K2))
    hit = [f for f in findings if "indefinite" in f.what]
    assert len(hit) == 1 and "%.3e" % np.linalg.eigvalsh(K2)[0] in hit[0].what


def test_check_per_body_on_two_bodies():
    """Galileo (two bodies, a revolute joint): 7 rigid and mechanism modes; each body's rigid energy is at round-off."""
    facts, findings = kryflex.check_scene(kryflex.load_scene(os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")))
    assert facts["rigid_modes"] == 7 and findings == []
    assert [b["name"] for b in facts["bodies"]] == ["stator", "rotor"]
    for b in facts["bodies"]:
        assert b["asymmetry"] == {"K": 0.0, "M": 0.0} and np.abs(b["rigid_hz"]).max() < 1e-3


@pytest.mark.fast
def system_at_first(scene):
    from kryflex import _core
    system = _core.CSystem(scene.cscene)
    system.set_angles(scene.angles_rad(scene.configurations[0]))
    return system


def test_reduce_model_check_limits_the_dense_spectra():
    """kryflex reduce's model check computes the dense spectra up to REDUCE_DENSE_MAX system dofs (below: the same
    facts as kryflex check's, M's rank against a dense NumPy rank), above it says they were skipped and where they are
    computed, and the rest of the check (rigid modes, their energy, symmetry) is unchanged."""
    from kryflex.check import DENSE_MAX, REDUCE_DENSE_MAX, _dense
    from kryflex.cli.reduce import model_check
    scene = kryflex.load_scene(os.path.join(ROOT, "meshes", "galileo", "galileo.yaml"))
    full, found = kryflex.check_scene(scene, factor=False)
    n = full["system_dofs"]
    assert n <= REDUCE_DENSE_MAX < DENSE_MAX and full["dense"] and "dense_skipped" not in full
    (inside, _), checked = model_check(scene)
    assert inside == full
    # the system it checked, which the reduction starts from: assembled at the first configuration
    assert checked.matrices()[0].equal(system_at_first(scene).matrices()[0])
    system = system_at_first(scene)
    assert full["mass_rank"] == np.linalg.matrix_rank(_dense(system.matrices()[0]))
    skipped, found_skipped = kryflex.check_scene(scene, factor=False, dense_max=n - 1)
    assert not skipped["dense"] and "mass_rank" not in skipped and "verification_modes" not in skipped
    assert "%d dofs > %d" % (n, n - 1) in skipped["dense_skipped"]
    assert "kryflex check computes them up to %d dofs" % DENSE_MAX in skipped["dense_skipped"]
    for key in ("rigid_modes", "rigid_hz", "bodies", "system_dofs"):
        assert skipped[key] == full[key], key
    assert found_skipped == found == []


@needs_cli
@pytest.mark.mpi
def test_check_command_serial_and_two_ranks(tmp_path):
    """kryflex check --json gives the same facts and findings on 1 and 2 ranks; the refusal of a missing scene is one
    line, exit 2."""
    K, M, nodes = generate.plate()
    K8 = np.vectorize(lambda x: float("%.7e" % x))(K)
    scipy.io.mmwrite(str(tmp_path / "K.mtx"), sp.coo_matrix(K8), symmetry="symmetric", precision=17)
    scipy.io.mmwrite(str(tmp_path / "M.mtx"), sp.coo_matrix(M), symmetry="symmetric", precision=17)
    with open(tmp_path / "nodes.txt", "w") as f:
        f.writelines("%d %r %r %r %s\n" % r for r in nodes)
    with open(tmp_path / "s.yaml", "w") as f:
        f.write("name: p\nbodies: {p: {mass: M.mtx, stiffness: K.mtx, nodes: nodes.txt}}\n"
                "inputs: {f: [{body: p, node: 20, dof: uz}]}\noutputs: {z: [{body: p, node: 1, dof: uz}]}\n"
                "band: [0.5, 100]\n")
    out = [json.loads(run(["check", str(tmp_path / "s.yaml"), "--json", "-quiet"], ranks=n).stdout) for n in (1, 2)]
    for key in ("rigid_modes", "stiffness_null", "mass_rank", "verification_modes"):
        assert out[0]["facts"][key] == out[1]["facts"][key]
    np.testing.assert_allclose(out[0]["facts"]["rigid_hz"], out[1]["facts"]["rigid_hz"], rtol=1e-6)
    assert [f["what"][:40] for f in out[0]["findings"]] == [f["what"][:40] for f in out[1]["findings"]]
    assert len(out[0]["findings"]) == 1
    p = run(["check", str(tmp_path / "missing.yaml")], ranks=2)
    assert p.returncode == 2 and "not found" in one_error(p)


# ------------------------------------------------------------------ convert MODEL.mat

def beam_mat(path, **parts):
    K, M = generate.beam()
    n = len(K)
    B = np.zeros((n, 2))
    B[n - 4, 0] = 1.0
    B[n - 5, 1] = 1.0
    C = np.zeros((2, n))
    C[0, n - 4] = 1.0
    C[1, 26] = 0.5
    data = dict(M=sp.csc_matrix(M), K=sp.csc_matrix(K), D=sp.csc_matrix(1e-5 * K), B=B, C=C)
    data.update(parts)
    data = {k: v for k, v in data.items() if v is not None}
    scipy.io.savemat(str(path), data)
    return data


@needs_cli
def test_convert_mat_writes_what_the_file_holds(tmp_path):
    d = beam_mat(tmp_path / "m.mat")
    p = run(["convert", str(tmp_path / "m.mat"), "--name", "m", "-o", str(tmp_path / "out"), "--format", "mtx"])
    assert p.returncode == 0, p.stderr
    out = tmp_path / "out"
    import yaml
    scene = yaml.safe_load(open(out / "m.yaml"))
    text = open(out / "m.yaml").read()
    assert "GUESS" in text and "damping:" not in text.split("# no damping key")[0].split("outputs:")[1]
    body = scene["bodies"]["m"]
    np.testing.assert_array_equal(scipy.io.mmread(str(out / body["mass"])).toarray(), d["M"].toarray())
    np.testing.assert_array_equal(scipy.io.mmread(str(out / body["damping"])).toarray(), d["D"].toarray())
    for j in range(2):
        np.testing.assert_array_equal(np.loadtxt(out / ("m_u%d.txt" % (j + 1))), d["B"][:, j])
        np.testing.assert_array_equal(np.loadtxt(out / ("m_y%d.txt" % (j + 1))), d["C"][j])
    K, M = d["K"].toarray(), d["M"].toarray()
    f1 = np.sqrt(sl.eigh(K, M, eigvals_only=True)[0]) / (2 * np.pi)
    np.testing.assert_allclose(scene["band"], [f1 / 100, 5 * f1], rtol=1e-5)
    assert all(line.split()[4] == "s" for line in open(out / "m_nodes.txt") if not line.startswith("#"))


@needs_cli
def test_convert_mat_velocity_outputs_and_key_overrides(tmp_path):
    K, M = generate.beam()
    n = len(K)
    B = np.zeros((n, 1))
    B[n - 4] = 1.0
    scipy.io.savemat(str(tmp_path / "v.mat"), dict(Mass=M, Stiff=K, Damp=1e-5 * K, In=B, Out=np.eye(n)[[n - 4]],
                                                  Vel=np.eye(n)[[26]]))
    args = ["convert", str(tmp_path / "v.mat"), "--name", "v", "-o", str(tmp_path / "o"), "--mass-key", "Mass",
            "--stiffness-key", "Stiff", "--damping-key", "Damp", "--input-key", "In", "--output-key", "Out",
            "--velocity-output-key", "Vel"]
    p = run(args)
    assert p.returncode == 0, p.stderr
    import yaml
    scene = yaml.safe_load(open(tmp_path / "o" / "v.yaml"))
    assert scene["outputs"]["v1"][0]["quantity"] == "velocity" and "quantity" not in scene["outputs"]["y1"][0]
    assert scene["bodies"]["v"]["damping"] == "v_D.petsc"
    # the MORwiki names: damping E, outputs Cp and Cv, and C as the damping beside Cp
    scipy.io.savemat(str(tmp_path / "e.mat"), dict(M=M, K=K, C=1e-5 * K, B=B, Cp=np.eye(n)[[n - 4]]))
    p = run(["convert", str(tmp_path / "e.mat"), "--name", "e", "-o", str(tmp_path / "e")])
    assert p.returncode == 0 and "damping matrix C" in p.stdout


@needs_cli
@pytest.mark.parametrize("case", ["first_order", "indefinite", "asymmetric", "ambiguous_c", "missing_key",
                                  "no_outputs", "wrong_b", "not_mat"])
def test_convert_mat_refusals(tmp_path, case):
    K, M = generate.beam()
    n = len(K)
    path = tmp_path / "x.mat"
    extra = []
    if case == "first_order":
        scipy.io.savemat(str(path), dict(A=-np.eye(3), B=np.ones((3, 1)), C=np.ones((1, 3))))
        want = "first-order model"
    elif case == "indefinite":
        lam, v = flexible_mode(K, M, 0)
        Mv = M @ v
        beam_mat(path, K=sp.csc_matrix(K - 2 * lam * np.outer(Mv, Mv)))
        want = "smallest eigenvalue is %.3e" % np.linalg.eigvalsh(K - 2 * lam * np.outer(Mv, Mv))[0]
    elif case == "asymmetric":
        K2 = K.copy()
        K2[2, 8] += 1e-3 * np.abs(K).max()
        beam_mat(path, K=sp.csc_matrix(K2))
        want = "not symmetric"
    elif case == "ambiguous_c":
        beam_mat(path, D=None, C=np.eye(n))
        want = "--damping-key C"
    elif case == "missing_key":
        beam_mat(path)
        extra = ["--damping-key", "Q"]
        want = "no key Q"
    elif case == "no_outputs":
        beam_mat(path, C=np.zeros((1, n)))
        want = "every output row is zero"
    elif case == "wrong_b":
        beam_mat(path, B=np.ones((n + 1, 1)))
        want = "input matrix B"
    else:
        path.write_text("not a MATLAB file")
        want = "not a MATLAB .mat file"
    p = run(["convert", str(path), "--name", "x", "-o", str(tmp_path / "out")] + extra)
    assert p.returncode == 2
    assert want in one_error(p), p.stderr
    assert not (tmp_path / "out").exists()


# ------------------------------------------------------------------ single structures on the command line

@pytest.fixture(scope="module")
def reduced(tmp_path_factory):
    """The example plate, the free beam with a damping matrix, and Galileo, reduced once (-quiet)."""
    out = tmp_path_factory.mktemp("reduced")
    for name, scene in (("plate", os.path.join(EXAMPLE, "plate.yaml")), ("beam", os.path.join(EXAMPLE, "beam_free.yaml")),
                        ("galileo", os.path.join(ROOT, "meshes", "galileo", "galileo.yaml"))):
        extra = ["-kf_moments", "6", "-scene.reduction.search", "false"] if name == "galileo" else []
        p = run(["reduce", scene, "-o", str(out / name), "-quiet"] + extra)
        assert p.returncode in (0, 6), p.stderr
    return out


@needs_cli
@pytest.mark.slow
def test_reassemble_angles(reduced):
    plate = str(reduced / "plate" / "reduced.h5")
    a, b = run(["reassemble", plate, "--json"]), run(["reassemble", plate, "--angle", "none", "--json"])
    assert a.returncode == b.returncode == 0 and json.loads(a.stdout) == [
        dict(r, seconds=json.loads(a.stdout)[0]["seconds"]) for r in json.loads(b.stdout)]
    assert json.loads(a.stdout)[0]["rigid_modes"] == 3
    p = run(["reassemble", plate, "--angle", "30"])
    assert p.returncode == 2 and "0 revolute joint(s)" in one_error(p)
    gal = str(reduced / "galileo" / "reduced.h5")
    p = run(["reassemble", gal])
    assert p.returncode == 2 and "1 revolute joint(s) (spin_bearing)" in one_error(p) and "--angle" in one_error(p)
    p = run(["reassemble", gal, "--angle", "none"])
    assert p.returncode == 2 and "give 1 angle(s)" in one_error(p)


@needs_cli
@pytest.mark.slow
@pytest.mark.mpi
def test_reassemble_and_export_on_two_ranks(reduced, tmp_path):
    """The same reassembled matrices and neutral file on 2 ranks as on 1."""
    for name in ("plate", "beam"):
        path = str(reduced / name / "reduced.h5")
        for n in (1, 2):
            assert run(["reassemble", path, "-o", str(tmp_path / ("%s%d.npz" % (name, n)))], ranks=n).returncode == 0
        a, b = np.load(tmp_path / ("%s1.npz" % name)), np.load(tmp_path / ("%s2.npz" % name))
        assert sorted(a.files) == sorted(b.files) and all(np.array_equal(a[k], b[k]) for k in a.files)
    beam = str(reduced / "beam" / "reduced.h5")
    for n in (1, 2):
        assert run(["export", beam, "-o", str(tmp_path / ("e%d.npz" % n))], ranks=n).returncode == 0
    a, b = np.load(tmp_path / "e1.npz"), np.load(tmp_path / "e2.npz")
    assert all(np.array_equal(a[k], b[k]) for k in a.files)
    plate = str(reduced / "plate" / "reduced.h5")     # no floating frame: the body as reduced, the system for Exudyn
    for n in (1, 2):
        p = run(["export", plate, "-o", str(tmp_path / ("p%d.npz" % n)), "--format", "exudyn", "--json"], ranks=n)
        assert p.returncode == 0, p.stderr
    a, b = np.load(tmp_path / "p1.npz"), np.load(tmp_path / "p2.npz")
    assert sorted(a.files) == sorted(b.files) and all(np.array_equal(a[k], b[k]) for k in a.files)


@needs_cli
@pytest.mark.slow
def test_export_single_structures(reduced, tmp_path):
    beam = str(reduced / "beam" / "reduced.h5")
    p = run(["export", beam, "-o", str(tmp_path / "b.npz"), "--format", "exudyn", "--json"])
    assert p.returncode == 0, p.stderr
    check = json.loads(p.stdout)["check"][0]
    assert check["angles_deg"] == [] and check["max_rel_diff"] <= 1e-6 and check["exudyn_zero"] == 6
    model = kryflex.ReducedModel.load(beam)
    z = np.load(tmp_path / "b.npz")
    C = model.bodies[0]["damping_matrix"]
    np.testing.assert_allclose(z["body0/C"], 0.5 * (C + C.T), atol=1e-14 * np.abs(C).max())
    assert z["body0/interface_names"].size == 0 and z["body0/iface"].shape == (0, C.shape[0])
    assert int(z["body0/floating"]) == 1 and z["body0/missing_rigid"].size == 0


@needs_cli
@pytest.mark.slow
def test_export_body_without_rigid_motions(reduced, tmp_path):
    """The (uz, rx, ry) plate: the neutral file holds its reduced M, K, G, H, C as the model has them (no floating-
    frame fields, the missing motions named) and its reassembled system; --format exudyn builds that system as one
    ObjectGenericODE2 whose linearized frequencies are the dense eigenvalues of the reduced (K, M) computed here."""
    from kryflex.export import read_neutral
    path = str(reduced / "plate" / "reduced.h5")
    model = kryflex.ReducedModel.load(path)
    p = run(["export", path, "-o", str(tmp_path / "p.npz")])
    assert p.returncode == 0, p.stderr
    assert "plate: %d reduced dofs, no floating frame (no rigid ux uy rz)" % model.bodies[0]["M"].shape[0] in p.stdout
    z = np.load(tmp_path / "p.npz")
    body = model.bodies[0]
    for key in ("M", "K", "G", "H"):
        A = body[key]
        np.testing.assert_allclose(z["body0/" + key], 0.5 * (A + A.T) if key in "MK" else A, rtol=0,
                                   atol=1e-15 * np.abs(A).max())
    assert int(z["body0/floating"]) == 0 and list(z["body0/missing_rigid"]) == ["ux", "uy", "rz"]
    assert "body0/rigid_coords" not in z.files and "body0/modes" not in z.files
    s = model.at([])
    assert int(z["nsystems"]) == 1 and z["system0/angles_deg"].size == 0
    for key in ("M", "K", "B", "C"):
        np.testing.assert_array_equal(z["system0/" + key], getattr(s, key))
    back = read_neutral(str(tmp_path / "p.npz"))
    assert not back.floating and back.bodies[0].missing_rigid == ("ux", "uy", "rz")
    np.testing.assert_array_equal(back.bodies[0].K, z["body0/K"])
    from kryflex.export import ExportError
    from kryflex.export.exudyn import build_mbs
    with pytest.raises(ExportError, match="body 'plate' cannot move rigidly along ux uy rz.*system_mbs"):
        build_mbs(back, [])                  # floating-frame bodies only: the system path is named
    # Exudyn: the reassembled system, its frequencies against a dense eigensolve of the file's system
    p = run(["export", path, "-o", str(tmp_path / "x.npz"), "--format", "exudyn", "--json"])
    assert p.returncode == 0, p.stderr
    check = json.loads(p.stdout)["check"][0]
    lam = sl.eigh(z["system0/K"], z["system0/M"], eigvals_only=True)
    top = np.abs(lam).max()
    dense = np.sqrt(lam[lam > 1e-10 * top]) / (2 * np.pi)
    assert check["exudyn_zero"] == 3 == int(np.sum(np.abs(lam) <= 1e-10 * top))
    np.testing.assert_allclose(check["exudyn_hz"], dense, rtol=1e-8)
    assert check["max_rel_diff"] <= 1e-6


def jointed_clamped_spec():
    """The grounded arm of bc_models with its post clamped at the base instead of its pivot: a scene with a revolute
    joint (the elbow) and a body without rigid motions."""
    from bc_models import grounded_arm
    spec = grounded_arm()
    spec["name"] = "clamped_arm"
    del spec["joints"]["pivot"]
    spec["bodies"]["post"]["constraints"] = [{"node": 1, "dofs": "123456"}]
    spec["angles"] = [0.0, 40.0]
    spec["accuracy"] = 0.05
    return spec


@pytest.mark.slow
@pytest.mark.mpi
def test_export_jointed_scene_with_a_clamped_body(tmp_path):
    """Neutral: the clamped post as reduced, the arm as a floating-frame body, the joint; Exudyn (floating-frame bodies
    and joints) refuses in one line naming the body, exit 5, nothing written."""
    from kryflex.export import from_model, read_neutral, write_neutral
    model = kryflex.Reducer(kryflex.scene_from_dict(jointed_clamped_spec(), quiet=True), quiet=True).reduce().model
    path = str(tmp_path / "m.h5")
    model.save(path)
    data = from_model(model)
    post, arm = data.bodies
    assert not post.floating and post.missing_rigid == ("ux", "uy", "uz", "rx", "ry", "rz") and arm.floating
    assert data.systems == []          # a jointed scene: no fixed-angle system added
    write_neutral(data, str(tmp_path / "n.npz"))
    back = read_neutral(str(tmp_path / "n.npz"))
    assert [b.floating for b in back.bodies] == [False, True] and back.revolute == ["elbow"]
    np.testing.assert_allclose(back.bodies[1].modes, arm.modes)
    if os.path.exists(KRYFLEX):
        for ranks in (1, 2):          # every rank exits 5, one error line
            p = run(["export", path, "-o", str(tmp_path / "x.npz"), "--format", "exudyn"], ranks=ranks)
            assert p.returncode == 5
            line = one_error(p)
            assert "body 'post' cannot move rigidly along ux uy uz rx ry rz" in line and "drop --format exudyn" in line
            assert not (tmp_path / "x.npz").exists()
        assert run(["export", path, "-o", str(tmp_path / "y.npz")]).returncode == 0


@needs_cli
@pytest.mark.slow
def test_reduce_texts_and_damping_defaults(reduced):
    plate = json.load(open(reduced / "plate" / "summary.json"))
    beam = json.load(open(reduced / "beam" / "summary.json"))
    assert plate["damping_model"]["modal"] == 0.01                # given
    assert beam["damping_model"]["modal"] == 0.0                  # a damping matrix, no damping key: nothing added
    assert beam["model_check"]["findings"] == []
    p = run(["info", os.path.join(EXAMPLE, "plate.yaml"), "-quiet"])
    assert "3 rigid-body and mechanism modes" in p.stdout and "fixed" not in p.stdout


def json_strings(value):
    """Every string of a JSON document, keys and values."""
    if isinstance(value, dict):
        return [t for k, v in value.items() for t in [k] + json_strings(v)]
    if isinstance(value, list):
        return [t for v in value for t in json_strings(v)]
    return [value] if isinstance(value, str) else []


NO_ANGLE = ("fixed", "alpha = ()", "α = ()", "α_G = (", "alpha_G =", "[[]]", "angle of interest", "angles of interest")


@needs_cli
@pytest.mark.slow
@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
def test_single_structure_is_never_an_angle(tmp_path, ranks):
    """A reduce of a scene without revolute joints speaks of the structure: no 'fixed deg', 'alpha = ()' nor a 'deg'
    of an angle that does not exist, in the progress and last lines, report.md, summary.json's texts and file names."""
    out = tmp_path / "plate"
    p = run(["reduce", os.path.join(EXAMPLE, "plate.yaml"), "-o", str(out), "-kf_reducer_view", "-kf_model_view"],
            ranks=ranks)
    assert p.returncode == 0, p.stderr
    assert "the structure (no revolute joint)" in p.stdout and "reference check of the structure:" in p.stdout
    assert "configuration: the structure" in p.stdout and "reduction configuration: the structure" in p.stdout
    assert "the single-angle model: max relative H-inf error" in p.stdout
    report = (out / "report.md").read_text(encoding="utf-8")
    summary = json.load(open(out / "summary.json"))
    # (the model view's settings dump 'reduction_angles_deg = [[]]' is a stored field, as in summary.json)
    texts = [line for line in (p.stdout + p.stderr).splitlines() if "timings" not in line and "_deg = " not in line]
    # report.md: "deg" stays legal as a phase unit of a plot axis only, which the markdown does not name
    texts += report.splitlines()
    texts += [t for t in json_strings(summary) if not t.endswith("_deg")]   # key names such as angles_deg are fields
    texts += os.listdir(out)
    for bad in NO_ANGLE:
        hits = [t for t in texts if bad in t]
        assert not hits, (bad, hits[:3])
    # "degrees of freedom" is no angle, nor the phase plots' "within 180°"
    hits = [t for t in texts if re.search(r"\bdeg\b|\ddeg|(?<!180)°", t)]
    assert not hits, hits[:3]
    assert summary["angle_labels"] == ["structure"] and summary["angles_deg"] == [[]]
    assert {"bode_structure.png", "importance_structure.png"} <= set(os.listdir(out))
    assert "Configurations: the structure." in report
    # no reduction configuration to choose: the report's headings, captions and tables name the structure
    assert "α_G" not in report and "at every angle" not in report, \
        re.findall(r".{40}(?:α_G|at every angle).{20}", report)
    assert re.search(r"^## (\d+\. )?The reduction configuration$", report, re.M)
    assert "Table 4b. System natural frequencies of the structure" in report


@needs_cli
@pytest.mark.slow
def test_jointed_scene_keeps_its_angle_texts(reduced):
    """With a revolute joint the texts are today's: angles in degrees, alpha_G, file names per angle."""
    out = reduced / "galileo"
    summary = json.load(open(out / "summary.json"))
    labels = summary["angle_labels"]
    assert "structure" not in labels
    assert summary["reduction_rule"].startswith("alpha_G = %s deg" % summary["reduction_label"])
    names = os.listdir(out)
    assert all(("importance_%sdeg.png" % label) in names for label in labels)
    assert all(("bode_%sdeg.png" % label) in names for label in labels)
    report = (out / "report.md").read_text(encoding="utf-8")
    assert "Configurations: α = " in report and "The reduction basis is built at α_G: α = " in report


def test_damping_zero_and_defaults():
    from kryflex.io.scene_schema import damping_spec
    assert damping_spec("s", 0)[1]["modal"] == 0.0 and damping_spec("s", 0)[0] is None
    assert damping_spec("s", 0.02) == (0.02, {"modal": 0.02, "rayleigh": {"alpha": 0.0, "beta": 0.0},
                                              "structural": 0.0})
    K, M, nodes = generate.plate()
    s = kryflex.scene_from_dict(plate_spec(), quiet=True)
    assert s.damping == 0.0025                      # no matrix, no key: the default modal ratio
    spec = plate_spec()
    spec["bodies"]["plate"]["damping"] = 1e-5 * K
    s = kryflex.scene_from_dict(spec, quiet=True)
    assert s.damping_model["modal"] == 0.0


@pytest.mark.slow
def test_model_file_damping_round_off(reduced, tmp_path):
    """A reduced C = Psi^T (beta K) Psi has round-off on its rigid coordinates' diagonal: a model file with -1e-14 of
    the largest entry there loads; one with a real negative entry (-1e-3 of it) is refused, naming the dataset."""
    import shutil

    import h5py
    for value, ok in ((-1e-14, True), (-1e-3, False)):
        path = str(tmp_path / ("m%g.h5" % value))
        shutil.copy(reduced / "beam" / "reduced.h5", path)
        with h5py.File(path, "r+") as h5:
            C = h5["bodies/beam/C"]
            top = np.abs(C[...]).max()
            C[0, 0] = value * top
        if ok:
            assert kryflex.ReducedModel.load(path).bodies[0]["damping_matrix"][0, 0] < 0
        else:
            with pytest.raises(kryflex.ModelFileError, match="dataset 'C' is not a damping matrix"):
                kryflex.ReducedModel.load(path)
