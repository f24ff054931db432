"""``--tuio-from ADDR`` without a port: two trackers on that address, one finger each,
alternating frames; only the first port heard moves a finger while it speaks."""

from frictex.rendering.input.trace_file import DOWN, MOVE
from frictex.rendering.input.tuio import TuioListener
from test_tuio import STILL, frame, received, sender


def test_two_ports_of_a_named_address_do_not_move_each_others_finger():
    """Issue: finger 0 went down at (20, 20), up, down at (80, 80), up, on every frame,
    and nothing was counted or said."""
    with TuioListener(0, width_mm=100.0, height_mm=100.0, clock=STILL,
                      accept_from=("127.0.0.1", None)) as listener, \
            sender("127.0.0.1") as a, sender("127.0.0.1") as b:
        to, samples = ("127.0.0.1", listener.port), []
        for k in range(1, 4):
            a.sendto(frame(k, [1], [(1, 0.25, 0.25)]), to)
            samples += received(listener, k, k - 1)
            b.sendto(frame(500 + k, [7], [(7, 0.8, 0.8)]), to)
            samples += received(listener, k, k)
        counts, a_port = listener.counters(), a.getsockname()[1]
    assert [(s.finger, s.x_mm, s.y_mm, s.event) for s in samples] == \
        [(0, 25.0, 25.0, DOWN), (0, 25.0, 25.0, MOVE), (0, 25.0, 25.0, MOVE)]
    assert counts["sender"] == f"127.0.0.1:{a_port}" and counts["refused"] == 3
