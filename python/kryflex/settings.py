"""The settings table of the C library (src/util/settings_table.c), for Python: every -kf_ option with its type,
default, range or choices, help, scene file key and reader.

    table()                 the rows, as dicts (the binding's settings_table()), read once per process
    row(name)               the row of "-kf_accuracy" (or "kf_accuracy")
    scene_row(key)          the row of a scene key ("reduction.moments"), None when no option has that key
    value(row)              the row's default as a Python value (auto stays "auto", none is None)
    scene_defaults(section) {key: default} of a scene section ("reduction", "verify"; "" for the top level)
    json_schema(row)        the JSON Schema of the row's scene value (type and range)
    schema_test(schema)     that schema as a predicate (is_valid), compiled once by fastjsonschema

The binding is imported on first use, not with this module: PETSc then starts with the command line's options.
"""
import functools

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


def schema_test(schema):
    """is_valid(value) of a JSON Schema made by json_schema(), compiled once. fastjsonschema (in the project's virtual
    environment, scripts/setup) compiles a schema into a Python function in half a millisecond and imports in 5 ms;
    jsonschema's import alone was 0.05 to 0.1 s of every kryflex reduce. Where it is missing (Debian's Python without
    the environment), jsonschema's Draft7Validator. test_settings_table compares the two on every row."""
    try:
        import fastjsonschema
    except ImportError:
        import jsonschema
        return jsonschema.Draft7Validator(schema).is_valid
    check = fastjsonschema.compile(dict(schema, **{"$schema": "http://json-schema.org/draft-07/schema#"}))

    def is_valid(value):
        try:
            check(value)
        except fastjsonschema.JsonSchemaException:
            return False
        return True
    return is_valid
