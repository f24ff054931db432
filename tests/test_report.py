"""``frictex report``: claims over paired draws, the files, the real-recordings section."""

import json
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.app.commands.cli import main
from frictex.app.measure.report_claims import claims, paired
from frictex.app.measure.figure_check import text_flaws
from frictex.app.measure.report_doc import SECTIONS, Report, Settings, Timing, headline
from frictex.app.measure.report_markdown import write_markdown
from frictex.app.measure.report_matrix import MOTIONS, Runner, matrix
from frictex.app.measure.report_output import cost_figure, pareto, period_figure
from frictex.app.measure.report_seeds import draws

REFDATA = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "android-getevent"


@pytest.fixture(scope="module")
def grating_rows():
    runner = Runner(live_s=0.02)
    cases = [c for c in matrix(quick=True, scenes=("grating-15mm", "grating-5mm", "grating-0.6mm"))
             if c.output_hz == 10_000.0 and c.inversion == "exact"]
    return [runner.run(c) for c in cases]


@pytest.fixture(scope="module")
def few_draws():
    return draws(8)


def test_paired_interval_against_a_hand_computation():
    """d = 1, 2, 3, 4: mean 2.5, s = sqrt(5/3), t(0.975, 3) = 3.182446 (tables), so the
    95 % interval is 2.5 -+ 3.182446 s / 2; pairs with an undefined side are left out."""
    mean, low, high, n = paired([1.0, 3.0, 4.0, 6.0, None], [0.0, 1.0, 1.0, 2.0, 5.0])
    half = 3.182446 * np.sqrt(5 / 3) / 2
    assert n == 4 and mean == 2.5
    assert_allclose([low, high], [2.5 - half, 2.5 + half], rtol=1e-6)
    # "within 5 %": d = a - 1.05 b
    assert_allclose(paired([1.0, 1.0], [1.0, 2.0], 1.05)[0], ((1 - 1.05) + (1 - 2.1)) / 2)


def test_claims_hold_only_where_the_interval_excludes_a_loss(few_draws):
    cs = claims(few_draws)
    assert {c.group for c in cs} == {"seed 003", "auto beats SHO and SHT", "auto near the best",
                                     "auto on fine gratings"}
    for c in cs:
        assert c.n == 8 or c.metric == "alignment_error_mm"
        assert c.passed == (c.high < 0 if " < " in c.text else c.high <= 0)
        assert c.low <= c.mean <= c.high
    # seed 003's experiment, on every kind of motion: SHT's spectrum at 0.6 mm, SHO's
    # alignment at 15 mm
    seed = [c for c in cs if c.group == "seed 003"]
    assert len(seed) == 6 and all(c.passed for c in seed), [c.text for c in seed if not c.passed]
    # auto against plain SHO and SHT on human-like motion, coarse gratings
    beats = [c for c in cs if c.group == "auto beats SHO and SHT" and c.motion == "human"]
    assert len(beats) == 8 and all(c.passed for c in beats), [c.text for c in beats if not c.passed]


def test_draws_pair_every_renderer_on_the_same_traces(few_draws):
    values = few_draws.values
    assert set(values) == {"grating-15mm", "grating-5mm", "grating-0.6mm"}
    for kinds in values.values():
        assert set(kinds) == {"human", "slow", "fast"}
        for per in kinds.values():
            assert set(per) == {"sho-held", "sho-predicted", "sht", "hybrid"}
            assert all(len(v) == 8 for r in per.values() for v in r.values())
    # the draws differ (each its own strokes and noise)
    human = values["grating-15mm"]["human"]["sht"]["time_error"]
    assert len(set(np.round(human, 9))) == 8


def test_rows_have_the_documented_fields(grating_rows):
    row = grating_rows[0].to_json()
    for key in ("scene", "period_mm", "motion", "touch_hz", "renderer", "output_hz",
                "time_error", "spectral_error", "alignment_error_mm", "cost_us_per_s"):
        assert key in row
    assert set(row["throughput"]) == {"replay_x_realtime", "live_block_p99_thread_cpu_us",
                                      "live_block_p99_wall_us", "live_blocks", "latency_ms"}
    assert row["throughput"]["live_blocks"] == 4  # live_s 0.02: four 5 ms blocks
    assert {"tracking", "layer:lines", "composition", "inversion", "actuation"} <= set(row["stages_us_per_s"])
    assert row["period_mm"] == 15.0
    # latency: at most one 5 ms block of waiting plus the link's jitter buffer
    from frictex.device.link.host import TARGET_S
    assert TARGET_S * 1e3 <= row["throughput"]["latency_ms"] <= TARGET_S * 1e3 + 5.0


