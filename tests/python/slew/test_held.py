"""`kryflex slew` on a structure without revolute joints (python/kryflex/slew, profiles step and pulse): the
full-order and the reduced time responses to a force history at rest against an independent modal solution (SciPy
eigh of the matrices read from the example's files, the flexible modes' state space integrated by scipy.signal.lsim),
on the free plate (uz, rx, ry nodes), the free beam (6-dof nodes), the plate clamped at one node and the plate with a
velocity output; the error
measure against the one of the independent solutions; the command's files and refusals."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.io as sio
import scipy.linalg as sl
import scipy.signal as ss

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
KRYFLEX = run_env.KRYFLEX
EXAMPLES = os.path.join(ROOT, "examples", "single_structure")
ENV = dict(run_env.ENV, MPLBACKEND="Agg")
PNG = b"\x89PNG\r\n\x1a\n"
DOFS = {"ux": 0, "uy": 1, "uz": 2, "rx": 3, "ry": 4, "rz": 5}


def _plate_variant(tmp_path, name):
    """plate.yaml with its commented clamp of node 1 switched on (the output on node 1 moved to node 2), or with its
    second output reading a velocity."""
    text = open(os.path.join(EXAMPLES, "plate.yaml")).read().replace("name: plate", "name: " + name)
    if name == "plate_clamped":
        text = text.replace("    # constraints:", "    constraints:")
        text = text.replace("{body: plate, node: 1, dof: uz}", "{body: plate, node: 2, dof: uz}")
    else:
        text = text.replace("{body: plate, node: 19, dof: ry}", "{body: plate, node: 19, dof: ry, quantity: velocity}")
    for f in ("plate_M.mtx", "plate_K.mtx", "plate_nodes.txt"):
        if not os.path.exists(tmp_path / f):
            os.symlink(os.path.join(EXAMPLES, f), tmp_path / f)
    path = tmp_path / (name + ".yaml")
    path.write_text(text)
    return str(path)


def _dense_model(scene_path):
    """M, K, G, H and the rigid-mode count of a one-body example read independently of kryflex: the Matrix Market
    files, the node table's layout (c345: uz rx ry; 6: all six), the scene's loads and readings, its clamps."""
    import yaml
    spec = yaml.safe_load(open(scene_path))
    base = os.path.dirname(scene_path)
    (body,) = spec["bodies"].values()
    M = sio.mmread(os.path.join(base, body["mass"])).toarray()
    K = sio.mmread(os.path.join(base, body["stiffness"])).toarray()
    where, first = {}, 0
    for line in open(os.path.join(base, body["nodes"])):
        if line.startswith("#") or not line.strip():
            continue
        nid, layout = int(line.split()[0]), line.split()[4]
        comps = [int(c) - 1 for c in layout[1:]] if layout.startswith("c") else list(range(int(layout)))
        for k, c in enumerate(comps):
            where[nid, c] = first + k
        first += len(comps)
    G = np.zeros((first, len(spec["inputs"])))
    for j, terms in enumerate(spec["inputs"].values()):
        for t in terms:
            G[where[t["node"], DOFS[t["dof"]]], j] += 1.0
    H = np.zeros((len(spec["outputs"]), first))
    velocity = np.zeros(len(spec["outputs"]), bool)
    for i, terms in enumerate(spec["outputs"].values()):
        for t in terms:
            H[i, where[t["node"], DOFS[t["dof"]]]] += 1.0
            velocity[i] = t.get("quantity") == "velocity"
    held = sorted(where[c["node"], int(d) - 1] for c in body.get("constraints", []) for d in c["dofs"]
                  if (c["node"], int(d) - 1) in where)
    keep = np.setdiff1d(np.arange(first), held)
    nrigid = 0 if held else (3 if len(where) < 6 * len(set(n for n, _ in where)) else 6)
    return M[np.ix_(keep, keep)], K[np.ix_(keep, keep)], G[keep], H[:, keep], nrigid, velocity


def _mode_damping(model):
    """The viscous coefficient of each flexible mode, c(w^2) = 2 zeta w + alpha + beta w^2, under the scene's damping
    model (a modal ratio and Rayleigh), which a held structure's time response takes as the frequency domain does."""
    zeta = float(model.get("modal") or 0.0)
    ray = model.get("rayleigh") or {}
    a, b = float(ray.get("alpha", 0.0)), float(ray.get("beta", 0.0))
    return lambda lam: 2 * zeta * np.sqrt(lam) + a + b * lam


