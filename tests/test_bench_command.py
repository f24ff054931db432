"""``frictex bench`` as a command: valid JSON with a failed figure, exit 1 where runs
failed, and the figures of finished sections kept when a later section is interrupted."""

from __future__ import annotations

import argparse
import json
import sys
from types import SimpleNamespace

import pytest

from frictex.app.commands import bench
from frictex.app.measure.figure import Figure


def _sections(monkeypatch, **runs):
    """Bench sections named by ``runs``' keys, each ``run(quick)`` its value."""
    monkeypatch.setattr(bench, "SECTIONS", {name: f"fake_bench_{name}" for name in runs})
    for name, run in runs.items():
        monkeypatch.setitem(sys.modules, f"fake_bench_{name}", SimpleNamespace(run=run))


def _args(json_out: bool) -> argparse.Namespace:
    return argparse.Namespace(sections=[], quick=True, json=json_out)


def _good(quick):
    return [Figure("good", "one-second replay, whole process (median of 5)", 0.4, "s")]


def _all_failed(quick):
    return [Figure("bad", "one-second replay, whole process (median of 0, 5 of 5 failed)",
                   float("nan"), "s")]


def test_json_writes_a_figure_of_failed_runs_as_null_and_exits_1(monkeypatch, capsys):
    _sections(monkeypatch, good=_good, bad=_all_failed)
    assert bench.run(_args(True)) == 1
    out, err = capsys.readouterr()
    rows = json.loads(out, parse_constant=lambda name: pytest.fail(f"bare {name} in JSON"))
    failed = [r for r in rows if r["label"].endswith("5 of 5 failed)")]
    assert [r["value"] for r in failed] == [None]
    assert err.strip().splitlines() == [
        "frictex: bench bad: 1 figure(s) include failed runs: "
        "one-second replay, whole process (median of 0, 5 of 5 failed)"]


def test_a_bench_whose_runs_all_succeeded_exits_0(monkeypatch, capsys):
    _sections(monkeypatch, good=_good)
    assert bench.run(_args(False)) == 0
    assert capsys.readouterr().err == ""


def _interrupted(quick):
    raise KeyboardInterrupt


def test_text_prints_a_sections_figures_when_it_ends_before_a_later_one_is_interrupted(
        monkeypatch, capsys):
    _sections(monkeypatch, good=_good, later=_interrupted)
    with pytest.raises(KeyboardInterrupt):
        bench.run(_args(False))
    assert "one-second replay, whole process (median of 5)" in capsys.readouterr().out


def test_json_prints_the_finished_sections_as_one_document_when_a_later_one_is_interrupted(
        monkeypatch, capsys):
    _sections(monkeypatch, good=_good, later=_interrupted)
    with pytest.raises(KeyboardInterrupt):
        bench.run(_args(True))
    rows = json.loads(capsys.readouterr().out)
    assert "one-second replay, whole process (median of 5)" in [r["label"] for r in rows]


def test_the_exit_status_follows_the_runs_that_failed_not_the_labels_words(monkeypatch, capsys):
    """A figure over runs some of which failed exits 1 whatever its label says; a label
    that only mentions the word (a 'failed' column of a report) does not."""
    def some_failed(quick):
        return [Figure("some", "batch of 16 jobs (median of 3)", 6.4, "jobs/s", failed=1)]

    def worded(quick):
        return [Figure("worded", "runs a manifest's failed jobs again", 2.0, "s")]

    _sections(monkeypatch, some=some_failed)
    assert bench.run(_args(False)) == 1
    assert "frictex: bench some: 1 figure(s) include failed runs" in capsys.readouterr().err
    _sections(monkeypatch, worded=worded)
    assert bench.run(_args(False)) == 0
