"""Scene files: bodies, joints, inputs, outputs and what the reduction must serve.

A scene is one YAML file (see README.md, "Scene file reference"). Every value can be overridden from the command
line with a PETSc option named after its path: ``-scene.damping 0.005``, ``-scene.reduction.moments 12``,
``-scene.angles 0,30,60``. Errors name the offending entry and the fix.
"""
import os

import numpy as np
import yaml
from petsc4py import PETSc

from .. import _core

DOF_NAMES = {"ux": 0, "uy": 1, "uz": 2, "rx": 3, "ry": 4, "rz": 5}

TOP_KEYS = {"name", "description", "units", "bodies", "joints", "inputs", "outputs", "angles", "band", "damping",
            "accuracy", "reduction", "verify"}
BODY_KEYS = {"mass", "stiffness", "nodes", "interfaces", "description"}
JOINT_KEYS = {"type", "parent", "parent_interface", "child", "child_interface", "axis", "orientation"}
TERM_KEYS = {"body", "node", "dof", "weight", "vector"}
REDUCTION_DEFAULTS = {
    "basis": "krylov",           # krylov (kryflex) | eigen (the eigenvector baseline it replaces: EP&A / COMPARE style)
    "eigen_cover": 1.0,          # eigen basis: full-order modes up to eigen_cover x the band's top frequency
    "moments": 10,               # low-frequency moments matched exactly (c in the paper)
    "output_blocks": 1,          # Krylov blocks started from K+ H^T (eq. 8's last vector)
    "importance": "h2",          # h2 | hinf | static
    "keep_threshold": 0.05,      # keep Krylov modes whose normalized importance reaches this
    "reduction_angle": "auto",   # alpha_G: auto, or an angle (list for several joints)
    "method": "single-angle",    # single-angle (the paper) | multi-angle (exact moments at several angles)
    "reduction_angles": None,    # multi-angle: configurations to build Krylov vectors at (default: all angles)
    "deflation_tol": 1e-10,      # Krylov block deflation (relative)
    "body_tol": 1e-10,           # per-body rank deflation of the projected modes
    "reassembly_rtol": 1e-9,     # SVD rank tolerance of the reduced interface constraints
    "static_correction": True,   # eq. 15-17
    "shift": 0.0,                # K + shift M instead of held dofs (moments then expand about -shift)
    "save_maps": "auto",         # store each reduced body's map back to its full dofs
}
VERIFY_DEFAULTS = {
    "modes": "auto",             # full-order modes for verification (auto: cover 3 x the band's top)
    "frequency_points": 400,     # log-spaced frequency-response points over the band (+ points at resonances)
    "full_order": True,          # run the full-order verification at all
    "frf_floor_db": -60.0,       # FRF error: notches deeper than this below the band's peak count against this level
}


class SceneError(ValueError):
    """A bad scene: the message names the entry and the fix."""


def _fail(where, msg):
    raise SceneError("%s: %s" % (where, msg))


def _number(where, value, kind=float):
    """A number from the scene, or a SceneError naming the entry."""
    if isinstance(value, bool) or value is None:
        _fail(where, "%r is not a number" % (value,))
    try:
        x = kind(value)
    except (TypeError, ValueError):
        _fail(where, "%r is not %s" % (value, "a number" if kind is float else "an integer"))
    if kind is int and float(value) != x:
        _fail(where, "%r is not an integer" % (value,))
    if not np.isfinite(x):
        _fail(where, "%r is not a finite number" % (value,))
    return x


def _check_keys(where, d, allowed):
    if not isinstance(d, dict):
        _fail(where, "expected a mapping of keys (%s), got %r" % (", ".join(sorted(allowed)), d))
    for k in d:
        if k not in allowed:
            import difflib
            close = difflib.get_close_matches(str(k), sorted(allowed), n=1)
            hint = " (did you mean '%s'?)" % close[0] if close else ""
            _fail(where, "unknown key '%s'%s; allowed keys: %s" % (k, hint, ", ".join(sorted(allowed))))


