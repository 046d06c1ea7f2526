"""The rules of a scene, checked on the parsed spec before any file is touched.

validate(spec, where) checks every key (types, ranges, names, references between bodies, interfaces and joints,
the joint tree, angles) and returns the scene in a normalized form that io/scene.py builds from without checking
again. node_table, check_node_references and check_vector are the rules on node lists and load vectors, which
scene.py applies once it has read those (small) files, still before any matrix is loaded. Nothing here reads
files or loads matrices, so a bad value anywhere is reported in milliseconds.

Every message reads "<scene file>: <key path>: <what is wrong, with the value>; <the fix>". The keys that are
settings (reduction.*, verify.*, band, damping, accuracy, accuracy_measure) take their defaults, choices and ranges
from the settings table (src/util/settings_table.c, through kryflex.settings), and their type and range checks are
the JSON Schema made from it (setting()); the ranges refuse at least everything the C setters
(src/reducer/interface.c, src/scene/scene.c) refuse, so that no scene value first fails inside the reducer.
"""
import difflib
import functools
import itertools
import math
import re

import numpy as np

from .. import settings
from .yaml_load import short_repr

DOF_NAMES = {"ux": 0, "uy": 1, "uz": 2, "rx": 3, "ry": 4, "rz": 5, "s": 6}   # s: a scalar point's one dof
ALL_COMPONENTS = 63                   # bit c: component c present (KF_COMPONENTS_ALL); 0: a scalar point
NODE_DOFS = (3, 6)                    # src/scene/scene.c KFSceneAddBody: ux uy uz (+ rx ry rz)
MAX_NODE_ID = 2 ** 31 - 1             # PetscInt is 32-bit in this build
MAX_NAME = 63                         # KF_MAX_NAME (64) holds the terminating NUL
MAX_SCENE_NAME = 255
ORIENTATION_TOL = 1e-6                # orthonormality of a joint orientation as written (7 digits are enough)
# the label of the one configuration of a scene without revolute joints: the structure itself, which has no angle
NO_JOINT_LABEL = "structure"
JOINT_TYPES = ("revolute", "fixed")

TOP_KEYS = {"name", "description", "units", "bodies", "joints", "inputs", "outputs", "angles", "band", "damping",
            "accuracy", "accuracy_measure", "reduction", "verify", "paper"}
PAPERS = ("lee",)                     # paper: lee adds the report's side-by-side section (report/paper.py)
BODY_KEYS = {"mass", "stiffness", "nodes", "interfaces", "description", "constraints", "springs",
             "damping"}
CONSTRAINT_KEYS = {"node", "dofs"}
SPRING_KEYS = {"node", "dof", "stiffness"}
GROUND = "ground"                     # a joint's parent: the child's interface node is grounded
JOINT_KEYS = {"type", "parent", "parent_interface", "child", "child_interface", "axis", "orientation"}
TERM_KEYS = {"body", "node", "dof", "weight", "vector", "quantity"}
QUANTITIES = ("displacement", "velocity", "acceleration")
DAMPING_KEYS = {"modal", "rayleigh", "structural"}
MAX_DAMPING_BANDS = 16                # KF_MAX_DAMPING_BANDS
# The defaults, choices and ranges of the keys that are settings (reduction.*, verify.*, band, damping, accuracy,
# accuracy_measure) are the settings table's (src/util/settings_table.c, kryflex.settings): REDUCTION_DEFAULTS,
# VERIFY_DEFAULTS, DEFAULTS, SECTION_KEYS, IMPORTANCES, BASES, METHODS, FLEX_SOLVERS and ACCURACY_MEASURES are made
# from it on first use (module __getattr__ below), when the binding is loaded.
_CHOICES_OF = {"IMPORTANCES": "-kf_importance", "BASES": "-kf_reducer_type", "METHODS": "-kf_method",
               "FLEX_SOLVERS": "-kf_flex_solver", "ACCURACY_MEASURES": "-kf_accuracy_measure"}


@functools.lru_cache(maxsize=None)
def _from_table(name):
    if name in _CHOICES_OF:
        return tuple(settings.row(_CHOICES_OF[name])["choices"])
    if name == "REDUCTION_DEFAULTS":
        return settings.scene_defaults("reduction")
    if name == "VERIFY_DEFAULTS":
        return settings.scene_defaults("verify")
    if name == "DEFAULTS":      # the top level's keys that have a default (angles has none)
        return {k: v for k, v in settings.scene_defaults("").items() if v is not None}
    if name == "SECTION_KEYS":  # the keys under each section, for -scene.<path> options and did-you-mean hints
        return {"reduction": set(_from_table("REDUCTION_DEFAULTS")), "verify": set(_from_table("VERIFY_DEFAULTS")),
                "bodies": BODY_KEYS, "joints": JOINT_KEYS}
    raise AttributeError("module %r has no attribute %r" % (__name__, name))


def __getattr__(name):
    """The table's constants (see _from_table); the mutable ones copied."""
    v = _from_table(name)
    return {k: (set(x) if isinstance(x, set) else x) for k, x in v.items()} if isinstance(v, dict) else v


NAME_RULE = ("use 1 to %d ASCII letters, digits, '_', '-', '.' or '+', not starting with '.' (names become file "
             "and HDF5 group names)" % MAX_NAME)
_NAME = re.compile(r"[A-Za-z0-9_+-][A-Za-z0-9_.+-]*\Z")


class SceneError(ValueError):
    """A bad scene: the message names the entry, the value and the fix."""


def fail(where, path, msg):
    raise SceneError("%s: %s: %s" % (where, path, msg) if path else "%s: %s" % (where, msg))


def unknown_key(key, allowed):
    """'unknown key ... (did you mean ...?); allowed keys: ...'"""
    close = difflib.get_close_matches(str(key), sorted(allowed), n=1)
    hint = " (did you mean '%s'?)" % close[0] if close else ""
    return "unknown key %s%s; allowed keys: %s" % (short_repr(key), hint, ", ".join(sorted(allowed)))


def unknown_body(value, names):
    """'body ... does not exist (bodies: ...); use one of them (did you mean ...?)'"""
    close = difflib.get_close_matches(str(value), names, n=1)
    hint = " (did you mean '%s'?)" % close[0] if close else ""
    return "body %s does not exist (bodies: %s); use one of them%s" % (short_repr(value), ", ".join(names), hint)


