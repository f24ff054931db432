"""batch.csv says which scene and trace each row's job folder holds: an ``earlier`` row kept
by a stopped rerun is the earlier batch's replay, which a new line of the same name may
not be."""

import csv
import json

from frictex.app.engine import replay
from frictex.app.engine.batch import RESULT_COLUMNS, Job, not_ok, run_job, write_results
from frictex.app.engine.batch_folder import BatchFolder
from tests.test_batch_columns import summary

OLD = Job(0, "grating-5mm", "swipe-40mms-50hz", None, 10_000.0, None, "csv", "a")
NEW = Job(0, "grating-5mm", "circle-30mms-60hz", None, 10_000.0, None, "csv", "a")


def _results(folder):
    with open(folder / "batch.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def test_each_row_names_its_scene_and_trace(tmp_path, monkeypatch):
    monkeypatch.setattr(replay, "run_replay", lambda *args, **kwargs: summary(actuator_limited=0))
    write_results(tmp_path, [run_job(OLD, str(tmp_path)), not_ok(NEW, "failed", "why")])
    rows = _results(tmp_path)
    assert list(rows[0]) == list(RESULT_COLUMNS)
    assert [(row["scene"], row["trace"], row["status"]) for row in rows] == [
        ("grating-5mm", "swipe-40mms-50hz", "ok"), ("grating-5mm", "circle-30mms-60hz", "failed")]


def test_an_earlier_row_names_the_earlier_jobs_trace_not_the_new_lines(tmp_path, monkeypatch):
    monkeypatch.setattr(replay, "run_replay", lambda *args, **kwargs: summary(actuator_limited=0))
    out = tmp_path / "o"
    (out / "a").mkdir(parents=True)
    (out / "a" / "summary.json").write_text(json.dumps(summary()))
    write_results(out, [run_job(OLD, str(tmp_path))])
    folder = BatchFolder(out, ["a"])
    folder.begin()
    folder.commit([not_ok(NEW, "interrupted", "not started")], stopped=True)
    (row,) = _results(out)
    assert (row["name"], row["status"], row["trace"]) == ("a", "earlier", "swipe-40mms-50hz")
