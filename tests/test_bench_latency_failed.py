"""frictex bench latency: a run in which no event played, or an audio output named by
FRICTEX_BENCH_AUDIO that could not be opened, is a failed figure (NaN; the bench exits
1), not "events played 0 of 20" with exit status 0; a machine without audio output, none
named, is not measured there (as one without QEMU)."""

import math

import numpy as np

from frictex.app.commands.bench import failed_figures
from frictex.app.measure import bench_latency


def test_no_touch_played_is_a_failed_figure_not_a_count_of_zero():
    [figure] = bench_latency._figures("tuio touch -> sim device played", np.empty(0), 20)
    assert figure.label == "tuio touch -> sim device played: none played of 20 touches"
    assert math.isnan(figure.value) and figure.failed == 20
    assert failed_figures([figure]) == [figure]


def test_an_audio_output_named_that_cannot_be_opened_is_a_failed_figure(monkeypatch):
    from frictex.device.audio import latency

    def no_device(*args, **kwargs):
        raise OSError("no such audio device 'hw:9'")

    monkeypatch.setattr(latency, "audio_latency", no_device)
    monkeypatch.setenv("FRICTEX_BENCH_AUDIO", "hw:9")
    reason = bench_latency._audio(20)
    [figure] = bench_latency._audio_figures("audio producer -> DAC (PortAudio)", reason, 20)
    assert figure.label == ("audio producer -> DAC (PortAudio): not measured, the audio output "
                            "could not be opened (OSError: no such audio device 'hw:9')")
    assert failed_figures([figure]) == [figure]
    monkeypatch.delenv("FRICTEX_BENCH_AUDIO")
    assert bench_latency._audio_figures("audio", reason, 20) == []  # none named: no output here


def test_an_audio_output_that_played_gives_its_percentiles():
    figures = bench_latency._audio_figures("audio", np.full(20, 0.004), 20)
    assert [f.value for f in figures] == [4.0, 4.0, 20]
    assert failed_figures(figures) == []
