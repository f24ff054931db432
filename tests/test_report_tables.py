"""report.md's section builders on made-up matrix rows: which rows each table and plot
averages, and what their captions say."""

from types import SimpleNamespace

import pytest

from frictex.app.measure import report_markdown as rmd
from frictex.app.measure.report_claims import GRATINGS
from frictex.app.measure.report_matrix import Row, Steps, Throughput


def row(motion="human", touch_hz=50.0, renderer="sho-held", scene="grating-0.6mm",
        spectral=0.5, alignment_mm=0.5) -> Row:
    """A matrix row at 10 kHz with exact inversion; only the fields named vary."""
    return Row(scene=scene, period_mm=GRATINGS.get(scene), motion=motion, touch_hz=touch_hz,
               renderer=renderer, output_hz=10_000.0, inversion="exact", time_error=0.5,
               spectral_error=spectral, alignment_error_mm=alignment_mm, chatter=0,
               steps=Steps(ideal=1, rendered=1), cost_us_per_s=100.0,
               stages_us_per_s={"inversion": 10.0},
               throughput=Throughput(replay_x_realtime=1e4, live_block_p99_us=100.0,
                                     latency_ms=40.0),
               clamps={})


#: the quick matrix's sho-held rows on the 0.6 mm grating (spectral errors of one run):
#: three motions at 50 Hz (fast is aliasing-degenerate there), human alone above it
TOUCH_ROWS = [row("slow", spectral=0.864), row("fast", spectral=1.0, alignment_mm=10.0),
              row("human", spectral=1.042), row("human", 120.0, spectral=0.926),
              row("human", 240.0, spectral=0.789)]


def test_the_touch_rate_table_averages_the_same_motions_at_every_rate():
    text = "\n".join(rmd._physical_limits(SimpleNamespace(rows=TOUCH_ROWS)))
    assert "| spectral error | 1.042 | 0.926 | 0.789 |" in text
    assert "aliasing-degenerate at none (human)" in text


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
    assert "leaving out sho-held's aliasing-degenerate rows" in rmd.PLOT_CAPTIONS[
        "error_vs_period.png"][1]


def test_the_end_to_end_peak_names_the_launcher_it_may_include():
    got = {"x_realtime_end_to_end": 900.0, "x_realtime_compute": 2000.0,
           "process_wall_s": 2.0, "peak_mib": 168.0, "launcher_mib": 8.5}
    text = rmd._end_to_end({"scene": "s", "duration_s": 20.0, "formats": {"csv": got}})[1]
    assert "peak 168 MiB, launcher 8 MiB" in text
    assert "at most the launcher's figure" in text
