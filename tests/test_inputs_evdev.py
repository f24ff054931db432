"""``--input evdev:PATH``: a touch screen of any counts range opens, positions as
fractions of its range; only a device without ranges is refused as no touch screen."""

import pytest

from frictex.app.live.inputs import open_source, parse_input
from frictex.rendering.input import evdev_live
from frictex.rendering.input.evdev_decode import (ABS_MT_POSITION_X as PX, ABS_MT_POSITION_Y as PY,
                                                  ABS_MT_SLOT as SLOT, ABS_MT_TRACKING_ID as TID,
                                                  EV_ABS, EV_SYN, SYN_REPORT, AbsInfo)
from frictex.rendering.input.evdev_live import INPUT_EVENT
from frictex.rendering.input.trace_file import DOWN


def touch_at(x: int, y: int) -> bytes:
    """One protocol B frame putting a finger down at device counts (x, y)."""
    return b"".join(INPUT_EVENT.pack(*e) for e in (
        (10, 0, EV_ABS, SLOT, 0), (10, 0, EV_ABS, TID, 1), (10, 0, EV_ABS, PX, x),
        (10, 0, EV_ABS, PY, y), (10, 0, EV_SYN, SYN_REPORT, 0)))


@pytest.mark.parametrize("maximum", [4095, 16383, 32767])
def test_a_screen_of_many_counts_opens_with_positions_as_fractions(tmp_path, monkeypatch, maximum):
    """Issue: a device reporting 0..32767 (or 0..16383) along its axes was refused as 'not
    a multi-touch device reporting its axis ranges': the demo's map of 1 x 1 was checked
    as a real size, 32767 counts over 1 mm being more than the 10,000 units/mm believed."""
    path = tmp_path / "event5"
    path.write_bytes(touch_at(maximum // 4, maximum // 2))
    monkeypatch.setattr(evdev_live, "read_absinfo", lambda fd, code: AbsInfo(0, maximum, 0))
    source = open_source(*parse_input(f"evdev:{path}"))
    try:
        (sample,) = source.poll()
    finally:
        source.close()
    assert sample.event == DOWN
    assert sample.x_mm == pytest.approx((maximum // 4) / maximum, abs=1e-12)
    assert sample.y_mm == pytest.approx((maximum // 2) / maximum, abs=1e-12)


def test_only_a_device_without_ranges_is_said_to_be_no_touch_screen(tmp_path, monkeypatch):
    path = tmp_path / "event5"
    path.write_bytes(b"")
    monkeypatch.setattr(evdev_live, "read_absinfo",
                        lambda fd, code: AbsInfo(0, 1000, 0) if code == PX else None)
    with pytest.raises(ValueError, match=r"event5 is not a multi-touch device reporting its "
                                         r"axis ranges"):
        open_source(*parse_input(f"evdev:{path}"))
