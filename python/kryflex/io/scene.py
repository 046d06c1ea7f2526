"""Scene files: bodies, joints, inputs, outputs and what the reduction must serve.

A scene is one YAML file (docs/reference/scene-file.md). Every value can be overridden from the command
line with a PETSc option named after its path: ``-scene.damping 0.005``, ``-scene.reduction.moments 12``,
``-scene.angles 0,30,60``. Loading goes from cheap to expensive, so that a mistake anywhere is found before any
heavy work: the YAML (io/yaml_load.py: size, nesting, aliases, duplicate keys), every key and value
(io/scene_schema.py), the files the scene names (present, readable; nodes and vectors read and checked), and only
then the body matrices. Errors are SceneError, naming the entry, the value and the fix.
"""
import io
import os
import re
import warnings

import numpy as np
from petsc4py import PETSc

from .. import _core
from .._runtime import quiet_progress
from . import scene_schema as schema
from .scene_schema import NO_JOINT_LABEL
from . import yaml_load
from .scene_schema import (DOF_NAMES, TOP_KEYS, BODY_KEYS, JOINT_KEYS, TERM_KEYS,  # noqa: F401 - the scene's keys
                           REDUCTION_DEFAULTS, VERIFY_DEFAULTS, SceneError)


def _fail(where, msg):
    raise SceneError("%s: %s" % (where, msg))


def _override_path(where, option, path, spec):
    """Checks a -scene.<path> option's path against the scene's keys (did-you-mean on a typo)."""
    w = "option -" + option
    if path[0] not in TOP_KEYS:
        schema.fail(where, w, schema.unknown_key(path[0], TOP_KEYS).replace("unknown key", "the scene has no entry", 1))
    section = path[0]
    if section in ("reduction", "verify"):
        if len(path) != 2:
            schema.fail(where, w, "give one %s key, e.g. -scene.%s.%s" % (section, section,
                                                                        sorted(schema.SECTION_KEYS[section])[0]))
        if path[1] not in schema.SECTION_KEYS[section]:
            schema.fail(where, w, schema.unknown_key(path[1], schema.SECTION_KEYS[section]))
    elif section in ("bodies", "joints", "inputs", "outputs") and len(path) > 1:
        names = spec.get(section) if isinstance(spec.get(section), dict) else {}
        if path[1] not in names:
            close = schema.unknown_key(path[1], set(map(str, names))).split(";")[0].replace("unknown key", "no entry")
            schema.fail(where, w, "the scene's %s have %s; use one of: %s" % (section, close,
                                                                             ", ".join(map(str, names)) or "none"))
        if section in schema.SECTION_KEYS and len(path) > 2 and path[2] not in schema.SECTION_KEYS[section]:
            schema.fail(where, w, schema.unknown_key(path[2], schema.SECTION_KEYS[section]))
    elif len(path) > 1:
        schema.fail(where, w, "'%s' has no keys below it; give -scene.%s VALUE" % (section, section))


def _apply_overrides(spec, where):
    """-scene.<path> <value> PETSc options replace scene values; the paths are checked here, the values with the
    rest of the scene."""
    opts = PETSc.Options().getAll()
    for name, raw in sorted(opts.items()):
        if not name.startswith("scene."):
            continue
        path = name[len("scene."):].split(".")
        if raw is None or str(raw) == "":
            _fail(where, "option -%s: no value; give one after the option, e.g. -%s %s"
                  % (name, name, "0,30,60" if path[-1] in ("angles", "reduction_angles", "band") else "VALUE"))
        _override_path(where, name, path, spec)
        text = str(raw)
        if "," in text and not text.strip().startswith(("[", "{")):
            text = "[" + text + "]"
        try:
            value = yaml_load.load_text(text)
        except yaml_load.YAMLInputError as e:
            _fail(where, "option -%s: %s" % (name, e))
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


# ------------------------------------------------------------------ the files a scene names

