"""Live evdev reading on a FIFO and a file of packed ``struct input_event`` (no device needed)."""

import os
import struct

import pytest

from frictex.rendering.input.evdev_decode import (ABS_MT_POSITION_X as PX, ABS_MT_POSITION_Y as PY,
                                    ABS_MT_SLOT as SLOT, ABS_MT_TRACKING_ID as TID, EV_ABS, EV_SYN,
                                    SYN_REPORT, ScreenSpec)
from frictex.rendering.input.evdev_live import EVIOCSCLOCKID, INPUT_EVENT, EvdevReader, eviocgabs, unpack_events
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, TraceError

SPEC = ScreenSpec(width_mm=100.0, height_mm=50.0, x_range=(0, 1000), y_range=(0, 1000))


def packed(*events):
    """(sec, usec, type, code, value) records as the kernel writes them."""
    return b"".join(INPUT_EVENT.pack(*e) for e in events)


# protocol B: touch at (500, 200), move x to 600, lift
STREAM = packed((10, 0, EV_ABS, SLOT, 0), (10, 0, EV_ABS, TID, 3), (10, 0, EV_ABS, PX, 500),
                (10, 0, EV_ABS, PY, 200), (10, 0, EV_SYN, SYN_REPORT, 0),
                (10, 8000, EV_ABS, PX, 600), (10, 8000, EV_SYN, SYN_REPORT, 0),
                (10, 16000, EV_ABS, TID, -1), (10, 16000, EV_SYN, SYN_REPORT, 0))


def test_ioctl_request_numbers_match_linux_headers():
    # <linux/input.h>: EVIOCGABS(ABS_X) = _IOR('E', 0x40, struct input_absinfo) = 0x80184540
    assert eviocgabs(0) == 0x80184540 and eviocgabs(0x35) == 0x80184575
    assert EVIOCSCLOCKID == 0x400445A0  # _IOW('E', 0xa0, int)


def test_unpack_keeps_the_incomplete_tail():
    events, rest = unpack_events(STREAM[:INPUT_EVENT.size * 2 + 5])
    assert [e[:4] for e in events] == [(10.0, EV_ABS, SLOT, 0), (10.0, EV_ABS, TID, 3)]
    assert rest == STREAM[INPUT_EVENT.size * 2:INPUT_EVENT.size * 2 + 5]
    events, _ = unpack_events(STREAM)
    assert events[5].t_s == 10.008 and events[7].value == -1


def test_fifo_with_records_split_across_writes(tmp_path):
    fifo = tmp_path / "events"
    os.mkfifo(fifo)
    with EvdevReader(fifo, SPEC) as reader:
        assert reader.poll() == []  # nothing written yet, and it does not block
        wfd = os.open(fifo, os.O_WRONLY)
        try:
            cut = INPUT_EVENT.size * 4 + 7  # inside the record of the first SYN_REPORT
            os.write(wfd, STREAM[:cut])
            assert reader.poll() == []
            os.write(wfd, STREAM[cut:INPUT_EVENT.size * 7])
            first = reader.poll()
            os.write(wfd, STREAM[INPUT_EVENT.size * 7:])
            second = reader.poll()
        finally:
            os.close(wfd)
    assert [(s.t_s, s.finger, s.x_mm, s.y_mm, s.event) for s in first + second] == [
        (10.0, 0, 50.0, 10.0, DOWN), (10.008, 0, 60.0, 10.0, MOVE), (10.016, 0, 60.0, 10.0, UP)]


def test_file_of_packed_events(tmp_path):
    path = tmp_path / "events.bin"
    path.write_bytes(STREAM)
    with EvdevReader(path, ScreenSpec(width_mm=100.0, height_mm=50.0, x_range=(0, 1000),
                                      y_range=(0, 1000), swap_xy=True)) as reader:
        samples = reader.poll()
    # swapped: screen x from device y (200 of 1000 over 100 mm), screen y from device x
    assert [(s.x_mm, s.y_mm) for s in samples] == [(20.0, 25.0), (20.0, 30.0), (20.0, 30.0)]


def test_ranges_are_required_without_a_device(tmp_path):
    path = tmp_path / "events.bin"
    path.write_bytes(b"")
    with pytest.raises(TraceError, match=r"device x range unknown: give --x-range"):
        EvdevReader(path, ScreenSpec(width_mm=1.0, height_mm=1.0))


def test_missing_device_is_a_clear_os_error(tmp_path):
    with pytest.raises(OSError, match=r"events9: cannot open input device \(No such file"):
        EvdevReader(tmp_path / "events9", SPEC)


def test_struct_layout_is_the_kernels():
    # struct timeval (two longs) + __u16 type + __u16 code + __s32 value
    assert INPUT_EVENT.size == 2 * struct.calcsize("l") + 8


def test_a_large_file_is_taken_a_bounded_piece_per_poll(tmp_path):
    """One poll reads at most _READS_PER_POLL x _READ_BYTES; the polls after it take the
    rest, every sample once (/dev/zero, a file that never ends, gives each poll a piece)."""
    from frictex.rendering.input import evdev_live
    moves = 3 * evdev_live._READS_PER_POLL * evdev_live._READ_BYTES // (2 * INPUT_EVENT.size)
    path = tmp_path / "events.bin"
    path.write_bytes(STREAM[:INPUT_EVENT.size * 5] + packed(*(
        e for k in range(moves) for e in ((11, k, EV_ABS, PX, k % 1000), (11, k, EV_SYN, SYN_REPORT, 0)))))
    with EvdevReader(path, SPEC) as reader:
        polls = [reader.poll() for _ in range(5)]
    assert [len(samples) > 0 for samples in polls] == [True, True, True, True, False]
    assert sum(map(len, polls)) == moves + 1  # the touch-down, then each move
