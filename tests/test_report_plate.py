"""The report's errors through the plate, its flagged cells, and what its tables say they
score (``report_matrix``, ``report_markdown``)."""

import dataclasses

import numpy as np
import pytest

from frictex.app.measure.report_markdown import cell_notes, loop_baselines
from frictex.app.measure.report_matrix import (MOTIONS, Case, Row, Runner, aliasing_degenerate,
                                               periods_per_sample, through_plate)
from frictex.device.finger import SensorParams


@pytest.fixture(scope="module")
def runner():
    return Runner(live_s=0.02)


def test_through_plate_is_the_first_order_loop_from_rest():
    """A step of 1 um: after one time constant of the 400 Hz loop the plate is at
    1 - 1/e of it; a constant amplitude held long enough is delivered in full."""
    rate = 10_000.0
    out = through_plate(np.ones(200), rate)
    tau_samples = rate / (2 * np.pi * SensorParams().plate_bw_hz)
    assert out[int(round(tau_samples)) - 1] == pytest.approx(1 - np.exp(-1), abs=0.03)
    assert out[0] < 0.3 and out[-1] == pytest.approx(1.0, abs=1e-6)


def test_a_fast_fine_grating_loses_its_spectrum_in_the_plate(runner):
    """0.6 mm at 120 mm/s is 200 Hz, with edges far above the 400 Hz loop: what the plate
    delivers is much further from the texture than what was commanded; a 15 mm grating at
    20 mm/s (1.3 Hz) is not."""
    fine = runner.run(Case("grating-0.6mm", "fast", 50.0, "hybrid", 10_000.0))
    assert fine.through_plate.spectral_error > 2 * fine.spectral_error
    coarse = runner.run(Case("grating-15mm", "slow", 50.0, "hybrid", 10_000.0))
    assert abs(coarse.through_plate.spectral_error - coarse.spectral_error) < 0.05
    assert abs(coarse.through_plate.time_error - coarse.time_error) < 0.05
    # report.json keeps them; a row written before them reads back without
    doc = fine.to_json()
    assert set(doc["through_plate"]) == {"time_error", "spectral_error"}
    assert Row.from_json(doc) == fine
    old = {k: v for k, v in doc.items() if k != "through_plate"}
    assert Row.from_json(old).through_plate is None


def test_draw_runners_skip_the_plate():
    row = Runner(live_s=0.005, plate=False).run(Case("grating-5mm", "slow", 50.0, "sht", 10_000.0))
    assert row.through_plate is None


def test_aliasing_degenerate_speeds():
    """120 mm/s at 50 Hz is 2.4 mm per touch sample: 4 periods of 0.6 mm, 0.48 of 5 mm."""
    assert periods_per_sample(MOTIONS["fast"], 50.0, 0.6) == pytest.approx(4.0)
    assert aliasing_degenerate(periods_per_sample(MOTIONS["fast"], 50.0, 0.6))
    assert not aliasing_degenerate(periods_per_sample(MOTIONS["fast"], 50.0, 5.0))
    assert not aliasing_degenerate(periods_per_sample(MOTIONS["slow"], 50.0, 0.6))
    assert periods_per_sample(MOTIONS["human"], 50.0, 0.6) is None  # not a constant speed
    assert periods_per_sample(MOTIONS["fast"], 50.0, None) is None


def test_cells_that_compare_nothing_are_flagged(runner):
    """The degenerate sho-held swipe is flagged; on the same swipe the other renderers
    differ and are not; renderers whose errors coincide are named."""
    rows = [runner.run(Case("grating-0.6mm", "fast", 50.0, r, 10_000.0))
            for r in ("sho-held", "sht")]
    notes = cell_notes(rows)
    assert notes[0] == "aliased: 4 periods per touch sample" and notes[1] == ""
    twin = dataclasses.replace(rows[1], renderer="hybrid")
    notes = cell_notes([*rows, twin])
    assert notes[1] == "same as hybrid" and notes[2] == "same as sht"
    other = dataclasses.replace(twin, time_error=twin.time_error + 1e-6)
    assert cell_notes([rows[1], other]) == ["", ""]


def test_loop_baselines_give_both_gains():
    from types import SimpleNamespace as NS
    section = NS(scenes={"grating-15mm": {
        "open": NS(rms_pop=0.08, gain_vs_open=None),
        "closed": NS(rms_pop=0.064, gain_vs_open=3.75)}})
    (text, blank) = loop_baselines(section)
    assert "'raw RMS' is the error of the delivered mu' against the texture's target" in text
    assert "grating-15mm: open 0.0800 -> closed 0.0640 (1.25x; against the reachable mu' 3.75x)" in text
    assert blank == ""
