"""A TUIO sender flooding frames (1 cursor, 142,802 frames in 4 s) had every MOVE forwarded
to the haptic side: 822 of 3573 blocks missed their deadline, the worst 533 ms late. The
pump forwards at most once a block: every DOWN and UP in order, of a finger's MOVEs since
the last forward only the latest, the others counted as coalesced."""

from frictex.app.live.touch_pump import TouchPump
from frictex.rendering.input.evdev_decode import TouchSample
from frictex.rendering.input.trace_file import DOWN, MOVE, UP

BLOCK_S = 0.0025


class FakeHaptic:
    """A haptic side on the sources' clock that keeps what it is given."""

    block_s = BLOCK_S

    def __init__(self):
        self.got = []  # (finger, x_mm, event)

    def now(self):
        return 0.0

    def touch_at(self, t_s, finger, x_mm, y_mm, force_n, event):
        self.got.append((finger, x_mm, event))


class ClockedSource:
    """Hands out one batch a poll and moves the clock ``step_s`` on; stops the pump after
    the last."""

    def __init__(self, batches, step_s):
        self.batches, self.step_s, self.t = list(batches), step_s, 0.0
        self.stop = None

    def wait(self, timeout_s):
        return True

    def poll(self):
        self.t += self.step_s
        if len(self.batches) == 1:
            self.stop()
        return self.batches.pop(0)

    def close(self):
        pass


def pumped(batches, step_s):
    """What reaches the haptic side (finger, x in mm of a 100 mm wide screen, event), and
    the pump's counters."""
    source, haptic = ClockedSource(batches, step_s), FakeHaptic()
    display = type("D", (), {"width_mm": 100.0, "height_mm": 100.0})
    pump = TouchPump(source, haptic, lambda: display, lambda: 0.5, clock=lambda: source.t)
    source.stop = pump._quit.set
    pump.run()
    return haptic.got, pump.counters()


def sample(finger, x, event):
    return TouchSample(0.0, finger, x, 0.5, 0.5, event)


def test_a_burst_of_moves_is_forwarded_as_the_latest_of_each_finger():
    moves = [sample(f, i / 1000, MOVE) for i in range(1000) for f in (0, 1)]
    got, counts = pumped([[sample(0, 0.0, DOWN), sample(1, 0.0, DOWN)], moves,
                          [sample(0, 0.5, UP)]], step_s=0.0)  # all within one block
    assert got == [(0, 0.0, DOWN), (1, 0.0, DOWN), (0, 99.9, MOVE), (1, 99.9, MOVE),
                   (0, 50.0, UP)]
    assert counts == {"samples": 5, "coalesced": 1998}


def test_a_touch_down_and_up_in_one_batch_is_kept_with_its_moves_in_order():
    batch = [sample(0, 0.1, DOWN), sample(0, 0.2, MOVE), sample(1, 0.9, MOVE),
             sample(0, 0.3, MOVE), sample(0, 0.4, UP), sample(0, 0.5, DOWN),
             sample(0, 0.6, MOVE), sample(0, 0.7, UP)]
    got, counts = pumped([batch], step_s=0.0)
    assert got == [(0, 10.0, DOWN), (1, 90.0, MOVE), (0, 30.0, MOVE), (0, 40.0, UP),
                   (0, 50.0, DOWN), (0, 60.0, MOVE), (0, 70.0, UP)]
    assert counts["coalesced"] == 1


def test_moves_a_block_apart_are_all_forwarded():
    batches = [[sample(0, 0.0, DOWN)]] + [[sample(0, i / 10, MOVE)] for i in range(1, 6)]
    got, counts = pumped(batches, step_s=BLOCK_S)
    assert [x for _, x, _ in got] == [0.0, 10.0, 20.0, 30.0, 40.0, 50.0]
    assert counts == {"samples": 6, "coalesced": 0}
