"""Scenes and dense yardsticks for the acceptance tests of accuracy-governed reduction (docs/guide/accuracy.md).

Helpers only (no tests): test_accuracy_target.py and accuracy_sweep.py (benchmarks/sweep/bench-sweep) use them.

* Scene builders write variants of three scenes into a folder: Galileo (meshes/galileo, a copy of the YAML with
  `accuracy`, angles and the reduction settings overridden), a generated 3-body beam frame of at least 5,000 dofs
  (meshes/frames.py) and the smallest 3-D solid pair of meshes/solid (refine 0.5, 2,760 dofs). A variant differs
  from its base only in the keys given, and names its body files by absolute path, so every variant of a scene
  shares one set of bodies and one dense reference.
* DenseReference: the full-order system of a scene at any angles from tests/python/support/reference.py alone (the scene
  file, SciPy, one dense generalized eigendecomposition per configuration), kept as modal data (eigenvalues,
  H Phi, Phi^T G) in memory and in a cache folder, so a 5k-dof frame costs its ~2 min per angle once per session.
* The accuracy measure the reducer promises (the manual's "Accuracy" page), implemented here in NumPy and not
  taken from kryflex: the relative H-infinity error per input/output pair on a check grid 4x finer than the reducer's, at the
  angles of interest and at every midpoint between consecutive ones.

Nothing here calls kryflex except evaluate_model, which asks a kryflex ReducedModel for its frequency response
(the thing under test) and compares it with the dense one.
"""
import hashlib
import os
import sys
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, HERE)
import reference as ref  # noqa: E402

GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")

# The generated frame: 3 bodies, >= 5,000 dofs in all. Two configurations of interest (one midpoint): the dense
# reference costs ~2 min per configuration (assembly through a dense null-space basis + one 5k generalized eigh),
# so three configurations are what a session can afford. The band holds the 8 lowest flexible modes (0.43-17 Hz).
FRAME_DOFS = 5200
FRAME_SEED = 1
FRAME_ANGLES = [[0.0, 0.0], [40.0, 60.0]]
FRAME_BAND = [0.01, 20.0]
FRAME_DAMPING = 0.0025

# The solid pair at refine 0.5 (bus 1,176 + rotor 1,584 dofs, 7 rigid/mechanism modes). Its band is widened from
# 15 to 20 Hz to take in the scan-arm pair at 17.06 / 17.08 Hz: a near-repeated cluster (gap 1e-3 relative) that a
# cluster-invariant importance must keep or drop as a whole. 7 flexible modes in the band (5.96 Hz up).
SOLID_REFINE = 0.5
SOLID_ANGLES = [[0.0], [45.0], [90.0]]
SOLID_BAND = [0.01, 20.0]

# kryflex's default reduction (the accuracy search), written out: a scene variant states it rather than trusting
# whatever the schema's defaults are, so these scenes keep testing the search if a default changes.
CONTRACT_REDUCTION = {"moments": "auto", "method": "auto", "search": True, "importance": "band"}

PAIR_FLOOR = 1e-4          # a pair whose peak is below PAIR_FLOOR x the largest pair's peak is measured against that
GRID_FACTOR = 4            # the check grid is this much finer than the reducer's
RESONANCE_SPAN = 2.0       # the reducer samples fr (1 + zeta {-2 .. 2}) around each resonance: 7 points


# ------------------------------------------------------------------ scene files

def _absolute_bodies(spec, base_dir):
    for body in spec["bodies"].values():
        for key in ("mass", "stiffness", "nodes"):
            body[key] = os.path.join(base_dir, body[key])
    return spec


def write_variant(base_yaml, out_path, accuracy=None, angles=None, band=None, damping=None, reduction=None,
                  verify=None, name=None):
    """A copy of the scene base_yaml at out_path with the keys given replaced, body files by absolute path.

    reduction: None drops the base's reduction section, so kryflex's defaults apply (moments auto, method
    auto, search on, importance band); a dict replaces it. verify: None keeps the base's (usually none: defaults).
    Returns out_path."""
    with open(base_yaml) as f:
        spec = yaml.safe_load(f)
    spec = _absolute_bodies(spec, os.path.dirname(os.path.abspath(base_yaml)))
    spec.pop("reduction", None)
    if reduction is not None:
        spec["reduction"] = dict(reduction)
    if verify is not None:
        spec["verify"] = dict(verify)
    for key, value in (("accuracy", accuracy), ("angles", angles), ("band", band), ("damping", damping),
                       ("name", name)):
        if value is not None:
            spec[key] = value
    os.makedirs(os.path.dirname(os.path.abspath(out_path)), exist_ok=True)
    with open(out_path, "w") as f:
        f.write("# written by tests/python/support/accuracy_scenes.py from %s\n" % os.path.abspath(base_yaml))
        yaml.safe_dump(spec, f, sort_keys=False, default_flow_style=None, width=120)
    return out_path


