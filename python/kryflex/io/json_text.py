"""JSON text indented by one space per level, the very text of json.dumps(value, indent=1, allow_nan=False), written
faster: json.dumps with an indent runs the standard library's Python encoder one yield per value (a quarter of a
second for a 57k-dof run's summary.json, whose bulk is long lists of numbers), where this joins each list of plain
numbers in one call. Anything it does not write the same way (keys that are not strings, other types) is left to
json.dumps itself."""
import json
import math
from json.encoder import encode_basestring_ascii

_SCALARS = {True: "true", False: "false"}


class _Other(Exception):
    """A value this writer leaves to json.dumps."""


_NUMBER_TYPES = frozenset((float, int))
_NON_FINITE = frozenset(("nan", "inf", "-inf"))


def _numbers(value):
    """The JSON texts of a list of plain floats and ints as json.dumps writes them (repr), None when it holds anything
    else; NaN and infinities refused as allow_nan=False refuses them."""
    if not _NUMBER_TYPES.issuperset(map(type, value)):
        return None
    texts = list(map(repr, value))
    if not _NON_FINITE.isdisjoint(texts):
        raise ValueError("Out of range float values are not JSON compliant")
    return texts


def _write(value, indent, out):
    t = type(value)
    if t is str:
        out.append(encode_basestring_ascii(value))
    elif value is None:
        out.append("null")
    elif t is bool:
        out.append(_SCALARS[value])
    elif t is float or t is int:
        out.append(_numbers((value,))[0])
    elif t is list or t is tuple:
        if not value:
            out.append("[]")
            return
        inner = "\n" + " " * (indent + 1)
        texts = _numbers(value)
        if texts is not None:
            out.append("[" + inner + ("," + inner).join(texts) + "\n" + " " * indent + "]")
            return
        out.append("[")
        for k, x in enumerate(value):
            out.append(inner if k == 0 else "," + inner)
            _write(x, indent + 1, out)
        out.append("\n" + " " * indent + "]")
    elif t is dict:
        if not value:
            out.append("{}")
            return
        inner = "\n" + " " * (indent + 1)
        out.append("{")
        for k, (key, x) in enumerate(value.items()):
            if type(key) is not str:
                raise _Other()
            out.append((inner if k == 0 else "," + inner) + encode_basestring_ascii(key) + ": ")
            _write(x, indent + 1, out)
        out.append("\n" + " " * indent + "}")
    else:
        raise _Other()


def dumps_indented(value):
    """json.dumps(value, indent=1, allow_nan=False), the same text."""
    out = []
    try:
        _write(value, 0, out)
    except _Other:
        return json.dumps(value, indent=1, allow_nan=False)
    return "".join(out)
