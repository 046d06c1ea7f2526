"""summary.json's text written by io/json_text.py is json.dumps(value, indent=1, allow_nan=False) character for
character: on values with every JSON type, empty and nested containers, non-ASCII strings, numbers at their extremes,
and on the ones it leaves to json.dumps (keys that are not strings, NumPy scalars)."""
import json
import math

import numpy as np
import pytest

from kryflex.io.json_text import dumps_indented


def reference(value):
    return json.dumps(value, indent=1, allow_nan=False)


VALUES = [
    {},
    [],
    {"a": [], "b": {}, "c": [[]], "d": [{}]},
    {"scene": "ré \"quoted\" \\ \n tab\t ☃", "n": None, "t": True, "f": False},
    {"x": [0.0, -0.0, 1e-300, 5e-324, 1.7976931348623157e308, 1e16, 0.1, 1 / 3, -2.5e-7, 3, -4, 10 ** 30]},
    {"mixed": [1, 2.0, True, None, "s", [1.5, 2], {"k": [False]}]},
    {"frf": [[[1.0, 2.0], [3.0, 4.0]], [[5.0, 6.0], [7.0, 8.0]]], "tuple": (1.0, 2)},
    [[1, 2], [], [[[]]], [{"a": 1}]],
    "plain",
    2.5,
    7,
    None,
]


@pytest.mark.fast
@pytest.mark.parametrize("value", VALUES)
def test_the_same_text_as_json_dumps(value):
    assert dumps_indented(value) == reference(value)


@pytest.mark.fast
def test_values_it_leaves_to_json_dumps():
    for value in ({1: "int key", "b": [1.0]}, {"np": [np.float64(0.1), 2.0]}, {"np": np.float64(3.25)}):
        assert dumps_indented(value) == reference(value)


@pytest.mark.fast
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_numbers_are_refused_as_json_refuses_them(bad):
    for value in ({"x": [1.0, bad]}, {"x": bad}):
        with pytest.raises(ValueError):
            reference(value)
        with pytest.raises(ValueError):
            dumps_indented(value)


def test_a_large_summary_like_value():
    rng = np.random.default_rng(1)
    value = {"frf": {str(k): {"full_re": rng.standard_normal((200, 3, 2)).tolist(), "ids": list(range(50))}
                     for k in range(4)}}
    assert dumps_indented(value) == reference(value)
