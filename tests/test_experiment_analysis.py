"""frictex experiment and experiment analyse as a user runs them: simulated sessions of
each method, analysed together, pooled by study; bad input is one line and exit 2."""

import json
from pathlib import Path

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.app.experiment import psychometric as P
from frictex.app.experiment.analysis import _play, mean_interval
from frictex.app.experiment.observer import p_choose_larger, ratio_at
from frictex.app.experiment.protocol import load_protocol

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = ROOT / "app" / "experiment" / "protocols"
SIM = "simulated:weber=0.11,lapse=0.02"

SAME_DIFFERENT = """format = 1
name = "depth-same-different"
method = "same-different"
repetitions = 3

[stimuli]
scene = "grating-5mm"
vary = "depth"
reference = 0.3
levels = [0.33, 0.45]

[presentation]
exploration_s = 0.5
"""

TWO_AFC = """format = 1
name = "depth-2afc"
method = "2afc"
repetitions = 3

[stimuli]
scene = "grating-5mm"
vary = "depth"
reference = 0.3
levels = [0.31, 0.33, 0.36, 0.42]

[presentation]
exploration_s = 0.5

[analysis]
bootstrap = 200
"""


def experiment(*args):
    return main(["experiment", *map(str, args), "--quiet"])


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    root = tmp_path_factory.mktemp("sessions")
    (root / "sd.toml").write_text(SAME_DIFFERENT)
    (root / "afc.toml").write_text(TWO_AFC)
    runs = [(BUNDLED / "seed003-gratings.toml", "g", 1), (root / "sd.toml", "sd", 2),
            (root / "afc.toml", "a1", 3), (root / "afc.toml", "a2", 4)]
    for protocol, name, seed in runs:
        assert experiment(protocol, "--participant", f"{SIM},seed={seed}", "--out", root / name,
                          "--seed", seed, "--record", "results") == 0  # both seeds: reproducible
    return root


