"""What the analysis says of numbers that could mislead: same-different rates named as
log-linear corrected beside their raw counts, and what d' 0 means there; intervals the
data cannot settle flagged in the text and the JSON; a pooled analysis never written
over a session's own."""

import json

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.app.experiment import same_different as SD
from frictex.app.experiment.analysis import analyse_study, report_lines, unsettled
from test_experiment_analysis_limits import forced, session


def test_same_different_names_its_correction_and_gives_the_counts():
    """The review's level: 4 of 10 hits and 5 of 10 false alarms printed as 'hits 0.409,
    false alarms 0.500', d' 0.000, with nothing saying so."""
    rows = [{"value": "5.2", "answer": a, "response": r}
            for a, r in [("different", "different")] * 4 + [("different", "same")] * 6
            + [("same", "different")] * 5 + [("same", "same")] * 5]
    summary = analyse_study([session("same-different", rows, bootstrap=0)])
    level = summary["levels"][0]
    assert (level["hit_rate_raw"], level["false_alarm_rate_raw"]) == (0.4, 0.5)
    assert level["hit_rate"] == pytest.approx(4.5 / 11)
    assert summary["rate_correction"] == SD.CORRECTION and "log-linear" in SD.CORRECTION
    assert level["d_prime"] == 0.0 and level["d_prime_note"] == SD.NO_DISCRIMINATION
    printed = "\n".join(report_lines(summary))
    assert ("period_mm 5.2: hits 4 of 10, false alarms 5 of 10 (corrected rates 0.409 and "
            "0.500), d' 0.000 (hits not above false alarms: d' set to 0, no discrimination "
            "shown") in printed
    assert "rates: log-linear correction, (count + 0.5) / (trials + 1)" in printed


@pytest.mark.parametrize("ci, flagged", [
    ((1.7e-08, 0.688), "spans a factor of 4.05e+07"), ((0.095, 5.4e5), "spans a factor"),
    ((0.0, 1.0), "reaches 0"), ((0.5, 49.0), None), ((None, None), None)])
def test_an_interval_the_data_cannot_settle_is_flagged(ci, flagged):
    found = unsettled(ci)
    assert (found is None) if flagged is None else (flagged in found)


def test_a_fit_flags_its_unsettled_interval_in_text_and_json():
    """Near-chance answers at every level: the slope's interval spans three decades, and
    the threshold's profile likelihood stays flat out to ten times the highest level."""
    pairs = [(d, c) for d, k in zip([0.2, 0.4, 0.6, 0.8], [5, 4, 6, 5])
             for c in [True] * k + [False] * (10 - k)]
    pooled = analyse_study([session("2afc", forced(pairs))])
    fit = pooled["pooled"]
    lo, hi = fit["slope_ci95"]
    assert hi / lo > 100 and "flat along the threshold" in fit["fit_unsettled"]
    for name in ("threshold", "slope"):
        assert fit[f"{name}_ci95_unsettled"] == f"unsettled: {fit['fit_unsettled']}"
    slope_line = [line for line in report_lines(pooled) if line.startswith("  slope")][0]
    assert "; unsettled: the likelihood is flat along the threshold" in slope_line
    # a settled fit has no flag
    rng = np.random.default_rng(3)
    good = forced((d, rng.random() < p) for d, p in zip([0.2, 0.4, 0.6, 0.8],
                                                        [0.55, 0.7, 0.85, 0.95])
                  for _ in range(50))
    settled = analyse_study([session("2afc", good)])["pooled"]
    assert settled["threshold_ci95_unsettled"] is None
    assert settled["slope_ci95_unsettled"] is None


def test_identical_ratings_give_a_flagged_interval():
    rows = [{"stimuli": "a", "value": "", "response": "6"}] * 2 + [
        {"stimuli": "b", "value": "", "response": r} for r in ("5", "7")]
    summary = analyse_study([session("magnitude", rows)])
    a, b = summary["stimuli"]
    assert a["ci95"] == [6.0, 6.0] and "from 1 distinct rating" in a["ci95_unsettled"]
    assert b["ci95_unsettled"] is None
    printed = report_lines(summary)
    assert any(line.startswith("  a: mean 6 (n 2, 95 % [6, 6]; unsettled: from 1 distinct")
               for line in printed)


def test_magnitude_stimuli_are_listed_by_their_value():
    """Before, by name: period_mm=10, period_mm=2, period_mm=5; a stimulus without a value
    (a list of scenes) comes after, by name."""
    rows = [{"stimuli": f"period_mm={v}", "value": v, "response": "3"}
            for v in ("10", "2", "5", "0.6")] + [{"stimuli": n, "value": "", "response": "3"}
                                                 for n in ("b", "a")]
    summary = analyse_study([session("magnitude", rows)])
    assert [st["stimulus"] for st in summary["stimuli"]] == [
        "period_mm=0.6", "period_mm=2", "period_mm=5", "period_mm=10", "a", "b"]


def test_pooling_sessions_without_out_is_refused(tmp_path, capsys):
    """`analyse A B` wrote the pooled analysis into A/analysis, over A's own."""
    folders = []
    for name, seed in (("a", 1), ("b", 2)):
        folder = tmp_path / name
        folder.mkdir()
        info = {"format": 1, "protocol": "p", "method": "2afc", "seed": seed,
                "participant": "simulated", "design": session("2afc", []).info["design"]}
        (folder / "session.json").write_text(json.dumps(info))
        (folder / "results.csv").write_text(
            "trial,practice,stimuli,value,difference,answer,response,correct,rt_s,ended_utc\n")
        folders.append(str(folder))
    assert main(["experiment", "analyse", *folders, "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert "give --out DIR" in err and err.count("\n") == 1
    assert not (tmp_path / "a" / "analysis").exists()
    assert main(["experiment", "analyse", *folders, "--no-plot", "--out",
                 str(tmp_path / "pooled")]) == 0
    assert main(["experiment", "analyse", folders[0], "--no-plot"]) == 0
    assert (tmp_path / "a" / "analysis" / "analysis.json").is_file()