def mapping(where, path, value, allowed=None, what=None):
    """A mapping whose keys are among allowed (None: any)."""
    if not isinstance(value, dict):
        fail(where, path, "%s is not a mapping; give a mapping of %s" % (short_repr(value),
                                                                          what or ", ".join(sorted(allowed))))
    if allowed is not None:
        for k in value:
            if k not in allowed:
                fail(where, path, unknown_key(k, allowed))
    return value


# ------------------------------------------------------------------ values

def _is_number(value):
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


class Interval:
    """An interval written as in the messages: '(0, 1]', '[2, 100000]', '[0, inf)'."""

    def __init__(self, text):
        self.text = text
        self.lo_open, self.hi_open = text[0] == "(", text[-1] == ")"
        lo, hi = text[1:-1].split(",")
        self.lo, self.hi = float(lo), float(hi)

    def __contains__(self, x):
        return ((x > self.lo if self.lo_open else x >= self.lo) and (x < self.hi if self.hi_open else x <= self.hi))


def real(where, path, value, interval, fix=None):
    """A finite number in interval (an Interval or its text)."""
    iv = Interval(interval) if isinstance(interval, str) else interval
    if not _is_number(value):
        fail(where, path, "%s is not a number; %s" % (short_repr(value), fix or "give a number in %s" % iv.text))
    x = float(value)
    if not math.isfinite(x):
        fail(where, path, "%s is not a finite number; %s" % (short_repr(value), fix or "give a value in %s" % iv.text))
    if x not in iv:
        fail(where, path, "%s is outside %s; %s" % (short_repr(value), iv.text, fix or "give a value in %s" % iv.text))
    return x


def integer(where, path, value, interval, fix=None):
    """An integer (10 or 10.0) in interval."""
    iv = Interval(interval) if isinstance(interval, str) else interval
    fix = fix or "give an integer in %s" % iv.text
    if not _is_number(value) or not math.isfinite(float(value)) or float(value) != math.floor(float(value)):
        fail(where, path, "%s is not an integer; %s" % (short_repr(value), fix))
    x = int(value)
    if x not in iv:
        fail(where, path, "%s is outside %s; %s" % (short_repr(value), iv.text, fix))
    return x


def choice(where, path, value, choices):
    if not isinstance(value, str) or value not in choices:
        fail(where, path, "%s is not one of %s; use one of them" % (short_repr(value), ", ".join(choices)))
    return value


@functools.lru_cache(maxsize=None)
def _validator(key, range_text, types_only):
    r = settings.scene_row(key)
    return settings.schema_test(settings.json_schema(r, range_text, types_only))


def setting(where, path, value, fix=None, range_text=None):
    """A scene key that is a setting (its row's scene key is path), checked on the JSON Schema made from the settings
    table: the type, the range (range_text: a narrower one than the option's) and the choices; a value that is not
    a finite number is refused too (JSON has none). Returns the value as its type; the message names the value,
    what is wrong and the fix (fix, or the range)."""
    r = settings.scene_row(path)
    kind, rng = r["type"], range_text or r["range"]
    value = value.item() if isinstance(value, np.generic) else value
    if _validator(path, rng, False)(value) and not (isinstance(value, float) and not math.isfinite(value)):
        if isinstance(value, str) or kind == "enum":
            return value
        return {"bool": bool, "int": int, "real": float}[kind](value)
    if kind == "bool":
        fail(where, path, "%s is not a boolean; give true or false" % short_repr(value))
    if kind == "enum":
        names = [c for c in r["choices"] if c not in ("true", "false")]
        listed = ", ".join(names) + (", true or false" if len(names) < len(r["choices"]) else "")
        fail(where, path, "%s is not one of %s; use one of them" % (short_repr(value), listed)
             if len(names) == len(r["choices"]) else "%s is not %s; use one of them" % (short_repr(value), listed))
    what = "an integer" if kind == "int" else "a number"
    if not _validator(path, rng, True)(value):
        fail(where, path, "%s is not %s; %s" % (short_repr(value), what,
                                                fix or "give %s in %s" % (what if kind == "int" else "a number", rng)))
    if isinstance(value, float) and not math.isfinite(value):
        fail(where, path, "%s is not a finite number; %s" % (short_repr(value), fix or "give a value in %s" % rng))
    fail(where, path, "%s is outside %s; %s" % (short_repr(value), rng,
                                                 fix or "give %s in %s" % ("an integer" if kind == "int" else "a value",
                                                                            rng)))


def text(where, path, value, fix="give it as text"):
    if not isinstance(value, str):
        fail(where, path, "%s is not text; %s" % (short_repr(value), fix))
    return value


def name(where, path, value, kind):
    """A body, joint, interface, input or output name (integers are taken as their digits)."""
    if _is_number(value) and isinstance(value, (int, np.integer)):
        value = str(value)
    if not isinstance(value, str):
        fail(where, path, "%s name %s is not text; %s" % (kind, short_repr(value), NAME_RULE))
    if not 1 <= len(value) <= MAX_NAME or not _NAME.match(value):
        fail(where, path, "%s name %s is not allowed; %s" % (kind, short_repr(value), NAME_RULE))
    return value


def node_id(where, path, value):
    if _is_number(value) and float(value) == math.floor(float(value)) and int(value) > MAX_NODE_ID:
        fail(where, path, "node id %d exceeds %d, the largest this build (32-bit PetscInt) holds; renumber the nodes"
             % (int(value), MAX_NODE_ID))
    return integer(where, path, value, "[0, %d]" % MAX_NODE_ID, "give the node id as an integer in [0, %d]"
                   % MAX_NODE_ID)


def _ref(value):
    """A reference to a name: integers are taken as their digits, as in name()."""
    return str(value) if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)) else value


def file_name(where, path, value):
    if not isinstance(value, str) or not value or "\0" in value:
        fail(where, path, "%s is not a file name; give the file's path relative to the scene file" % short_repr(value))
    return value