def test_analyse_pools_each_study(sessions, capsys):
    out = sessions / "analysis"
    folders = [sessions / n for n in ("g", "sd", "a1", "a2")]
    assert main(["experiment", "analyse", *map(str, folders), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    studies = {s["study"]: s for s in json.loads((out / "analysis.json").read_text())["studies"]}
    assert set(studies) == {"seed003-gratings", "depth-same-different", "depth-2afc"}
    afc = studies["depth-2afc"]
    assert afc["sessions"] == 2 and len(afc["per_session"]) == 2
    assert [lv["trials"] for lv in afc["pooled"]["levels"]] == [12, 12, 12, 12]  # 2 x 3 x 2
    lo, hi = afc["pooled"]["threshold_ci95"]
    assert lo <= afc["pooled"]["threshold"] <= hi
    assert 0.0 <= afc["pooled"]["lapse"] <= 0.06 and afc["pooled"]["guess"] == 0.5
    rated = {st["stimulus"]: st for st in studies["seed003-gratings"]["stimuli"]}
    assert len(rated) == 6 and all(st["n"] == 3 and 1 <= st["mean"] <= 10 for st in rated.values())
    assert all(1 <= st["ci95"][0] <= st["mean"] <= st["ci95"][1] <= 10 for st in rated.values())
    assert "intervals: Student's t on the ratings (n >= 2), clipped to the rating scale" in printed
    levels = studies["depth-same-different"]["levels"]
    assert [(lv["different"], lv["same"]) for lv in levels] == [(6, 6), (6, 6)]
    assert levels[1]["d_prime"] > levels[0]["d_prime"]  # the larger difference is easier
    assert "depth-2afc: 2afc, 2 sessions" in printed and "threshold of 2 sessions' trials pooled" in printed
    png = (out / "analysis.png").read_bytes()
    assert png.startswith(b"\x89PNG") and len(png) > 10_000


@pytest.mark.parametrize("ratings, expected, clipped", [
    # the review's 0.6mm-sht: 10, 10, 6 (mean 8.67; t gives [4.87, 12.5] on a 1-10 scale)
    ([10, 10, 6], (8.667 - 4.303 * 2.309 / 3 ** 0.5, 10.0), True),
    ([1, 2, 1, 1], (1.0, 1.25 + 3.182 * 0.5 / 2), True),
    ([4, 6, 5], (5 - 4.303 / 3 ** 0.5, 5 + 4.303 / 3 ** 0.5), False),
])
def test_a_mean_ratings_interval_stays_on_the_scale(ratings, expected, clipped):
    """Student's t (written out: t(0.975, n - 1) sd / sqrt n) clipped to the 1-10 scale,
    and marked clipped where it was; one rating has no interval."""
    ci, was = mean_interval(np.array(ratings, dtype=float), (1, 10))
    assert ci == pytest.approx(expected, abs=2e-3) and was is clipped
    assert all(np.isnan(mean_interval(np.array([7.0]), (1, 10))[0]))
    assert mean_interval(np.array([9.0, 10.0]), None)[0][1] > 10  # no scale: nothing to clip


def test_sessions_of_one_name_must_share_their_protocol(sessions, tmp_path, capsys):
    changed = tmp_path / "afc.toml"
    changed.write_text(TWO_AFC.replace("repetitions = 3", "repetitions = 2"))
    assert experiment(changed, "--participant", SIM, "--out", tmp_path / "a3",
                      "--record", "results") == 0
    capsys.readouterr()
    assert main(["experiment", "analyse", str(sessions / "a1"), str(tmp_path / "a3"),
                 "--no-plot", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "ran another protocol file" in err


@pytest.mark.parametrize("args, words", [
    (["analyse"], "give one or more session folders"),
    (["analyse", "."], "not a session folder"),
    ([str(BUNDLED / "period-2afc.toml"), "--out", "x"], "--participant is required"),
    ([str(BUNDLED / "period-2afc.toml"), "--participant", "robot", "--out", "x"],
     "expected one of simulated, window"),
    ([str(BUNDLED / "period-2afc.toml"), "--participant", "simulated:weber=-1", "--out", "x"],
     "outside"),
    (["a.toml", "b.toml"], "expected one protocol file"),
])
def test_bad_command_lines_are_one_line(tmp_path, monkeypatch, capsys, args, words):
    monkeypatch.chdir(tmp_path)
    assert main(["experiment", *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: ") and err.count("\n") == 1 and words in err


def test_check_counts_the_trials(capsys):
    assert main(["experiment", str(BUNDLED / "period-2afc.toml"), "--check"]) == 0
    assert "4 practice and 120 main trials" in capsys.readouterr().out


def test_staircase_credible_intervals_cover_in_100_sessions():
    """100 sessions of the bundled 1-up-2-down depth staircase played by the analytic
    observer (Weber 0.11, lapse 0.02; its answers drawn from its model, no pipeline),
    each fitted alone: the threshold's 95 % credible interval covers the observer's
    70.7 % point in at least 88 (nominal 95; the percentile bootstrap's covered 76)."""
    protocol = load_protocol(BUNDLED / "depth-staircase.toml")
    reference = protocol.stimuli.reference
    true = reference * (ratio_at(protocol.target, 0.11, 0.02) - 1.0)
    rng = np.random.default_rng(29)
    covered = 0
    for _ in range(100):
        x, correct, _ = _play(protocol.staircase,
                              lambda d: p_choose_larger((reference + d) / reference, 0.11, 0.02),
                              rng)
        levels, inverse = np.unique(P._significant(x), return_inverse=True)
        n = np.bincount(inverse).astype(np.float64)
        k = np.bincount(inverse, np.asarray(correct, dtype=np.float64))
        lo, hi = P.credible_threshold("weibull", levels, n, k, target=protocol.target)
        covered += lo <= true <= hi
    assert covered >= 88, covered


def test_staircase_analysis_names_its_interval_method(sessions, capsys):
    assert main(["experiment", "analyse", str(sessions / "g"), str(sessions / "a1"),
                 "--no-plot", "--out", str(sessions / "named")]) == 0
    printed = capsys.readouterr().out
    assert f"threshold interval: {P.BOOTSTRAP}" in printed
    fit = P.fit_adaptive([0.02, 0.03, 0.02, 0.03, 0.04], [0, 1, 1, 1, 1],
                         lambda p, rng: ([0.02, 0.03], [True, True]), bootstrap=5)
    assert fit.threshold_ci_method == P.CREDIBLE
    assert fit.threshold_ci[0] < fit.threshold < fit.threshold_ci[1]


def test_a_fit_pooled_over_sessions_says_so_and_gives_each_sessions_threshold(sessions,
                                                                                capsys):
    """Two sessions fitted as one observer were printed as a plain threshold and interval."""
    out = sessions / "pooled"
    assert main(["experiment", "analyse", str(sessions / "a1"), str(sessions / "a2"),
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    study = json.loads((out / "analysis.json").read_text())["studies"][0]
    each = [e["fit"]["threshold"] for e in study["per_session"]]
    summary = study["session_thresholds"]
    assert summary["thresholds"] == each and summary["sessions"] == 2
    assert summary["mean"] == pytest.approx(np.mean(each))
    assert summary["se"] == pytest.approx(abs(each[0] - each[1]) / 2)
    assert ("  threshold of 2 sessions' trials pooled (one fit, as one observer; its interval "
            "is not a between-participant interval) (0.75 correct") in printed
    assert (f"  per session: thresholds {each[0]:.4g}, {each[1]:.4g} depth; mean "
            f"{summary['mean']:.4g} ± {summary['se']:.2g} depth (SE across 2 sessions)"
            in printed)
    assert main(["experiment", "analyse", str(sessions / "a1"), "--out",
                 str(sessions / "alone")]) == 0
    alone = capsys.readouterr().out
    assert "pooled" not in alone and "per session:" not in alone
