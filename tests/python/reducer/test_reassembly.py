"""Reassembly of reduced bodies at any angle (paper eq. 20-24) and the reduced-model file it works from.

Three scenes, each reduced once per module: the Galileo-like model (one revolute joint), a random 3-body frame
scene with two skew revolute joints, and one with a revolute and a fixed joint (random R0). Reassembly is
checked against a NumPy reassembly built here from the stored reduced bodies (constraint matrix D of eq. 20,
its null space by SVD, eq. 21-24), at angles of interest and at angles the reduction never saw.
"""
import copy
import json
import os
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest
import scipy.linalg as sl
import yaml
from petsc4py import PETSc

import kryflex
from kryflex import _core

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
KRYFLEX_CMD = os.path.join(ROOT, "build", "kryflex")
sys.path.insert(0, SUPPORT)
sys.path.insert(0, os.path.join(ROOT, "meshes"))
import frames  # noqa: E402
import reference as ref  # noqa: E402
from conftest import reassembled  # noqa: E402

SAME = 1e-12          # file round trip: the same model
BODY_ARRAYS = ("M", "K", "G", "H", "iface", "rigid")


class Case:
    def __init__(self, name, path, extra_angles):
        self.name, self.path = name, path
        with open(path) as f:
            self.spec = yaml.safe_load(f)
        self.scene = kryflex.load_scene(path)
        self.result = kryflex.reduce(self.scene, quiet=True)
        self.model = self.result.model
        self.nrev = len(self.scene.revolute)
        self.nfixed = sum(1 for j in self.scene.joints if j["type"] == "fixed")
        self.nrigid = 6 + self.nrev
        # angles of interest and angles the reduction never saw
        self.angles = [list(c) for c in self.scene.configurations] + extra_angles
        assert not any(a in self.scene.configurations for a in extra_angles)


pytestmark = pytest.mark.usefixtures("quiet_library")   # tests/python/conftest.py


@pytest.fixture(scope="module")
def galileo():
    return Case("galileo", GALILEO, [[7.5], [100.0], [-45.0], [200.0], [359.0]])


@pytest.fixture(scope="module")
def frames_rev(tmp_path_factory):
    path = frames.write_random_scene(str(tmp_path_factory.mktemp("frames_rev")), 240, nbodies=3, ninputs=3,
                                     noutputs=2, seed=1)
    return Case("frames_revolute", path, [[10.0, 250.0], [-30.0, 95.0], [333.0, 17.0]])


@pytest.fixture(scope="module")
def frames_fixed(tmp_path_factory):
    path = frames.write_random_scene(str(tmp_path_factory.mktemp("frames_fixed")), 240, nbodies=3, ninputs=3,
                                     noutputs=2, seed=2, fixed_joint=True)
    return Case("frames_fixed", path, [[22.0], [181.0], [-100.0]])


@pytest.fixture(scope="module", params=["galileo", "frames_rev", "frames_fixed"])
def case(request):
    return request.getfixturevalue(request.param)


# ================================================================================================ helpers

def generalized_eigenvalues(K, M):
    return sl.eigh(K, M, eigvals_only=True)


def transfer(M, K, G, H, w):
    """Undamped H (K - w^2 M)^-1 G at one frequency (rad/s): basis-independent."""
    return H @ np.linalg.solve(K - w ** 2 * M, G)


def numpy_constraints(model, angles_deg):
    """D of eq. (20) on the stacked reduced coordinates, from the stored interface rows of each body."""
    sizes = model.sizes
    off = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
    rows, irev = [], 0
    for j in model.joints:
        p, c = j["parent"], j["child"]
        Ip = model.bodies[p]["iface"][6 * j["parent_interface"]:6 * j["parent_interface"] + 6]
        Ic = model.bodies[c]["iface"][6 * j["child_interface"]:6 * j["child_interface"] + 6]
        if j["type"] == "revolute":
            axis = np.asarray(j["axis"], float) / np.linalg.norm(j["axis"])
            R = ref.rotation(axis, np.radians(angles_deg[irev]), j.get("R0"))
            irev += 1
            across = sl.null_space(axis[None, :]).T
        else:
            R = np.eye(3) if j.get("R0") is None else np.asarray(j["R0"], float)
            across = np.eye(3)
        for proj, k in ((np.eye(3), 0), (across, 3)):
            block = np.zeros((len(proj), off[-1]))
            block[:, off[p]:off[p + 1]] = proj @ Ip[k:k + 3]
            block[:, off[c]:off[c + 1]] = -proj @ R @ Ic[k:k + 3]
            rows.append(block)
    if model.ties is not None:      # a model compressed or reduced tied: its coordinate ties appended to the joints'
        rows.append(model.ties)
    return np.vstack(rows), off


