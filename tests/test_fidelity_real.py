"""The refdata Android recordings (real fingers: phone and tablet, one and two fingers,
taps, drags, games) replayed through every renderer on the 5 mm grating
(``app.measure.report_real``, what ``frictex report --real`` writes)."""

from pathlib import Path

import numpy as np
import pytest

from app.measure.report_real import real_section

REFDATA = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "android-getevent"
pytestmark = pytest.mark.skipif(not REFDATA.is_dir(),
                                reason=f"refdata Android getevent logs not found at {REFDATA}")


@pytest.fixture(scope="module")
def section():
    return real_section(REFDATA, ["grating-5mm"])


def test_every_recording_replays_finite_and_unclamped(section):
    """18 logs: the two single taps cannot be mapped (one position: no range) and say so;
    the other 16 replay with finite outputs, no clamp and no finger jump."""
    assert {s["recording"] for s in section["skipped"]} == {"phone-single-touch.txt",
                                                          "tablet-single-touch.txt"}
    assert all("--x-range" in s["reason"] for s in section["skipped"])
    assert len(section["runs"]) == 16
    for run in section["runs"]:
        assert run["tracker"]["jumps"] == 0, run["recording"]
        for name, r in run["renderers"].items():
            assert r["finite"] and r["clamps"] == 0, (run["recording"], name)
            # an edge of the 0.6 / 1.0 grating is the largest amplitude step there is
            assert r["largest_step_um"] <= 2.5


def test_renderers_agree_where_they_should(section):
    """On real strokes the hybrid renders the 5 mm grating much as SHO-predicted does
    (the same locked position: spectral distance under 0.25, under 0.05 in most) and far
    from plain SHT, whose phase starts anywhere at each touch; its edge pairs (chatter)
    are about SHO-predicted's (within 10 % and 2), more than SHT's, which never jumps
    (see rendering/RENDERERS.md)."""
    moving = [run for run in section["runs"]
              if run["renderers"]["sht"]["spectral_distance_from_hybrid"] is not None]
    assert len(moving) >= 10
    near = [run["renderers"]["sho-predicted"]["spectral_distance_from_hybrid"] for run in moving]
    assert max(near) < 0.25 and np.median(near) < 0.05
    assert sum(run["renderers"]["sht"]["spectral_distance_from_hybrid"] > 0.3
               for run in moving) >= 0.8 * len(moving)
    for run in section["runs"]:
        r = run["renderers"]
        assert r["hybrid"]["chatter"] <= 1.1 * r["sho-predicted"]["chatter"] + 2, run["recording"]


def test_two_finger_roles_are_stable_on_both_devices(section):
    """Positional selection on the two two-finger drags: with the default hysteresis the
    left-most role changes hands at most once per recording (without: 3 on the phone,
    9 on the tablet)."""
    roles = {run["recording"]: run["roles"] for run in section["runs"]}
    for name, plain in (("phone-two-finger-drag.txt", 3), ("tablet-two-finger-drag.txt", 9)):
        assert roles[name]["left_most_swaps_without_hysteresis"] == plain
        assert roles[name]["left_most_swaps"] <= 1