def _modal_elastic(M, K, G, H, nrigid, damping, u, t, velocity):
    """The elastic outputs H Phi_f q_f(t) (H Phi_f q_f'(t) for the velocity rows) of M z'' + C z' + K z = G u(t)
    from rest, C damping each flexible mode by its own coefficient: the modes' state space (each mode
    q'' + c(w^2) q' + w^2 q = phi^T G u) by scipy.signal.lsim, exact for the piecewise-linear input on the fine grid t."""
    lam, Phi = sl.eigh(K, M)
    lam, Phi = lam[nrigid:], Phi[:, nrigid:]
    n = len(lam)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(lam), -np.diag(damping(lam))]])
    B = np.vstack([np.zeros((n, G.shape[1])), Phi.T @ G]).sum(axis=1, keepdims=True)
    C = np.hstack([H @ Phi, np.zeros((H.shape[0], n))])
    C[velocity] = np.roll(C[velocity], n, axis=1)
    _, y, _ = ss.lsim((A, B, C, np.zeros((H.shape[0], 1))), u, t, interp=True)
    return y.reshape(len(t), -1)


@pytest.fixture(scope="module")
def studies(quiet_library, tmp_path_factory):
    import kryflex
    from kryflex.slew.study import SlewStudy
    out = {}
    for name, path in (("plate", os.path.join(EXAMPLES, "plate.yaml")),
                       ("beam_free", os.path.join(EXAMPLES, "beam_free.yaml")),
                       ("plate_clamped", _plate_variant(tmp_path_factory.mktemp("clamped"), "plate_clamped")),
                       ("plate_velocity", _plate_variant(tmp_path_factory.mktemp("velocity"), "plate_velocity"))):
        scene = kryflex.load_scene(path)
        model = kryflex.Reducer(scene, quiet=True).reduce().model
        out[name] = path, SlewStudy(scene, model, steps_per_period=200, settle_periods=2.0)
    return out


@pytest.mark.parametrize("name", ["plate", "beam_free", "plate_clamped", "plate_velocity"])
@pytest.mark.parametrize("kind, periods", [("step", 1.0), ("pulse", 0.5)])
def test_held_response_matches_modal_solution(studies, name, kind, periods):
    """Both models' elastic output histories against the modal solution of their own matrices, and the error the
    study reports against the same measure of the two modal solutions."""
    path, study = studies[name]
    study.kind, study.held = kind, True
    row = study.run(periods)
    t = row["full"][0]
    fine = np.linspace(0, t[-1], 40 * len(t) + 1)
    u = study.profile(row["duration_s"]).torque(fine)
    M, K, G, H, nrigid, velocity = _dense_model(path)
    assert study.full.dofs == M.shape[0] and velocity.any() == (name == "plate_velocity")
    damping = _mode_damping(study.damping_model)
    ref_full = _modal_elastic(M, K, G, H, nrigid, damping, u, fine, velocity)
    b = study.model.bodies[0]
    ref_red = _modal_elastic(b["M"], b["K"], b["G"], b["H"], nrigid, damping, u, fine, velocity)
    for ref, run in ((ref_full, row["full"]), (ref_red, row["reduced"])):
        at_t = np.stack([np.interp(t, fine, ref[:, o]) for o in range(ref.shape[1])], axis=1)
        scale = np.abs(at_t).max(axis=0)
        assert np.all(scale > 0)
        # Newmark's period error at h = 1/(200 f_top): measured up to 2.5e-3 of the peak on displacements and 5.5e-3
        # on the velocity (which weighs the higher modes by their frequency). Modal damping leaves the modes above the
        # band at the scene's ratio (stiffness-proportional damping took them out), so a short pulse keeps them
        # ringing and their period error shows in the history
        tol = np.where(velocity, 8e-3, 4e-3)
        assert np.all(np.abs(run[2] - at_t).max(axis=0) < tol * scale), (name, kind)
    err_ref = (np.abs(ref_full - ref_red).max(axis=0) / np.abs(ref_full).max(axis=0)).max()
    assert abs(row["elastic_error"] - err_ref) < 0.05 * err_ref + 1e-5, (row["elastic_error"], err_ref)


