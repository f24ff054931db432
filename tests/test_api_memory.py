"""Runs that keep their output in memory are refused up front when it would not fit: an
InputError naming the size and the way out (replay(out=...)), not a raw MemoryError
after minutes, or numpy's 'Unable to allocate 74.5 GiB'."""

import pytest

import frictex
from frictex.app.engine import tables

SCENE = "grating-5mm"


def long_pause(pause_s: float):
    """Two touches of one finger ``pause_s`` apart: one valid trace, mostly pause."""
    return frictex.make_trace([0.0, 0.01, pause_s, pause_s + 0.01], [0] * 4,
                              [20.0, 21.0, 22.0, 23.0], [30.0] * 4)


@pytest.fixture
def memory_of(monkeypatch):
    """Make the memory available ``bytes_available`` (None: unknown)."""
    def set_available(bytes_available):
        monkeypatch.setattr(tables, "available_memory", lambda: bytes_available)
    return set_available


def test_process_refuses_an_output_too_big_for_memory_naming_its_size():
    """1e6 s at 10 kHz: 1e10 samples, 1.92 TB by the rule, more than any machine here."""
    with pytest.raises(frictex.InputError, match=r"^the output of this 1e\+06 s trace "
                                                 r"\(10000000150 samples at 10000 Hz, 1 "
                                                 r"finger, pauses included\) would take "
                                                 r"about 1\.92 TB of memory, more than 50% "
                                                 r"of the .* available: replay\(out=\.\.\.\)"):
        frictex.build_pipeline(SCENE).process(long_pause(1e6))


def test_process_checks_against_the_memory_available(memory_of):
    """10 s: 100,150 samples of 8 values, 3 x 6.4 MB; refused with 20 MB, run with 40."""
    pipeline = frictex.build_pipeline(SCENE)
    memory_of(20e6)
    with pytest.raises(frictex.InputError, match="about 19.2 MB of memory, more than 50% of "
                                                 "the 20 MB available"):
        pipeline.process(long_pause(10.0))
    memory_of(40e6)
    assert pipeline.process(long_pause(10.0)).commands_um.shape == (100150, 1)
    memory_of(None)  # unknown: not checked
    assert pipeline.process(long_pause(10.0)).commands_um.shape == (100150, 1)


def test_replay_in_memory_is_refused_before_computing_and_to_a_folder_is_not(memory_of,
                                                                             tmp_path):
    trace = frictex.synth_trace("swipe", duration_s=1.0)
    memory_of(1e6)
    with pytest.raises(frictex.InputError, match=r"^the tables kept in memory \(1\.01 s at "
                                                 r"10000 Hz, one finger\) would take "
                                                 r"about .* MB of memory, more than 50% of the "
                                                 r"1 MB available: write them into a folder "
                                                 r"instead, a chunk at a time "
                                                 r"\(replay\(out=\.\.\.\)\)$"):
        frictex.replay(SCENE, trace)
    done = frictex.replay(SCENE, trace, out=tmp_path / "out")
    assert done.commands.num_rows == done.summary.output.samples


def test_the_memory_available_is_read_from_the_system():
    available = tables.available_memory()
    assert available is None or available > 0
