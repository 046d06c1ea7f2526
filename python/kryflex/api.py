"""The results of a reduction, in pyMOR's shape, on the C library's objects:

    model = kryflex.Reducer(scene).reduce().model        # a ReducedModel (KFReducedModel)
    system = model.at([37.5])                             # a ReducedSystem (KFReducedSystem)
    T = system.frf(np.geomspace(0.01, 10, 500)); L = system.moments(10)

Every number comes from C (src/model, src/measure); this module only names and shapes them. The Reducer that makes
the models (on KFReducer) is in reducer.py.
"""
import functools
import json
import os

import numpy as np

from . import _core


class ModelFileError(ValueError):
    """A reduced-model file that cannot be used: the message names the file and the fix."""


class ReducedSystem:
    """A reduced model reassembled at one configuration (paper eq. 20-24): small, dense, the same on every rank.

    M, K (n x n), B = G (n x inputs), C = H (outputs x n); damping: the uniform modal damping ratio the reduction
    served; eigenvalues (ascending) and M-orthonormal modes of (K, M); rigid_modes: the rigid-body and mechanism
    modes from the bodies' rigid motions (n x r, or None when the model lacks them); frequencies_hz: the flexible
    ones; constraint_rank, sigma_ratio: the reassembly's SVD of the interface constraints.
    Trimmed (reduction.max_frequency; docs/guide/trimming.md): M, K, B, C are then the kept modes' modal system (M = I,
    K = diag of the eigenvalues) and y = C x + feedthrough u; trimmed: modes taken out, max_frequency_hz the limit,
    untrimmed_top_hz the highest frequency before; feedthrough None when nothing was trimmed.
    damping_matrix: the viscous damping in reduced coordinates (n x n: the bodies' C_b projected and reassembled plus
    Rayleigh alpha M + beta K), None when there is none; damping_model: {modal, rayleigh, structural} as the model
    records it; output_quantities: per output displacement, velocity or acceleration.

    The matrices come from the allocation-free reassembly (KFReassemblyApply); the eigen-decomposition
    (eigenvalues, modes, frequencies_hz) is computed on first use (KFReassemblyEig), and the C system that frf,
    response and moments run on (handle, a KFReducedSystem) is made on first use too. A simulation that only needs
    M, K, B, C and the damping matrix at each step pays for neither."""

    def __init__(self, angles_deg, M, K, damping, B, C, rigid_modes, constraint_rank, sigma_ratio, damping_matrix=None,
                 damping_model=None, output_quantities=None, *, nrigid=None, reassembly=None, model=None,
                 handle=None, eigen=None, feedthrough=None, trimmed=0, max_frequency_hz=0.0, untrimmed_top_hz=0.0,
                 lazy_info=False):
        self.feedthrough, self.trimmed = feedthrough, trimmed
        self.max_frequency_hz, self._untrimmed_top_hz = max_frequency_hz, untrimmed_top_hz
        self.angles_deg, self.M, self.K, self.damping, self.B, self.C = tuple(angles_deg), M, K, damping, B, C
        self._info = None if lazy_info else (rigid_modes, constraint_rank, sigma_ratio)
        self.damping_matrix, self.damping_model, self.output_quantities = damping_matrix, damping_model, \
            output_quantities
        self._nrigid, self._reassembly, self._model, self._handle, self._eigen = nrigid, reassembly, model, handle, \
            eigen

    def __repr__(self):
        return "ReducedSystem(angles_deg=%s, dofs=%d, inputs=%d, outputs=%d)" % (
            self.angles_deg, self.dofs, self.B.shape[1], self.C.shape[0])

    @classmethod
    def from_handle(cls, handle, angles_deg, damping, output_quantities=None):
        """From a C system (CReducedSystem) made by CReducedModel.reassemble: every array copied from it."""
        M, K, G, H = handle.matrices()
        lam, Phi, nrigid, Phir = handle.modes()
        rank, ratio = handle.reassembly_info()
        Cd, model = handle.damping()
        ntrim, fmax, ftop, D = handle.trim_info()
        return cls(angles_deg, M, K, damping, G, H, Phir, int(rank), float(ratio), Cd, model, output_quantities,
                   nrigid=int(nrigid), handle=handle, eigen=(lam, Phi, handle.frequencies_hz()), feedthrough=D,
                   trimmed=ntrim, max_frequency_hz=fmax, untrimmed_top_hz=ftop)

    def _reassembly_info(self):
        """(rigid modes, constraint rank, sigma ratio): from the workspace's SVDs of the ties on first use when at()
        left them out. Where the ties degenerate at these angles that call takes the SVD path, whose matrices then
        replace the closed form's (the same system in another basis)."""
        if self._info is None:
            M, K, Cd, G, H, Phir, rank, ratio = self._reassembly.apply(np.radians(np.asarray(self.angles_deg, float)))
            if M.shape != self.M.shape or not np.array_equal(M, self.M):
                self.M, self.K, self.damping_matrix, self.B, self.C, self._eigen = M, K, Cd, G, H, None
            self._info = (Phir, int(rank), float(ratio))
            if Phir is not None:
                self._nrigid = Phir.shape[1]
        return self._info

    @property
    def rigid_modes(self):
        return self._reassembly_info()[0]

    @property
    def constraint_rank(self):
        return self._reassembly_info()[1]

    @property
    def sigma_ratio(self):
        return self._reassembly_info()[2]

    @property
    def dofs(self):
        return self.M.shape[0]

    @property
    def top_frequency_hz(self):
        """The highest flexible frequency the system keeps in its dynamics (Hz; 0 without flexible modes)."""
        return float(self.frequencies_hz[-1]) if len(self.frequencies_hz) else 0.0

    @property
    def untrimmed_top_hz(self):
        """The highest flexible frequency before trimming (Hz): top_frequency_hz when nothing was trimmed."""
        return self._untrimmed_top_hz if self.trimmed else self.top_frequency_hz

    @property
    def explicit_step_s(self):
        """The largest stable step of an explicit central-difference integration of the undamped system, 2 / omega_max
        (s; inf without flexible modes)."""
        f = self.top_frequency_hz
        return 2.0 / (2 * np.pi * f) if f > 0 else float("inf")

    def _eig(self):
        """(eigenvalues, modes, flexible frequencies): the rigid modes from the bodies' rigid motions when known and no
        more than the dofs, else the whole pencil with the model's rigid count (as KFReducedModelReassemble)."""
        if self._eigen is None:
            Phir = self.rigid_modes
            known = Phir is not None and Phir.shape[1] <= self.dofs
            lam, Phi = self._reassembly.eig(self.M, self.K, Phir if known else None)
            nrigid = self._nrigid
            freqs = np.sqrt(np.maximum(lam[nrigid:], 0.0)) / (2 * np.pi)
            self._eigen = (lam, Phi, freqs)
        return self._eigen

    @property
    def eigenvalues(self):
        return self._eig()[0]

    @property
    def modes(self):
        return self._eig()[1]

    @property
    def frequencies_hz(self):
        return self._eig()[2]

    @property
    def handle(self):
        """The C system (CReducedSystem) at this configuration, made on first use."""
        if self._handle is None:
            self._handle = self._model.reassemble(np.radians(np.asarray(self.angles_deg, dtype=float)))
        return self._handle

    def frf(self, freqs_hz, damping=None):
        """Frequency response (frequencies, outputs, inputs), complex. damping None: the model's damping (modal,
        Rayleigh, structural, the viscous matrix) and output quantities, as the reduction measured it; a number:
        uniform modal damping of that ratio alone, displacement outputs. Rigid-body and mechanism modes get no modal
        damping."""
        w = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
        if damping is None:
            return self.handle.response(w)
        return self.handle.frf(float(damping), w)

    def rigid_frf(self, freqs_hz):
        """The rigid-body and mechanism part of frf(freqs_hz) (the model's damping and output quantities): its rigid
        modes alone. frf - rigid_frf is the elastic response, the one the default accuracy measure is stated on."""
        return self.handle.rigid_response(2 * np.pi * np.asarray(freqs_hz, dtype=float))

    def elastic_frf(self, freqs_hz):
        """The elastic response: frf(freqs_hz) minus its rigid-body and mechanism part (rigid_frf)."""
        return self.frf(freqs_hz) - self.rigid_frf(freqs_hz)

    def moments(self, k):
        """The low-frequency moments L^0 .. L^(k-1) on the flexible subspace: (k, outputs, inputs)."""
        return self.handle.moments(int(k))

    def view(self):
        self.handle.view()


