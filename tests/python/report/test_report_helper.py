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


def test_helper_share_splits_the_figures(summary, monkeypatch):
    jobs = figures.figure_jobs(summary, figures.plot_file_names(summary))
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", "1")
    share = helper.helper_share(jobs)
    assert share and len(share) < len(jobs)             # the helper draws some of the figures, this process the rest
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", "0")
    assert helper.helper_share(jobs) == set()


@pytest.mark.fast
def test_helper_gives_the_same_files(summary, tmp_path, monkeypatch):
    alone = written(summary, tmp_path / "alone", monkeypatch, "0")
    shared = written(summary, tmp_path / "shared", monkeypatch, "1")
    assert sorted(shared) == sorted(alone)
    assert sum(name.endswith(".png") for name in alone) >= 10
    assert [name for name in alone if shared[name] != alone[name]] == []


def test_a_failing_helper_leaves_the_figures_to_this_process(summary, tmp_path, monkeypatch):
    alone = written(summary, tmp_path / "alone", monkeypatch, "0")
    monkeypatch.setattr(sys, "executable", "/bin/false")       # the helper exits 1 at once
    shared = written(summary, tmp_path / "failed", monkeypatch, "1")
    assert shared == alone
