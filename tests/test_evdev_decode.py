"""evdev multi-touch decoding (protocols A and B) and the device-to-screen map."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from frictex.rendering.input.evdev_decode import (ABS_MT_POSITION_X as PX, ABS_MT_POSITION_Y as PY,
                                    ABS_MT_PRESSURE as PRESSURE, ABS_MT_SLOT as SLOT,
                                    ABS_MT_TOUCH_MAJOR as MAJOR, ABS_MT_TRACKING_ID as TID,
                                    BTN_TOUCH, EV_ABS, EV_KEY, EV_SYN, SYN_DROPPED, SYN_MT_REPORT,
                                    SYN_REPORT, AbsInfo, AxisMap, EvdevDecoder, RawSample,
                                    ScreenMap, ScreenSpec, decode_all, screen_map, signed32)
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, TraceError


def abs_(t, code, value):
    return (t, EV_ABS, code, value)


def syn(t, code=SYN_REPORT):
    return (t, EV_SYN, code, 0)


def frame_a(t, contacts):
    """A protocol A frame: contacts are (x, y) or (x, y, tracking_id)."""
    out = []
    for c in contacts:
        out += [abs_(t, PX, c[0]), abs_(t, PY, c[1])]
        if len(c) > 2:
            out.append(abs_(t, TID, c[2]))
        out.append(syn(t, SYN_MT_REPORT))
    if not contacts:
        out.append(syn(t, SYN_MT_REPORT))
    return out + [syn(t)]


def summary(samples):
    return [(s.t_s, s.finger, s.x, s.y, s.event) for s in samples]


def test_protocol_a_with_tracking_ids():
    ev = (frame_a(0.0, [(10, 20, 5)]) + frame_a(0.01, [(11, 21, 5), (50, 60, 6)])
          + frame_a(0.02, [(51, 61, 6)]) + frame_a(0.03, []))
    samples, dec = decode_all(ev, "<a>")
    assert dec.protocol == "A" and dec.frames == 4
    assert summary(samples) == [
        (0.0, 0, 10, 20, DOWN),
        (0.01, 0, 11, 21, MOVE), (0.01, 1, 50, 60, DOWN),
        (0.02, 0, 11, 21, UP), (0.02, 1, 51, 61, MOVE),
        (0.03, 1, 51, 61, UP)]


def test_protocol_a_without_ids_matches_by_distance_not_order():
    # two fingers; then the one reported first lifts: the remaining one keeps its id
    ev = (frame_a(0.0, [(100, 100), (500, 500)]) + frame_a(0.01, [(102, 101), (505, 503)])
          + frame_a(0.02, [(510, 506)]))
    samples, _ = decode_all(ev, "<a>")
    assert summary(samples)[-2:] == [(0.02, 0, 102, 101, UP), (0.02, 1, 510, 506, MOVE)]
    # reported in the other order: still matched to the nearest
    ev = frame_a(0.0, [(100, 100), (500, 500)]) + frame_a(0.01, [(505, 503), (102, 101)])
    samples, _ = decode_all(ev, "<a>")
    assert [(s.finger, s.x) for s in samples[2:]] == [(1, 505), (0, 102)]


def test_protocol_a_finger_ids_are_reused_after_lift():
    ev = (frame_a(0.0, [(1, 1, 7)]) + frame_a(0.01, [(1, 1, 7), (9, 9, 8)]) + frame_a(0.02, [(9, 9, 8)])
          + frame_a(0.03, [(9, 9, 8), (3, 3, 9)]))
    samples, _ = decode_all(ev, "<a>")
    assert [(s.finger, s.event) for s in samples if s.t_s == 0.03] == [(1, MOVE), (0, DOWN)]


def test_protocol_a_btn_touch_release_lifts_and_other_frames_change_nothing():
    ev = frame_a(0.0, [(1, 2)]) + [abs_(0.01, 0x28, 7), syn(0.01)]  # ABS_MISC only
    ev += [(0.02, EV_KEY, BTN_TOUCH, 0), syn(0.02)]
    samples, _ = decode_all(ev, "<a>")
    assert summary(samples) == [(0.0, 0, 1, 2, DOWN), (0.02, 0, 1, 2, UP)]


def test_protocol_a_keeps_pressure_and_touch_major():
    ev = [abs_(0, PX, 1), abs_(0, PY, 2), abs_(0, PRESSURE, 40), abs_(0, MAJOR, 6),
          syn(0, SYN_MT_REPORT), syn(0)]
    (s,), _ = decode_all(ev, "<a>")
    assert (s.pressure, s.touch_major) == (40.0, 6.0)


def test_protocol_a_unchanged_rereport_is_kept():
    # refdata phone-two-finger-drag: finger 1 re-reported unmoved 0.57 ms after finger 0 moved
    ev = frame_a(0.0, [(10, 10, 0), (90, 90, 1)]) + frame_a(0.00057, [(12, 10, 0), (90, 90, 1)])
    samples, _ = decode_all(ev, "<a>")
    assert summary(samples)[2:] == [(0.00057, 0, 12, 10, MOVE), (0.00057, 1, 90, 90, MOVE)]


def test_protocol_b_slots_changed_axes_only():
    ev = [abs_(0, TID, 40), abs_(0, PX, 100), abs_(0, PY, 200), syn(0),
          abs_(0.01, PX, 110), syn(0.01),                                    # only x sent
          abs_(0.02, SLOT, 1), abs_(0.02, TID, 41), abs_(0.02, PX, 300), abs_(0.02, PY, 400), syn(0.02),
          abs_(0.03, SLOT, 0), abs_(0.03, PY, 210), syn(0.03),
          abs_(0.04, TID, signed32(0xFFFFFFFF)), syn(0.04),                  # slot 0 lifts
          abs_(0.05, SLOT, 1), abs_(0.05, PX, 305), syn(0.05)]
    samples, dec = decode_all(ev, "<b>")
    assert dec.protocol == "B"
    assert summary(samples) == [
        (0.0, 0, 100, 200, DOWN), (0.01, 0, 110, 200, MOVE), (0.02, 1, 300, 400, DOWN),
        (0.03, 0, 110, 210, MOVE), (0.04, 0, 110, 210, UP), (0.05, 1, 305, 400, MOVE)]


def test_protocol_b_new_tracking_id_in_a_slot_is_a_lift_and_a_touch():
    ev = [abs_(0, TID, 1), abs_(0, PX, 5), abs_(0, PY, 5), syn(0),
          abs_(0.01, TID, 2), abs_(0.01, PX, 80), syn(0.01)]
    samples, _ = decode_all(ev, "<b>")
    assert summary(samples) == [(0.0, 0, 5, 5, DOWN), (0.01, 0, 5, 5, UP), (0.01, 0, 80, 5, DOWN)]


def test_protocol_b_contact_without_position_waits_and_is_counted():
    ev = [abs_(0, TID, 1), abs_(0, PX, 5), syn(0), abs_(0.01, PY, 7), syn(0.01)]
    samples, dec = decode_all(ev, "<b>")
    assert summary(samples) == [(0.01, 0, 5, 7, DOWN)] and dec.unplaced == 1


def test_protocol_b_positions_without_a_tracking_id_are_counted_and_named():
    """Issue: a recording whose only frame set a slot's X and Y with no ABS_MT_TRACKING_ID
    was refused as 'no touches found (3 events, 1 frames; expected ABS_MT_* contacts)',
    although it holds ABS_MT_* events; the reason is now said."""
    with pytest.raises(TraceError, match=r"^rec.evemu: no touches found: positions in 2 frames "
                                         r"came with no ABS_MT_TRACKING_ID \(protocol B "
                                         r"contacts start with one\)$"):
        decode_all([abs_(1, PX, 5), abs_(1, PY, 5), syn(1), abs_(2, PX, 9), syn(2)], "rec.evemu")
    ev = [abs_(0, PX, 5), abs_(0, PY, 5), syn(0), abs_(0.01, TID, 7), syn(0.01),
          abs_(0.02, PX, 6), syn(0.02)]
    samples, dec = decode_all(ev, "<b>")  # with touches: counted, no error
    assert summary(samples) == [(0.01, 0, 5, 5, DOWN), (0.02, 0, 6, 5, MOVE)]
    assert dec.untracked == 1


def test_syn_dropped_discards_until_the_next_report():
    ev = frame_a(0.0, [(1, 1)]) + [abs_(0.01, PX, 999), syn(0.01, SYN_DROPPED), abs_(0.01, PY, 5),
                                   syn(0.01)] + frame_a(0.02, [(2, 2)])
    samples, dec = decode_all(ev, "<a>")
    assert dec.dropped == 1 and [s.x for s in samples] == [1, 2]


def test_a_protocol_a_lift_lost_in_a_drop_is_inferred_after_a_silence():
    """A Samsung screen reuses tracking id 0 for every tap: with the lifting frame lost
    in a drop, the next tap 2 s on carried on the first as one touch (a 54 mm jump across
    2 s without a sample). Past LIFT_LOST_S of silence after a drop, the contacts are
    lifted where last seen; a drop within a touch still moving lifts nothing."""
    from frictex.rendering.input.evdev_decode import LIFT_LOST_S
    ev = (frame_a(10.0, [(10, 20, 0)]) + frame_a(10.015, [(11, 20, 0)])
          + [syn(10.02, SYN_DROPPED), syn(10.02, SYN_MT_REPORT), syn(10.02)]
          + frame_a(12.0, [(400, 600, 0)]) + frame_a(12.05, []))
    samples, dec = decode_all(ev, "<a>")
    assert summary(samples) == [(10.0, 0, 10, 20, DOWN), (10.015, 0, 11, 20, MOVE),
                                (10.015, 0, 11, 20, UP), (12.0, 0, 400, 600, DOWN),
                                (12.05, 0, 400, 600, UP)]
    assert dec.dropped == 1 and dec.lifts_lost == 1
    moving = (frame_a(0.0, [(10, 20, 0)]) + [syn(0.005, SYN_DROPPED), syn(0.005)]
              + frame_a(0.01 + LIFT_LOST_S / 2, [(12, 20, 0)]))
    samples, dec = decode_all(moving, "<a>")
    assert [s.event for s in samples] == [DOWN, MOVE] and dec.lifts_lost == 0


def test_syn_dropped_keeps_the_slot_an_abs_mt_slot_names_in_the_dropped_span():
    # slot 1 holds id 0x65, slot 0 (the current slot) 0x66; after the drop, slot 1 moves,
    # then frames without ABS_MT_SLOT lift slot 1, and slot 0 lifts last
    ev = [abs_(0, SLOT, 1), abs_(0, TID, 0x65), abs_(0, PX, 0x200), abs_(0, PY, 0x200),
          abs_(0, SLOT, 0), abs_(0, TID, 0x66), abs_(0, PX, 0x100), abs_(0, PY, 0x100), syn(0),
          syn(0.05, SYN_DROPPED),
          abs_(0.07, SLOT, 1), abs_(0.07, PY, 0x300), syn(0.07),
          abs_(0.08, TID, -1), syn(0.08),
          abs_(0.09, SLOT, 0), abs_(0.09, TID, -1), syn(0.09)]
    samples, dec = decode_all(ev, "<b>")
    assert dec.dropped == 1
    assert summary(samples) == [
        (0, 0, 0x100, 0x100, DOWN), (0, 1, 0x200, 0x200, DOWN), (0.07, 1, 0x200, 0x300, MOVE),
        (0.08, 1, 0x200, 0x300, UP), (0.09, 0, 0x100, 0x100, UP)]


def test_syn_dropped_discards_events_of_an_unknown_slot():
    # before the span's ABS_MT_SLOT the lost events may have chosen any slot: x 999 is not kept
    ev = [abs_(0, TID, 7), abs_(0, PX, 1), abs_(0, PY, 1), syn(0), syn(0.01, SYN_DROPPED),
          abs_(0.01, PX, 999), abs_(0.01, SLOT, 0), abs_(0.01, PY, 2), syn(0.01)]
    samples, dec = decode_all(ev, "<b>")
    assert dec.dropped == 1 and summary(samples) == [(0, 0, 1, 1, DOWN), (0.01, 0, 1, 2, MOVE)]


def test_unfinished_frame_is_pending():
    ev = frame_a(0.0, [(1, 1)]) + [abs_(0.01, PX, 3)]
    samples, dec = decode_all(ev, "<a>")
    assert len(samples) == 1 and dec.pending == 1


@pytest.mark.parametrize("events, message", [
    (frame_a(1.0, [(1, 1)]) + frame_a(0.5, [(1, 1)]), r"^<e>: time goes back from 1.0 to 0.5"),
    ([abs_(0, SLOT, 1), syn(0, SYN_MT_REPORT), syn(0)], "mixes SYN_MT_REPORT"),
    (frame_a(0, [(1, 1)]) + [abs_(1, SLOT, 0), abs_(1, PX, 3), syn(1)], "protocol B but the stream so far used protocol A"),
    ([abs_(0, SLOT, 99), syn(0)], "ABS_MT_SLOT 99 is out of range"),
    (frame_a(0, [(1, 1, 3), (2, 2, 3)]), "tracking id 3 twice"),
    ([syn(math.nan)], "not a finite number"),
])
def test_bad_streams_raise_trace_errors(events, message):
    with pytest.raises(TraceError, match=message):
        decode_all(events, "<e>")


def test_error_names_the_line():
    ev = [(1.0, EV_SYN, SYN_REPORT, 0, 12), (0.5, EV_SYN, SYN_REPORT, 0, 13)]
    with pytest.raises(TraceError, match=r"^rec.txt:13: time goes back"):
        decode_all(ev, "rec.txt")


def test_signed32():
    assert [signed32(v) for v in (0, 5, 0x7FFFFFFF, 0xFFFFFFFF, 0x80000000)] == \
        [0, 5, 2 ** 31 - 1, -1, -2 ** 31]


# -- random streams -------------------------------------------------------------------------
_value = st.integers(0, 1100)
_contact_a = st.tuples(st.sampled_from([PX, PY, PRESSURE]), _value).map(lambda e: [e]) | \
    st.tuples(_value, _value, st.sampled_from([None, 0, 1, 2, 3])).map(
        lambda c: [(PX, c[0]), (PY, c[1])] + ([] if c[2] is None else [(TID, c[2])]))
_frame_a = st.lists(_contact_a, max_size=4).map(
    lambda cs: [e for c in cs for e in [(EV_ABS, *a) for a in c] + [(EV_SYN, SYN_MT_REPORT, 0)]])
_op_b = st.one_of(st.tuples(st.just(SLOT), st.integers(0, 3)),
                  st.tuples(st.just(TID), st.sampled_from([-1, 10, 11, 12, 13])),
                  st.tuples(st.sampled_from([PX, PY, PRESSURE, MAJOR]), _value))
_frame_b = st.lists(_op_b, max_size=8).map(lambda ops: [(EV_ABS, *o) for o in ops])
_noise = st.sampled_from([(EV_SYN, SYN_DROPPED, 0), (EV_KEY, BTN_TOUCH, 0), (EV_KEY, BTN_TOUCH, 1),
                          (EV_ABS, 0x28, 5), (EV_ABS, SLOT, 99), (EV_SYN, SYN_MT_REPORT, 0)])


@st.composite
def _stream(draw):
    """Mostly well-formed protocol A or B frames, with some noise; times non-decreasing."""
    frame = _frame_a if draw(st.booleans()) else _frame_b
    events, t = [], 0.0
    for _ in range(draw(st.integers(0, 12))):
        body = draw(frame)
        if draw(st.integers(0, 9)) == 0:
            body.insert(draw(st.integers(0, len(body))), draw(_noise))
        t += draw(st.sampled_from([0.0, 0.00057, 0.015]))
        events += [(t, *e) for e in body] + [(t, EV_SYN, SYN_REPORT, 0)]
    return events


def check_event_sequence(samples):
    """Samples in time order, finite, each finger down before it moves, up before it is down again."""
    down: set[int] = set()
    for s in samples:
        assert isinstance(s, RawSample) and s.finger >= 0
        assert math.isfinite(s.x) and math.isfinite(s.y)
        if s.event == DOWN:
            assert s.finger not in down
            down.add(s.finger)
        else:
            assert s.finger in down
            if s.event == UP:
                down.remove(s.finger)
    assert all(b.t_s >= a.t_s for a, b in zip(samples, samples[1:]))


@settings(max_examples=200, derandomize=True, deadline=None)
@given(_stream())
def test_random_streams_give_consistent_samples_or_trace_errors(events):
    try:
        samples, _ = decode_all(events, "<random>")
    except TraceError:
        return
    check_event_sequence(samples)


@settings(max_examples=100, derandomize=True, deadline=None)
@given(_stream(), st.lists(st.integers(0, 120), max_size=4))
def test_feeding_in_pieces_equals_feeding_whole(events, cuts):
    try:
        whole, _ = decode_all(events, "<r>")
    except TraceError:
        return
    dec = EvdevDecoder("<r>")
    pieces = []
    bounds = [0] + sorted(cuts) + [len(events)]
    for a, b in zip(bounds, bounds[1:]):
        pieces += dec.feed(events[a:b])
    assert pieces == whole


# -- device to screen -----------------------------------------------------------------------
def test_axis_map_and_flip():
    assert_allclose(AxisMap(0, 1023, 52.0).mm(np.array([0, 1023, 511.5])), [0, 52, 26], rtol=1e-12)
    assert_allclose(AxisMap(100, 200, 10.0, flip=True).mm(np.array([100, 150])), [10, 5], rtol=1e-12)
    with pytest.raises(TraceError, match="axis range 5.0..5.0"):
        AxisMap(5.0, 5.0, 1.0)
    with pytest.raises(TraceError, match="screen size -1 mm"):
        AxisMap(0, 1, -1)


def test_screen_map_swap_and_pressure():
    samples = [RawSample(0.0, 0, 1000.0, 0.0, 50.0, 3.0, DOWN)]
    spec = ScreenSpec(width_mm=100, height_mm=200, x_range=(0, 1000), y_range=(0, 500), swap_xy=True,
                      pressure_n=0.01)
    screen, warnings = screen_map(spec, {})
    cols = screen.arrays(samples)
    # device X (1000 of 0..1000) runs along screen y (200 mm); device Y 0 -> screen x 0
    assert (cols["x_mm"][0], cols["y_mm"][0], cols["force_n"][0]) == (0.0, 200.0, 0.5)
    assert warnings == []
    no_pressure = [samples[0]._replace(pressure=math.nan)]
    with pytest.raises(TraceError, match="has no pressure, but a pressure scale was given"):
        screen.arrays(no_pressure)


def test_screen_map_sources_in_order_of_trust():
    observed = {PX: (10.0, 90.0), PY: (20.0, 80.0)}
    absinfo = {PX: AbsInfo(0, 4000, 40), PY: AbsInfo(0, 3000, 40)}
    screen, warnings = screen_map(ScreenSpec(), absinfo, observed)
    # size from the resolution: 4000 / 40 units/mm = 100 mm
    assert (screen.x.lo, screen.x.hi, screen.x.size_mm, screen.y.size_mm) == (0, 4000, 100, 75)
    screen, _ = screen_map(ScreenSpec(width_mm=50, height_mm=60, x_range=(5, 6)), absinfo, observed)
    assert (screen.x.lo, screen.x.hi, screen.x.size_mm, screen.y.hi) == (5, 6, 50, 3000)
    screen, warnings = screen_map(ScreenSpec(width_mm=50, height_mm=60), {}, observed)
    assert (screen.x.lo, screen.x.hi) == (10, 90) and len(warnings) == 2
    assert "device x range unknown: using the observed 10..90 at 1.6 units/mm" in warnings[0]
    # one scale for both axes: y's 60 units are 37.5 mm of the 60, not stretched to 60
    assert (screen.y.lo, screen.y.hi) == (20, 20 + 1.6 * 60)
    assert "using the observed 20..80 at 1.6 units/mm, one scale for both axes" in warnings[1]
    with pytest.raises(TraceError, match="give --width-mm"):
        screen_map(ScreenSpec(), {}, observed)
    with pytest.raises(TraceError, match=r"only shows x = 7\): give --x-range"):
        screen_map(ScreenSpec(width_mm=1, height_mm=1), {}, {PX: (7.0, 7.0), PY: (1.0, 2.0)})


def test_screen_touches_are_mm():
    screen = ScreenMap(AxisMap(0, 1, 200.0), AxisMap(0, 1, 100.0), force_n=0.3)
    (t,) = screen.touches([RawSample(1.5, 2, 0.25, 0.5, math.nan, math.nan, MOVE)])
    assert t == (1.5, 2, 50.0, 50.0, 0.3, MOVE)
    assert screen.touches([]) == []
