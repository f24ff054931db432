"""frictex.replay(clock=...): a clock's name, or an object with wait(k) and finished(k, n),
as sinks take names or objects."""

import pytest

import frictex
from frictex.device.errors import InputError


class CountingClock:
    """A clock that paces nothing and keeps what it was asked and told."""

    def __init__(self):
        self.waited, self.finished_blocks = [], []

    def wait(self, k):
        self.waited.append(k)

    def finished(self, k, n):
        self.finished_blocks.extend(range(k, k + n))


def test_an_object_with_wait_and_finished_paces_the_replay():
    clock = CountingClock()
    done = frictex.replay("grating-5mm", "swipe-40mms-50hz", clock=clock)
    # any clock but "virtual" computes one block per call: the wall clock's run is the same
    paced = frictex.replay("grating-5mm", "swipe-40mms-50hz", clock="wall")
    blocks = done.summary.output.samples // done.summary.output.block_size
    assert clock.waited == clock.finished_blocks and len(clock.waited) >= blocks
    assert clock.waited == sorted(set(clock.waited)) and clock.waited[0] == 0
    for table in ("friction", "commands"):
        assert getattr(done, table).equals(getattr(paced, table))


@pytest.mark.parametrize("clock", [object(), 3, None, CountingClock.wait])
def test_anything_else_is_one_clear_error(clock):
    with pytest.raises(InputError, match=r"^clock: \w+ is neither a clock's name \(NAME\[:ARG\]\) "
                                         r"nor a Clock \(wait\(k\) and finished\(k, n\)\)$"):
        frictex.replay("grating-5mm", "swipe-40mms-50hz", clock=clock)


def test_an_object_missing_finished_is_refused():
    class WaitOnly:
        def wait(self, k):
            pass

    with pytest.raises(InputError, match="WaitOnly is neither"):
        frictex.replay("grating-5mm", "swipe-40mms-50hz", clock=WaitOnly())