def test_pareto_front():
    pts = [(1.0, 5.0), (2.0, 3.0), (3.0, 3.0), (4.0, 1.0), (5.0, 2.0)]
    assert pareto(pts) == [True, True, False, True, False]


def test_report_writes_its_files(tmp_path, capsys):
    out = tmp_path / "rep"
    assert main(["report", "--quick", "--scenes", "grating-15mm", "--out", str(out),
                 "--no-progress"]) == 0
    doc = json.loads((out / "report.json").read_text())
    assert {r["renderer"] for r in doc["rows"]} == {"sho-held", "sho-predicted", "sht", "hybrid"}
    assert {r["output_hz"] for r in doc["rows"]} == {2000.0, 5000.0, 10_000.0, 20_000.0}
    assert (out / "error_vs_cost.png").stat().st_size > 10_000
    assert (out / "error_vs_period.png").stat().st_size > 10_000
    markdown = (out / "report.md").read_text()
    assert "## Physical limits" in markdown and "## Draws" in markdown
    assert "**holds**" in markdown and "not shown" in markdown.split("## Draws")[0] or all(
        c["passed"] for c in doc["claims"])
    # two fingers with modal actuation: measured, with its stages
    assert doc["modal_replay"]["replay_x_realtime"] > 0
    assert doc["modal_replay"]["stages_us_per_s"]["actuation"] > 0
    assert doc["draws"]["n"] == 8 and set(doc["draws"]["values"]) == {"grating-15mm"}
    # the scene run, and the loop's stability margin, which holds for every scene
    assert {c["scene"] for c in doc["claims"]} == {"grating-15mm", "all"}
    assert all({"mean", "low", "high", "n", "passed"} <= set(c) for c in doc["claims"])
    assert doc["real"] is None
    assert "claims hold" in capsys.readouterr().out
    # each part's wall time and load, the whole report's too; the parts run in its time
    timings = doc["timings"]
    assert set(timings) == set(SECTIONS) - {"real recordings"}
    assert all(len(t["load_1min"]) == 2 and t["wall_s"] > 0 for t in timings.values())
    assert sum(t["wall_s"] for k, t in timings.items() if k != "whole report") <= (
        timings["whole report"]["wall_s"])
    assert "one run of each format, 1-minute load " in markdown
    # claims decided by one number carry no interval
    assert all((c["low"] is None) == (c["decided_by"] != "95 % interval") for c in doc["claims"])
    # issue 5: each modal inversion method's speed and error, measured
    modal = {f["label"].split(" (")[0]: f["value"] for f in doc["modal_inversion"]}
    for method in ("exact", "regularised", "bounded"):
        assert modal[f"{method} random: time per sample"] > 0
        assert 0 <= modal[f"{method} near-singular: mean error"] < 0.5
    # the default stays continuous across a singular locus; the exact inverse jumps
    assert (modal["regularised: largest command step, finger b crossing a in 1 um steps"]
            < 0.01 < modal["exact: largest command step, finger b crossing a in 1 um steps"])
    # issue 16: the closed-loop section on the scenes chosen, its claims in the list
    loop = doc["closed_loop"]
    assert set(loop["scenes"]) == {"grating-15mm"} and "adaptation" not in loop
    assert set(loop["scenes"]["grating-15mm"]) == {"open", "closed", "adaptive"}
    assert len(loop["scenes"]["grating-15mm"]["open"]["per_finger"]["rms_reachable"]) == 20
    groups = {c["group"] for c in doc["claims"] if c["group"].startswith("closed loop")}
    assert groups == {"closed loop: RMS error", "closed loop: worst finger",
                      "closed loop: amplitude limit", "closed loop: no growing oscillation",
                      "closed loop: added noise", "closed loop: stability margin"}
    assert "## Closed-loop friction" in markdown and "![closed_loop.png]" in markdown
    assert ("closed-loop runs of 4 s on 20 fingers (full: 60 s)" in markdown
            and "adaptation study" not in markdown.split("## Claims")[0])
    assert (out / "closed_loop.png").stat().st_size > 10_000
    # report.json reads back into the report's records and writes the same document
    back = Report.read(out / "report.json")
    assert json.dumps(back.to_json(), indent=1) + "\n" == (out / "report.json").read_text()
    # every plot the report wrote, drawn again from the records: no text overlaps another
    # or leaves the canvas
    from frictex.app.measure.report_closed_loop import figure
    for fig in (cost_figure(back.rows), period_figure(back.rows), figure(back.closed_loop)):
        assert text_flaws(fig) == []