def file_or_array(where, path, value, what):
    """A key that takes a file or, in a Python scene, the data itself (io/scene.py resolve() reads either): a file
    name is checked here, data (a NumPy / SciPy array, a petsc4py Vec or Mat, a list) when it is resolved."""
    if isinstance(value, str):
        return file_name(where, path, value)
    if value is None or isinstance(value, (bool, dict, int, float)) or _is_number(value):
        fail(where, path, "%s is neither a file name nor %s; give the file's path relative to the scene file, or "
             "the data (a NumPy or SciPy array, a petsc4py object or a list)" % (short_repr(value), what))
    return value


def vector3(where, path, value, what):
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        fail(where, path, "%s is not a 3-vector; give %s as [x, y, z]" % (short_repr(value), what))
    return [real(where, path, x, "(-inf, inf)", "give %s as [x, y, z] of finite numbers" % what) for x in value]


def rotation(where, path, value):
    """A 3x3 rotation matrix (rows), orthonormal to ORIENTATION_TOL with det +1. Returned exactly orthonormal (the
    nearest rotation) when it is not already to 1e-9, so that a matrix written with 7 digits passes the C check."""
    fix = "give a 3x3 rotation matrix as rows, e.g. [[1, 0, 0], [0, 1, 0], [0, 0, 1]]"
    rows = value.tolist() if isinstance(value, np.ndarray) else value
    if not isinstance(rows, (list, tuple)) or len(rows) != 3 or \
            not all(isinstance(r, (list, tuple)) and len(r) == 3 for r in rows):
        fail(where, path, "%s is not a 3x3 matrix; %s" % (short_repr(value), fix))
    R = np.array([[real(where, path, x, "(-inf, inf)", fix) for x in r] for r in rows])
    err = np.abs(R.T @ R - np.eye(3)).max()
    det = np.linalg.det(R)
    if err > ORIENTATION_TOL or det <= 0:
        fail(where, path, "%s is not a rotation (orthonormality error %.2g, det %.3g); %s, orthonormal to %g with "
             "det +1" % (short_repr(value), err, det, fix, ORIENTATION_TOL))
    if err > 1e-9:
        U, _, Vt = np.linalg.svd(R)
        R = U @ Vt
    return R.tolist()


# ------------------------------------------------------------------ angles

def _angle(where, path, value):
    rng = settings.row("-kf_angles")["range"]
    return real(where, path, value, rng, "give angles in degrees in %s" % rng)


def configuration(where, path, c, revolute):
    """One configuration: a number (one revolute joint), [a1, a2, ...] or {joint: angle}, in degrees."""
    nr = len(revolute)
    if isinstance(c, dict):
        missing = [j for j in revolute if j not in c]
        extra = [j for j in c if j not in revolute]
        if missing or extra:
            fail(where, path, "%s: give one angle per revolute joint (%s); missing %s, unknown %s"
                 % (short_repr(c), ", ".join(revolute) or "none", ", ".join(missing) or "none",
                    ", ".join(map(str, extra)) or "none"))
        c = [c[j] for j in revolute]
    elif isinstance(c, np.ndarray):
        c = c.tolist()
    elif not isinstance(c, (list, tuple)):
        c = [c]
    if len(c) != nr:
        fail(where, path, "%s: the scene has %d revolute joint(s) (%s); give %d angle(s) per configuration"
             % (short_repr(c), nr, ", ".join(revolute) or "none", nr))
    return [_angle(where, path, x) for x in c]


def configurations(where, path, raw, revolute):
    """A list of distinct configurations (a lone number is one configuration)."""
    if isinstance(raw, np.ndarray):
        raw = raw.tolist()
    if not isinstance(raw, (list, tuple)):
        raw = [raw]
    if not raw:
        fail(where, path, "an empty list; give at least one configuration, e.g. %s: [0, 30, 60]" % path)
    configs = []
    for i, c in enumerate(raw):
        configs.append(configuration(where, "%s[%d]" % (path, i), c, revolute))
        for k, d in enumerate(configs[:-1]):
            if d == configs[-1]:
                fail(where, path, "configuration %s appears twice (entries %d and %d); give each configuration once"
                     % (short_repr(c), k, i))
    return configs


def _angles_of_interest(where, spec, revolute):
    raw = spec.get("angles")
    if raw is None:
        if revolute:
            fail(where, "angles", "missing; list the articulation angles of interest in degrees, e.g. "
                 "angles: [0, 30, 60]")
        return [[]]
    if not revolute:
        fail(where, "angles", "%s, but the scene has no revolute joint; remove 'angles'" % short_repr(raw))
    return configurations(where, "angles", raw, revolute)


def _reduction_angle(where, value, revolute):
    path = "reduction.reduction_angle"
    if value == "auto":
        return value
    if not revolute:
        fail(where, path, "%s, but the scene has no revolute joint; use auto" % short_repr(value))
    if isinstance(value, str):
        fail(where, path, "%s is neither auto nor an angle; give auto or an angle in degrees" % short_repr(value))
    if isinstance(value, (list, tuple)) and len(value) == 1 and isinstance(value[0], (list, tuple, dict)):
        value = value[0]        # [[a1, a2]]: one configuration written as a list of one
    return configuration(where, path, value, revolute)


# ------------------------------------------------------------------ nodes

class NodeTable(tuple):
    """(ids, xyz, ndof) of a body's nodes, ndof the dofs per node; .comps the component sets (bit c: component c of
    ux uy uz rx ry rz; 0: a scalar point)."""
    def __new__(cls, ids, xyz, ndof, comps):
        t = tuple.__new__(cls, (ids, xyz, ndof))
        t.comps = comps
        return t


def node_components(value):
    """A node's dofs column: 6, 3, a Nastran component string 'c345' (components ascending) or 's' (scalar point);
    the component set, or None if the value is none of these."""
    if isinstance(value, str):
        v = value.strip()
        if v in ("6", "3"):
            return ALL_COMPONENTS if v == "6" else 7
        if v == "s":
            return 0
        if re.fullmatch(r"c[1-6]+", v) and list(v[1:]) == sorted(set(v[1:])):
            return sum(1 << (int(ch) - 1) for ch in v[1:])
        return None
    if _is_number(value) and float(value) in NODE_DOFS:
        return ALL_COMPONENTS if float(value) == 6 else 7
    return None


