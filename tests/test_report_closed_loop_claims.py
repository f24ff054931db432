"""The closed-loop section's claims and text, on made-up runs."""

from frictex.app.measure.report_closed_loop import claims

from test_closed_loop_parts import OPEN, _section


def test_the_oscillation_claim_gives_each_modes_longest_run_and_no_interval():
    section = _section(OPEN, OPEN, swings=3)  # closed swings 3 times, adaptive 2
    found = {c.group: c for c in claims(section)}
    text = found["closed loop: no growing oscillation"].text
    assert "closed 3, adaptive 2, against" in text
    assert "interval" not in text and f"{2 * len(OPEN)} runs" in text


def test_the_adaptation_gap_is_stated_over_the_scenes_amplitude_limit(monkeypatch):
    from dataclasses import replace
    from types import SimpleNamespace

    from frictex.app.measure import report_closed_loop as rcl
    from frictex.app.measure.report_loop_records import Adaptation
    section = replace(_section(OPEN, OPEN), adaptation=Adaptation(
        scene="objects-bump-edge-disc", duration_s=20.0, fingers=2, gap_max=0.05,
        gap_median=0.04, gaps=[0.03, 0.05]))
    device = SimpleNamespace(amplitude_limit_um=3.5)
    monkeypatch.setattr(rcl, "load", lambda scene: SimpleNamespace(device=device))
    text = "\n".join(rcl.markdown(section))
    assert "finger over 0-3.5 um (the device's amplitude limit)" in text
    assert "2.5 um" not in text


def test_the_closed_loop_plot_has_a_caption_naming_its_points_and_lines():
    from frictex.app.measure.report_markdown import plot_captions
    from test_report_tables import SETTINGS
    caption = plot_captions(SETTINGS)["closed_loop.png"][1]
    assert "each point is one finger" in caption and "against its RMS in open loop" in caption
    assert "the dashed line the scene's target" in caption


def test_a_count_with_no_interval_claims_leaves_the_interval_count_out():
    from frictex.app.measure.report_claims import INTERVAL, count_line
    found = [c for c in claims(_section(OPEN, OPEN)) if c.decided_by != INTERVAL]
    line = count_line(found)
    assert "95 % interval" not in line
    assert "(decided by one number, no interval: " in line


def test_the_throughput_heading_names_the_touch_rate_its_rows_have():
    from test_report_timings import COMPOSED, _throughput
    from test_report_tables import row
    heading = next(line for line in _throughput([row(scene=COMPOSED)]).splitlines()
                   if line.startswith("## Throughput"))
    assert heading == "## Throughput and latency (composed scene, one finger, 50 Hz touch, 10 kHz)"


def test_the_adaptation_claim_says_it_tests_the_mean_gap_and_gives_the_largest():
    """The claim's interval is over the mean gap: one finger above the target does not
    stop it holding, so the text says mean and counts the fingers above."""
    from dataclasses import replace

    from frictex.app.measure.report_loop_records import Adaptation
    gaps = [0.03, 0.04, 0.05, 0.04, 0.03, 0.05, 0.04, 0.12]
    section = replace(_section(OPEN, OPEN), adaptation=Adaptation(
        scene="objects-bump-edge-disc", duration_s=4.0, fingers=len(gaps), gap_max=max(gaps),
        gap_median=0.04, gaps=gaps))
    claim = next(c for c in claims(section) if c.group == "closed loop: adaptation")
    assert claim.passed
    assert "within 10% RMS of the true finger in the mean over the fingers: mean gap - 0.1" \
        in claim.text
    assert "8 fingers; largest gap 0.120 (1 of 8 fingers above 0.1)" in claim.text
