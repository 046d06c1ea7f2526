"""Reduced models: the reduced bodies, how they are jointed, their inputs and outputs, and the file that holds them.

A ReducedModel is small and dense and the same on every rank. It reassembles at any angle from the reduced bodies
alone (paper eq. 20-24, in C), and is stored as HDF5 (layout in README.md) or NumPy .npz.
"""
import hashlib
import json
import os
import numpy as np

from . import _core
from .io.files import atomic_path

FORMAT = "kryflex-reduced-model"
BODY_ARRAYS = ("M", "K", "G", "H", "iface", "rigid")
VERSION = 1


class ModelFileError(ValueError):
    """A reduced-model file that cannot be used: the message names the file and the fix."""


def scene_fingerprint(scene):
    """What a reduced model must agree with to stand for a scene: bodies, dofs, interfaces, joints, inputs, outputs."""
    desc = dict(bodies=list(zip(scene.body_names, scene.body_dofs, scene.interfaces)),
                joints=[(j["name"], j["type"], j["parent"], j["child"], j["parent_interface"], j["child_interface"],
                         [round(x, 12) for x in j["axis"]]) for j in scene.joints],
                inputs=scene.input_names, outputs=scene.output_names)
    return hashlib.sha256(json.dumps(desc, sort_keys=True).encode()).hexdigest()[:16]


def rigid_tolerance(lam, nrigid):
    """A relative tolerance that separates the nrigid lowest eigenvalues (rigid and mechanism modes) from the rest:
    the geometric mean of the last rigid and the first flexible eigenvalue, relative to the largest."""
    lam = np.sort(np.asarray(lam, dtype=float))
    top = max(abs(lam[-1]), 1e-300)
    if nrigid <= 0:
        return 0.0
    if nrigid >= lam.size:
        return 1.0
    lo, hi = max(abs(lam[nrigid - 1]), 1e-300 * top), max(lam[nrigid], 1e-300 * top)
    return float(np.sqrt(lo * hi) / top)


def reduced_moments(reassembled, nmom, nrigid):
    """Moments of a reassembled model: by solves with its geometric rigid modes when it has them."""
    Mh, Kh, Gh, Hh, _, _, Phir = reassembled
    if Phir is not None and Phir.shape[1] == nrigid:
        return _core.dense_moments_rigid(Kh, Mh, Gh, Hh, Phir, nmom)
    lam = _core.dense_eig(Kh, Mh)[0]
    return _core.dense_moments(Kh, Mh, Gh, Hh, nmom, rigid_tolerance(lam, nrigid))


