"""The report's figures shared with a helper process (report/helper.py) are the very files one process writes: every
PNG, summary.json and report.md byte for byte, with the helper forced on, off, and failing (its figures then drawn by
the process itself). The summary is test_report's, computed there from a spring-mass chain."""
import sys

import pytest

from kryflex import report
from kryflex.report import figures, helper

from test_report import build_summary      # noqa: E402  (tests/python/report is on the path under pytest)


@pytest.fixture(scope="module")
def summary():
    return build_summary()


def written(summary, out, monkeypatch, mode):
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", mode)
    report.write_report(summary, str(out))
    return {p.name: p.read_bytes() for p in out.iterdir()}


class _Started:
    """A stand-in for a helper process in the share computation: what its start still costs, what it prepared."""
    def __init__(self, start_weight=0.0, prepared=()):
        self.start_weight = start_weight
        self.prepared = set(prepared)


def test_helper_shares_split_the_figures(summary, monkeypatch):
    jobs = figures.figure_jobs(summary, figures.plot_file_names(summary))
    everything = set(range(len(jobs)))
    # 4 cores, one helper: it and this process both draw
    monkeypatch.setattr(helper, "_idle_cores", lambda: (4, 3.5))
    (share,) = helper.helper_shares(jobs, [_Started()])
    assert share and share < everything
    # as many helpers as cores: they draw every figure between them, this process none (it writes the rest)
    monkeypatch.setattr(helper, "_idle_cores", lambda: (2, 1.5))
    a, b = helper.helper_shares(jobs, [_Started(), _Started()])
    assert a and b and not a & b and a | b == everything
    weight = {k: jobs[k][0] for k in everything}
    assert abs(sum(weight[k] for k in a) - sum(weight[k] for k in b)) <= max(weight.values())
    assert helper.helper_shares(jobs, []) == []
    # the figures a helper prepared (start_helpers' roles) go to it, the rest by weight
    kinds = {k: jobs[k][2] for k in everything}
    a, b = helper.helper_shares(jobs, [_Started(prepared=r) for r in helper.PREPARED_ROLES])
    assert a and b and not a & b and a | b == everything
    assert "overview" in {kinds[k] for k in a} and "importance" not in {kinds[k] for k in a}
    assert "importance" in {kinds[k] for k in b} and "overview" not in {kinds[k] for k in b}
    assert abs(sum(weight[k] for k in a) - sum(weight[k] for k in b)) <= max(weight.values())


def test_helpers_are_not_started_when_turned_off(monkeypatch):
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", "0")
    assert helper.start_helpers() == 0
    assert helper._take_helpers() == []


def test_helpers_are_started_where_the_run_leaves_a_core(monkeypatch):
    """kryflex reduce's rule: a core beyond the run's ranks, whatever the load average (it made the report's time
    depend on the minute before the run)."""
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", "auto")
    monkeypatch.setattr(helper, "_idle_cores", lambda: (2, -5.0))        # a loaded machine: 7 processes running
    assert helper.start_helpers(ranks=1) == helper.HELPERS_AHEAD
    helper.stop_helpers()
    assert helper.start_helpers(ranks=2) == 0
    monkeypatch.setattr(helper, "_idle_cores", lambda: (1, 0.9))
    assert helper.start_helpers(ranks=1) == 0
    assert helper._ahead == []


def test_helpers_started_ahead_give_the_same_files(summary, tmp_path, monkeypatch):
    """kryflex reduce starts the helpers as the run starts, telling them the band and the configurations (their
    figures prepared meanwhile); the report takes them (none left afterwards)."""
    alone = written(summary, tmp_path / "alone", monkeypatch, "0")
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", "1")
    labels = list(summary["frf"])
    freq = summary["frf"][labels[0]]["freq_hz"]
    assert helper._prepared({"band_hz": [freq[0], freq[-1]], "configurations": len(labels)}) is not None
    assert helper.start_helpers(prepare={"band_hz": [freq[0], freq[-1]], "configurations": len(labels)}) \
        == helper.HELPERS_AHEAD
    started = [h.proc for h in helper._ahead]
    pending = report.begin_report(summary, str(tmp_path / "ahead"))
    assert helper._ahead == [] and len(pending.rendering.helpers) >= 1      # taken, and given work
    pending.finish()
    assert {p.name: p.read_bytes() for p in (tmp_path / "ahead").iterdir()} == alone
    assert all(p.poll() is not None for p in started)                      # ended: done, or stopped unused


def test_unused_helpers_end(monkeypatch):
    """A run that draws no figure (it failed, or estimated its error) stops the helpers it started; a helper whose
    parent died reads the end of its input and exits by itself."""
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", "1")
    helper.start_helpers()
    procs = [h.proc for h in helper._ahead]
    helper.stop_helpers()
    assert helper._ahead == [] and all(p.poll() is not None for p in procs)
    lone = helper._Helper(start_weight=0.0)
    lone.proc.stdin.close()                                                # what the parent's exit does
    assert lone.proc.wait(timeout=60) == 0
    lone.stop()


def test_a_stopped_report_writes_nothing(summary, tmp_path, monkeypatch):
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", "1")
    pending = report.begin_report(summary, str(tmp_path / "stopped"))
    procs = [h.proc for h in pending.rendering.helpers]
    pending.stop()
    assert not (tmp_path / "stopped").exists() or not list((tmp_path / "stopped").iterdir())
    assert all(p.poll() is not None for p in procs)


@pytest.mark.fast
def test_helper_gives_the_same_files(summary, tmp_path, monkeypatch):
    alone = written(summary, tmp_path / "alone", monkeypatch, "0")
    shared = written(summary, tmp_path / "shared", monkeypatch, "1")
    assert sorted(shared) == sorted(alone)
    # a Bode and an importance figure per configuration (3), the overview, the moments and the error
    assert sum(name.endswith(".png") for name in alone) == 9
    assert [name for name in alone if shared[name] != alone[name]] == []


def test_a_failing_helper_leaves_the_figures_to_this_process(summary, tmp_path, monkeypatch):
    alone = written(summary, tmp_path / "alone", monkeypatch, "0")
    monkeypatch.setattr(sys, "executable", "/bin/false")       # the helper exits 1 at once
    shared = written(summary, tmp_path / "failed", monkeypatch, "1")
    assert shared == alone
