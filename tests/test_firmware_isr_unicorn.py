"""The STM32G0 build's per-sample path run as Cortex-M0+ code in unicorn: it plays the
commanded samples to the DAC, and its instructions per sample (deterministic, unlike
time) keep its estimated cycles within half the 6,400 a 10 kHz sample has at 64 MHz."""

import numpy as np
import pytest

from frictex.device.firmware.build import FirmwareBuildError

isr_unicorn = pytest.importorskip("frictex.device.firmware.isr_unicorn")
pytest.importorskip("unicorn", reason="unicorn not installed (pip install frictex[test])")


@pytest.fixture(scope="module")
def run():
    try:
        return isr_unicorn.measure(ticks=1200, prefill=100)
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)


def test_the_sample_interrupt_stores_the_commanded_samples_to_the_dac(run):
    _, words = run
    started = int(np.flatnonzero(words)[0])  # the commanded amplitudes are never zero
    # the second Block (at tick 50) fills the prefill of 100 samples: playing starts
    assert started == 50
    expected = isr_unicorn.dac_word(isr_unicorn.commanded(len(words) - started))
    np.testing.assert_array_equal(words[started:], expected)


def test_the_sample_interrupt_uses_at_most_half_the_cycles_of_a_sample(run):
    cost, _ = run
    assert cost.ticks == 1000
    assert isr_unicorn.BUDGET_CYCLES == 6400
    assert cost.cycles_max <= isr_unicorn.BUDGET_CYCLES // 2, cost.summary()
    # every instruction costs at least one cycle, entry and return on top
    assert cost.instructions_max + isr_unicorn.ENTRY_EXIT_CYCLES <= cost.cycles_max


def test_the_cycle_model_counts_taken_branches_and_register_lists():
    cycles = isr_unicorn._isr_cycles().cycles
    assert cycles("adds", "r0, #1", False) == 1
    assert cycles("ldr", "r0, [r1, #4]", False) == 2
    assert (cycles("bne.n", "8000100", True), cycles("bne.n", "8000100", False)) == (2, 1)
    assert cycles("push", "{r4, r5, r6, lr}", False) == 5
    assert cycles("pop", "{r4, r5, r6, pc}", True) == 7
