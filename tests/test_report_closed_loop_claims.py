"""The closed-loop section's claims and text, on made-up runs."""

from frictex.app.measure.report_closed_loop import claims

from test_closed_loop_parts import OPEN, _section


def test_the_oscillation_claim_gives_each_modes_longest_run_and_no_interval():
    section = _section(OPEN, OPEN, swings=3)  # closed swings 3 times, adaptive 2
    found = {c.group: c for c in claims(section)}
    text = found["closed loop: no growing oscillation"].text
    assert "closed 3, adaptive 2, against" in text
    assert "interval" not in text and f"{2 * len(OPEN)} runs" in text