def _file(where, key, name, base, what="file"):
    """The path of a file the scene names, checked to be a readable regular file."""
    path = os.path.join(base, name)
    if not os.path.exists(path):
        _fail("%s: %s" % (where, key), "%s '%s' not found (looked for %s); fix the path (relative to the scene file)"
              % (what, name, os.path.abspath(path)))
    if not os.path.isfile(path):
        _fail("%s: %s" % (where, key), "'%s' is %s (%s); give the path of the %s itself"
              % (name, _not_a_file(path), os.path.abspath(path), what))
    if not os.access(path, os.R_OK):
        _fail("%s: %s" % (where, key), "%s '%s' is not readable; give read permission (chmod +r %s)"
              % (what, name, os.path.abspath(path)))
    return path


def _not_a_file(path):
    """What a path that exists but is no regular file is, for the messages."""
    return "a folder, not a file" if os.path.isdir(path) else "not a regular file"


def _text_lines(where, key, path, name):
    """(line number, text) of the non-empty lines of a small text file, '#' (and '%') comments removed."""
    try:
        with open(path, "rb") as f:
            data = f.read()
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        _fail("%s: %s" % (where, key), "%s is not UTF-8 text at byte %d; save it as plain text" % (name, e.start))
    except OSError as e:
        _fail("%s: %s" % (where, key), "cannot read %s (%s); check the file" % (name, e.strerror))
    for lineno, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].split("%", 1)[0].strip()
        if line:
            yield lineno, line


# a nodes file's columns as NumPy's C reader takes them: integer id and ndof, three reals
_NODE_COLUMNS = np.dtype([("id", np.int64), ("x", np.float64), ("y", np.float64), ("z", np.float64),
                          ("ndof", np.int64)])
# line breaks str.splitlines() takes beside \n (and \r\n), which NumPy's reader does not
_OTHER_BREAKS = re.compile("[\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029]")