def test_held_error_small_when_slow_and_growing_when_fast(studies):
    """The reduced plate's error against the input's duration: below the scene's accuracy for an input of many
    first periods, above it for one far shorter than the band's top period."""
    _, study = studies["plate"]
    study.kind, study.held = "step", True
    slow, fast = study.run(10.0), study.run(0.05)
    assert slow["error"] < study.accuracy < fast["error"]
    assert slow["peak_rate_deg_s"] == 0.0 and study.baseline() is None


@pytest.mark.fast
def test_held_profiles():
    from kryflex.slew.profiles import Profile
    t = np.linspace(0, 3, 30001)
    step, pulse = Profile("step", 2.0, [], [], 5.0), Profile("pulse", 2.0, [], [], 5.0)
    assert step.torque(0.0) == 0.0 and np.isclose(step.torque(2.0), 5.0) and np.all(step.torque(t[t > 2]) == 5.0)
    assert np.all(np.diff(step.torque(t)) >= -1e-15)
    assert np.isclose(pulse.torque(t).max(), 5.0) and pulse.torque(0.0) == 0.0 and np.all(pulse.torque(t[t > 2]) == 0)
    assert step.angles(t).shape == (len(t), 0) and step.peak_rate == 0.0
    held = Profile("step", 1.0, [0.7], [0.2])
    assert np.all(held.angles(t) == 0.2)


pytestmark_cli = pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built")


@pytestmark_cli
def test_command_on_single_structure(tmp_path):
    out = tmp_path / "slew"
    proc = subprocess.run([KRYFLEX, "slew", os.path.join(EXAMPLES, "plate.yaml"), "-o", str(out), "--rates", "3",
                           "--periods-min", "0.5", "--force", "2", "-quiet"], env=ENV, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    for name in ("slew.png", "slew_histories.png"):
        assert (out / name).read_bytes()[:8] == PNG
    data = json.loads((out / "slew.json").read_text())
    assert data["profile"] == "step" and data["held"] and data["force"] == 2.0 and data["angles_deg"] is None
    assert len(data["rows"]) == 3 and data["rows"][0]["periods"] > data["rows"][-1]["periods"]
    assert all(r["error"] >= r["elastic_error"] > 0 for r in data["rows"])
    md = (out / "slew.md").read_text()
    assert "# Time response at rest: plate" in md and "| input duration T (s) |" in md and " deg" not in md
    csv_head = (out / "slew.csv").read_text().splitlines()[0]
    assert csv_head.startswith("duration_s,periods") and "error_corner_uz" in csv_head
    assert "the structure's step response" in proc.stdout and "Traceback" not in proc.stderr


@pytestmark_cli
@pytest.mark.parametrize("args, message", [
    (["--profile", "slew"], "has no revolute joint: there is no angle to slew with --profile slew; use --profile step"),
    (["--profile", "pulse", "--amplitude", "30"], "give the input history's peak with --force"),
    (["--force", "0"], "--force must be a finite, non-zero number"),
    (["--exudyn-ffrf"], "--exudyn-ffrf slews the reduced bodies"),
])
def test_command_refuses_on_single_structure(tmp_path, args, message):
    out = tmp_path / "o"
    proc = subprocess.run([KRYFLEX, "slew", os.path.join(EXAMPLES, "plate.yaml"), "-o", str(out), "-quiet"] + args,
                          env=ENV, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr
    assert not out.exists() or not any(p.name.startswith("slew") for p in out.iterdir())


@pytest.mark.mpi
@pytestmark_cli
def test_command_on_single_structure_refuses_several_ranks(tmp_path):
    proc = subprocess.run(["mpiexec", "-n", "2", KRYFLEX, "slew", os.path.join(EXAMPLES, "plate.yaml"), "-o",
                           str(tmp_path / "o"), "-quiet"], env=ENV, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "one rank" in proc.stderr and "Traceback" not in proc.stderr
