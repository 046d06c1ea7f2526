"""The settings table (src/util/settings_table.c) is the one list of kryflex's settings: every -kf_ option the C
library or the command reads has a row and every row is read; the C readers take their help text from it (no
PetscOptions* call of a -kf_ option is left in src/); the defaults the C objects start from, as -help prints them,
are the table's; the scene schema's defaults, choices and JSON Schema are the table's; the command knows every name.
"""
import math
import os
import re
import subprocess
import sys

import jsonschema
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
SRC = os.path.join(ROOT, "src")
TABLE_FILE = os.path.join(SRC, "util", "settings_table.c")
ENV = dict(run_env.BASE_ENV, PYTHONPATH=run_env.PACKAGE)

pytestmark = pytest.mark.fast


def _sources(top, ext):
    for folder, _, files in os.walk(top):
        for name in files:
            path = os.path.join(folder, name)
            if name.endswith(ext) and path != TABLE_FILE:
                yield path, open(path).read()


def _options_in_c():
    """{option: [files]} of every whole string literal "-kf_..." in src/ but the table itself."""
    out = {}
    for path, text in _sources(SRC, (".c", ".h")):
        for name in re.findall(r'"(-kf_[a-z0-9_]+)"', text):
            out.setdefault(name, []).append(os.path.relpath(path, ROOT))
    return out


def _options_in_python():
    """Options the Python package reads itself through PETSc's database ("kf_..." string literals)."""
    out = set()
    for _, text in _sources(os.path.join(ROOT, "python", "kryflex"), ".py"):
        out |= {"-" + n for n in re.findall(r'"(kf_[a-z0-9_]+)"', text)}
    return out


@pytest.fixture(scope="module")
def table():
    from kryflex import settings
    return settings.table()


def test_every_option_the_c_code_reads_is_in_the_table(table):
    names = {r["name"] for r in table}
    missing = {n: files for n, files in _options_in_c().items() if n not in names}
    assert not missing, "options read in src/ without a row in src/util/settings_table.c: %s" % missing


def test_every_row_is_read_somewhere(table):
    read = set(_options_in_c()) | _options_in_python()
    unread = [r["name"] for r in table if r["name"] not in read]
    assert not unread, "rows of the settings table that nothing reads: %s" % unread


def test_the_c_readers_take_their_help_from_the_table():
    """A -kf_ option read with PetscOptionsReal and friends carries its own help text, not the table's."""
    direct = []
    for path, text in _sources(SRC, ".c"):
        direct += ["%s: %s" % (os.path.relpath(path, ROOT), m) for m in
                   re.findall(r'PetscOptions(?:Real|Int|Bool|String|RealArray|EList|Enum|FList|BoundedInt|'
                              r'RangeInt)\("-kf_\w+"', text)]
    assert not direct, direct


def test_rows_are_well_formed(table):
    from kryflex import settings
    names = [r["name"] for r in table]
    assert len(names) == len(set(names)), "an option with two rows"
    scene = [r["scene"] for r in table if r["scene"]]
    assert len(scene) == len(set(scene)), "a scene key with two rows"
    for r in table:
        assert r["help"] and r["object"], r
        if r["type"] == "enum":
            assert r["default"] in r["choices"], r
        if r["range"]:
            lo, _, hi, _ = settings.interval(r["range"])
            assert lo < hi, r
            v = settings.value(r)
            for x in (v if isinstance(v, list) else [v]):
                if isinstance(x, (int, float)) and not isinstance(x, bool):
                    assert jsonschema.Draft7Validator(settings.json_schema(r)).is_valid(v), (r, v)


def _help_defaults():
    """{option: default} as `kryflex reduce -help` prints them: the values the C objects start from."""
    p = subprocess.run([sys.executable, "-m", "kryflex", "reduce", "-help"], capture_output=True, text=True, env=ENV,
                       timeout=120, cwd=ROOT)
    assert p.returncode == 0, p.stderr
    out = {}
    for m in re.finditer(r"^\s+(-kf_\w+):?\s*<([^>]*)>", p.stdout, re.M):
        now = m.group(2).split(" : ")[0].strip()
        out[m.group(1)] = now[len("now "):] if now.startswith("now ") else now   # an FList: <now X : formerly X>
    assert len(out) > 40, p.stdout
    return out


def test_the_c_defaults_are_the_tables(table):
    """Every option -help lists starts from the table's default (a list from its first entry: -help prints that)."""
    shown = _help_defaults()
    from kryflex import settings
    checked = 0
    for r in table:
        if r["name"] not in shown or r["default"] in ("", "none", "auto") and r["type"] != "enum":
            continue    # no default, or one decided at run time (auto: a sentinel in C)
        c, want = shown[r["name"]], settings.value(r)
        if r["type"] == "bool" or isinstance(want, bool):
            assert c.lower() == str(want).lower(), (r["name"], c, want)
        elif r["type"] in ("int", "real"):
            assert math.isclose(float(c), want, rel_tol=1e-12), (r["name"], c, want)
        elif r["type"] == "list":
            assert math.isclose(float(c), want[0], rel_tol=1e-12), (r["name"], c, want)
        else:
            assert c == want, (r["name"], c, want)
        checked += 1
    assert checked >= 40, checked


