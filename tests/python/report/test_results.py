"""The typed summary (kryflex.results): summary.json read into dataclasses and written back unchanged.

- A version-1 summary.json (tests/python/report/data: written by kryflex before the summary had a version) is read,
  every key lands in a typed field (nothing left in `extra`), and to_json gives its keys and values back.
- Every key the version-1 schema documented (its docstring, kept in data/) is a key of the dataclass tree.
- Summaries of real runs (`kryflex reduce`, serially and on 2 ranks) round-trip: to_json(from_json(x)) == x, and the
  typed verdict agrees with the relative H-inf error recomputed here in NumPy from the responses the summary holds.
- `kryflex info OUT` reads a results folder through the typed summary; the API's summary is typed, and the old
  string-key access warns.
"""
import gzip
import json
import os
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest
import yaml

from kryflex.results import (SUMMARY_VERSION, Candidate, ChosenModel, FrequencyResponse, Record, Summary,
                             SummaryError, Verdict, _json_text)

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "support"))
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
DATA = os.path.join(HERE, "data")
KRYFLEX = run_env.KRYFLEX
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
ENV = run_env.ENV


def old_summary():
    with gzip.open(os.path.join(DATA, "summary_v1_galileo_small.json.gz"), "rt", encoding="utf-8") as f:
        return json.load(f)


def records(node, path="summary"):
    """(path, record) for every Record in a typed tree."""
    if isinstance(node, Record):
        yield path, node
        for f in node.json_fields():
            yield from records(getattr(node, f.name), "%s.%s" % (path, f.name))
    elif isinstance(node, list):
        for k, item in enumerate(node):
            yield from records(item, "%s[%d]" % (path, k))
    elif isinstance(node, dict):
        for key, item in node.items():
            if isinstance(item, Record):
                yield from records(item, "%s[%r]" % (path, key))


def all_json_keys(cls, seen=None):
    """Every JSON key of a record class and of the record classes below it."""
    seen = set() if seen is None else seen
    if cls in seen:
        return set()
    seen.add(cls)
    keys = set(cls.json_keys())
    for f in cls.json_fields():
        sub = getattr(f.metadata["codec"], "cls", None)
        if sub is not None:
            keys |= all_json_keys(sub, seen)
    return keys


# =============================================================================================== version 1, offline

@pytest.mark.fast
def test_a_version_1_summary_is_read_into_typed_fields_and_written_back():
    data = old_summary()
    assert "summary_version" not in data
    summary = Summary.from_json(data)
    assert summary.summary_version == 1
    untyped = [(path, sorted(r.extra)) for path, r in records(summary) if r.extra]
    assert untyped == [], "keys with no typed field: %s" % untyped
    out = summary.to_json()
    assert out.pop("summary_version") == SUMMARY_VERSION
    assert out == data and list(out) == list(data)
    # typed reads give the file's values
    assert isinstance(summary.verdict, Verdict) and summary.verdict.target_met is data["target_met"]
    assert summary.verdict.error_max == data["error_max"]
    assert isinstance(summary.chosen, ChosenModel) and summary.chosen.worst_where == data["chosen"]["worst_where"]
    assert all(isinstance(c, Candidate) for c in summary.search) and len(summary.search) == len(data["search"])
    assert summary.chosen_candidate.error == data["search"][data["search_chosen"]]["error"]
    assert summary.performance.solve_calls == data["performance"]["solve_calls"]
    assert summary.verdict.reference_check.per_angle["30"].error == data["reference_check"]["per_angle"]["30"]["error"]
    frf = summary.frf["30"]
    assert isinstance(frf, FrequencyResponse)
    np.testing.assert_array_equal(frf.full().real, np.array(data["frf"]["30"]["full_re"]))
    np.testing.assert_array_equal(frf.full().imag, np.array(data["frf"]["30"]["full_im"]))
    config = summary.configuration("60")
    assert config.angles_deg == data["angles_deg"][data["angle_labels"].index("60")]
    assert config.frf_error == data["chosen"]["frf_error"]["60"]
    assert config.full_frequencies_hz == data["full"]["frequencies_hz"]["60"]