def frame_base(out_dir):
    """The 3-body frame's bodies and base scene in out_dir (written once; reused when already there)."""
    sys.path.insert(0, os.path.join(ROOT, "meshes"))
    import frames
    path = os.path.join(out_dir, "scene.yaml")
    if not os.path.exists(path):
        path = frames.write_random_scene(out_dir, FRAME_DOFS, nbodies=3, ninputs=3, noutputs=2, seed=FRAME_SEED,
                                         nangles=len(FRAME_ANGLES))
    total = sum(ref.read_matrix(os.path.join(out_dir, b["stiffness"])).shape[0]
                for b in yaml.safe_load(open(path))["bodies"].values())
    if total < 5000:
        raise AssertionError("the frame scene has %d dofs, the tests need at least 5,000 (a large model): raise FRAME_DOFS" % total)
    return path


def solid_base(out_dir):
    """The solid bus/rotor pair at SOLID_REFINE in out_dir (written once; collective over PETSc.COMM_WORLD)."""
    path = os.path.join(out_dir, "spacecraft.yaml")
    if not os.path.exists(path):
        sys.path.insert(0, os.path.join(ROOT, "meshes", "solid"))
        import generate
        from petsc4py import PETSc
        path = generate.write_spacecraft(out_dir, refine=SOLID_REFINE, comm=PETSc.COMM_SELF)
    return path


@dataclass
class SceneSpec:
    """One of the three test scenes: its base scene file and the overrides every variant gets."""
    name: str
    base: str
    angles: list
    band: list = None
    damping: float = None

    def variant(self, out_path, accuracy, reduction=None, verify=None):
        return write_variant(self.base, out_path, accuracy=accuracy, angles=self.angles, band=self.band,
                             damping=self.damping, reduction=reduction, verify=verify)

    @property
    def configurations(self):
        return [list(np.atleast_1d(np.asarray(a, float))) for a in self.angles]


def galileo_spec():
    with open(GALILEO) as f:
        angles = [[float(a)] for a in yaml.safe_load(f)["angles"]]
    return SceneSpec("galileo", GALILEO, angles)


def frame_spec(out_dir):
    return SceneSpec("frame", frame_base(out_dir), FRAME_ANGLES, FRAME_BAND, FRAME_DAMPING)


def solid_spec(out_dir):
    return SceneSpec("solid", solid_base(out_dir), SOLID_ANGLES, SOLID_BAND)


def with_midpoints(configurations):
    """[(angles, kind)]: each configuration of interest ("angle") and the midpoint between consecutive ones
    ("midpoint"), in order."""
    out = []
    for k, c in enumerate(configurations):
        if k:
            out.append(([0.5 * (a + b) for a, b in zip(configurations[k - 1], c)], "midpoint"))
        out.append((list(c), "angle"))
    return out


# ------------------------------------------------------------------ the dense full-order reference

@dataclass
class ModalData:
    """The full-order system at one configuration as its modes: lam (ascending, rigid ones set to 0), the rigid mask,
    hp = H Phi (t x n), pg = Phi^T G (n x a), with Phi^T M Phi = I."""
    lam: np.ndarray
    rigid: np.ndarray
    hp: np.ndarray
    pg: np.ndarray

    @property
    def flexible_hz(self):
        return np.sqrt(self.lam[~self.rigid]) / (2 * np.pi)

    @property
    def nrigid(self):
        return int(self.rigid.sum())

    def frf(self, freqs_hz, zeta, chunk=256):
        """T(w) = sum_i hp_i pg_i / (lam_i - w^2 + 2 i zeta sqrt(lam_i) w), rigid modes 1 / (-w^2): (nf, t, a).
        The formula of reference.modal_frf, on modes computed once, a chunk of frequencies at a time."""
        w = 2 * np.pi * np.asarray(freqs_hz, float)
        sq = np.sqrt(self.lam)
        out = np.empty((len(w), self.hp.shape[0], self.pg.shape[1]), complex)
        for k in range(0, len(w), chunk):
            wk = w[k:k + chunk, None]
            inv = 1.0 / (self.lam[None, :] - wk**2 + 2j * zeta * sq[None, :] * wk)
            out[k:k + chunk] = np.einsum("tn,fn,na->fta", self.hp, inv, self.pg, optimize=True)
        return out


