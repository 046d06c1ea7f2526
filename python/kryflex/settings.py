"""The settings table of the C library (src/util/settings_table.c), for Python: every -kf_ option with its type,
default, range or choices, help, scene file key and reader.

    table()                 the rows, as dicts (the binding's settings_table()), read once per process
    row(name)               the row of "-kf_accuracy" (or "kf_accuracy")
    scene_row(key)          the row of a scene key ("reduction.moments"), None when no option has that key
    value(row)              the row's default as a Python value (auto stays "auto", none is None)
    scene_defaults(section) {key: default} of a scene section ("reduction", "verify"; "" for the top level)
    json_schema(row)        the JSON Schema of the row's scene value (type and range)
    schema_test(schema)     that schema as a predicate (is_valid), compiled once: no validator library imported

The binding is imported on first use, not with this module: PETSc then starts with the command line's options.
"""
import functools
import numbers

INF = float("inf")


@functools.lru_cache(maxsize=None)
def _rows():
    from . import _core
    return tuple(_core.settings_table())


def table():
    """Every row, as a new list of new dicts."""
    return [dict(r, choices=list(r["choices"])) for r in _rows()]


@functools.lru_cache(maxsize=None)
def _by_name():
    return {r["name"]: r for r in _rows()}


@functools.lru_cache(maxsize=None)
def _by_scene():
    return {r["scene"]: r for r in _rows() if r["scene"]}


def row(name):
    """The row of an option, given with or without its dash; KeyError when the table has none."""
    return _by_name()["-" + name.lstrip("-")]


def scene_row(key):
    """The row whose scene key is key, or None."""
    return _by_scene().get(key)


def interval(text):
    """(lo, lo_open, hi, hi_open) of an interval's text "[0, inf)"."""
    lo, hi = text[1:-1].split(",")
    return float(lo), text[0] == "(", float(hi), text[-1] == ")"


def _number(text, kind):
    return int(text) if kind == "int" else float(text)


def value(r, text=None):
    """The row's default (or text) as a Python value: a bool, int, float, list of floats or str; "auto" (and any word
    the row's choices list) stays text, "none" or "" is None. An enum with true and false among its choices takes
    them as booleans."""
    text = r["default"] if text is None else text
    if text in ("", "none"):
        return None
    if text == "auto" or text in r["choices"] and r["type"] != "enum":
        return text                  # decided at run time, or a word a number also takes
    kind = r["type"]
    if kind == "bool" or (kind == "enum" and text in ("true", "false") and "auto" in r["choices"]):
        return text == "true"
    if kind in ("int", "real"):
        return _number(text, kind)
    if kind == "list":
        return [float(x) for x in text.split(",")]
    return text


def scene_defaults(section):
    """{key: default} of the settings whose scene key lies in section ("" : the top level's plain keys)."""
    out = {}
    for r in _rows():
        key = r["scene"]
        if not key:
            continue
        head, _, tail = key.rpartition(".")
        if head == section:
            out[tail] = value(r)
    return out


def _bounds(r):
    if not r["range"]:
        return {}
    lo, lo_open, hi, hi_open = interval(r["range"])
    num = int if r["type"] == "int" else float
    out = {}
    if lo != -INF:
        out["exclusiveMinimum" if lo_open else "minimum"] = num(lo)
    if hi != INF:
        out["exclusiveMaximum" if hi_open else "maximum"] = num(hi)
    return out


def json_schema(r, range_text=None, types_only=False):
    """The JSON Schema (draft 7) of the row's scene value: its type, range (range_text: a narrower one) and choices.
    types_only: the type alone, to tell a value of the wrong type from one out of range."""
    kind = r["type"]
    words = [w for w in r["choices"] if kind != "enum"]
    bounds = {} if types_only else _bounds(dict(r, range=range_text or r["range"]))
    if kind == "bool":
        schema = {"type": "boolean"}
    elif kind in ("int", "real"):
        schema = dict({"type": "integer" if kind == "int" else "number"}, **bounds)
    elif kind == "list":
        schema = {"type": "array", "items": dict({"type": "number"}, **bounds)}
    elif kind == "enum":
        names = [c for c in r["choices"] if c not in ("true", "false")]
        schema = {"enum": names} if len(names) == len(r["choices"]) else \
            {"anyOf": [{"enum": names}, {"type": "boolean"}]}
    else:
        schema = {"type": ["string", "number", "null"]}
    if words:
        schema = {"anyOf": [{"enum": words}, schema]}
    return dict(schema, description=r["help"])