@pytest.mark.fast
def test_every_key_the_version_1_schema_documented_is_a_dataclass_field():
    with open(os.path.join(DATA, "summary_schema_v1.txt"), encoding="utf-8") as f:
        text = f.read()
    quoted = set(re.findall(r'"([A-Za-z_][A-Za-z0-9_ ]*)"', text))
    # quoted values, not keys: the accuracy measures, methods, worst_kind's and kept_clusters' words, example labels
    values = {"elastic", "total", "single-angle", "multi-angle", "angle", "midpoint", "per body", "structure"}
    documented = quoted - values
    assert len(documented) > 100    # the parse found the schema's keys
    missing = sorted(documented - all_json_keys(Summary))
    assert missing == [], "keys the version-1 schema documented without a typed field: %s" % missing


@pytest.mark.fast
def test_unknown_keys_are_kept_and_bad_summaries_are_refused():
    data = old_summary()
    data["written_by_a_later_tool"] = {"x": 1}
    data["chosen"]["a_new_measure"] = [1, 2]
    summary = Summary.from_json(data)
    assert summary.extra == {"written_by_a_later_tool": {"x": 1}}
    assert summary.chosen.extra == {"a_new_measure": [1, 2]}
    out = summary.to_json()
    out.pop("summary_version")
    assert out == data
    with pytest.raises(SummaryError, match="summary_version 99.*reads versions 1 to %d" % SUMMARY_VERSION):
        Summary.from_json(dict(data, summary_version=99))
    with pytest.raises(SummaryError, match=r"summary\['search'\] is a dict, not a list"):
        Summary.from_json(dict(data, search={}))
    with pytest.raises(SummaryError, match="JSON object"):
        Summary.from_json([data])


@pytest.mark.fast
def test_the_dict_access_of_version_1_still_reads_and_warns():
    summary = Summary.from_json(old_summary())
    with pytest.warns(DeprecationWarning, match="summary.chosen"):
        assert summary["chosen"]["worst_where"] == summary.chosen.worst_where
    with pytest.warns(DeprecationWarning):
        assert summary["target_met"] is summary.verdict.target_met          # a key of the flat verdict
    with pytest.warns(DeprecationWarning):
        assert summary.get("paper", "none") == "none"                        # absent: the default
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert "model_check" in summary and "paper" not in summary


# =============================================================================================== real runs