def _apply_overrides(spec, where):
    """-scene.<path> <value> PETSc options replace scene values; unknown paths are errors."""
    opts = PETSc.Options().getAll()
    for name, raw in sorted(opts.items()):
        if not name.startswith("scene."):
            continue
        path = name[len("scene."):].split(".")
        if raw is None or str(raw) == "":
            _fail(where, "option -%s needs a value, e.g. -%s 0,30,60" % (name, name))
        text = str(raw)
        if "," in text and not text.strip().startswith(("[", "{")):
            text = "[" + text + "]"
        value = yaml.safe_load(text) if text != "" else True
        node = spec
        for i, key in enumerate(path[:-1]):
            if not isinstance(node, dict) or key not in node:
                if isinstance(node, dict) and key in ("reduction", "verify") and i == 0:
                    node[key] = {}
                else:
                    _fail(where, "option -%s: the scene has no entry '%s'" % (name, ".".join(path[:i + 1])))
            node = node[key]
        if not isinstance(node, dict):
            _fail(where, "option -%s: '%s' is not a mapping" % (name, ".".join(path[:-1])))
        node[path[-1]] = value


def _read_nodes(where, entry, base):
    """Nodes inline ([[id, x, y, z, ndof], ...]) or from a file ('id x y z ndof' per line)."""
    if isinstance(entry, str):
        path = os.path.join(base, entry)
        if not os.path.isfile(path):
            _fail(where, "nodes file '%s' not found (looked for %s)" % (entry, os.path.abspath(path)))
        rows = []
        with open(path) as f:
            for lineno, line in enumerate(f, 1):
                line = line.split("#", 1)[0].strip()
                if not line:
                    continue
                parts = line.split()
                if len(parts) != 5:
                    _fail(where, "%s line %d: expected 'id x y z ndof', got %r" % (entry, lineno, line))
                try:
                    rows.append((int(parts[0]), float(parts[1]), float(parts[2]), float(parts[3]), int(parts[4])))
                except ValueError:
                    _fail(where, "%s line %d: not numbers: %r" % (entry, lineno, line))
    elif isinstance(entry, (list, np.ndarray)):
        rows = []
        for i, r in enumerate(entry):
            if not isinstance(r, (list, tuple, np.ndarray)) or len(r) != 5:
                _fail(where, "inline node %d must be [id, x, y, z, ndof], got %r" % (i, r))
            rows.append((int(r[0]), float(r[1]), float(r[2]), float(r[3]), int(r[4])))
    else:
        _fail(where, "give a nodes file name or an inline list of [id, x, y, z, ndof]")
    if not rows:
        _fail(where, "no nodes")
    ids = np.array([r[0] for r in rows], dtype=np.intc)
    xyz = np.array([r[1:4] for r in rows], dtype=np.float64)
    ndof = np.array([r[4] for r in rows], dtype=np.intc)
    return ids, xyz, ndof


def _angles(where, raw, revolute):
    """Configurations as a list of lists of degrees, one entry per revolute joint in scene order."""
    nr = len(revolute)
    if raw is None:
        if nr:
            _fail(where, "'angles' is missing: list the articulation angles of interest in degrees, e.g. angles: [0, 30, 60]")
        return [[]]
    if not isinstance(raw, list):
        raw = [raw]
    if not raw:
        _fail(where, "'angles' is an empty list: give at least one configuration, e.g. angles: [0, 30, 60]")
    configs = []
    for i, c in enumerate(raw):
        if isinstance(c, dict):
            missing = [j for j in revolute if j not in c]
            extra = [j for j in c if j not in revolute]
            if missing or extra:
                _fail(where, "angles[%d]: give one angle per revolute joint (%s); missing %s, unknown %s"
                      % (i, ", ".join(revolute), missing or "none", extra or "none"))
            c = [c[j] for j in revolute]
        elif not isinstance(c, list):
            c = [c]
        if len(c) != nr:
            _fail(where, "angles[%d] = %r: the scene has %d revolute joint(s) (%s); give %d angle(s) per configuration"
                  % (i, c, nr, ", ".join(revolute) or "none", nr))
        try:
            configs.append([float(x) for x in c])
        except (TypeError, ValueError):
            _fail(where, "angles[%d] = %r: angles are numbers in degrees" % (i, c))
        if not all(np.isfinite(configs[-1])):
            _fail(where, "angles[%d]: not finite" % i)
    return configs