def modal_data(Ms, Ks, Gs, Hs, rigid_modes=None):
    """The modes of (K_S, M_S) by one dense eigendecomposition. Given the geometric rigid modes
    (reference.geometric_rigid_modes), those, M-orthonormalized, replace the eigensolver's null space as the rigid
    modes: the eigensolver knows K_S's null space only to eps lam_max / lam_1 (2.2e-9 rad on the 2,755-dof solid), and
    the rigid part is what the elastic measure subtracts, 670 times the elastic peak at the solid's band bottom. The
    flexible modes stay the eigensolver's (their static sum L^0 agrees with kryflex's to 1.4e-10 there; modes solved
    on the geometric modes' M-orthogonal complement gave 1e-9). The geometric modes must be as many as the zero
    eigenvalues and carry no energy beyond K_S's rounding (ref.RIGID_RTOL lam_max)."""
    lam, phi = sl.eigh(Ks, Ms)
    rigid = np.abs(lam) <= ref.RIGID_RTOL * np.abs(lam).max()
    if rigid_modes is not None and rigid_modes.shape[1]:
        Q = rigid_modes @ np.linalg.inv(sl.cholesky(rigid_modes.T @ Ms @ rigid_modes))     # Q^T M Q = I
        energy = np.abs(np.linalg.eigvalsh(Q.T @ Ks @ Q)).max()
        if Q.shape[1] != rigid.sum() or energy > ref.RIGID_RTOL * np.abs(lam).max():
            raise ValueError("the geometric rigid modes are not K_S's null space: %d of them, %d zero eigenvalues, "
                             "their energy %.3g against the largest eigenvalue %.3g"
                             % (Q.shape[1], rigid.sum(), energy, np.abs(lam).max()))
        order = np.argsort(~rigid, kind="stable")       # the rigid ones first
        lam, rigid, phi = lam[order], rigid[order], phi[:, order]
        phi[:, :Q.shape[1]] = Q
    return ModalData(np.where(rigid, 0.0, lam), rigid, Hs @ phi, phi.T @ Gs)


class DenseReference:
    """The dense full-order modal data of a scene at any configuration, computed once per configuration and kept in
    memory and under cache_dir (npz per configuration, keyed by the scene's bodies, joints, inputs and outputs)."""

    def __init__(self, scene_path, cache_dir):
        self.scene = ref.load_scene(scene_path)
        raw = self.scene.raw
        key = yaml.safe_dump({k: raw.get(k) for k in ("bodies", "joints", "inputs", "outputs")}, sort_keys=True)
        key += "rigid modes from geometry, flexible from eigh\n"     # older caches are not reused
        for b in raw["bodies"].values():         # the body files' sizes and times: a regenerated body is a new key
            for k in ("mass", "stiffness", "nodes"):
                st = os.stat(os.path.join(self.scene.here, b[k]))
                key += "%s %d %d\n" % (b[k], st.st_size, st.st_mtime_ns)
        self.key = hashlib.sha1(key.encode()).hexdigest()[:12]
        self.cache_dir = cache_dir
        self.seconds = 0.0
        self._memo = {}
        self._responses = {}
        os.makedirs(cache_dir, exist_ok=True)

    def at(self, angles_deg):
        angles = tuple(float(a) for a in np.atleast_1d(angles_deg))
        if angles not in self._memo:
            path = os.path.join(self.cache_dir, "modal_%s_%s.npz" % (self.key, "_".join("%.6g" % a for a in angles)))
            if os.path.exists(path):
                with np.load(path) as z:
                    data = ModalData(z["lam"], z["rigid"], z["hp"], z["pg"])
            else:
                import time
                t0 = time.perf_counter()
                data = modal_data(*ref.assemble(self.scene, list(angles)),
                                  rigid_modes=ref.geometric_rigid_modes(self.scene, list(angles)))
                self.seconds += time.perf_counter() - t0
                tmp = path + ".tmp.npz"
                np.savez(tmp, lam=data.lam, rigid=data.rigid, hp=data.hp, pg=data.pg)
                os.replace(tmp, path)
            self._memo[angles] = data
        return self._memo[angles]

    def response(self, angles_deg, freqs_hz, zeta):
        """The dense frequency response at a configuration on a grid, kept for the next model checked on it."""
        angles = tuple(float(a) for a in np.atleast_1d(angles_deg))
        f = np.asarray(freqs_hz, float)
        key = (angles, float(zeta), f.size, hashlib.sha1(f.tobytes()).hexdigest())
        if key not in self._responses:
            self._responses[key] = self.at(angles).frf(f, zeta)
        return self._responses[key]


