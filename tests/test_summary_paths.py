"""summary.json's paths and version: the same run says the same whatever folder it
started in, and SUMMARY.md states the version the files carry."""

import json
import os
import re
import shutil
from pathlib import Path

import frictex
import frictex.app.engine.summary
from frictex.app.commands.cli import main
from frictex.app.engine.summary import SUMMARY_VERSION
from frictex.textures.library import resolve_scene, resolve_trace

SUMMARY_MD = Path(frictex.app.engine.summary.__file__).with_name("SUMMARY.md")


def test_summary_md_states_the_version_written():
    stated = re.search(r"`summary_version` is (\d+)\.", SUMMARY_MD.read_text(encoding="utf-8"))
    assert stated and int(stated.group(1)) == SUMMARY_VERSION


def test_paths_are_absolute_and_resolved_wherever_the_run_starts(tmp_path, monkeypatch):
    study = tmp_path / "study"
    (study / "sub").mkdir(parents=True)
    shutil.copy(resolve_scene("grating-5mm"), study / "s.toml")
    shutil.copy(resolve_trace("swipe-40mms-50hz"), study / "t.csv")
    os.symlink(study / "t.csv", study / "sub" / "link.csv")
    docs = []
    for cwd, scene, trace in ((tmp_path, "study/sub/../s.toml", "study/../study/t.csv"),
                              (study / "sub", "../s.toml", "link.csv")):
        monkeypatch.chdir(cwd)
        out = tmp_path / f"out{len(docs)}"
        assert main(["replay", scene, trace, "--out", str(out), "--quiet"]) == 0
        docs.append(json.loads((out / "summary.json").read_text()))
    for doc in docs:
        assert doc["scene"]["path"] == os.path.realpath(study / "s.toml")
        assert doc["trace"]["path"] == os.path.realpath(study / "t.csv")


def test_a_trace_object_has_no_path_and_no_time_order_as_summary_md_says():
    path = resolve_trace("swipe-40mms-50hz")
    done = frictex.replay("grating-5mm", frictex.read_trace(path))
    assert done.summary.trace.path is None and done.summary.trace.time_order is None
    text = SUMMARY_MD.read_text(encoding="utf-8")
    assert "null for a trace given as a `frictex.Trace` object, `frictex.read_trace(path)`'s" in text
    by_path = frictex.replay("grating-5mm", str(path)).summary.trace
    assert by_path.path == os.path.realpath(path) and by_path.time_order is not None
