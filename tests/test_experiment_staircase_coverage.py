"""A staircase's slope interval is flagged as falling short of 95 %, and the coverage
measured on the bundled depth-staircase (50 of 100 runs) is quoted only where it was
measured: one complete session of that protocol, run unchanged. Three sessions pooled, or
a session of an edited copy, printed that figure beside "its coverage is not measured for
this design". Sessions written out here from the bundled staircase played by the
analytic observer (Weber 0.11, lapse 0.02; no pipeline)."""

import hashlib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from frictex.app.experiment import psychometric as P
from frictex.app.experiment.analysis import (NOT_MEASURED, SessionData, _play, analyse_study,
                                             report_lines)
from frictex.app.experiment.observer import p_choose_larger
from frictex.app.experiment.protocol import PROTOCOLS_DIR, load_protocol
from frictex.app.experiment.session import design

BUNDLED = PROTOCOLS_DIR / "depth-staircase.toml"
#: the measured figure, as printed
FIGURE = "50 of 100"


def staircase_session(name: str, seed: int, text: bytes) -> SessionData:
    """One complete session of the bundled depth-staircase's design, its protocol file
    ``text`` (the bundled file's or an edited copy's), bootstrap cut to 40 runs."""
    protocol = load_protocol(BUNDLED)
    reference = protocol.stimuli.reference
    x, correct, _ = _play(protocol.staircase,
                          lambda d: p_choose_larger((reference + d) / reference, 0.11, 0.02),
                          np.random.default_rng(seed))
    shown = design(protocol)
    shown["analysis"] = {**shown["analysis"], "bootstrap": 40}
    info = {"protocol": "depth-staircase", "method": "staircase", "design": shown,
            "protocol_sha256": hashlib.sha256(text).hexdigest(),
            "ended_utc": "2026-01-01T00:00:00+00:00",
            "parts": [{"ended": "complete", "trials": len(x)}]}
    rows = [{"practice": "0", "difference": repr(float(d)), "correct": str(int(c))}
            for d, c in zip(x, correct)]
    return SessionData(Path(name), info, rows)


@pytest.fixture
def settled_slope(monkeypatch):
    """A staircase fit whose slope the data settle (as two sessions' pooled trials do;
    one session's ~45 trials leave it only bounded below): its interval 20 % either
    side."""
    fit_adaptive = P.fit_adaptive

    def settled(*args, **kwargs):
        fit = fit_adaptive(*args, **kwargs)
        return replace(fit, slope_unsettled=None,
                       slope_ci=(0.8 * fit.slope, 1.2 * fit.slope))
    monkeypatch.setattr(P, "fit_adaptive", settled)


def test_one_complete_bundled_session_quotes_the_measured_coverage(settled_slope):
    summary = analyse_study([staircase_session("ds3", 3, BUNDLED.read_bytes())])
    fit = summary["pooled"]
    assert fit["slope_ci_method"].endswith("; " + P.RERUN_COVERAGE)
    assert fit["slope_ci95_unsettled"] == P.RERUN_SHORT
    assert FIGURE in P.RERUN_SHORT


def test_pooled_sessions_do_not_quote_it():
    """Two sessions pooled (their slope settled by the data)."""
    text = BUNDLED.read_bytes()
    summary = analyse_study([staircase_session(f"ds{seed}", seed, text) for seed in (3, 4)])
    fit = summary["pooled"]
    assert fit["slope_ci_method"].endswith("; " + NOT_MEASURED)
    assert fit["slope_ci95_unsettled"] == P.RERUN_LOOSE
    assert FIGURE not in "\n".join(report_lines(summary))


def test_an_edited_copy_does_not_quote_it(settled_slope):
    edited = BUNDLED.read_bytes().replace(b"reversals = 14", b"reversals = 16")
    summary = analyse_study([staircase_session("own", 3, edited)])
    fit = summary["pooled"]
    assert fit["slope_ci_method"].endswith("; " + NOT_MEASURED)
    assert fit["slope_ci95_unsettled"] == P.RERUN_LOOSE
    assert FIGURE not in "\n".join(report_lines(summary))