# ------------------------------------------------------------------ the accuracy measure

def check_grid(band_hz, n_log, resonances_hz, zeta, factor=GRID_FACTOR):
    """The check grid: factor x n_log log-spaced points over the band, plus factor x 7 + 1 points over
    fr (1 + zeta [-2, 2]) around each resonance fr in the band (the reducer takes 7 there), sorted, unique."""
    f0, f1 = float(band_hz[0]), float(band_hz[1])
    parts = [np.geomspace(f0, f1, factor * int(n_log))]
    offsets = np.linspace(-RESONANCE_SPAN, RESONANCE_SPAN, factor * 7 + 1)
    for fr in np.asarray(resonances_hz, float):
        if f0 <= fr <= f1:
            parts.append(fr * (1 + zeta * offsets))
    f = np.clip(np.concatenate(parts), f0, f1)
    return np.unique(f)


def pair_hinf_errors(Tf, Tr, floor=PAIR_FLOOR):
    """Per pair (i, j): max_w |Tf_ij - Tr_ij| / max_w |Tf_ij|, a pair's peak floored at floor x the largest pair's
    peak; (t, a) array. The accuracy measure is its maximum."""
    Tf, Tr = np.asarray(Tf), np.asarray(Tr)
    if Tf.shape != Tr.shape:
        raise ValueError("full response %s and reduced %s differ in shape" % (Tf.shape, Tr.shape))
    peak = np.abs(Tf).max(axis=0)
    return np.abs(Tf - Tr).max(axis=0) / np.maximum(peak, floor * peak.max())


def pointwise_errors(Tf, Tr, floor_db=-60.0):
    """Per pair: max_w |Tf - Tr| / max(|Tf(w)|, 10^(floor_db/20) max_w |Tf|) (for information, never pass/fail)."""
    Tf, Tr = np.asarray(Tf), np.asarray(Tr)
    level = 10 ** (floor_db / 20.0) * np.abs(Tf).max(axis=0)
    return (np.abs(Tf - Tr) / np.maximum(np.abs(Tf), level[None])).max(axis=0)


@dataclass
class Check:
    """The error of a reduced model at one configuration on the check grid."""
    angles: list
    kind: str            # "angle" or "midpoint"
    error: float         # relative H-inf per pair, max over pairs
    pointwise: float
    npoints: int
    worst_pair: tuple
    reduced_dofs: int
    full_first_hz: float          # lowest flexible dense frequency
    reduced_low_hz: np.ndarray    # reduced frequencies below full_first_hz / 2: rigid, mechanism or spurious
    reduced_zero: int             # how many (a spurious mode makes it exceed full_rigid)
    full_rigid: int


def evaluate_model(model, dense, configurations, band_hz, zeta, n_log):
    """The reduced model (a kryflex ReducedModel) against the dense reference at every configuration of interest
    and every midpoint: [Check]. n_log: the reducer's log-spaced point count (the check grid has GRID_FACTOR x)."""
    checks = []
    for angles, kind in with_midpoints(configurations):
        full = dense.at(angles)
        fr = full.flexible_hz
        f = check_grid(band_hz, n_log, fr, zeta)
        system = model.at(angles)
        Tr = system.frf(f)              # with the model's own damping (the scene's, if the model is right)
        Tf = dense.response(angles, f, zeta)
        e = pair_hinf_errors(Tf, Tr)
        worst = np.unravel_index(int(np.argmax(e)), e.shape)
        lam = np.asarray(system.eigenvalues, float)
        f_red = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
        low = f_red < 0.5 * fr[0]
        checks.append(Check(list(angles), kind, float(e.max()), float(pointwise_errors(Tf, Tr).max()), len(f),
                            tuple(int(i) for i in worst), int(system.dofs), float(fr[0]),
                            np.asarray(f_red[low]), int(low.sum()), full.nrigid))
    return checks


def label(angles):
    """The reducer's label of a configuration ("15", "15_30"): C's %g of each angle in degrees."""
    return "_".join("%g" % a for a in angles)


def worst(checks):
    return max(c.error for c in checks)


def describe(checks):
    """One line per check, for the test logs and the lead."""
    return "\n".join("  %-8s %-18s e = %.3e  pointwise %.3e  (%d points, pair %s, %d dofs)"
                     % (c.kind, c.angles, c.error, c.pointwise, c.npoints, c.worst_pair, c.reduced_dofs)
                     for c in checks)
