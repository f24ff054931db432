"""trace synth: jitter against the sample interval, help defaults."""

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.device.errors import InputError
from frictex.rendering.input.trace_synth import make_motion, sample


def _swipe():
    return make_motion("swipe", speed_mm_s=40.0, duration_s=2.0, x0_mm=14.0, y0_mm=32.4,
                       angle_deg=0.0, length_mm=80.0, radius_mm=20.0, area_mm=(108.0, 64.8), seed=0)


@pytest.mark.parametrize("jitter_s", [0.01, 0.05, 1.0])
def test_jitter_of_half_the_interval_or_more_is_refused(jitter_s):
    with pytest.raises(InputError, match=rf"^jitter {jitter_s:g} s: expected less than half the "
                                         r"sample interval, 0\.01 s at 50 Hz"):
        sample(_swipe(), 50.0, jitter_s=jitter_s)


def test_a_small_jitter_keeps_every_timestamp_distinct():
    t = sample(_swipe(), 50.0, jitter_s=0.002).t_s
    assert np.all(np.diff(t) > 0)


def test_the_cli_names_the_jitter(tmp_path, capsys):
    assert main(["trace", "synth", "swipe", "-o", str(tmp_path / "s.csv"), "--jitter", "0.05"]) == 2
    assert "jitter 0.05 s: expected less than half" in capsys.readouterr().err


def test_synth_help_shows_every_default(capsys):
    with pytest.raises(SystemExit):
        main(["trace", "synth", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for said in ("(default 2 s)", "(default 0 deg)", "(default 80 mm)", "(default 20 mm)",
                 "(default 0 mm: none)", "(default 0 s: none)", "default 0.5 N)", "default 0)",
                 "(default 10000 Hz)"):
        assert said in text
