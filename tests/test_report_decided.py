"""Claims decided by one number, not an interval, and the family of claims (``report_claims``)."""

import json
from dataclasses import asdict

from test_closed_loop_parts import OPEN, _section
from test_report_verdicts import _fine

from frictex.app.measure.report_claims import (BOUND, BY_CONSTRUCTION, INTERVAL, WORST_RUN,
                                               Claim, count_line, family_note)
from frictex.app.measure.report_closed_loop import claims


def _loop_claims() -> dict:
    return {(c.group, c.metric): c for c in claims(_section(OPEN, OPEN))}


def test_a_claim_decided_by_one_number_has_no_interval_and_says_how_it_was_decided():
    found = _loop_claims()
    decided = {(g, m): c.decided_by for (g, m), c in found.items() if c.decided_by != INTERVAL}
    assert decided == {
        ("closed loop: worst finger", "worst rms_reachable ratio, closed"): WORST_RUN,
        ("closed loop: worst finger", "worst rms_reachable ratio, adaptive"): WORST_RUN,
        ("closed loop: no growing oscillation", "swings"): WORST_RUN,
        ("closed loop: amplitude limit", "max_command_um"): BY_CONSTRUCTION,
        ("closed loop: stability margin", "gain margin / steepest s"): BOUND}
    for key in decided:
        c = found[key]
        assert c.low is None and c.high is None, c  # no zero-width "interval over n runs"
        doc = json.loads(json.dumps(asdict(c)))
        assert doc["decided_by"] == c.decided_by and Claim(**doc) == c
    assert "by construction" in found[("closed loop: amplitude limit", "max_command_um")].text
    assert found[("closed loop: RMS error", "rms_reachable, closed")].decided_by == INTERVAL


def test_the_count_line_counts_claims_decided_by_one_number_apart():
    found = list(_loop_claims().values())
    line = count_line(found)
    assert line.startswith(f"{sum(c.passed for c in found)} of {len(found)} claims hold")
    statistical = [c for c in found if c.decided_by == INTERVAL]
    assert (f"by a 95 % interval: {sum(c.passed for c in statistical)} of "
            f"{len(statistical)} hold; decided by one number, no interval: ") in line
    assert "1 of them by construction" in line
    plain = [_fine([0.1, 0.11, 0.12], [0.2, 0.22, 0.21])]
    assert count_line(plain) == "1 of 1 claims hold, 0 do not, 0 not shown"


def test_the_family_note_names_its_size_and_that_each_interval_is_per_claim():
    found = list(_loop_claims().values())
    statistical = sum(c.decided_by == INTERVAL for c in found)
    note = family_note(found)
    assert f"{len(found)} claims, {statistical} of them judged by a 95 % interval" in note
    assert "per claim, not adjusted" in note and "1 time in 40" in note