def scene_json_schema():
    """The JSON Schema of the scene keys the table types (not lists and free text: the angles, the band, the damping
    bands, max_frequency are checked in io/scene_schema.py's code), nested by section. A key that is both a value and
    a section (damping: a ratio, or a mapping of modal, rayleigh, structural) takes either."""
    props = {}
    for r in _rows():
        if not r["scene"] or r["type"] in ("list", "string") or "." in r["scene"] and r["scene"].startswith("damping."):
            continue
        *path, key = r["scene"].split(".")
        node = props
        for p in path:
            node = node.setdefault(p, {"type": "object", "properties": {}})["properties"]
        node[key] = json_schema(r)
    if "damping" in props:
        props["damping"] = {"anyOf": [props["damping"], {"type": "object"}]}
    return {"$schema": "http://json-schema.org/draft-07/schema#", "type": "object", "properties": props}


# JSON Schema draft 7's types (jsonschema's Draft7Validator: bool is no number, 1.0 is an integer)
_JSON_TYPES = {
    "boolean": lambda v: isinstance(v, bool),
    "integer": lambda v: not isinstance(v, bool) and (isinstance(v, int) or isinstance(v, float) and v.is_integer()),
    "number": lambda v: not isinstance(v, bool) and isinstance(v, numbers.Number),
    "string": lambda v: isinstance(v, str),
    "null": lambda v: v is None,
    "array": lambda v: isinstance(v, list),
    "object": lambda v: isinstance(v, dict),
}
# the bounds apply to numbers only, as in draft 7: the value fails where the test holds
_JSON_BOUNDS = {
    "minimum": lambda v, b: v < b,
    "maximum": lambda v, b: v > b,
    "exclusiveMinimum": lambda v, b: v <= b,
    "exclusiveMaximum": lambda v, b: v >= b,
}


def schema_test(schema):
    """is_valid(value) of a JSON Schema made by json_schema(): the draft-7 meaning of the keywords it uses (type,
    enum of words, anyOf, items, minimum, maximum and their exclusive forms; description ignored), compiled into
    nested closures once. A scene's settings were checked by the jsonschema package, whose import alone was 0.05 to
    0.1 s of every kryflex reduce; test_settings_table compares the two on every row. A keyword outside that set is
    refused here (ValueError), never ignored."""
    tests = []
    for key, arg in schema.items():
        if key == "description":
            continue
        if key == "type":
            kinds = [_JSON_TYPES[t] for t in ([arg] if isinstance(arg, str) else arg)]
            tests.append(lambda v, kinds=kinds: any(k(v) for k in kinds))
        elif key == "enum":
            if not all(isinstance(w, str) for w in arg):
                raise ValueError("schema_test: an enum of other than words: %r" % (arg,))
            words = frozenset(arg)
            tests.append(lambda v, words=words: isinstance(v, str) and v in words)
        elif key == "anyOf":
            subs = [schema_test(s) for s in arg]
            tests.append(lambda v, subs=subs: any(t(v) for t in subs))
        elif key == "items":
            item = schema_test(arg)
            tests.append(lambda v, item=item: not isinstance(v, list) or all(map(item, v)))
        elif key in _JSON_BOUNDS:
            fails = _JSON_BOUNDS[key]
            tests.append(lambda v, b=arg, fails=fails: not _JSON_TYPES["number"](v) or not fails(v, b))
        else:
            raise ValueError("schema_test: keyword %r not supported" % key)
    return lambda v: all(t(v) for t in tests)
