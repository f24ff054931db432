"""report.md's section builders on made-up matrix rows: which rows each table and plot
averages, and what their captions say."""

from dataclasses import replace
from types import SimpleNamespace

import pytest

from frictex.app.measure import report_markdown as rmd
from frictex.app.measure.report_claims import GRATINGS
from frictex.app.measure.report_doc import Settings, headline
from frictex.app.measure.report_matrix import MOTIONS, PlateErrors, Row, Steps, Throughput

SETTINGS = Settings(reference_hz=20_000.0, touch_noise_mm=0.05, block_s=0.005,
                    motions=MOTIONS, lut_max_error_um=1e-3, cpu_count=2, jobs=2,
                    scheduler=None, wall_s=1.0, load_1min=(1.0, 1.5))


def row(motion="human", touch_hz=50.0, renderer="sho-held", scene="grating-0.6mm",
        spectral=0.5, alignment_mm=0.5, **changes) -> Row:
    """A matrix row at 10 kHz with exact inversion; the fields named, and ``changes``,
    vary."""
    made = Row(scene=scene, period_mm=GRATINGS.get(scene), motion=motion, touch_hz=touch_hz,
               renderer=renderer, output_hz=10_000.0, inversion="exact", time_error=0.5,
               spectral_error=spectral, alignment_error_mm=alignment_mm, chatter=0,
               steps=Steps(ideal=1, rendered=1), cost_us_per_s=100.0,
               stages_us_per_s={"inversion": 10.0},
               throughput=Throughput(replay_x_realtime=1e4, live_block_p99_thread_cpu_us=100.0,
                                     live_block_p99_wall_us=150.0, live_blocks=100,
                                     latency_ms=40.0),
               clamps={})
    return replace(made, **changes)


#: the quick matrix's sho-held rows on the 0.6 mm grating (spectral errors of one run):
#: three motions at 50 Hz (fast is aliasing-degenerate there), human alone above it
TOUCH_ROWS = [row("slow", spectral=0.864), row("fast", spectral=1.0, alignment_mm=10.0),
              row("human", spectral=1.042), row("human", 120.0, spectral=0.926),
              row("human", 240.0, spectral=0.789)]


def test_the_touch_rate_table_averages_the_same_motions_at_every_rate():
    text = "\n".join(rmd._physical_limits(SimpleNamespace(rows=TOUCH_ROWS, settings=SETTINGS)))
    assert "| spectral error | 1.042 | 0.926 | 0.789 |" in text
    assert "aliasing-degenerate at none (human)" in text
    assert "v / P (0.6 mm at human's 60 mm/s: 100 Hz)" in text  # the table's motion


def test_the_unclaimed_time_error_gives_its_offset_as_a_share_of_the_period():
    from frictex.app.measure.report_claims import NOT_CLAIMED
    assert "0.1-0.3 mm off, a sixth to a half of the 0.6 mm period" in NOT_CLAIMED


def test_a_motion_aliased_at_one_rate_is_left_out_at_every_rate():
    rows = [row(m, t, spectral=s) for m, s in (("fast", 1.0), ("human", 0.5))
            for t in (50.0, 120.0)]
    assert rmd.motions_at_every(rows, [50.0, 120.0]) == ["human"]


def test_the_period_plot_leaves_the_aliased_row_out_of_its_mean():
    fig = pytest.importorskip("frictex.app.measure.report_output").period_figure(TOUCH_ROWS)
    alignment = fig.axes[2]
    held = next(line for line in alignment.get_lines() if line.get_label() == "sho-held")
    at_06 = dict(zip(held.get_xdata(), held.get_ydata()))[0.6]
    assert at_06 == pytest.approx(0.5)  # slow and human; fast's 10 mm cap left out
    assert "leaving out sho-held's aliasing-degenerate rows" in rmd.plot_captions(SETTINGS)[
        "error_vs_period.png"][1]


def test_the_end_to_end_peak_names_the_launcher_it_may_include():
    got = {"x_realtime_end_to_end": 900.0, "x_realtime_compute": 2000.0,
           "process_wall_s": 2.0, "peak_mib": 168.0, "launcher_mib": 8.5}
    text = rmd._end_to_end({"scene": "s", "duration_s": 20.0, "formats": {"csv": got}},
                           None)[1]
    assert "peak 168 MiB, launcher 8 MiB" in text
    assert "at most the launcher's figure" in text