@pytest.mark.parametrize("argv, message", [
    (["report", "--scenes", "grating-7mm"], "--scenes: grating-7mm is not among the report"),
    (["report", "--real", "/nonexistent/recordings"], "--real /nonexistent/recordings: not a folder"),
])
def test_bad_input_is_one_line_and_exit_2(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: ") and message in err and err.count("\n") == 1


def test_out_that_is_a_file_is_refused(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["report", "--quick", "--out", str(f)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err


def test_real_folder_without_recordings_is_refused(tmp_path, capsys):
    (tmp_path / "notes.md").write_text("# not a recording\n")
    assert main(["report", "--quick", "--real", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "no touch recordings found" in err and err.count("\n") == 1


@pytest.mark.skipif(not REFDATA.is_dir(), reason=f"refdata Android getevent logs not found at {REFDATA}")
def test_real_recordings_replay_with_their_figures():
    """The tablet two-finger drag on the 15 mm grating, every renderer: outputs finite, no
    clamp, the hybrid's distance from itself 0 and plain SHT's far from it (a texture
    whose phase drifts), left-most stable with hysteresis (1 hand-over, 9 without)."""
    from frictex.app.measure.report_real import replay, summary_lines
    run = replay(REFDATA / "Tablet" / "tablet-two-finger-drag.txt", "grating-15mm")
    assert run["fingers"] == 2 and run["samples"] == 265
    for r in run["renderers"].values():
        assert r["finite"] and r["clamps"] == 0
        # a 15 mm grating edge is the largest step: mu' 0.6 -> 1 needs 0 -> the full swing
        assert 0.0 < r["largest_step_um"] <= 2.5
        assert r["chatter"] is not None
    assert run["renderers"]["hybrid"]["spectral_distance_from_hybrid"] == 0.0
    assert run["renderers"]["sht"]["spectral_distance_from_hybrid"] > 0.3
    assert run["roles"] == {"two_or_more_s": pytest.approx(1.47, abs=0.01), "left_most_swaps": 1,
                            "left_most_swaps_without_hysteresis": 9}
    assert run["tracker"] == {"jumps": 0, "out_of_order": 0}
    lines = summary_lines({"folder": "refdata", "runs": [run], "skipped": []})
    assert any("tablet-two-finger-drag.txt | 2 | 1.47 | 1 | 9" in line for line in lines)


def _report(rows, few_draws) -> Report:
    settings = Settings(reference_hz=20_000.0, touch_noise_mm=0.05, block_s=0.005,
                        motions=MOTIONS, lut_max_error_um=1e-3, cpu_count=2, jobs=2,
                        scheduler=None, wall_s=1.0)
    return Report(quick=True, settings=settings, rows=rows, claims=[], headline=headline(rows),
                  modal_replay={"scene": "s", "trace": "t", "output_hz": 10_000.0,
                                "replay_x_realtime": 300.0, "stages_us_per_s": {"actuation": 2.0}},
                  draws=few_draws, real=None, modal_inversion=[], end_to_end=None,
                  closed_loop=None, timings={"whole report": Timing(5.0, (1.0, 2.0))})


def test_markdown_has_no_empty_table(grating_rows, few_draws, tmp_path):
    """Sections the scenes chosen leave without rows (here: no object or composed scene,
    no modal figures) say so in a sentence instead of a table of headers alone."""
    write_markdown(_report(grating_rows, few_draws), tmp_path / "report.md", [])
    lines = (tmp_path / "report.md").read_text().splitlines()
    rules = [k for k, line in enumerate(lines) if line.startswith("|---")]
    assert rules and all(lines[k + 1].startswith("| ") for k in rules if k + 1 < len(lines))
    assert all(k + 1 < len(lines) for k in rules)
    text = "\n".join(lines)
    assert "None in this report: only gratings among the scenes chosen." in text
    assert "None in this report: the composed scene is not among the scenes chosen." in text
    # a quick report says what it ran against the full one
    assert "What --quick runs: " in text and "8 draws of each motion (full: 16)" in text


def test_report_json_reads_back(grating_rows, few_draws, tmp_path):
    doc = _report(grating_rows, few_draws)
    doc.write(tmp_path / "report.json")
    text = (tmp_path / "report.json").read_text()
    assert json.dumps(Report.read(tmp_path / "report.json").to_json(), indent=1) + "\n" == text
    assert json.loads((tmp_path / "report.json").read_text())["report_version"] == 3


def test_report_json_of_another_version_is_refused(tmp_path):
    (tmp_path / "report.json").write_text('{"report_version": 1}')
    with pytest.raises(ValueError, match="report_version 1; this frictex reads version 3"):
        Report.read(tmp_path / "report.json")


def test_matrix_plots_are_legible(grating_rows):
    """The cost plot labels its Pareto front beside the points, the period plot its
    log axes, without a text over another."""
    for fig in (cost_figure(grating_rows), period_figure(grating_rows)):
        assert text_flaws(fig) == []
