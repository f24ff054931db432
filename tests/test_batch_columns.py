"""batch.csv counts the samples an actuator limit changed, those the modal solve could
not give independent amplitudes and the finger samples it did not serve, beside the
inversion's clamps."""

import csv

import pytest

from frictex.app.engine import batch_folder, replay
from frictex.app.engine.batch import Job, run_job, write_results

JOB = Job(0, "grating-5mm", "swipe-40mms-50hz", None, 10_000.0, None, "csv", "good")


def summary(**counts) -> dict:
    """A replay's summary document, as much of it as a batch reads."""
    return {"output": {"duration_s": 4.4}, "timings": {"x_realtime_end_to_end": 9.0},
            "clamps": {"above_one": 0, "unreachable": 0}, "warnings": ["w"],
            "counts": counts}


@pytest.mark.parametrize("counts, expected", [
    ({"actuator_limited": 11933, "modal_capped": 27, "modal_unserved": 9950}, (11933, 27, 9950)),
    # a summary from before modal_unserved (version 6): not counted, an empty cell, not 0
    ({"actuator_limited": 11933, "modal_capped": 27}, (11933, 27, None)),
    # a summary from before modal_capped (version 5): not counted, an empty cell, not 0
    ({"actuator_limited": 11933}, (11933, None, None)),
])
def test_a_jobs_row_counts_actuator_limited_modal_capped_and_unserved_samples(
        tmp_path, monkeypatch, counts, expected):
    monkeypatch.setattr(replay, "run_replay", lambda *args, **kwargs: summary(**counts))
    row = run_job(JOB, str(tmp_path))
    assert (row["status"], row["clamps"]) == ("ok", 0)
    assert (row["actuator_limited"], row["modal_capped"], row["modal_unserved"]) == expected
    write_results(tmp_path, [row])
    with open(tmp_path / "batch.csv", newline="") as fh:
        written = next(csv.DictReader(fh))
    assert (written["actuator_limited"], written["modal_capped"], written["modal_unserved"]) == tuple(
        "" if count is None else str(count) for count in expected)


def test_an_earlier_batch_csv_without_the_new_columns_keeps_its_figures(tmp_path):
    (tmp_path / "batch.csv").write_text(
        "job,name,status,error,output_s,wall_s,x_realtime,x_realtime_end_to_end,clamps,"
        "warnings\n0,good,ok,,4.4000,2.0000,2.2000,9.0000,3,1\n")
    figures = batch_folder._earlier_rows(tmp_path / "batch.csv")["good"]
    assert (figures["output_s"], figures["clamps"], figures["actuator_limited"]) == (
        "4.4000", "3", None)