def _node_file_rows(path):
    """The rows of a nodes file as an (n, 5) float64 array, read by NumPy's C reader (a 57k-dof solid's two files in
    a third of the time of the line-by-line reader below), or None wherever that reader might take the file otherwise
    than _read_nodes' lines do: text that is not UTF-8, other line breaks, a value that is not a plain integer id or
    ndof (c345, s: other layouts) or a number; the line-by-line reader then reads it and names any bad line."""
    try:
        with open(path, "rb") as f:
            text = f.read().decode("utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    text = text.replace("\r\n", "\n")
    if _OTHER_BREAKS.search(text):
        return None
    # a comment runs from the first '#' or '%' to the line's end: as '#' both, the C reader's one comment character
    # (given two, NumPy strips them line by line in Python)
    text = text.replace("%", "#")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")      # an empty file's warning: no rows, said by the reader below
            cols = np.loadtxt(io.StringIO(text), dtype=_NODE_COLUMNS, comments="#", ndmin=1)
    except (ValueError, TypeError, UserWarning):
        return None
    A = np.empty((cols.shape[0], 5))
    for i, name in enumerate(_NODE_COLUMNS.names):
        A[:, i] = cols[name]
    return A


def _read_nodes(where, key, name, base):
    """A nodes file: 'id x y z ndof' per line, '#' comments; checked by the same rules as inline nodes."""
    path = _file(where, key, name, base, "nodes file")
    rows = _node_file_rows(path)
    table = schema.node_array_table(rows) if rows is not None else None
    if table is not None:
        return table
    rows, labels = [], []
    for lineno, line in _text_lines(where, key, path, name):
        parts = line.split()
        if len(parts) != 5:
            _fail("%s: %s" % (where, key), "%s line %d: %r is not 'id x y z ndof'; give five numbers per line"
                  % (name, lineno, line[:80]))
        try:
            dofs = parts[4] if parts[4][:1] in ("c", "s") else int(parts[4])   # c345, s: other layouts
            rows.append([int(parts[0]), float(parts[1]), float(parts[2]), float(parts[3]), dofs])
        except ValueError:
            _fail("%s: %s" % (where, key), "%s line %d: %r is not numbers; give 'id x y z ndof' (integer id and "
                  "ndof)" % (name, lineno, line[:80]))
        labels.append("%s line %d" % (name, lineno))
    if not rows:
        _fail("%s: %s" % (where, key), "%s lists no nodes; give 'id x y z ndof' per line" % name)
    return schema.node_table(where, key, rows, labels)


def _read_vector(where, key, name, base):
    """A load or reading vector file: numbers (text, any layout) or Matrix Market (.mtx)."""
    path = _file(where, key, name, base, "vector file")
    if path.endswith(".mtx"):
        try:
            import scipy.io
            m = scipy.io.mmread(path)
            return np.asarray(m.todense() if hasattr(m, "todense") else m, dtype=np.float64).ravel()
        except Exception as e:  # noqa: BLE001 - any parse failure is a bad file
            _fail("%s: %s" % (where, key), "cannot read %s as Matrix Market (%s); re-export it"
                  % (name, " ".join(str(e).split())[:120]))
    data = []
    for lineno, line in _text_lines(where, key, path, name):
        for word in line.replace(",", " ").split():
            try:
                x = float(word)
            except ValueError:
                _fail("%s: %s" % (where, key), "%s line %d (%r): %r is not a number; give one number per dof"
                      % (name, lineno, line[:80], word[:40]))
            if not np.isfinite(x):
                _fail("%s: %s" % (where, key), "%s line %d: %r is not finite; give finite numbers"
                      % (name, lineno, word[:40]))
            data.append(x)
    return np.array(data, dtype=np.float64)


def _as_petsc(where, A, comm):
    """A body matrix given in memory: a petsc4py Mat as is, a SciPy sparse or NumPy array distributed as AIJ."""
    if isinstance(A, PETSc.Mat):
        if A.getComm().getSize() == comm.getSize():
            return A
        if A.getComm().getSize() > 1:
            _fail(where, "the petsc4py Mat lives on %d ranks but the scene on %d; create it on the scene's "
                  "communicator, or give a SciPy/NumPy matrix" % (A.getComm().getSize(), comm.getSize()))
        import scipy.sparse as sp
        indptr, indices, data = A.getValuesCSR()      # a sequential Mat (the same on every rank): distributed below
        A = sp.csr_matrix((data, indices, indptr), shape=A.getSize())
    try:
        import scipy.sparse as sp
        A = sp.csr_matrix(A, dtype=np.float64)
    except Exception as e:  # noqa: BLE001 - whatever it is, it is not a matrix
        _fail(where, "expected a file name, a petsc4py Mat, a SciPy sparse matrix or a NumPy array (%s)" % e)
    n, m = A.shape
    if n != m:
        _fail(where, "the matrix is %d x %d; body matrices are square" % (n, m))
    if not np.all(np.isfinite(A.data)):
        _fail(where, "the matrix holds non-finite values (NaN or Inf); give finite entries")
    M = PETSc.Mat().createAIJ((n, n), comm=comm)
    M.setPreallocationNNZ(0)
    lo, hi = M.getOwnershipRange()
    local = A[lo:hi]
    M.setPreallocationCSR((local.indptr, local.indices, local.data))
    M.assemble()
    return M


# ------------------------------------------------------------------ one resolver for every key that takes a file or data

RESOLVED_KINDS = ("matrix", "vector", "dense", "nodes")


def resolve(where, key, value, base, kind, comm=None):
    """The value of a scene key that takes a file or, in a Python scene, the data itself: every such key is read
    here, so each accepts the same things.

    kind 'matrix': a sparse body matrix (mass, stiffness, damping): a Matrix Market / PETSc binary file, a petsc4py
                   Mat, a SciPy sparse matrix or a NumPy array -> a petsc4py Mat on comm.
         'vector': a load or reading vector over a body: a text or Matrix Market file, a 1-D NumPy array or list, an
                   n x 1 SciPy matrix, a petsc4py Vec -> a 1-D float64 array (checked finite by the caller's rule).
         'dense':  a small dense block (e.g. rigid-body modes, n x r): a text (one row per line), .npy or .mtx file,
                   a 2-D array, a list of rows, a SciPy sparse matrix or a petsc4py Mat -> a 2-D float64 array.
         'nodes':  a nodes file, an (n, 5) array or a list of (id, x, y, z, dofs) rows -> (ids, xyz, ndof).
    Errors are SceneError naming '<where>: <key>', the value and the fix."""
    if kind not in RESOLVED_KINDS:
        raise ValueError("resolve: kind %r is not one of %s" % (kind, ", ".join(RESOLVED_KINDS)))
    named = isinstance(value, (str, os.PathLike))
    if kind == "nodes":
        return _read_nodes(where, key, os.fspath(value), base) if named else schema.node_table(where, key, value)
    if kind == "matrix":
        if named:
            path = _file(where, key, os.fspath(value), base, "matrix file")
            try:
                return _core.load_matrix(path, comm or PETSc.COMM_WORLD)
            except _core.Error as e:
                _fail("%s: %s" % (where, key), str(e))
        return _as_petsc("%s: %s" % (where, key), value, comm or PETSc.COMM_WORLD)
    if kind == "vector":
        if named:
            return _read_vector(where, key, os.fspath(value), base)
        return _memory_array(where, key, value, 1)
    if named:
        return _read_dense(where, key, os.fspath(value), base)
    return _memory_array(where, key, value, 2)


def _memory_array(where, key, value, ndim):
    """Data given in memory as a float64 array of ndim dimensions (a vector: any n, n x 1 or 1 x n shape)."""
    w = "%s: %s" % (where, key)
    what = "a vector (1-D array)" if ndim == 1 else "a 2-D array"
    try:
        if isinstance(value, PETSc.Vec):
            scatter, full = PETSc.Scatter.toAll(value)
            scatter.scatter(value, full, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
            data = full.getArray().copy()
            scatter.destroy()
            full.destroy()
        elif isinstance(value, PETSc.Mat):
            if value.getComm().getSize() > 1:
                _fail(w, "a petsc4py Mat on %d ranks: give %s as a NumPy array (the same on every rank)"
                      % (value.getComm().getSize(), what))
            indptr, indices, vals = value.getValuesCSR()
            import scipy.sparse as sp
            data = sp.csr_matrix((vals, indices, indptr), shape=value.getSize()).toarray()
        elif hasattr(value, "toarray"):
            data = value.toarray()
        else:
            data = np.asarray(value, dtype=np.float64)
        data = np.asarray(data, dtype=np.float64)
    except SceneError:
        raise
    except (TypeError, ValueError) as e:
        _fail(w, "%s is not numeric data (%s); give %s of numbers" % (type(value).__name__, e, what))
    if ndim == 1 and data.ndim == 2 and 1 in data.shape:
        data = data.ravel()
    if data.ndim != ndim:
        _fail(w, "the array has shape %s; give %s" % (data.shape, what))
    if data.size == 0:
        _fail(w, "the array is empty; give %s with one entry per dof" % what)
    if not np.all(np.isfinite(data)):
        _fail(w, "the array holds non-finite values (NaN or Inf); give finite numbers")
    return data


def _read_dense(where, key, name, base):
    """A small dense matrix file: .npy, Matrix Market (.mtx), or text with one row per line."""
    path = _file(where, key, name, base, "matrix file")
    w = "%s: %s" % (where, key)
    try:
        if path.endswith(".npy"):
            data = np.load(path, allow_pickle=False)
        elif path.endswith(".mtx"):
            import scipy.io
            m = scipy.io.mmread(path)
            data = m.toarray() if hasattr(m, "toarray") else m
        else:
            rows = [[float(x) for x in line.replace(",", " ").split()] for _, line in _text_lines(where, key, path, name)]
            if len({len(r) for r in rows}) > 1:
                _fail(w, "%s has rows of different lengths; give one row of the matrix per line" % name)
            data = np.array(rows)
    except SceneError:
        raise
    except Exception as e:  # noqa: BLE001 - any parse failure is a bad file
        _fail(w, "cannot read %s as a matrix (%s); give .npy, .mtx or one row of numbers per line"
              % (name, " ".join(str(e).split())[:120]))
    return _memory_array(where, key, data, 2)


class Scene:
    """A loaded scene: the C scene plus the names and settings the reduction and the report need."""

    def __init__(self, spec, path=None, comm=None):
        self.path = os.path.abspath(path) if path else None
        where = os.path.basename(path) if path else "scene"
        base = os.path.dirname(self.path) if path else os.getcwd()
        self.comm = comm or PETSc.COMM_WORLD
        valid = schema.validate(spec, where, os.path.splitext(os.path.basename(path))[0] if path else "scene")
        self.spec = spec
        self.name = valid["name"]
        bodies = valid["bodies"]

        # the files the scene names, before any matrix is loaded: the matrix files present and readable, the
        # (small) nodes and vector files read and checked against each other
        mats = {}
        for body in bodies:
            for key in ("mass", "stiffness", "damping"):
                if isinstance(body.get(key), str):
                    mats[body["name"], key] = _file(where, "bodies.%s.%s" % (body["name"], key), body[key], base,
                                                    "matrix file")
        nodes = [body["nodes"] if not isinstance(body["nodes"], str) else
                 resolve(where, "bodies.%s.nodes" % body["name"], body["nodes"], base, "nodes") for body in bodies]
        schema.check_node_references(where, valid, nodes)
        dofs = [int(nd.sum()) for _, _, nd in nodes]
        vectors = {}
        for key in ("inputs", "outputs"):
            for ioname, terms in valid[key]:
                for i, t in enumerate(terms):
                    if "vector" in t:
                        tpath = "%s.%s[%d].vector" % (key, ioname, i)
                        data = resolve(where, tpath, t["vector"], base, "vector")
                        label = t["vector"] if isinstance(t["vector"], str) else "array"
                        vectors[key, ioname, i] = t["weight"] * schema.check_vector(
                            where, "%s (%s)" % (tpath, label), data, bodies[t["body"]]["name"], dofs[t["body"]])

        # the C scene
        self.cscene = _core.CScene(self.comm)
        self.cscene.set_name(self.name)   # recorded in reduced models, with the input and output names
        self.body_names = [body["name"] for body in bodies]
        self.matrix_files = mats               # {(body, "mass" | "stiffness"): path} for bodies given as files
        self.body_dofs = dofs
        self.body_nodes = nodes
        self.interfaces = [[iname for iname, _ in body["interfaces"]] for body in bodies]
        for body, table in zip(bodies, nodes):
            ids, xyz, _ = table
            bw = "%s: bodies.%s" % (where, body["name"])
            M, K = (self._matrix(where, body, key, mats.get((body["name"], key))) for key in ("mass", "stiffness"))
            try:
                index = self.cscene.add_body_components(body["name"], M, K, ids, xyz, table.comps)
                if body.get("damping") is not None:   # the body's viscous damping matrix C_b
                    C = self._matrix(bw + ".damping", body, "damping", mats.get((body["name"], "damping")))
                    self.cscene.set_body_damping(index, C)
                for iname, nid in body["interfaces"]:
                    self.cscene.add_interface(index, iname, nid)
                for c in body["constraints"]:
                    self.cscene.add_constraint(index, c["node"], c["dofs"])
                for c in body["springs"]:
                    self.cscene.add_spring(index, c["node"], c["dof"], c["stiffness"])
            except _core.Error as e:
                _fail(bw, str(e))

        self.joints, self.revolute = [], list(valid["revolute"])
        self.ground_joints = []
        for j in valid["joints"]:
            p, c = j["parent"], j["child"]
            if j.get("ground"):   # a boundary condition on the child, no joint of the tree (no angle)
                try:
                    self.cscene.add_ground_joint(j["name"], j["type"], c, j["child_interface"], j["axis"],
                                                 None if j["R0"] is None else np.array(j["R0"]))
                except _core.Error as e:
                    _fail("%s: joints.%s" % (where, j["name"]), str(e))
                self.ground_joints.append(dict(name=j["name"], type=j["type"], child=c))
                continue
            try:
                self.cscene.add_joint(j["name"], j["type"], p, j["parent_interface"], c, j["child_interface"],
                                      j["axis"], None if j["R0"] is None else np.array(j["R0"]))
            except _core.Error as e:
                _fail("%s: joints.%s" % (where, j["name"]), str(e))
            self.joints.append(dict(name=j["name"], type=j["type"], parent=p, child=c,
                                    parent_interface=self.interfaces[p].index(j["parent_interface"]),
                                    child_interface=self.interfaces[c].index(j["child_interface"]),
                                    axis=j["axis"], R0=j["R0"]))

        self.cscene.set_num_io(len(valid["inputs"]), len(valid["outputs"]))
        self.input_names = [n for n, _ in valid["inputs"]]
        self.output_names = [n for n, _ in valid["outputs"]]
        for key, is_input in (("inputs", True), ("outputs", False)):
            for k, (ioname, terms) in enumerate(valid[key]):
                try:
                    self.cscene.set_io_name(is_input, k, ioname)
                    for i, t in enumerate(terms):
                        if "vector" in t:
                            vec = self._vec(vectors[key, ioname, i])
                            (self.cscene.add_input_vector if is_input else self.cscene.add_output_vector)(k, t["body"], vec)
                        else:
                            (self.cscene.add_input_load if is_input else self.cscene.add_output_reading)(
                                k, t["body"], t["node"], t["dof"], t["weight"])
                    if not is_input and terms[0]["quantity"] != "displacement":
                        self.cscene.set_output_quantity(k, terms[0]["quantity"])
                except _core.Error as e:
                    _fail("%s: %s.%s" % (where, key, ioname), str(e))
        self.output_quantities = [terms[0]["quantity"] for _, terms in valid["outputs"]]

        # what the reduction must serve
        self.configurations = valid["configurations"]
        self.band = valid["band"]
        # damping: the uniform modal ratio (None when the scene gives more than one) and the whole description
        uniform, self.damping_model = valid["damping"]
        self.damping_uniform = uniform is not None
        modal = self.damping_model["modal"]
        self.damping = uniform if uniform is not None else (modal if not isinstance(modal, list) else
                                                            min(z for _, z in modal))
        self.damping_matrices = [b["name"] for b in bodies if b.get("damping") is not None]
        self.accuracy = valid["accuracy"]
        self.accuracy_measure = valid["accuracy_measure"]   # elastic | total: the response the accuracy is stated on
        self.reduction = valid["reduction"]
        self.verify = valid["verify"]
        self.paper = valid["paper"]            # "lee": the report compares with the paper (report/paper.py)
        try:
            self.cscene.setup()
        except _core.Error as e:
            _fail(where, str(e))
        self.info = self.cscene.info()

    def _matrix(self, where, body, key, path):
        """A body matrix: loaded from its (checked) file, or given in memory."""
        A = resolve(where, "bodies.%s.%s" % (body["name"], key), body[key] if path is None else path, "", "matrix",
                    self.comm)
        if path is None:
            return A
        if not PETSc.Options().getBool("kf_quiet", False):
            _core.progress("loaded %s of body '%s': %s (%d dofs)" % (key, body["name"], body[key], A.getSize()[0]),
                           self.comm)
        return A

    def _vec(self, data):
        vec = PETSc.Vec().createMPI(data.size, comm=self.comm)
        lo, hi = vec.getOwnershipRange()
        vec.setArray(data[lo:hi])
        return vec

    def angles_rad(self, config):
        return np.radians(np.asarray(config, dtype=np.float64))

    @staticmethod
    def label(config):
        return "_".join("%g" % a for a in config) if config else NO_JOINT_LABEL


def scene_from_dict(spec, comm=None, base=None, quiet=None):
    """A scene built in a script: the same keys as a scene file, and wherever a key takes a file, the data itself
    (resolve()): body matrices as petsc4py Mats, SciPy sparse matrices or NumPy arrays, nodes as an (n, 5) array
    or a list of (id, x, y, z, dofs) rows, input/output vectors as 1-D arrays or petsc4py Vecs. Relative file
    names are taken from base (default: the working folder). quiet=True: no progress lines while loading."""
    with quiet_progress(quiet):
        return Scene(spec, os.path.join(base, "scene.yaml") if base else None, comm)


def load_scene(path, comm=None, overrides=True, quiet=None):
    """Reads a scene file (YAML) and its body files; -scene.<path> PETSc options override its values. quiet=True: no
    progress lines while loading (the body files read), as Reducer(scene, quiet=True) has none while reducing."""
    where = os.path.basename(str(path))
    if not os.path.isfile(path):
        if os.path.exists(path):
            raise SceneError("%s: is %s (%s); give the path of the scene's .yaml file"
                             % (where, _not_a_file(path), os.path.abspath(path)))
        raise SceneError("%s: scene file not found (looked for %s); fix the path" % (where, os.path.abspath(path)))
    try:
        spec = yaml_load.load_file(path)
    except yaml_load.YAMLInputError as e:
        raise SceneError("%s: %s" % (where, e)) from None
    except OSError as e:
        raise SceneError("%s: cannot read the scene file (%s); check its permissions" % (where, e.strerror)) from None
    if overrides and isinstance(spec, dict):
        _apply_overrides(spec, where)
    with quiet_progress(quiet):
        return Scene(spec, path, comm)