def small_scene(folder):
    """The Galileo-like scene at 0, 30 and 60 deg, 40 response points, default reduction (the search)."""
    with open(GALILEO) as f:
        spec = yaml.safe_load(f)
    base = os.path.dirname(GALILEO)
    for body in spec["bodies"].values():
        for key in ("mass", "stiffness", "nodes"):
            body[key] = os.path.join(base, body[key])
    for key in ("paper", "reduction"):
        spec.pop(key)
    spec.update(name="galileo_small", angles=[0, 30, 60], verify={"frequency_points": 40})
    path = os.path.join(folder, "small.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(spec, f, sort_keys=False)
    return path


def reduce(scene, out, ranks):
    cmd = [KRYFLEX, "reduce", scene, "-o", out, "-quiet"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    run = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
        return json.load(f)


def hinf_errors(frf, measure):
    """The relative H-inf error per pair (max over pairs) of one configuration's single-angle response, recomputed
    from the summary's arrays: max_w |Tf - Tr| / max_w |Tf - Tf_rigid| (elastic) or / max_w |Tf| (total), a pair
    whose peak is below 1e-4 of the largest pair's measured against 1e-4 x that peak."""
    full = np.array(frf["full_re"]) + 1j * np.array(frf["full_im"])
    red = np.array(frf["reduced_re"]) + 1j * np.array(frf["reduced_im"])
    ref = full - (np.array(frf["full_rigid_re"]) + 1j * np.array(frf["full_rigid_im"])) if measure == "elastic" \
        else full
    peak = np.abs(ref).max(axis=0)
    peak = np.maximum(peak, 1e-4 * peak.max())
    return float((np.abs(full - red).max(axis=0) / peak).max())


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    if not os.path.exists(KRYFLEX):
        pytest.skip("build/kryflex not built (cmake --build build)")
    folder = str(tmp_path_factory.mktemp("typed"))
    scene = small_scene(folder)
    return {ranks: (os.path.join(folder, "out%d" % ranks), reduce(scene, os.path.join(folder, "out%d" % ranks), ranks))
            for ranks in (1, 2)}


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("ranks", [1, 2])
def test_summaries_of_real_runs_round_trip(runs, ranks):
    out, data = runs[ranks]
    assert data["summary_version"] == SUMMARY_VERSION
    summary = Summary.from_json(data)
    assert summary.to_json() == data
    assert [(path, sorted(r.extra)) for path, r in records(summary) if r.extra] == []
    assert Summary.load(out).to_json() == data          # from the folder, as kryflex info reads it
    # the typed verdict against the error recomputed from the responses the summary holds: C measures on the
    # verification grid merged with the reduced model's resonances and a golden-section search around the worst
    # point (src/reducer/evaluate.c), so the stored grid's error is a lower bound of it, and close (the grid has
    # points around every full-order resonance)
    if summary.verdict.chosen_method == "single-angle":
        for c in summary.configurations:
            mine = hinf_errors(data["frf"][c.label], summary.verdict.accuracy_measure)
            assert 0.85 * c.frf_error <= mine <= c.frf_error * (1 + 1e-9), (c.label, mine, c.frf_error)
        worst = max([c.frf_error for c in summary.configurations] + [m.frf_error for m in summary.midpoints])
        assert summary.verdict.error_max == pytest.approx(worst, rel=1e-12)
        assert summary.verdict.target_met is (worst <= summary.accuracy)


@pytest.mark.mpi
@pytest.mark.slow
def test_two_ranks_give_the_serial_summary(runs):
    serial, parallel = (Summary.from_json(runs[r][1]) for r in (1, 2))
    assert parallel.verdict.chosen_method == serial.verdict.chosen_method
    assert parallel.chosen.dofs_per_body == serial.chosen.dofs_per_body
    assert parallel.verdict.target_met is serial.verdict.target_met
    assert parallel.verdict.error_max == pytest.approx(serial.verdict.error_max, rel=1e-6)
    assert [c.family for c in parallel.search] == [c.family for c in serial.search]


@pytest.mark.mpi
@pytest.mark.slow
def test_kryflex_info_reads_a_results_folder(runs, tmp_path):
    out, data = runs[1]
    run = subprocess.run([KRYFLEX, "info", out], env=ENV, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert "summary version %d" % SUMMARY_VERSION in run.stdout
    assert "worst %s error %.3g" % (data["accuracy_measure"], data["error_max"]) in run.stdout
    # a version-1 file reads too, and a file that is no summary is refused with its name (exit 2, no traceback)
    old = tmp_path / "old.json"
    old.write_text(json.dumps(old_summary()))
    run = subprocess.run([KRYFLEX, "info", str(old)], env=ENV, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and "summary version 1" in run.stdout, run.stderr
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2]")
    run = subprocess.run([KRYFLEX, "info", str(bad)], env=ENV, capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and str(bad) in run.stderr and "Traceback" not in run.stderr


def test_summary_text_keeps_lists_without_objects_on_one_line():
    # the layout summary.json is written in, spelled out by hand: objects indented one space per level, a list that
    # holds no object (numbers, nested lists of them, NumPy numbers, tuples) on one line, a list with an object broken
    value = {"a": [[1.0, 2.0], [3.0, 4.0]], "b": [{"c": [1, [2, 3]]}, 5], "e": [], "f": (np.float64(1.5), [2, None])}
    assert _json_text(value) == ('{\n "a": [[1.0, 2.0], [3.0, 4.0]],\n "b": [\n  {\n   "c": [1, [2, 3]]\n  },\n  5\n ],'
                                 '\n "e": [],\n "f": [1.5, [2, null]]\n}')
    deep = {"frf": [[[0.5, -1.0]] * 3] * 4, "rows": [[1.0], [{"x": 1}]]}
    text = _json_text(deep)
    assert '"frf": [[[0.5, -1.0], [0.5, -1.0], [0.5, -1.0]], ' in text and '\n  [1.0],\n  [\n   {\n    "x": 1\n' in text
    assert json.loads(text) == json.loads(json.dumps(deep))