def layout_name(comps):
    return "a scalar point" if comps == 0 else "c" + "".join(str(c + 1) for c in range(6) if comps >> c & 1)


# the dofs of each component set (6 bits: ux uy uz rx ry rz; a scalar point, no bit, has 1)
_SET_DOFS = np.array([bin(c).count("1") or 1 for c in range(64)], dtype=np.int32)


def _table(ids, xyz, comps):
    comps = np.asarray(comps, dtype=np.int32)
    return NodeTable(ids, xyz, _SET_DOFS[comps], comps)

def node_table(where, path, rows, labels=None):
    """Node rows (id, x, y, z, ndof) as (ids int32, xyz float64, ndof int32); labels[i] says where row i was written
    (e.g. 'line 12'), default '[i]'."""
    def at(i):
        return "%s (%s)" % (path, labels[i]) if labels is not None else "%s[%d]" % (path, i)

    if isinstance(rows, np.ndarray):
        rows = rows.tolist()
    if not isinstance(rows, (list, tuple)):
        fail(where, path, "%s is neither a nodes file name nor a list; give a file or [[id, x, y, z, ndof], ...]"
             % short_repr(rows))
    if not rows:
        fail(where, path, "no nodes; list 'id x y z ndof' per node")
    table = _node_array(rows)
    if table is not None:
        return _table(*table)
    # row by row: the first bad row, and what is wrong with it
    n = len(rows)
    ids = np.empty(n, dtype=np.int32)
    xyz = np.empty((n, 3))
    ndof = np.empty(n, dtype=np.int32)
    first = {}
    for i, r in enumerate(rows):
        if isinstance(r, np.ndarray):
            r = r.tolist()
        if not isinstance(r, (list, tuple)) or len(r) != 5:
            fail(where, at(i), "%s is not [id, x, y, z, ndof]; give five numbers per node" % short_repr(r))
        ids[i] = node_id(where, at(i), r[0])
        for c in range(3):
            xyz[i, c] = real(where, at(i), r[1 + c], "(-inf, inf)", "give the coordinates as finite numbers")
        comps = node_components(r[4])
        if comps is None:
            fail(where, at(i), "node %d has ndof %s; give 6 (ux uy uz rx ry rz) or 3 (ux uy uz), a component string "
                 "such as c345 (uz rx ry, components ascending) or s (a scalar point)" % (ids[i], short_repr(r[4])))
        ndof[i] = comps
        k = first.setdefault(int(ids[i]), i)
        if k != i:
            fail(where, at(i), "node id %d appears twice (%s and %s); give each node once"
                 % (ids[i], labels[k] if labels is not None else "[%d]" % k,
                    labels[i] if labels is not None else "[%d]" % i))
    return _table(ids, xyz, ndof)


