"""A 2AFC participant who always answers interval 1: analyse reports each session's
share of answers per interval and warns of the bias, where it still fits a threshold."""

import csv
import json

from frictex.app.experiment.analysis import analyse, report_lines
from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import make_presenter, run_session

PROTOCOL = """format = 1
method = "2afc"
repetitions = 5
[stimuli]
scene = "grating-5mm"
vary = "period_mm"
reference = 5.0
levels = [5.5, 6.5, 8.0]
[presentation]
exploration_s = 0.3
[analysis]
bootstrap = 0
"""


def session(tmp_path, always_one: bool):
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    out = tmp_path / ("one" if always_one else "fair")
    spec = "simulated:weber=0.11,seed=1"
    run_session(load_protocol(path), make_presenter(spec), out, seed=3, participant=spec,
                record="results")
    if always_one:
        table = out / "results.csv"
        with open(table, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
        for row in rows:
            row.update(response="1", correct=str(int(row["answer"] == "1")))
        with open(table, "w", newline="", encoding="utf-8") as fh:
            writer = csv.DictWriter(fh, rows[0].keys(), lineterminator="\n")
            writer.writeheader()
            writer.writerows(rows)
    return out


def test_always_interval_one_is_warned_of(tmp_path):
    out = session(tmp_path, always_one=True)
    summary = analyse([out], tmp_path / "a", plot=False)[0]
    entry = json.loads((tmp_path / "a" / "analysis.json").read_text())["studies"][0][
        "per_session"][0]
    assert entry["response_shares"] == {"1": 1.0, "2": 0.0}
    assert "answered interval 1 in 100% of 30 main trials" in entry["response_bias"]
    warned = [line for line in report_lines(summary) if line.startswith("  warning: ")]
    assert len(warned) == 1 and "interval 1 100%, interval 2 0%" in warned[0]


def test_an_even_split_is_reported_without_a_warning(tmp_path):
    out = session(tmp_path, always_one=False)
    summary = analyse([out], tmp_path / "a", plot=False)[0]
    entry = summary["per_session"][0]
    assert entry["response_bias"] is None and 0.2 < entry["response_shares"]["1"] < 0.8
    assert any(line.startswith(f"  {out}: answers interval 1 ") for line in report_lines(summary))