BODY_KEYS = ("M", "K", "G", "H", "iface", "rigid", "damping_matrix")


class BodyArrays(dict):
    """A reduced body's arrays by name (ReducedModel.bodies). The damping matrix's former key "C" reads it with a
    DeprecationWarning, so that C names one thing in the API: a ReducedSystem's output matrix."""

    @staticmethod
    def _key(key):
        if key == "C":
            import warnings
            warnings.warn('the reduced body\'s damping matrix is body["damping_matrix"]; body["C"] is deprecated '
                          "(C is a ReducedSystem's output matrix)", DeprecationWarning, stacklevel=3)
            return "damping_matrix"
        return key

    def __getitem__(self, key):
        return super().__getitem__(self._key(key))

    def get(self, key, default=None):
        return super().get(self._key(key), default)

    def __contains__(self, key):
        return super().__contains__(self._key(key))


def _setting_value(text):
    """Settings are strings in C; numbers, lists and booleans are stored as JSON (-kf_ option values as text)."""
    try:
        return json.loads(text)
    except ValueError:
        return text


class ReducedModel(_core.CReducedModel):
    """Reduced bodies + joints + names + settings (KFReducedModel): everything reassembly needs, nothing of the
    full-order model. The same on every rank."""

    def at(self, angles_deg, trimmed=True):
        """The reduced system at one configuration (degrees, one angle per revolute joint): the matrices now, through
        the model's allocation-free reassembly (KFReassemblyApply, made once per model), the modes on first use.
        A model reduced with reduction.max_frequency is trimmed (docs/guide/trimming.md) by the C reassembly, which
        needs the modes anyway; trimmed=False: every mode, as its bodies give."""
        fast = self._fast
        angles = np.asarray(angles_deg, dtype=float)
        if angles.ndim == 0:
            angles = angles.reshape(1)
        if angles.ndim != 1 or angles.shape[0] != fast["nrevolute"]:
            names = self.revolute
            raise ValueError("the model has %d revolute joint(s) (%s): give %d angle(s), got %d"
                             % (len(names), ", ".join(names), len(names), angles.size))
        if not np.isfinite(angles).all():
            raise ValueError("the angles must be finite numbers (degrees), got %s" % angles)
        limit = fast["max_frequency_hz"]
        if limit is not None and float(limit) > 0:
            if trimmed:
                handle = self.reassemble(np.radians(angles))
            else:   # the reassembly reads the limit from the settings: off for this one call
                self.set_setting("max_frequency_hz", "0")
                try:
                    handle = self.reassemble(np.radians(angles))
                finally:
                    self.set_setting("max_frequency_hz", limit)
            return ReducedSystem.from_handle(handle, angles.tolist(), float(self.settings.get("damping", 0.0)),
                                             self.output_quantities())
        # the matrices alone: the rigid modes and the ties' rank come from SVDs, made when they are read
        M, K, Cd, G, H, _, _, _ = fast["reassembly"].apply(angles * (np.pi / 180.0), False, False)
        return ReducedSystem(angles.tolist(), M, K, fast["damping"], G, H, None, None, None, Cd,
                             fast["damping_model"], fast["quantities"], nrigid=fast["nrigid"],
                             reassembly=fast["reassembly"], model=self, lazy_info=True)

    @property
    def _fast(self):
        """What at() needs that does not change with the angles: the reassembly workspace and the model's settings,
        made on first use and dropped when the damping or a setting changes."""
        fast = self.__dict__.get("_fast_cache")
        if fast is None:
            fast = dict(reassembly=_core.CReassembly(self), nrevolute=self.info()["revolute"],
                        nrigid=self.info()["rigid"], damping=float(self.settings.get("damping", 0.0)),
                        damping_model=self.damping(), quantities=self.output_quantities(),
                        max_frequency_hz=self.setting_strings().get("max_frequency_hz"))
            self.__dict__["_fast_cache"] = fast
        return fast

    def set_damping(self, d):
        self.__dict__.pop("_fast_cache", None)
        return super().set_damping(d)

    def set_setting(self, key, value):
        self.__dict__.pop("_fast_cache", None)
        return super().set_setting(key, value)

    # ------------------------------------------------------------------ what the model holds (copies, cached)

    @functools.cached_property
    def _bodies(self):
        return [self.body(b) for b in range(self.info()["bodies"])]

    @property
    def bodies(self):
        """Per body a dict of NumPy arrays: M, K (v x v), G (v x a), H (t x v), iface (6 n_if x v), rigid (v x 6), and
        damping_matrix (v x v reduced viscous damping) for a body that has one. (Its old key "C" still reads, with a
        DeprecationWarning: C is the output matrix of a ReducedSystem.)"""
        return [BodyArrays((k, b[k]) for k in BODY_KEYS if b[k] is not None) for b in self._bodies]

    @property
    def maps(self):
        """Per body its map back to the full dofs (n_b x v), or None when the model does not keep maps."""
        maps = [b["map"] for b in self._bodies]
        return maps if any(m is not None for m in maps) else None

    @functools.cached_property
    def ties(self):
        """The coordinate ties between the bodies of a model of shared directions (-kf_shared_directions): ms x n
        (n = sum(sizes)), rows D with D q = 0 on the stacked body coordinates q, appended to the joints' ties at every
        reassembly; None for a model without them."""
        return self.coordinate_ties()

    @property
    def body_names(self):
        return [b["name"] for b in self._bodies]

    @property
    def body_dofs(self):
        return [b["full_dofs"] for b in self._bodies]

    @property
    def sizes(self):
        return [b["M"].shape[0] for b in self._bodies]

    @property
    def interfaces(self):
        return [b["interfaces"] for b in self._bodies]

    @functools.cached_property
    def joints(self):
        return [self.joint(j) for j in range(self.info()["joints"])]

    @property
    def revolute(self):
        return [j["name"] for j in self.joints if j["type"] == "revolute"]

    @functools.cached_property
    def input_names(self):
        return self.io_names(True)

    @functools.cached_property
    def output_names(self):
        return self.io_names(False)

    @property
    def nrigid(self):
        return self.info()["rigid"]

    @property
    def settings(self):
        return {k: _setting_value(v) for k, v in self.setting_strings().items()}

    # ------------------------------------------------------------------ files and scenes

    def save(self, path):
        """Writes the model as HDF5 (docs/guide/results.md: the reduced.h5 layout) through the C writer, atomically."""
        if os.path.splitext(str(path))[1].lower() not in (".h5", ".hdf5"):
            raise ModelFileError("%s: reduced models are written as .h5 (HDF5); export_npz writes the arrays for NumPy"
                                 % path)
        return super().save(str(path))

    @classmethod
    def load(cls, path, comm=None):
        """Reads a model written by save (checked: format, version, shapes, names, checksums)."""
        if os.path.isdir(path):
            raise ModelFileError("%s: a folder, not a reduced-model file: give the .h5 file 'kryflex reduce' wrote "
                                 "(OUT/reduced.h5)" % path)
        if not os.path.isfile(path):
            raise ModelFileError("%s: reduced-model file not found" % path)
        try:
            return super().load(str(path), comm)
        except _core.Error as e:
            # the C reader's message names the file, the dataset, the fault and the fix: said once, not wrapped
            detail = str(e)
            if detail.startswith("%s: " % path):
                detail = detail[len(str(path)) + 2:]
            raise ModelFileError("%s: not a readable kryflex reduced model: %s" % (path, detail)) from None

    def export_npz(self, path):
        """A plain NumPy export of the reduced bodies (<body>__M, __K, __G, __H, __iface, __rigid, and
        __damping_matrix for a body that has one) and the names, for tools without HDF5; kryflex itself reads only the
        HDF5 file."""
        from .io.files import atomic_path
        arrays = {"%s__%s" % (name, key): body[key] for name, body in zip(self.body_names, self.bodies) for key in body}
        arrays.update(inputs=np.array(self.input_names), outputs=np.array(self.output_names),
                      revolute_joints=np.array(self.revolute))
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.savez(f, **arrays)
        return path

    def check_scene(self, scene, path="reduced model"):
        """A model used with a scene must come from that scene (the C fingerprint of bodies, joints, inputs, outputs)."""
        if scene.cscene.fingerprint() != self.fingerprint:
            raise ModelFileError("%s was reduced from scene '%s', not from this scene '%s' (its bodies, joints, inputs or "
                                 "outputs differ): reduce this scene again with 'kryflex reduce'"
                                 % (path, self.scene_name, scene.name))