def numpy_reassemble(model, angles_deg, rtol):
    """(Mh, Kh, Gh, Hh, rank, sigma ratio) by SVD of D, the reduced bodies projected on its null space."""
    D, off = numpy_constraints(model, angles_deg)
    _, s, vt = np.linalg.svd(D)
    rank = int(np.sum(s > rtol * s[0]))
    N = vt[rank:].T
    M = sl.block_diag(*[b["M"] for b in model.bodies])
    K = sl.block_diag(*[b["K"] for b in model.bodies])
    G = np.vstack([b["G"] for b in model.bodies])
    H = np.hstack([b["H"] for b in model.bodies])
    return N.T @ M @ N, N.T @ K @ N, N.T @ G, H @ N, rank, s[rank - 1] / s[0]


# ================================================================================================ file round trip

def test_reassembly_from_file_equals_in_memory(case, tmp_path):
    path = case.model.save(str(tmp_path / "reduced.h5"))
    loaded = kryflex.ReducedModel.load(path)
    loaded.check_scene(case.scene)
    assert loaded.body_names == case.model.body_names and loaded.revolute == case.model.revolute
    for a, b in zip(loaded.bodies, case.model.bodies):
        for key in BODY_ARRAYS:
            np.testing.assert_array_equal(a[key], b[key])
    nmom = int(case.scene.reduction["moments"])
    for angles in case.angles:
        mem, disk = reassembled(case.model, angles), reassembled(loaded, angles)
        for x, y in zip(mem[:4], disk[:4]):
            assert x.shape == y.shape and np.abs(x - y).max() <= SAME * max(np.abs(x).max(), 1e-300)
        assert mem[4] == disk[4] and mem[6].shape == disk[6].shape
        lam_m = generalized_eigenvalues(mem[1], mem[0])
        lam_d = generalized_eigenvalues(disk[1], disk[0])
        assert np.abs(lam_m - lam_d).max() <= SAME * lam_m.max()
        Lm, Ld = case.model.at(angles).moments(nmom), loaded.at(angles).moments(nmom)
        scale = np.abs(Lm).reshape(nmom, -1).max(axis=1)[:, None, None]
        assert np.all(np.abs(Lm - Ld) <= SAME * scale), angles