def test_the_output_rate_table_scores_what_the_plate_delivers():
    plate = PlateErrors(time_error=0.7, spectral_error=0.9)
    rows = [row(renderer="hybrid", scene="grating-5mm", output_hz=hz, through_plate=plate,
                time_error=0.1, spectral=0.2) for hz in (2000.0, 10_000.0)]
    text = "\n".join(rmd._physical_limits(SimpleNamespace(rows=rows, settings=SETTINGS)))
    assert "| time_error, plate | 0.700 | 0.700 |" in text
    assert "| spectral_error, plate | 0.900 | 0.900 |" in text
    assert "-3 dB at 400 Hz" in text and "passes 37% of a 1 kHz component" in text
    assert "follows nothing" not in text
    assert "0.088" not in text and "0.18 mm" not in text  # no earlier run's figures


#: one inversion stage timing per grating and renderer, two of them stalled (us/s)
LUT_US = [70, 84, 94, 70, 69, 230, 78, 69, 70, 1095, 1096, 74]


def test_inversion_costs_are_medians_a_stall_does_not_move():
    rows = [row(scene=scene, renderer=renderer, inversion=inversion,
                cost_us_per_s=200.0 + us, stages_us_per_s={"inversion": us})
            for inversion, timings in (("exact", [28] * 12), ("lut", LUT_US))
            for (scene, renderer), us in zip(
                [(s, r) for s in GRATINGS for r in ("sho-held", "sho-predicted", "sht",
                                                    "hybrid")], timings)]
    text = "\n".join(rmd._inversion(SimpleNamespace(rows=rows, settings=SETTINGS)))
    assert "| inversion us/s (median) | 28 | 76 |" in text  # the mean: 258
    assert "| cost us/s (median) | 228 | 276 |" in text
    assert "2 cases at once on 2 CPUs, 1-minute load 1.0-1.5" in text
    caption = rmd.plot_captions(SETTINGS)["error_vs_cost.png"][1]
    assert "median over the gratings of one timing each" in caption
    assert "2 cases at once on 2 CPUs" in caption


def test_the_cost_plot_takes_the_median_over_the_gratings():
    from frictex.app.measure.report_output import _config_points
    rows = [row(scene=s, cost_us_per_s=us) for s, us in zip(GRATINGS, (100.0, 110.0, 5000.0))]
    assert _config_points(rows)["sho-held 10 kHz exact"]["cost"] == 110.0


def test_the_latency_bound_is_not_a_verdict_no_row_could_miss():
    rows = [row(scene="composed-fine-grating-in-disc", renderer=r) for r in ("sht", "hybrid")]
    doc = SimpleNamespace(headline=headline(rows), settings=SETTINGS)
    verdicts = rmd._throughput_verdicts(doc.headline, SETTINGS)
    assert "latency <= one block plus the link buffer (45 ms): not judged here" in verdicts
    assert "met in every row" not in verdicts
    assert ("replay >= 1000x real time, judged here on compute only (end to end: section "
            "below): every row's figure meets it, which is no verdict: one timing a row has "
            "no interval") in verdicts
    assert verdicts.count("which is no verdict") == 2  # replay and the p99 of 100 blocks
    table = "\n".join(rmd._throughput(SimpleNamespace(
        headline=doc.headline, settings=SETTINGS, end_to_end=None, timings={},
        modal_replay={"scene": "s", "trace": "t", "output_hz": 1e4, "replay_x_realtime": 300.0,
                      "stages_us_per_s": {}})))
    assert "schedule latency ms (block wait + link buffer)" in table
    assert "computed from the block schedule, not timed" in table


def test_the_one_draw_note_points_at_where_the_draws_are():
    assert "Draws below" not in rmd.ONE_DRAW_NOTE
    assert "Draws (after the gratings' table)" in rmd.ONE_DRAW_NOTE


def test_reports_quick_help_names_all_it_runs(capsys):
    from frictex.app.commands.cli import main
    with pytest.raises(SystemExit):
        main(["report", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "120 and 240 Hz" in help_text and "2-20 kHz" in help_text and "LUT" in help_text
