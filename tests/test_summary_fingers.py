"""The per-finger sections of summary.json are bounded however many ids a trace holds."""

import json

import numpy as np

from frictex.app.commands.cli import main
from frictex.app.engine.finger_table import MAX_LISTED, FingerTable


def test_the_table_keeps_a_bounded_number_of_rows_and_conserves_the_sums():
    """2,500 ids, id k with k % 97 + 1 samples, one output each: at most 2 x kept rows
    at any time; the report lists the `listed` ids with the most samples and aggregates
    the rest, counted once each, sums and maxima conserved."""
    table = FingerTable(("sum", "max"), listed=10, kept=50)
    most = 0
    for fid in range(2500):
        row = table.row(fid)
        row[0] += fid % 97 + 1
        row[1] = max(row[1], float(fid))
        table.done_adding([fid])
        most = max(most, len(table.rows))
    assert most <= 2 * 50 + 1
    listed, (count, others) = table.report()
    assert len(listed) == 10 and count == 2490
    assert all(row[0] == 97 for row in listed.values())
    assert sum(r[0] for r in listed.values()) + others[0] == sum(k % 97 + 1 for k in range(2500))
    assert sorted(listed) == [96 + 97 * j for j in range(10)] and others[1] == 2499.0


def test_an_id_aggregated_that_touches_again_is_counted_once():
    table = FingerTable(("sum",), listed=1, kept=1)
    for fid in (1, 2, 3, 1, 4):
        table.row(fid)[0] += 1 if fid != 4 else 5
        table.done_adding([fid])
    listed, (count, others) = table.report()
    assert list(listed) == [4] and count == 3 and others == [4]


def _taps_csv(path, ids):
    """``ids`` taps one after another, a new id each, each held over three output blocks."""
    rows = ["t_s,finger,x_mm,y_mm,event"]
    for k in range(ids):
        t0 = 0.03 * k
        for i, event in enumerate(("down", "move", "up")):
            rows.append(f"{t0 + 0.01 * i:.6f},{k},{20 + k % 40},32.4,{event}")
    path.write_text("\n".join(rows) + "\n")


def test_a_replay_of_many_ids_lists_100_and_aggregates_the_rest(tmp_path):
    trace = tmp_path / "taps.csv"
    _taps_csv(trace, MAX_LISTED + 30)
    out = tmp_path / "out"
    assert main(["replay", "grating-5mm", str(trace), "--out", str(out), "--quiet"]) == 0
    doc = json.loads((out / "summary.json").read_text())
    fingers, others = doc["fingers"], doc["fingers_others"]
    assert len(fingers) == MAX_LISTED and others["fingers"] == 30
    assert doc["trace"]["fingers"] == list(range(MAX_LISTED))
    assert doc["trace"]["finger_count"] == MAX_LISTED + 30
    listed = sum(v["contact_samples"] for v in fingers.values())
    assert listed + others["contact_samples"] == doc["counts"]["contact_samples"]
    assert min(v["contact_samples"] for v in fingers.values()) >= 1
    assert set(others) == {"fingers", "contact_samples", "amplitude_error_rms_um",
                           "amplitude_error_max_um"}
    assert np.isfinite(others["amplitude_error_rms_um"])
    from frictex.app.engine.summary_types import Summary
    assert Summary.from_dict(doc).to_dict() == doc


def test_few_ids_have_no_aggregate(tmp_path):
    trace = tmp_path / "taps.csv"
    _taps_csv(trace, 5)
    out = tmp_path / "out"
    assert main(["replay", "grating-5mm", str(trace), "--out", str(out), "--quiet"]) == 0
    doc = json.loads((out / "summary.json").read_text())
    assert sorted(doc["fingers"], key=int) == ["0", "1", "2", "3", "4"]
    assert "fingers_others" not in doc