def test_command_reassembles_from_the_file_alone(case, tmp_path):
    """'kryflex reassemble' sees the reduced-model file and nothing else; its matrices equal the in-memory ones."""
    path = case.model.save(str(tmp_path / "reduced.h5"))
    angles = [a for a in case.angles if a[0] >= 0][-2:]     # negative first angles: see test_command_takes_a_negative_first_angle
    assert any(a not in case.scene.configurations for a in angles)
    out = str(tmp_path / "reassembled.npz")
    cmd = [KRYFLEX_CMD, "reassemble", path, "-o", out, "--json", "-quiet"]
    for a in angles:
        cmd += ["--angle", ",".join("%g" % x for x in a)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, cwd=str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    results = json.loads(proc.stdout)
    with np.load(out) as z:
        for a, r in zip(angles, results):
            key = "_".join("%g" % x for x in a)
            mem = reassembled(case.model, a)
            for name, x in zip("MKGH", mem[:4]):
                np.testing.assert_allclose(z["%s_%s" % (name, key)], x, rtol=0, atol=SAME * np.abs(x).max())
            assert r["dofs"] == mem[0].shape[0] and r["constraint_rank"] == mem[4]
            assert r["rigid_modes"] == case.nrigid


@pytest.mark.parametrize("spelling", [["--angle", "-30,95"], ["--angle=-30,95"]])
def test_command_takes_a_negative_first_angle(frames_rev, tmp_path, spelling):
    path = frames_rev.model.save(str(tmp_path / "reduced.h5"))
    proc = subprocess.run([KRYFLEX_CMD, "reassemble", path, "--json", "-quiet"] + spelling, capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)[0]["angles_deg"] == [-30.0, 95.0]


# ================================================================================================ rigid modes

def test_exactly_the_rigid_and_mechanism_modes(case):
    rng = np.random.default_rng(7)
    angles = case.angles + [list(rng.uniform(-360, 360, case.nrev)) for _ in range(4)]
    for a in angles:
        Mh, Kh, _, _, _, _, Phir = reassembled(case.model, a)
        assert Phir is not None and Phir.shape == (Mh.shape[0], case.nrigid), a
        s = np.linalg.svd(Phir, compute_uv=False)
        assert s[-1] >= 1e-6 * s[0], "the rigid modes are not independent at %s deg" % a
        assert np.linalg.norm(Kh @ Phir) <= 1e-12 * np.linalg.norm(Kh) * np.linalg.norm(Phir)
        lam = generalized_eigenvalues(Kh, Mh)
        top = lam.max()
        zero = np.abs(lam) <= 1e-10 * top   # 3e-12 on Galileo fitted to the paper (a dense modal K); gap below
        assert zero.sum() == case.nrigid and np.all(zero[:case.nrigid]), (a, lam[:case.nrigid + 1] / top)
        assert lam[case.nrigid] >= 1e6 * np.abs(lam[:case.nrigid]).max()


# ================================================================================================ constraints

def test_constraint_rank_and_numpy_reassembly(case):
    """Rank = 5 per revolute + 6 per fixed joint (+ the model's coordinate ties); the sigma ratio and the
    reassembled system agree with NumPy."""
    rtol = case.model.settings["reassembly_rtol"]
    expected_rank = 5 * case.nrev + 6 * case.nfixed
    assert expected_rank == 5 * sum(j["type"] == "revolute" for j in case.spec["joints"].values()) \
        + 6 * sum(j["type"] == "fixed" for j in case.spec["joints"].values())
    expected_rank += 0 if case.model.ties is None else case.model.ties.shape[0]
    n = sum(case.model.sizes)
    for a in case.angles:
        Mh, Kh, Gh, Hh, rank, ratio, _ = reassembled(case.model, a)
        assert rank == expected_rank and Mh.shape[0] == n - rank, a
        Mn, Kn, Gn, Hn, rank_n, ratio_n = numpy_reassemble(case.model, a, rtol)
        assert rank_n == rank
        assert ratio == pytest.approx(ratio_n, rel=1e-10)
        # sensible: far above the rank cut, and at most 1
        assert 1e3 * rtol < ratio <= 1.0
        lam, lam_n = generalized_eigenvalues(Kh, Mh), generalized_eigenvalues(Kn, Mn)
        flex = slice(case.nrigid, None)
        np.testing.assert_allclose(lam[flex], lam_n[flex], rtol=1e-7)
        # G and H: the transfer function below the first flexible mode, which does not depend on the basis of
        # the null space. Solving with K - w^2 M loses cond(K - w^2 M) * eps (Galileo: 5e8 * 2e-16) in double,
        # whichever the basis, relative to ||H|| ||(K - w^2 M)^-1 G||: T = H x may cancel below that (Galileo at
        # 60 deg: |T| 3.7e-6 and T - Tn 4.4e-15, beyond 1e3 eps cond |T| once the reduced bodies were another
        # rotation of the same bases; measured: 3 eps cond |H| |x| at most); a wrong map would be off by O(1).
        w = 0.5 * np.sqrt(lam[case.nrigid])
        T, Tn = transfer(Mh, Kh, Gh, Hh, w), transfer(Mn, Kn, Gn, Hn, w)
        cond = np.linalg.cond(Kn - w ** 2 * Mn)
        scale = np.linalg.norm(Hn, 2) * np.linalg.norm(np.linalg.solve(Kn - w ** 2 * Mn, Gn), 2)
        assert np.linalg.norm(T - Tn) <= 1e3 * np.finfo(float).eps * cond * scale, a
        # and far below what a wrong map gives (O(1)); the rounding itself is bounded just above: Galileo's elastic-
        # measure model at 60 deg (kHz static-correction modes beside a 0.11 Hz mode) measured 2.3e-6 of |T|
        assert np.linalg.norm(T - Tn) <= 1e-4 * np.linalg.norm(Tn), a
    print("%s: constraint rank %d, sigma ratio %.3g" % (case.name, rank, ratio))


def test_reassembly_time_per_call(case):
    a = case.angles[-1]
    first = reassembled(case.model, a)
    calls = 20
    t0 = time.perf_counter()
    for _ in range(calls):
        again = reassembled(case.model, a)
    dt = (time.perf_counter() - t0) / calls
    print("%s: reassembly of %s reduced dofs in %.3g ms per call" % (case.name, " + ".join(map(str, case.model.sizes)),
                                                                   1e3 * dt))
    for x, y in zip(first[:4], again[:4]):     # deterministic
        np.testing.assert_array_equal(x, y)


# ================================================================================================ bad arguments

def bad_reassemble_calls(model):
    """(what, bodies, joints, angles_rad, ninputs, noutputs, rtol, message regex) - each must raise, not crash."""
    B, J = model.bodies, model.joints
    a, t = len(model.input_names), len(model.output_names)
    good = np.radians([30.0] * len(model.revolute))

    def body(i, **change):
        out = [dict(b) for b in B]
        out[i].update(change)
        return out

    def joint(i, **change):
        out = copy.deepcopy(J)
        out[i].update(change)
        return out

    v1 = B[1]["M"].shape[0]
    return [
        ("M not square", body(0, M=B[0]["M"][:-1]), J, good, a, t, 1e-9, "body 0 has inconsistent array sizes"),
        ("K one-dimensional", body(1, K=np.zeros(5)), J, good, a, t, 1e-9, "K must have 2 dimension"),
        ("G with a wrong column count", body(1, G=np.zeros((v1, a + 1))), J, good, a, t, 1e-9, "inconsistent"),
        ("H with a wrong row count", body(1, H=np.zeros((t + 1, v1))), J, good, a, t, 1e-9, "inconsistent"),
        ("iface rows not 6 per interface", body(1, iface=B[1]["iface"][:5]), J, good, a, t, 1e-9, "inconsistent"),
        ("rigid not v x 6", body(1, rigid=B[1]["rigid"][:, :5]), J, good, a, t, 1e-9, "rigid must be"),
        ("non-finite K", body(1, K=np.where(np.eye(v1) > 0, np.nan, B[1]["K"])), J, good, a, t, 1e-9, "non-finite"),
        ("ninputs mismatch", B, J, good, a + 1, t, 1e-9, "inconsistent"),
        ("noutputs mismatch", B, J, good, a, t + 1, 1e-9, "inconsistent"),
        ("unknown joint type", B, joint(0, type="prismatic"), good, a, t, 1e-9, "prismatic"),
        ("missing child interface", B, joint(0, child_interface=B[J[0]["child"]]["iface"].shape[0] // 6), good, a, t,
         1e-9, "interface"),
        ("negative parent interface", B, joint(0, parent_interface=-1), good, a, t, 1e-9, "interface"),
        ("unknown child body", B, joint(0, child=len(B)), good, a, t, 1e-9, "does not exist"),
        ("joint to itself", B, joint(0, child=J[0]["parent"]), good, a, t, 1e-9, "itself"),
        ("zero axis", B, joint(0, axis=[0.0, 0.0, 0.0]), good, a, t, 1e-9, "axis"),
        ("R0 not a rotation", B, joint(0, R0=np.zeros((3, 3)).tolist()), good, a, t, 1e-9, "R0 is not a rotation"),
        ("no angle", B, J, [], a, t, 1e-9, "need %d angle" % len(model.revolute)),
        ("one angle too many", B, J, np.append(good, 0.1), a, t, 1e-9, "need %d angle" % len(model.revolute)),
        ("NaN angle", B, J, np.full(len(good), np.nan), a, t, 1e-9, ""),
        ("negative rank tolerance", B, J, good, a, t, -1.0, "tolerance"),
        ("no bodies", [], [], [], a, t, 1e-9, "no reduced bodies"),
        # these raise, but not with a message that names the problem (IndexError from NumPy, LAPACK's SVD failure)
        ("axis of 2 components", B, joint(0, axis=[0.0, 1.0]), good, a, t, 1e-9, ""),
        ("R0 of 2 x 2", B, joint(0, R0=np.eye(2).tolist()), good, a, t, 1e-9, ""),
    ]


def test_reassemble_rejects_bad_arguments(galileo, frames_fixed):
    for case in (galileo, frames_fixed):
        for what, bodies, joints, angles, a, t, rtol, message in bad_reassemble_calls(case.model):
            with pytest.raises((ValueError, IndexError, kryflex.Error), match=message) as info:
                _core.reassemble(bodies, joints, angles, a, t, rtol)
            assert str(info.value), what
    # a ReducedModel names its joints when given the wrong number of angles
    with pytest.raises(ValueError, match="spin_bearing"):
        reassembled(galileo.model, [10.0, 20.0])


# ================================================================================================ the file

def test_h5_layout(galileo, frames_fixed, tmp_path):
    for case in (galileo, frames_fixed):
        path = case.model.save(str(tmp_path / ("%s.h5" % case.name)))
        spec = case.spec
        names = list(spec["bodies"])
        with h5py.File(path, "r") as f:
            assert f.attrs["format"] == "kryflex-reduced-model"
            assert int(f.attrs["version"]) >= 1
            assert f.attrs["scene"] == case.scene.name
            assert sorted(f["bodies"]) == sorted(names)
            a, t = len(spec["inputs"]), len(spec["outputs"])
            for i, name in enumerate(names):
                g = f["bodies"][name]
                assert int(g.attrs["index"]) == i
                assert int(g.attrs["full_dofs"]) == case.scene.body_dofs[i]
                v = g["M"].shape[0]
                nif = len(spec["bodies"][name].get("interfaces") or {})
                shapes = {"M": (v, v), "K": (v, v), "G": (v, a), "H": (t, v), "iface": (6 * nif, v), "rigid": (v, 6)}
                for key, shape in shapes.items():
                    assert g[key].shape == shape, (name, key)
                    np.testing.assert_array_equal(g[key][...], case.model.bodies[i][key])
            assert sorted(f["joints"]) == sorted(spec["joints"])
            for jname, j in spec["joints"].items():
                g = f["joints"][jname]
                assert g.attrs["type"] == j["type"]
                assert int(g.attrs["parent"]) == names.index(j["parent"])
                assert int(g.attrs["child"]) == names.index(j["child"])
                assert int(g.attrs["parent_interface"]) == list(spec["bodies"][j["parent"]]["interfaces"]).index(
                    j["parent_interface"])
                assert int(g.attrs["child_interface"]) == list(spec["bodies"][j["child"]]["interfaces"]).index(
                    j["child_interface"])
                if j["type"] == "revolute":
                    np.testing.assert_allclose(g.attrs["axis"], j["axis"], rtol=1e-15)
                np.testing.assert_allclose(g.attrs["orientation"], j.get("orientation", np.eye(3)), rtol=1e-15)
            decode = lambda arr: [s.decode() if isinstance(s, bytes) else s for s in arr]   # noqa: E731
            assert decode(f["inputs"][...]) == list(spec["inputs"])
            assert decode(f["outputs"][...]) == list(spec["outputs"])


def test_model_from_another_scene_is_refused(galileo, frames_rev, tmp_path):
    path = frames_rev.model.save(str(tmp_path / "frames.h5"))
    other = kryflex.ReducedModel.load(path)
    with pytest.raises(kryflex.ModelFileError, match="galileo"):
        other.check_scene(galileo.scene)
    # its own scene is accepted, and so is the Galileo model with the Galileo scene
    other.check_scene(frames_rev.scene)
    galileo.model.check_scene(galileo.scene)
    # a Galileo scene with another output is another scene
    spec = copy.deepcopy(galileo.spec)
    spec["outputs"] = {"pointA_rx": [{"body": "stator", "node": 2, "dof": "rx"}]}
    changed = kryflex.scene_from_dict(spec, base=os.path.dirname(GALILEO))
    with pytest.raises(kryflex.ModelFileError):
        galileo.model.check_scene(changed)
    # the command refuses it too, with its exit code for unusable model files
    proc = subprocess.run([KRYFLEX_CMD, "reassemble", path, "--angle", "10,20", "--scene", GALILEO, "-quiet"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 5 and "galileo" in proc.stderr, (proc.returncode, proc.stderr)


@pytest.fixture(scope="module")
def saved_galileo(galileo, tmp_path_factory):
    folder = tmp_path_factory.mktemp("saved")
    return galileo.model.save(str(folder / "good.h5")), galileo.model.export_npz(str(folder / "good.npz"))


def write_bytes(path, data):
    with open(path, "wb") as f:
        f.write(data)
    return str(path)


def test_unreadable_files_are_refused(saved_galileo, tmp_path):
    h5, npz = saved_galileo
    with open(h5, "rb") as f:
        h5_bytes = f.read()
    with open(npz, "rb") as f:
        npz_bytes = f.read()
    bad = [write_bytes(tmp_path / "half.h5", h5_bytes[:len(h5_bytes) // 2]),
           write_bytes(tmp_path / "head.h5", h5_bytes[:200]),
           write_bytes(tmp_path / "half.npz", npz_bytes[:len(npz_bytes) // 2]),
           write_bytes(tmp_path / "garbage.h5", b"not a model " * 100),
           write_bytes(tmp_path / "garbage.npz", b"not a model " * 100),
           write_bytes(tmp_path / "empty.h5", b""),
           str(tmp_path / "missing.h5")]
    missing_dataset = shutil.copy(h5, tmp_path / "no_K.h5")
    with h5py.File(missing_dataset, "a") as f:
        del f["bodies/rotor/K"]
    wrong_format = shutil.copy(h5, tmp_path / "format.h5")
    with h5py.File(wrong_format, "a") as f:
        f.attrs["format"] = "something-else"
    for path in bad + [str(missing_dataset), str(wrong_format)]:
        with pytest.raises(kryflex.ModelFileError, match=os.path.basename(path)):
            kryflex.ReducedModel.load(path)


def test_corrupted_npz_data_is_refused(saved_galileo, tmp_path):
    """A NumPy export is not a model file: loading it, intact or with a flipped bit, is refused."""
    import zipfile
    _, npz = saved_galileo
    with zipfile.ZipFile(npz) as z:
        info = z.getinfo("stator__K.npy")
    data = bytearray(open(npz, "rb").read())
    data[info.header_offset + 30 + len(info.filename) + len(info.extra) + 200] ^= 0x10
    path = write_bytes(tmp_path / "flipped.npz", bytes(data))
    with pytest.raises(kryflex.ModelFileError):
        kryflex.ReducedModel.load(path)


def test_corrupted_h5_data_is_refused(saved_galileo, tmp_path):
    h5, _ = saved_galileo
    with h5py.File(h5, "r") as f:
        K = f["bodies/stator/K"]
        # contiguous or in one chunk (small arrays), C order: entry i is 8 i bytes in
        base = K.id.get_offset() if K.chunks is None else K.id.get_chunk_info(0).byte_offset
        offset = base + 8 * int(np.argmax(np.abs(K[...])))
    data = bytearray(open(h5, "rb").read())
    data[offset + 7] ^= 0x10          # the exponent byte of the stator's largest stiffness entry
    path = write_bytes(tmp_path / "flipped.h5", bytes(data))
    with pytest.raises(kryflex.ModelFileError):
        kryflex.ReducedModel.load(path)


def test_inconsistent_h5_is_refused(saved_galileo, tmp_path):
    h5, _ = saved_galileo
    path = shutil.copy(h5, tmp_path / "inconsistent.h5")
    with h5py.File(path, "a") as f:
        del f["bodies/rotor/K"]
        f["bodies/rotor/K"] = np.eye(3)
    with pytest.raises(kryflex.ModelFileError):
        kryflex.ReducedModel.load(str(path))