def test_the_scene_schema_takes_the_tables_defaults_and_choices(table):
    from kryflex import settings
    from kryflex.io import scene_schema as schema
    rows = {r["scene"]: r for r in table if r["scene"]}
    for section, defaults in (("reduction", schema.REDUCTION_DEFAULTS), ("verify", schema.VERIFY_DEFAULTS)):
        assert set(defaults) == {k.split(".", 1)[1] for k in rows if k.startswith(section + ".")}
        for key, v in defaults.items():
            assert v == settings.value(rows[section + "." + key]), key
    assert schema.DEFAULTS == {"band": [0.01, 10.0], "damping": 0.0025, "accuracy": 0.05,
                               "accuracy_measure": "elastic"}
    for name, option in (("IMPORTANCES", "-kf_importance"), ("METHODS", "-kf_method"), ("BASES", "-kf_reducer_type"),
                         ("FLEX_SOLVERS", "-kf_flex_solver"), ("ACCURACY_MEASURES", "-kf_accuracy_measure")):
        assert list(getattr(schema, name)) == settings.row(option)["choices"]


def test_the_scene_defaults_pass_the_json_schema(table):
    """The defaults are valid scene values of the generated JSON Schema, and it refuses what the table refuses."""
    from kryflex import settings
    from kryflex.io import scene_schema as schema
    whole = settings.scene_json_schema()
    jsonschema.Draft7Validator.check_schema(whole)
    spec = dict(schema.DEFAULTS, reduction=schema.REDUCTION_DEFAULTS, verify=schema.VERIFY_DEFAULTS)
    spec = {k: v for k, v in spec.items() if k != "band"}
    spec["reduction"] = {k: v for k, v in spec["reduction"].items()
                         if k not in ("reduction_angle", "reduction_angles", "max_frequency")}
    jsonschema.validate(spec, whole)
    for bad in ({"accuracy": 1.0}, {"reduction": {"moments": 201}}, {"reduction": {"importance": "h3"}},
                {"verify": {"frequency_points": 1}}, {"reduction": {"save_maps": "maybe"}},
                {"reduction": {"search": 1}}):
        assert not jsonschema.Draft7Validator(whole).is_valid(bad), bad


def test_the_compiled_schema_test_is_jsonschemas(table):
    """settings.schema_test (what a scene's settings are checked with: fastjsonschema) says valid exactly where
    jsonschema's Draft7Validator does, on every row's schema (its range, a narrower one, the types alone) and values
    of every kind: in and out of range, at the bounds, integral floats, booleans, words, lists, None, non-finite
    numbers; what a scene file's YAML can hold (no tuple or Fraction: no JSON values, and the two libraries differ
    on them)."""
    from kryflex import settings
    values = [None, True, False, 0, 1, -1, 2, 3, 7, 12, 200, 201, 10 ** 6, 0.0, 1.0, -1.0, 0.5, 1e-12, 1e-3, 2.5, 1e300,
              -1e300, float("inf"), float("-inf"), float("nan"), "", "auto", "none", "true", "yes",
              "h2", "elastic", "total", "1", [], [0.1, 2.0], [1, "a"], [True], [float("nan")], [-1.0, 1e9], {},
              {"a": 1}]
    rows = [r for r in table if r["scene"]]
    for r in rows:
        values += [w for w in r["choices"]] + [settings.value(r)]
        if r["range"]:
            lo, _, hi, _ = settings.interval(r["range"])
            values += [x for x in (lo, hi, lo - 1, hi + 1, (lo + hi) / 2) if math.isfinite(x)]
    checked = 0
    for r in rows:
        ranges = [None] + (["[0.5, 3]", "(0, 1)"] if r["type"] in ("int", "real", "list") else [])
        for rng in ranges:
            for types_only in (False, True):
                schema = settings.json_schema(r, rng, types_only)
                ours, theirs = settings.schema_test(schema), jsonschema.Draft7Validator(schema)
                for v in values:
                    assert ours(v) == theirs.is_valid(v), (r["name"], rng, types_only, v)
                    checked += 1
    assert checked > 5000, checked


def test_the_command_knows_every_option(table):
    from kryflex.cli.common import AGREEMENT_TIMEOUT, reducer_option_names
    from kryflex import settings
    assert reducer_option_names() == sorted(r["name"][1:] for r in table)
    assert AGREEMENT_TIMEOUT == settings.value(settings.row("-kf_error_agreement_timeout"))


def test_a_value_outside_the_range_is_refused_naming_it():
    """The C readers check a given value against the row's range (here a stage's option, read before any work)."""
    from kryflex import _core
    from petsc4py import PETSc
    opts = PETSc.Options()
    opts.setValue("kf_shift_blocks", "101")
    try:
        with pytest.raises(_core.Error, match=r"^-kf_shift_blocks 101 is outside \[1, 100\]; give an integer in "
                                              r"\[1, 100\]$"):
            _core.CReducer(PETSc.COMM_SELF).set_from_options()
    finally:
        opts.delValue("kf_shift_blocks")