def _node_array(rows):
    """All rows at once when every rule holds (a large body's nodes in milliseconds), else None."""
    try:
        # a nodes file's rows are lists of Python ints and floats: their types collected in passes of C; other rows
        # (NumPy numbers, bools, strings) are looked at one value at a time
        if not (set(map(type, rows)) <= {list, tuple} and set(map(len, rows)) == {5}
                and set(map(type, itertools.chain.from_iterable(rows))) <= {int, float}) \
                and not all(isinstance(r, (list, tuple)) and len(r) == 5 and all(map(_is_number, r)) for r in rows):
            return None
        A = np.array(rows, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    return _node_rows(A)


def node_array_table(A):
    """The node table of an (n, 5) float64 array of rows (id, x, y, z, ndof) when every rule holds, else None
    (node_table on the rows then names the first bad one)."""
    table = _node_rows(A)
    return _table(*table) if table is not None else None


def _node_rows(A):
    """(ids, xyz, component sets) of an (n, 5) float64 array of rows when every rule holds, else None."""
    if A.ndim != 2 or A.shape[1] != 5 or not len(A):
        return None
    ids, xyz, ndof = A[:, 0], A[:, 1:4], A[:, 4]
    if not ((ids == np.floor(ids)) & (ids >= 0) & (ids <= MAX_NODE_ID) & np.isfinite(xyz).all(axis=1)
            & np.isin(ndof, NODE_DOFS)).all():
        return None
    ids = ids.astype(np.int32)
    if np.unique(ids).size != ids.size:
        return None
    return ids, np.ascontiguousarray(xyz), np.where(ndof == 6, ALL_COMPONENTS, 7).astype(np.int32)


def check_node_references(where, valid, nodes):
    """Interfaces on existing 6-dof nodes, input/output terms on existing nodes and dofs. nodes[b] = (ids, xyz, ndof)."""
    index = [dict(zip(t[0].tolist(), t.comps.tolist())) for t in nodes]
    count = lambda c: bin(c).count("1") or 1   # noqa: E731 - dofs of a component set
    for b, body in enumerate(valid["bodies"]):
        for iname, nid in body["interfaces"]:
            path = "bodies.%s.interfaces.%s" % (body["name"], iname)
            if nid not in index[b]:
                fail(where, path, "node %d is not in the body's nodes list; use one of its node ids" % nid)
            if index[b][nid] != ALL_COMPONENTS:
                fail(where, path, "node %d has %d dofs (%s); interface nodes need 6 (translations and rotations: a "
                     "joint ties them all)" % (nid, count(index[b][nid]), layout_name(index[b][nid])))
        for key in ("constraints", "springs"):
            for i, c in enumerate(body.get(key, [])):
                path = "bodies.%s.%s[%d]" % (body["name"], key, i)
                comps = index[b].get(c["node"])
                if comps is None:
                    fail(where, path + ".node", "body '%s' has no node %d; use one of its node ids"
                         % (body["name"], c["node"]))
                wanted = [int(ch) - 1 for ch in c["dofs"]] if key == "constraints" else [c["dof"]]
                for w in wanted:
                    if (w == 6) != (comps == 0) or (w < 6 and not comps >> w & 1):
                        fail(where, path, "node %d of body '%s' has no component %s (it is %s); %s only the "
                             "components the node carries" % (c["node"], body["name"],
                                                             list(DOF_NAMES)[w], layout_name(comps),
                                                             "clamp" if key == "constraints" else "attach springs to"))
    for key in ("inputs", "outputs"):
        for ioname, terms in valid[key]:
            for i, t in enumerate(terms):
                if "node" not in t:
                    continue
                path = "%s.%s[%d]" % (key, ioname, i)
                body = valid["bodies"][t["body"]]["name"]
                comps = index[t["body"]].get(t["node"])
                if comps is None:
                    fail(where, path + ".node", "body '%s' has no node %d; use one of its node ids" % (body, t["node"]))
                w = t["dof"]
                if (w == 6) != (comps == 0) or (w < 6 and not comps >> w & 1):
                    fail(where, path + ".dof", "node %d of body '%s' has %d dofs (%s), so no %s; address a component "
                         "the node carries (rotations rx ry rz need a 6-dof node or a layout that lists them, e.g. "
                         "c345; a scalar point's dof is s)" % (t["node"], body, count(comps), layout_name(comps),
                                                              short_repr(t["dof_name"])))


def check_vector(where, path, data, body, ndofs):
    """A load or reading vector over a whole body: ndofs finite entries."""
    data = np.asarray(data, dtype=np.float64).ravel()
    if data.size != ndofs:
        fail(where, path, "%d entries, but body '%s' has %d dofs; give one entry per dof" % (data.size, body, ndofs))
    bad = np.flatnonzero(~np.isfinite(data))
    if bad.size:
        fail(where, path, "entry %d is %r; give finite numbers" % (bad[0], data[bad[0]]))
    return data


# ------------------------------------------------------------------ the scene

def _bodies(where, spec):
    raw = mapping(where, "bodies", spec["bodies"], what="body names to {mass, stiffness, nodes, interfaces}")
    bodies = []
    for bname, b in raw.items():
        bname = name(where, "bodies", bname, "body")
        path = "bodies." + bname
        mapping(where, path, b, BODY_KEYS)
        for key in ("mass", "stiffness", "nodes"):
            if key not in b:
                fail(where, path, "'%s' is missing; give it (see the scene reference)" % key)
        body = {"name": bname, "interfaces": []}
        for key in ("mass", "stiffness", "damping"):
            if key not in b:
                continue
            v = b[key]
            if isinstance(v, str) or v is None or _is_number(v) or isinstance(v, (bool, dict)):
                file_name(where, path + "." + key, v)
            body[key] = v             # a file name, or a matrix given in memory (checked when it is converted)
        if isinstance(b["nodes"], str):
            body["nodes"] = file_name(where, path + ".nodes", b["nodes"])
        else:
            body["nodes"] = node_table(where, path + ".nodes", b["nodes"])
        if "description" in b:
            text(where, path + ".description", b["description"])
        ifaces = b.get("interfaces")
        if ifaces is not None:
            mapping(where, path + ".interfaces", ifaces, what="interface names to node ids, e.g. {bearing: 101}")
            for iname, nid in ifaces.items():
                iname = name(where, path + ".interfaces", iname, "interface")
                body["interfaces"].append((iname, node_id(where, "%s.interfaces.%s" % (path, iname), nid)))
        body["constraints"], body["springs"] = _boundary_conditions(where, path, b)
        if any(n == body["name"] for n in (x["name"] for x in bodies)):
            fail(where, path, "body '%s' is defined twice; give each body a unique name" % bname)
        bodies.append(body)
    return bodies


def _boundary_conditions(where, path, b):
    """constraints: [{node, dofs}] (clamped components, a Nastran component string, default all the node has) and
    springs: [{node, dof, stiffness}] (springs to ground) of one body."""
    constraints, springs = [], []
    for key, keys, out in (("constraints", CONSTRAINT_KEYS, constraints), ("springs", SPRING_KEYS, springs)):
        raw = b.get(key)
        if raw is None:
            continue
        if isinstance(raw, dict):
            raw = [raw]
        if not isinstance(raw, list):
            fail(where, path + "." + key, "%s is not a list; give a list of {%s}" % (short_repr(raw), ", ".join(sorted(keys))))
        for i, c in enumerate(raw):
            cpath = "%s.%s[%d]" % (path, key, i)
            mapping(where, cpath, c, keys)
            if "node" not in c:
                fail(where, cpath, "'node' is missing; give the node id")
            entry = {"node": node_id(where, cpath + ".node", c["node"])}
            if key == "constraints":
                dofs = c.get("dofs", "")
                if isinstance(dofs, (int, np.integer)) and not isinstance(dofs, bool):
                    dofs = str(dofs)      # YAML reads dofs: 123456 as a number
                text(where, cpath + ".dofs", dofs)
                if dofs and (not re.fullmatch(r"[1-6]+", dofs) or len(set(dofs)) != len(dofs)):
                    fail(where, cpath + ".dofs", "%s is not a component string; give digits 1-6 once each (1 2 3 = "
                         "ux uy uz, 4 5 6 = rx ry rz), e.g. \"123456\"" % short_repr(dofs))
                entry["dofs"] = "".join(sorted(dofs))
            else:
                if "dof" not in c or "stiffness" not in c:
                    fail(where, cpath, "give node, dof (%s) and stiffness" % ", ".join(DOF_NAMES))
                entry["dof_name"] = choice(where, cpath + ".dof", c["dof"], tuple(DOF_NAMES))
                entry["dof"] = DOF_NAMES[c["dof"]]
                entry["stiffness"] = real(where, cpath + ".stiffness", c["stiffness"], "(0, inf)",
                                          "give the spring stiffness as a positive number")
            out.append(entry)
    return constraints, springs


def _joints(where, spec, bodies):
    raw = spec.get("joints")
    if raw is None:
        raw = {}
    mapping(where, "joints", raw, what="joint names to {type, parent, parent_interface, child, child_interface, axis}")
    names = [b["name"] for b in bodies]
    joints, seen = [], set()
    for jname, j in raw.items():
        jname = name(where, "joints", jname, "joint")
        path = "joints." + jname
        if jname in seen:
            fail(where, path, "joint '%s' is defined twice; give each joint a unique name" % jname)
        seen.add(jname)
        mapping(where, path, j, JOINT_KEYS)
        kind = choice(where, path + ".type", j.get("type", "revolute"), JOINT_TYPES)
        if _ref(j.get("parent")) == GROUND and GROUND not in names:
            joints.append(_ground_joint(where, path, jname, kind, j, bodies, names))
            continue
        for key in ("parent", "child", "parent_interface", "child_interface"):
            if key not in j:
                fail(where, path, "'%s' is missing; give it" % key)
        ends = {}
        for key in ("parent", "child"):
            if _ref(j[key]) not in names:
                fail(where, path + "." + key, unknown_body(j[key], names))
            ends[key] = names.index(_ref(j[key]))
        if ends["parent"] == ends["child"]:
            fail(where, path, "ties body '%s' to itself; a joint connects two different bodies" % names[ends["parent"]])
        for key, b in (("parent_interface", ends["parent"]), ("child_interface", ends["child"])):
            have = [i for i, _ in bodies[b]["interfaces"]]
            if _ref(j[key]) not in have:
                fail(where, path + "." + key, "body '%s' has no interface %s (it has: %s); declare it under bodies.%s."
                     "interfaces" % (names[b], short_repr(j[key]), ", ".join(have) or "none", names[b]))
        axis = vector3(where, path + ".axis", j.get("axis", [0, 0, 1]), "the rotation axis")
        if not any(axis):
            fail(where, path + ".axis", "%s is zero; give a direction such as [0, 0, 1]" % short_repr(j.get("axis")))
        R0 = j.get("orientation")
        joints.append({"name": jname, "type": kind, "parent": ends["parent"], "child": ends["child"],
                       "parent_interface": _ref(j["parent_interface"]), "child_interface": _ref(j["child_interface"]),
                       "axis": axis if kind == "revolute" else [0.0, 0.0, 1.0],
                       "R0": None if R0 is None else rotation(where, path + ".orientation", R0)})
    _tree(where, names, [j for j in joints if not j.get("ground")])
    return joints


def _ground_joint(where, path, jname, kind, j, bodies, names):
    """A joint with parent: ground grounds its child's interface node (no parent_interface)."""
    if "parent_interface" in j:
        fail(where, path + ".parent_interface", "a joint to ground has no parent interface; remove the key")
    for key in ("child", "child_interface"):
        if key not in j:
            fail(where, path, "'%s' is missing; give it" % key)
    if _ref(j["child"]) not in names:
        fail(where, path + ".child", unknown_body(j["child"], names))
    c = names.index(_ref(j["child"]))
    have = [i for i, _ in bodies[c]["interfaces"]]
    if _ref(j["child_interface"]) not in have:
        fail(where, path + ".child_interface", "body '%s' has no interface %s (it has: %s); declare it under bodies.%s."
             "interfaces" % (names[c], short_repr(j["child_interface"]), ", ".join(have) or "none", names[c]))
    axis = vector3(where, path + ".axis", j.get("axis", [0, 0, 1]), "the rotation axis")
    if not any(axis):
        fail(where, path + ".axis", "%s is zero; give a direction such as [0, 0, 1]" % short_repr(j.get("axis")))
    R0 = j.get("orientation")
    return {"name": jname, "type": kind, "ground": True, "parent": -1, "child": c, "parent_interface": None,
            "child_interface": _ref(j["child_interface"]), "axis": axis if kind == "revolute" else [0.0, 0.0, 1.0],
            "R0": None if R0 is None else rotation(where, path + ".orientation", R0)}


def _tree(where, names, joints):
    """Joints join the bodies into one tree (the C scene's setup checks the same on its own input)."""
    if len(names) > 1 and not joints:
        fail(where, "joints", "%d bodies but no joints; attach every body but one by a joint" % len(names))
    parent = {}
    for j in joints:
        c = j["child"]
        if c in parent:
            fail(where, "joints." + j["name"], "body '%s' is the child of two joints ('%s' and '%s'); a scene is a tree: "
                 "make one of them its parent instead" % (names[c], parent[c]["name"], j["name"]))
        parent[c] = j
    roots = [b for b in range(len(names)) if b not in parent]
    if not roots:
        fail(where, "joints", "the joints form a loop: every body is some joint's child; kryflex needs a tree (one "
             "root body that is no joint's child)")
    seen, todo = {roots[0]}, [roots[0]]
    while todo:
        b = todo.pop()
        for j in joints:
            if j["parent"] == b and j["child"] not in seen:
                seen.add(j["child"])
                todo.append(j["child"])
    for b in range(len(names)):
        if b not in seen:
            fail(where, "bodies." + names[b], "body '%s' is not attached to the root body '%s': no chain of joints "
                 "reaches it; add a joint that connects it (or remove the body)" % (names[b], names[roots[0]]))


def _io(where, key, spec, bodies):
    raw = mapping(where, key, spec[key], what="%s names to lists of {body, node, dof, weight} terms" % key)
    names = [b["name"] for b in bodies]
    result = []
    for ioname, terms in raw.items():
        ioname = name(where, key, ioname, key[:-1])
        path = "%s.%s" % (key, ioname)
        if any(n == ioname for n, _ in result):
            fail(where, path, "%s name '%s' is used twice; give each a unique name" % (key[:-1], ioname))
        if isinstance(terms, dict):
            terms = [terms]
        if not isinstance(terms, list) or not terms:
            fail(where, path, "%s is not a list of terms; give a list of {body, node, dof, weight} terms"
                 % short_repr(terms))
        checked = []
        for i, t in enumerate(terms):
            tpath = "%s[%d]" % (path, i)
            mapping(where, tpath, t, TERM_KEYS)
            if _ref(t.get("body")) not in names:
                fail(where, tpath + ".body", unknown_body(t.get("body"), names))
            term = {"body": names.index(_ref(t["body"])),
                    "weight": real(where, tpath + ".weight", t.get("weight", 1.0), "(-inf, inf)",
                                   "give the weight as a finite number")}
            if "vector" in t:
                if "node" in t or "dof" in t:
                    fail(where, tpath, "both a vector and node/dof; give node and dof, or a vector file, not both")
                term["vector"] = file_or_array(where, tpath + ".vector", t["vector"], "a vector")
            else:
                if "node" not in t or "dof" not in t:
                    fail(where, tpath, "node or dof is missing; give node and dof (%s), or a vector file"
                         % ", ".join(DOF_NAMES))
                term["node"] = node_id(where, tpath + ".node", t["node"])
                term["dof_name"] = choice(where, tpath + ".dof", t["dof"], tuple(DOF_NAMES))
                term["dof"] = DOF_NAMES[t["dof"]]
            if "quantity" in t:
                if key != "outputs":
                    fail(where, tpath + ".quantity", "an input has no quantity; give quantity on outputs only")
                term["quantity"] = choice(where, tpath + ".quantity", t["quantity"], QUANTITIES)
            checked.append(term)
        quantities = {t["quantity"] for t in checked if "quantity" in t}
        if len(quantities) > 1:
            fail(where, path, "its terms read different quantities (%s); an output reads one quantity: give the same "
                 "quantity on every term" % ", ".join(sorted(quantities)))
        if key == "outputs":
            q = quantities.pop() if quantities else "displacement"
            for t in checked:
                t["quantity"] = q
        result.append((ioname, checked))
    return result


def damping_spec(where, value):
    """The top-level damping: a number (the uniform modal ratio, as before) or a mapping {modal: zeta or
    [[f_max_hz, zeta], ...], rayleigh: {alpha, beta}, structural: g}. Returns (the uniform ratio for a number, None
    for a mapping; the mapping normalized: absent parts zero)."""
    if not isinstance(value, dict):
        z = real(where, "damping", value, settings.row("-kf_damping")["range"],
                 "give the modal damping ratio in [0, 1), e.g. 0.0025, or a mapping {modal, rayleigh, structural}")
        if z == 0.0:   # no modal damping: the same as {modal: 0} (the damping matrices, if any, alone)
            return damping_spec(where, {"modal": 0.0})
        return z, {"modal": z, "rayleigh": {"alpha": 0.0, "beta": 0.0}, "structural": 0.0}
    mapping(where, "damping", value, DAMPING_KEYS)
    out = {"modal": 0.0, "rayleigh": {"alpha": 0.0, "beta": 0.0}, "structural": 0.0}
    modal = value.get("modal", 0.0)
    if isinstance(modal, (list, tuple, np.ndarray)):
        bands = list(modal)
        if not 1 <= len(bands) <= MAX_DAMPING_BANDS:
            fail(where, "damping.modal", "%d bands; give 1 to %d pairs [f_max_hz, zeta]" % (len(bands), MAX_DAMPING_BANDS))
        norm = []
        for k, b in enumerate(bands):
            bp = "damping.modal[%d]" % k
            if not isinstance(b, (list, tuple, np.ndarray)) or len(b) != 2:
                fail(where, bp, "%s is not a pair [f_max_hz, zeta]; give [f_max_hz, zeta]" % short_repr(b))
            f = real(where, bp, b[0], "(0, inf)", "give the band's upper frequency in Hz, positive")
            z = real(where, bp, b[1], "[0, 1)", "give the band's modal damping ratio in [0, 1)")
            if norm and f <= norm[-1][0]:
                fail(where, bp, "f_max_hz %g is not above the previous band's %g; list the bands in ascending f_max_hz"
                     % (f, norm[-1][0]))
            norm.append([f, z])
        out["modal"] = norm
    else:
        out["modal"] = real(where, "damping.modal", modal, "[0, 1)", "give the modal damping ratio in [0, 1), or "
                            "bands [[f_max_hz, zeta], ...]")
    if "rayleigh" in value:
        ray = mapping(where, "damping.rayleigh", value["rayleigh"], {"alpha", "beta"})
        for k in ("alpha", "beta"):
            out["rayleigh"][k] = real(where, "damping.rayleigh." + k, ray.get(k, 0.0),
                                      settings.row("-kf_damping_rayleigh")["range"],
                                      "give a non-negative coefficient (C = alpha M + beta K)")
    if "structural" in value:
        out["structural"] = real(where, "damping.structural", value["structural"],
                                 settings.row("-kf_damping_structural")["range"],
                                 "give the structural damping factor g in [0, 1) (stiffness K (1 + i g))")
    return None, out   # a mapping goes to the reducer whole (a zero modal ratio is allowed there)


# the fixes the scene's messages give, by key (the range is the settings table's unless narrower here)
_FIXES = {
    "reduction.cluster_rtol": "give a relative frequency gap in [0, 1)",
    "reduction.output_blocks": "give an integer >= 0 and below moments",
    "reduction.keep_threshold": "importances are normalized to 1: give a value in (0, 1]",
    "reduction.deflation_tol": "tolerances are relative: give a value in (0, 1)",
    "reduction.body_tol": "tolerances are relative: give a value in (0, 1)",
    "reduction.reassembly_rtol": "tolerances are relative: give a value in (0, 1)",
    "reduction.shift": "give a shift >= 0 (0: hold dofs instead)",
    "reduction.eigen_cover": "give a multiple >= 1 of the band's top frequency",
    "verify.modes": "give auto or a positive integer",
    "verify.frf_floor_db": "give a level below the peak in dB (negative), e.g. -60",
    "accuracy": "give the target relative error in (0, 1), e.g. 0.05",
}
# narrower in a scene than as options, which kryflex study also sets: a scene keeps at least one mode
# (keep_threshold 0 keeps them all) and covers at least its band (eigen_cover below 1 is a study's undercover run)
SCENE_RANGES = {"reduction.keep_threshold": "(0, 1]", "reduction.eigen_cover": "[1, inf)"}


def _setting(where, path, value):
    return setting(where, path, value, _FIXES.get(path), SCENE_RANGES.get(path))


def _reduction(where, given, revolute):
    defaults = __getattr__("REDUCTION_DEFAULTS")
    red = dict(defaults)
    red.update(mapping(where, "reduction", given if given is not None else {}, set(defaults)))
    p = "reduction."
    for key in ("basis", "method", "flex_solver", "bodywise_spread", "importance", "moments", "moments_max", "search",
                "cluster_rtol", "output_blocks"):
        red[key] = _setting(where, p + key, red[key])
    if red["moments"] != "auto" and red["output_blocks"] >= red["moments"]:
        fail(where, p + "output_blocks", "%d is not below moments (%d); give fewer output blocks than moments"
             % (red["output_blocks"], red["moments"]))
    for key in ("keep_threshold", "deflation_tol", "body_tol", "reassembly_rtol", "shift", "eigen_cover",
                "static_correction", "damped_moments", "save_maps", "compress", "static_exact", "shared_directions"):
        red[key] = _setting(where, p + key, red[key])
    red["max_frequency"] = _max_frequency(where, p + "max_frequency", red["max_frequency"])
    red["reduction_angle"] = _reduction_angle(where, red["reduction_angle"], revolute)
    if red["reduction_angles"] is not None:
        if not revolute:
            fail(where, p + "reduction_angles", "%s, but the scene has no revolute joint; remove it"
                 % short_repr(red["reduction_angles"]))
        red["reduction_angles"] = configurations(where, p + "reduction_angles", red["reduction_angles"], revolute)
    return red


def _verify(where, given):
    defaults = __getattr__("VERIFY_DEFAULTS")
    ver = dict(defaults)
    ver.update(mapping(where, "verify", given if given is not None else {}, set(defaults)))
    for key in ("modes", "frequency_points", "full_order", "frf_floor_db", "certified_min_dofs"):
        ver[key] = _setting(where, "verify." + key, ver[key])
    return ver


def validate(spec, where, default_name="scene"):
    """The scene's spec (a parsed scene file, or scene_from_dict's dict) checked and normalized; SceneError at the
    first bad entry."""
    if not isinstance(spec, dict):
        fail(where, None, "%s is not a scene; write the scene as a YAML mapping with bodies, joints, inputs, "
             "outputs, angles" % ("an empty file" if spec is None else short_repr(spec, 40)))
    for k in spec:
        if k not in TOP_KEYS:
            fail(where, None, unknown_key(k, TOP_KEYS))
    for key in ("bodies", "inputs", "outputs"):
        if not spec.get(key):
            fail(where, key, "missing or empty; give at least one (see the scene reference)")
    scene_name = spec.get("name", default_name)
    if isinstance(scene_name, (int, np.integer)) and not isinstance(scene_name, bool):
        scene_name = str(scene_name)
    text(where, "name", scene_name)
    if not 1 <= len(scene_name) <= MAX_SCENE_NAME or not scene_name.isprintable():
        fail(where, "name", "%s is not a usable scene name; give 1 to %d printable characters"
             % (short_repr(scene_name), MAX_SCENE_NAME))
    for key in ("description", "units"):
        if key in spec:
            text(where, key, spec[key])
    paper = spec.get("paper")
    if paper is not None and paper not in PAPERS:
        fail(where, "paper", "%s is not a paper kryflex can compare with; give one of %s (or leave the key out)"
             % (short_repr(paper), ", ".join(PAPERS)))
    bodies = _bodies(where, spec)
    joints = _joints(where, spec, bodies)
    revolute = [j["name"] for j in joints if j["type"] == "revolute" and not j.get("ground")]
    defaults = __getattr__("DEFAULTS")
    band = spec.get("band", defaults["band"])
    if isinstance(band, (tuple, np.ndarray)):
        band = list(band)
    if not isinstance(band, list) or len(band) != 2:
        fail(where, "band", "%s is not [f_low, f_high]; give [f_low, f_high] in Hz with 0 < f_low < f_high"
             % short_repr(band))
    band = [real(where, "band", x, settings.row("-kf_band")["range"],
                 "give [f_low, f_high] in Hz with 0 < f_low < f_high") for x in band]
    if not band[0] < band[1]:
        fail(where, "band", "%s: f_low is not below f_high; give [f_low, f_high] in Hz with 0 < f_low < f_high" % band)
    return {
        "name": scene_name,
        "bodies": bodies,
        "joints": joints,
        "revolute": revolute,
        "inputs": _io(where, "inputs", spec, bodies),
        "outputs": _io(where, "outputs", spec, bodies),
        "configurations": _angles_of_interest(where, spec, revolute),
        "band": band,
        # bodies with their own damping matrices and no `damping:` key: those matrices are the whole damping (no
        # default modal ratio is added on top of them)
        "damping": damping_spec(where, spec["damping"] if "damping" in spec else
                                {"modal": 0.0} if any("damping" in b for b in bodies) else defaults["damping"]),
        "accuracy": _setting(where, "accuracy", spec.get("accuracy", defaults["accuracy"])),
        "accuracy_measure": _setting(where, "accuracy_measure", spec.get("accuracy_measure",
                                                                          defaults["accuracy_measure"])),
        "reduction": _reduction(where, spec.get("reduction"), revolute),
        "verify": _verify(where, spec.get("verify")),
        "paper": paper,
    }


_MAX_FREQUENCY = re.compile(r"\s*([0-9.eE+-]+)\s*(x|X|[Hh][Zz])?\s*\Z")


def _max_frequency(where, path, value):
    """reduction.max_frequency: null/none (no trimming), a multiple >= 1 of the band's top (3 or "3x"), or a frequency
    ("40 Hz"); returned as the text the C library parses (KFParseMaxFrequency)."""
    fix = "give a multiple >= 1 of the band's top (3), a frequency (\"40 Hz\") or null"
    if value is None or (isinstance(value, str) and value.strip().lower() in ("none", "off", "null")):
        return None
    if isinstance(value, (bool, np.bool_)):
        fail(where, path, "%s is not a frequency limit; %s" % (short_repr(value), fix))
    if isinstance(value, (int, float, np.integer, np.floating)):
        x, unit = float(value), None
    else:
        m = _MAX_FREQUENCY.match(str(value))
        try:
            x, unit = float(m.group(1)), m.group(2)
        except (AttributeError, ValueError):
            fail(where, path, "%s is not a frequency limit; %s" % (short_repr(value), fix))
    if not math.isfinite(x) or x < 0:
        fail(where, path, "%s is not a non-negative finite number; %s" % (short_repr(value), fix))
    hz = unit is not None and unit.lower() == "hz"
    if x == 0:
        return None
    if not hz and x < 1:
        fail(where, path, "%s is below the band's top (the band's own modes would go); %s" % (short_repr(value), fix))
    return "%.12g Hz" % x if hz else "%.12g" % x