def _as_petsc(where, A, comm):
    """A body matrix given in memory: a petsc4py Mat as is, a SciPy sparse or NumPy array distributed as AIJ."""
    if isinstance(A, PETSc.Mat):
        return A
    try:
        import scipy.sparse as sp
        A = sp.csr_matrix(A, dtype=np.float64)
    except Exception as e:  # noqa: BLE001 - whatever it is, it is not a matrix
        _fail(where, "expected a file name, a petsc4py Mat, a SciPy sparse matrix or a NumPy array (%s)" % e)
    n, m = A.shape
    if n != m:
        _fail(where, "the matrix is %d x %d; body matrices are square" % (n, m))
    if not np.all(np.isfinite(A.data)):
        _fail(where, "the matrix holds non-finite values")
    M = PETSc.Mat().createAIJ((n, n), comm=comm)
    M.setPreallocationNNZ(0)
    lo, hi = M.getOwnershipRange()
    local = A[lo:hi]
    M.setPreallocationCSR((local.indptr, local.indices, local.data))
    M.assemble()
    return M


class Scene:
    """A loaded scene: the C scene plus the names and settings the reduction and the report need."""

    def __init__(self, spec, path=None, comm=None):
        self.path = os.path.abspath(path) if path else None
        where = os.path.basename(path) if path else "scene"
        base = os.path.dirname(self.path) if path else os.getcwd()
        self.comm = comm or PETSc.COMM_WORLD
        if not isinstance(spec, dict):
            _fail(where, "a scene is a YAML mapping with bodies, joints, inputs, outputs, angles")
        _check_keys(where, spec, TOP_KEYS)
        for key in ("bodies", "inputs", "outputs"):
            if not spec.get(key):
                _fail(where, "'%s' is missing or empty" % key)
        self.spec = spec
        self.name = str(spec.get("name", os.path.splitext(os.path.basename(path))[0] if path else "scene"))
        self.cscene = _core.CScene(self.comm)
        self.cscene.set_name(self.name)   # recorded in reduced models, with the input and output names

        # bodies
        bodies = spec["bodies"]
        if not isinstance(bodies, dict):
            _fail(where, "'bodies' must map body names to {mass, stiffness, nodes, interfaces}")
        self.body_names, self.body_dofs, self.interfaces = [], [], []
        self.body_nodes = []
        for bname, b in bodies.items():
            bw = "%s: bodies.%s" % (where, bname)
            _check_keys(bw, b, BODY_KEYS)
            for key in ("mass", "stiffness", "nodes"):
                if key not in b:
                    _fail(bw, "'%s' is missing" % key)
            mats = []
            for key in ("mass", "stiffness"):
                if not isinstance(b[key], str):
                    mats.append(_as_petsc(bw + "." + key, b[key], self.comm))
                    continue
                fpath = os.path.join(base, str(b[key]))
                if not os.path.isfile(fpath):
                    _fail(bw + "." + key, "file '%s' not found (looked for %s); fix the path (relative to the scene file)"
                          % (b[key], os.path.abspath(fpath)))
                try:
                    mats.append(_core.load_matrix(fpath, self.comm))
                except _core.Error as e:
                    _fail(bw + "." + key, str(e))
                if not PETSc.Options().getBool("kf_quiet", False):
                    _core.progress("loaded %s of body '%s': %s (%d dofs)" % (key, bname, b[key], mats[-1].getSize()[0]),
                                   self.comm)
            ids, xyz, ndof = _read_nodes(bw + ".nodes", b["nodes"], base)
            try:
                index = self.cscene.add_body(bname, mats[0], mats[1], ids, xyz, ndof)
            except _core.Error as e:
                _fail(bw, str(e))
            ifaces = b.get("interfaces") or {}
            if not isinstance(ifaces, dict):
                _fail(bw + ".interfaces", "map interface names to node ids, e.g. {bearing: 101}")
            names = []
            for iname, node in ifaces.items():
                try:
                    self.cscene.add_interface(index, iname, _number(bw + ".interfaces." + str(iname), node, int))
                except (_core.Error, TypeError, ValueError) as e:
                    _fail(bw + ".interfaces." + str(iname), str(e))
                names.append(str(iname))
            self.body_names.append(str(bname))
            self.body_dofs.append(int(ndof.sum()))
            self.interfaces.append(names)
            self.body_nodes.append((ids, xyz, ndof))

        # joints
        joints = spec.get("joints") or {}
        if not isinstance(joints, dict):
            _fail(where, "'joints' must map joint names to {type, parent, parent_interface, child, child_interface, axis}")
        if len(self.body_names) > 1 and not joints:
            _fail(where, "%d bodies but no joints: every body but one must be attached by a joint" % len(self.body_names))
        self.joints, self.revolute = [], []
        for jname, j in joints.items():
            jw = "%s: joints.%s" % (where, jname)
            _check_keys(jw, j, JOINT_KEYS)
            kind = j.get("type", "revolute")
            if kind not in ("revolute", "fixed"):
                _fail(jw + ".type", "'%s' is not a joint type: use revolute or fixed" % kind)
            for key in ("parent", "child", "parent_interface", "child_interface"):
                if key not in j:
                    _fail(jw, "'%s' is missing" % key)
            for key in ("parent", "child"):
                if j[key] not in self.body_names:
                    _fail(jw + "." + key, "body '%s' does not exist (bodies: %s)" % (j[key], ", ".join(self.body_names)))
            p, c = self.body_names.index(j["parent"]), self.body_names.index(j["child"])
            for key, b in (("parent_interface", p), ("child_interface", c)):
                if str(j[key]) not in self.interfaces[b]:
                    _fail(jw + "." + key, "body '%s' has no interface '%s' (it has: %s); declare it under bodies.%s.interfaces"
                          % (self.body_names[b], j[key], ", ".join(self.interfaces[b]) or "none", self.body_names[b]))
            axis = j.get("axis", [0, 0, 1])
            if kind == "revolute" and (not isinstance(axis, list) or len(axis) != 3):
                _fail(jw + ".axis", "give the rotation axis as [x, y, z] in the parent body's frame")
            axis = [_number(jw + ".axis", x) for x in axis] if isinstance(axis, list) else axis
            R0 = j.get("orientation")
            if R0 is not None:
                R0 = np.asarray(R0, dtype=np.float64)
                if R0.shape != (3, 3):
                    _fail(jw + ".orientation", "give a 3x3 rotation matrix (rows)")
            try:
                self.cscene.add_joint(jname, kind, p, str(j["parent_interface"]), c, str(j["child_interface"]), axis, R0)
            except _core.Error as e:
                _fail(jw, str(e))
            self.joints.append(dict(name=str(jname), type=kind, parent=p, child=c,
                                    parent_interface=self.interfaces[p].index(str(j["parent_interface"])),
                                    child_interface=self.interfaces[c].index(str(j["child_interface"])),
                                    axis=[float(x) for x in axis] if kind == "revolute" else [0.0, 0.0, 1.0],
                                    R0=None if R0 is None else R0.tolist()))
            if kind == "revolute":
                self.revolute.append(str(jname))

        # inputs and outputs
        for key in ("inputs", "outputs"):
            if not isinstance(spec[key], dict):
                _fail(where + ": " + key, "map %s names to lists of {body, node, dof, weight} terms" % key)
        self.cscene.set_num_io(len(spec["inputs"]), len(spec["outputs"]))
        self.input_names = self._io(where, "inputs", spec["inputs"], base, True)
        self.output_names = self._io(where, "outputs", spec["outputs"], base, False)
        for is_input, names in ((True, self.input_names), (False, self.output_names)):
            for i, name in enumerate(names):
                try:
                    self.cscene.set_io_name(is_input, i, name)
                except _core.Error as e:
                    _fail(where + (": inputs." if is_input else ": outputs.") + name, str(e))

        # what the reduction must serve
        self.configurations = _angles(where + ": angles", spec.get("angles"), self.revolute)
        band = spec.get("band", [0.01, 10.0])
        if not isinstance(band, list) or len(band) != 2:
            _fail(where + ": band", "give [f_low, f_high] in Hz, got %r" % (band,))
        band = [_number(where + ": band", x) for x in band]
        if not 0 < band[0] < band[1]:
            _fail(where + ": band", "give [f_low, f_high] in Hz with 0 < f_low < f_high, got %r" % (band,))
        self.band = band
        self.damping = _number(where + ": damping", spec.get("damping", 0.0025))
        if not 0 < self.damping < 1:
            _fail(where + ": damping", "the modal damping ratio must lie in (0, 1), got %g" % self.damping)
        self.accuracy = _number(where + ": accuracy", spec.get("accuracy", 0.05))
        red = dict(REDUCTION_DEFAULTS)
        given = spec.get("reduction") or {}
        _check_keys(where + ": reduction", given, set(REDUCTION_DEFAULTS))
        red.update(given)
        for key in ("moments", "output_blocks"):
            red[key] = _number(where + ": reduction." + key, red[key], int)
        for key in ("keep_threshold", "deflation_tol", "body_tol", "reassembly_rtol", "shift", "eigen_cover"):
            red[key] = _number(where + ": reduction." + key, red[key])
        if red["moments"] < 1 or red["output_blocks"] < 0 or red["moments"] <= red["output_blocks"]:
            _fail(where + ": reduction", "moments (%s) must exceed output_blocks (%s) >= 0" % (red["moments"], red["output_blocks"]))
        if red["importance"] not in _core.IMPORTANCE:
            _fail(where + ": reduction.importance", "'%s' is not one of %s" % (red["importance"], ", ".join(_core.IMPORTANCE)))
        if red["basis"] not in ("krylov", "eigen"):
            _fail(where + ": reduction.basis", "'%s' is not krylov or eigen" % red["basis"])
        if red["method"] not in ("single-angle", "multi-angle"):
            _fail(where + ": reduction.method", "'%s' is not single-angle or multi-angle" % red["method"])
        if red["reduction_angle"] != "auto":
            red["reduction_angle"] = _angles(where + ": reduction.reduction_angle", [red["reduction_angle"]]
                                             if not isinstance(red["reduction_angle"], list) or len(self.revolute) > 1
                                             and not isinstance(red["reduction_angle"][0], list) else red["reduction_angle"],
                                             self.revolute)[0]
        if red["reduction_angles"] is not None:
            red["reduction_angles"] = _angles(where + ": reduction.reduction_angles", red["reduction_angles"], self.revolute)
        self.reduction = red
        ver = dict(VERIFY_DEFAULTS)
        given = spec.get("verify") or {}
        _check_keys(where + ": verify", given, set(VERIFY_DEFAULTS))
        ver.update(given)
        self.verify = ver
        try:
            self.cscene.setup()
        except _core.Error as e:
            _fail(where, str(e))
        self.info = self.cscene.info()

    def _io(self, where, key, entries, base, is_input):
        if not isinstance(entries, dict):
            _fail(where + ": " + key, "map %s names to lists of {body, node, dof, weight} terms" % key)
        names = list(entries)
        for k, (name, terms) in enumerate(entries.items()):
            w = "%s: %s.%s" % (where, key, name)
            if isinstance(terms, dict):
                terms = [terms]
            if not isinstance(terms, list) or not terms:
                _fail(w, "give a list of {body, node, dof, weight} terms")
            for i, t in enumerate(terms):
                tw = "%s[%d]" % (w, i)
                _check_keys(tw, t, TERM_KEYS)
                if t.get("body") not in self.body_names:
                    _fail(tw + ".body", "body '%s' does not exist (bodies: %s)" % (t.get("body"), ", ".join(self.body_names)))
                b = self.body_names.index(t["body"])
                weight = _number(tw + ".weight", t.get("weight", 1.0))
                if "vector" in t:
                    vec = self._vector(tw, b, os.path.join(base, str(t["vector"])))
                    (self.cscene.add_input_vector if is_input else self.cscene.add_output_vector)(k, b, vec)
                    continue
                if "node" not in t or "dof" not in t:
                    _fail(tw, "give node and dof (%s), or a vector file" % ", ".join(DOF_NAMES))
                if t["dof"] not in DOF_NAMES:
                    _fail(tw + ".dof", "'%s' is not a dof name: use one of %s" % (t["dof"], ", ".join(DOF_NAMES)))
                try:
                    (self.cscene.add_input_load if is_input else self.cscene.add_output_reading)(
                        k, b, _number(tw + ".node", t["node"], int), DOF_NAMES[t["dof"]], weight)
                except (_core.Error, TypeError, ValueError) as e:  # ValueError: a node id that is not an integer
                    _fail(tw, str(e))
        return [str(n) for n in names]

    def _vector(self, where, b, path):
        if not os.path.isfile(path):
            _fail(where + ".vector", "file %s not found" % path)
        try:
            if path.endswith(".mtx"):
                import scipy.io
                m = scipy.io.mmread(path)
                data = np.asarray(m.todense() if hasattr(m, "todense") else m).ravel()
            else:
                data = np.loadtxt(path, comments=("#", "%")).ravel()
        except Exception as e:  # noqa: BLE001 - any parse failure is a bad file
            _fail(where + ".vector", "cannot read %s: %s" % (path, e))
        if data.size != self.body_dofs[b]:
            _fail(where + ".vector", "%s has %d entries, body '%s' has %d dofs" % (path, data.size, self.body_names[b], self.body_dofs[b]))
        vec = PETSc.Vec().createMPI(self.body_dofs[b], comm=self.comm)
        lo, hi = vec.getOwnershipRange()
        vec.setArray(data[lo:hi])
        return vec

    def angles_rad(self, config):
        return np.radians(np.asarray(config, dtype=np.float64))

    @staticmethod
    def label(config):
        return "_".join("%g" % a for a in config) if config else "fixed"


def scene_from_dict(spec, comm=None, base=None):
    """A scene built in a script: the same keys as a scene file; body matrices may be petsc4py Mats, SciPy sparse
    matrices or NumPy arrays, and nodes an array of rows (id, x, y, z, ndof). Relative file names are taken from
    base (default: the working folder)."""
    return Scene(spec, os.path.join(base, "scene.yaml") if base else None, comm)


def load_scene(path, comm=None, overrides=True):
    """Reads a scene file (YAML) and its body files; -scene.<path> PETSc options override its values."""
    where = os.path.basename(str(path))
    if not os.path.isfile(path):
        raise SceneError("%s: scene file not found (looked for %s)" % (where, os.path.abspath(path)))
    try:
        with open(path) as f:
            spec = yaml.safe_load(f)
    except yaml.YAMLError as e:
        raise SceneError("%s: not valid YAML: %s" % (where, e)) from None
    if overrides:
        _apply_overrides(spec if isinstance(spec, dict) else {}, where)
    return Scene(spec, path, comm)