class ReducedModel:
    """Reduced bodies + joints + names: everything reassembly needs, nothing of the full-order model."""

    def __init__(self, scene_name, fingerprint, body_names, body_dofs, interfaces, bodies, joints, revolute,
                 input_names, output_names, settings, maps=None):
        self.scene_name = scene_name
        self.fingerprint = fingerprint
        self.body_names = list(body_names)
        self.body_dofs = [int(n) for n in body_dofs]
        self.interfaces = [list(i) for i in interfaces]
        self.bodies = bodies              # list of dicts: M, K, G, H, iface
        self.joints = joints              # list of dicts: name, type, parent, child, parent_interface, child_interface, axis, R0
        self.revolute = list(revolute)
        self.input_names = list(input_names)
        self.output_names = list(output_names)
        self.settings = dict(settings)
        self.maps = maps                  # optional list of (n_b x v) arrays, the map back to full dofs
        self.nrigid = 6 + len(self.revolute)

    @property
    def sizes(self):
        return [b["M"].shape[0] for b in self.bodies]

    def reassemble(self, angles_deg, rtol=None):
        """(Mh, Kh, Gh, Hh, rank, sigma_ratio, Phir) at one configuration (degrees, one per revolute joint);
        Phir holds the rigid-body and mechanism modes, found from the bodies' rigid motions."""
        angles = np.atleast_1d(np.asarray(angles_deg, dtype=float))
        if angles.size != len(self.revolute):
            raise ValueError("the model has %d revolute joint(s) (%s): give %d angle(s), got %d"
                             % (len(self.revolute), ", ".join(self.revolute), len(self.revolute), angles.size))
        rtol = self.settings.get("reassembly_rtol", 1e-9) if rtol is None else rtol
        return _core.reassemble(self.bodies, self.joints, np.radians(angles), len(self.input_names),
                                len(self.output_names), rtol)

    def modes(self, angles_deg):
        """Eigenvalues and M-orthonormal modes of the reassembled model, and the rigid tolerance."""
        Mh, Kh = self.reassemble(angles_deg)[:2]
        lam, Phi = _core.dense_eig(Kh, Mh)
        return lam, Phi, rigid_tolerance(lam, self.nrigid)

    def frequencies_hz(self, angles_deg):
        lam = self.modes(angles_deg)[0]
        return np.sqrt(np.maximum(lam[self.nrigid:], 0.0)) / (2 * np.pi)

    def moments(self, angles_deg, nmom):
        return reduced_moments(self.reassemble(angles_deg), nmom, self.nrigid)

    def frf(self, angles_deg, freqs_hz, zeta):
        """Frequency response (nf, outputs, inputs) with uniform modal damping zeta."""
        Mh, Kh, Gh, Hh = self.reassemble(angles_deg)[:4]
        lam, Phi = _core.dense_eig(Kh, Mh)
        w = 2 * np.pi * np.asarray(freqs_hz, dtype=float)
        return _core.modal_frf(lam, Hh @ Phi, Phi.T @ Gh, zeta, w, rigid_tolerance(lam, self.nrigid))

    # ------------------------------------------------------------------ files

    def save(self, path):
        """Writes .h5 (HDF5) or .npz, atomically: a temporary file renamed into place."""
        ext = os.path.splitext(path)[1].lower()
        if ext not in (".h5", ".hdf5", ".npz"):
            raise ModelFileError("%s: reduced models are written as .h5 or .npz" % path)
        with atomic_path(path) as tmp:
            (self._write_npz if ext == ".npz" else self._write_h5)(tmp)
        return path

    def _meta(self):
        return dict(format=FORMAT, version=VERSION, scene=self.scene_name, scene_fingerprint=self.fingerprint,
                    bodies=self.body_names, body_dofs=self.body_dofs, interfaces=self.interfaces,
                    joints=self.joints, revolute=self.revolute, inputs=self.input_names, outputs=self.output_names,
                    settings=self.settings)

    def _write_h5(self, path):
        import h5py
        with h5py.File(path, "w") as f:
            meta = self._meta()
            for key in ("format", "version", "scene", "scene_fingerprint"):
                f.attrs[key] = meta[key]
            f.attrs["settings_json"] = json.dumps(self.settings)
            f.create_dataset("inputs", data=np.array(self.input_names, dtype=object), dtype=h5py.string_dtype())
            f.create_dataset("outputs", data=np.array(self.output_names, dtype=object), dtype=h5py.string_dtype())
            bg = f.create_group("bodies")
            for i, name in enumerate(self.body_names):
                g = bg.create_group(name)
                g.attrs["index"] = i
                g.attrs["full_dofs"] = self.body_dofs[i]
                g.attrs["interfaces"] = json.dumps(self.interfaces[i])
                # fletcher32: a flipped bit in a stored matrix is refused on reading instead of giving a wrong model
                for key in BODY_ARRAYS:
                    g.create_dataset(key, data=np.ascontiguousarray(self.bodies[i][key]), fletcher32=True)
                if self.maps is not None and self.maps[i] is not None:
                    g.create_dataset("map", data=np.ascontiguousarray(self.maps[i]), compression="gzip", fletcher32=True)
            jg = f.create_group("joints")
            for j in self.joints:
                g = jg.create_group(j["name"])
                for key in ("type", "parent", "child", "parent_interface", "child_interface"):
                    g.attrs[key] = j[key]
                g.attrs["axis"] = np.asarray(j["axis"], dtype=float)
                g.attrs["orientation"] = np.eye(3) if j.get("R0") is None else np.asarray(j["R0"], dtype=float)
                g.attrs["revolute_index"] = self.revolute.index(j["name"]) if j["name"] in self.revolute else -1

    def _write_npz(self, path):
        arrays = {"meta_json": np.array(json.dumps(self._meta()))}
        for i, name in enumerate(self.body_names):
            for key in BODY_ARRAYS:
                arrays["%s__%s" % (name, key)] = self.bodies[i][key]
        with open(path, "wb") as f:
            np.savez(f, **arrays)

    @classmethod
    def load(cls, path):
        if not os.path.isfile(path):
            raise ModelFileError("%s: reduced-model file not found" % path)
        ext = os.path.splitext(path)[1].lower()
        try:
            model = cls._read_npz(path) if ext == ".npz" else cls._read_h5(path)
            model._check_sizes(path)
            return model
        except ModelFileError:
            raise
        except Exception as e:  # noqa: BLE001 - any read failure means an unusable file
            raise ModelFileError("%s: not a readable kryflex reduced model (%s); write it again with 'kryflex reduce'"
                                 % (path, e)) from None

    @classmethod
    def _read_h5(cls, path):
        import h5py
        with h5py.File(path, "r") as f:
            if f.attrs.get("format") != FORMAT:
                raise ModelFileError("%s: not a kryflex reduced model (format attribute %r)" % (path, f.attrs.get("format")))
            names = sorted(f["bodies"], key=lambda n: int(f["bodies"][n].attrs["index"]))
            bodies, maps, dofs, ifaces = [], [], [], []
            for n in names:
                g = f["bodies"][n]
                bodies.append({k: np.asfortranarray(g[k][...]) for k in BODY_ARRAYS})
                maps.append(g["map"][...] if "map" in g else None)
                dofs.append(int(g.attrs["full_dofs"]))
                ifaces.append(json.loads(g.attrs["interfaces"]))
            joints, revolute = [], []
            for jn in f["joints"]:
                g = f["joints"][jn]
                j = dict(name=jn, type=str(g.attrs["type"]), parent=int(g.attrs["parent"]), child=int(g.attrs["child"]),
                         parent_interface=int(g.attrs["parent_interface"]), child_interface=int(g.attrs["child_interface"]),
                         axis=[float(x) for x in g.attrs["axis"]], R0=np.asarray(g.attrs["orientation"]).tolist(),
                         revolute_index=int(g.attrs["revolute_index"]))
                joints.append(j)
            joints.sort(key=lambda j: (j["revolute_index"] < 0, j["revolute_index"]))
            revolute = [j["name"] for j in joints if j["type"] == "revolute"]
            for j in joints:
                j.pop("revolute_index")
            return cls(str(f.attrs["scene"]), str(f.attrs["scene_fingerprint"]), names, dofs, ifaces, bodies, joints,
                       revolute, [s.decode() if isinstance(s, bytes) else s for s in f["inputs"][...]],
                       [s.decode() if isinstance(s, bytes) else s for s in f["outputs"][...]],
                       json.loads(f.attrs["settings_json"]), maps if any(m is not None for m in maps) else None)

    @classmethod
    def _read_npz(cls, path):
        with np.load(path, allow_pickle=False) as z:
            meta = json.loads(str(z["meta_json"]))
            if meta.get("format") != FORMAT:
                raise ModelFileError("%s: not a kryflex reduced model" % path)
            bodies = [{k: np.asfortranarray(z["%s__%s" % (n, k)]) for k in BODY_ARRAYS}
                      for n in meta["bodies"]]
        return cls(meta["scene"], meta["scene_fingerprint"], meta["bodies"], meta["body_dofs"], meta["interfaces"],
                   bodies, meta["joints"], meta["revolute"], meta["inputs"], meta["outputs"], meta["settings"])

    def _check_sizes(self, path):
        """The arrays of every body and the joints must fit together, or reassembly would fail far from the cause."""
        a, t = len(self.input_names), len(self.output_names)
        for name, b, nif in zip(self.body_names, self.bodies, self.interfaces):
            v = b["M"].shape[0]
            expected = dict(M=(v, v), K=(v, v), G=(v, a), H=(t, v), iface=(6 * len(nif), v), rigid=(v, 6))
            for key, shape in expected.items():
                if tuple(b[key].shape) != shape:
                    raise ModelFileError("%s: body '%s' array %s is %s, expected %s: the file is inconsistent; write it "
                                         "again with 'kryflex reduce'" % (path, name, key, tuple(b[key].shape), shape))
        for j in self.joints:
            for side in ("parent", "child"):
                b, i = j[side], j[side + "_interface"]
                if not (0 <= b < len(self.bodies) and 0 <= i < len(self.interfaces[b])):
                    raise ModelFileError("%s: joint '%s' names a %s body or interface that is not in the file" % (path, j["name"], side))

    def check_scene(self, scene, path="reduced model"):
        """A model used with a scene must come from that scene."""
        fp = scene_fingerprint(scene)
        if fp != self.fingerprint:
            raise ModelFileError("%s was reduced from scene '%s', not from this scene '%s' (its bodies, joints, inputs or "
                                 "outputs differ): reduce this scene again with 'kryflex reduce'"
                                 % (path, self.scene_name, scene.name))
