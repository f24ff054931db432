"""rendering.perception's pair checks: the Weber fraction taken of the higher friction
level, a period's dp/p of the smaller period, clip events compared by the difference of
their lengths (Gueorguiev et al. 2019's 2.3 ms is a difference threshold, not the
shortest drop felt), and values that are no stimulus refused."""

import math
import tomllib
from pathlib import Path

import pytest

from frictex.app.commands.cli import main
from frictex.app.experiment.perception_check import protocol_findings
from frictex.app.experiment.protocol import load_protocol
from frictex.device.errors import InputError
from frictex.rendering.perception import THRESHOLDS, compare_values, scene_findings
from test_perception import GRATING, HEAD, LISTED, RAMP, scene

ROOT = Path(__file__).resolve().parents[1]


def test_a_friction_drop_is_taken_relative_to_the_higher_level():
    """Depths 0.3 and 0.37 play mu' 0.7 and 0.63: a drop of 0.07, 10 % of 0.7 (under
    0.11); over the lower level, 0.63, it read 11.1 % and was not flagged."""
    found = compare_values("depth", 0.3, 0.37, "x")
    high, low = 1.0 - 0.3, 1.0 - 0.37
    assert found is not None and found.kind == "weber"
    assert found.value == pytest.approx((high - low) / high, rel=1e-12)
    assert compare_values("depth", 0.37, 0.3, "x").value == pytest.approx(found.value)
    # 0.7 -> 0.62 drops 11.4 % of 0.7: over the threshold
    assert compare_values("depth", 0.3, 0.38, "x") is None


def test_a_design_of_depths_from_no_drop_is_flagged(tmp_path, capsys):
    """grating-5mm (mu_high 1), depths 0.0 against 0.05 and 0.1: mu' 1 -> 0.9, a 10 %
    drop, under the Weber fraction; it passed `validate --perception` with 0 warnings."""
    (tmp_path / "p.toml").write_text('format = 1\nname = "d"\nmethod = "2afc"\n'
                                     'repetitions = 10\n\n[stimuli]\nscene = "grating-5mm"\n'
                                     'vary = "depth"\nreference = 0.0\nlevels = [0.05, 0.1]\n')
    [found] = protocol_findings(load_protocol(tmp_path / "p.toml"))
    assert found.kind == "weber" and found.value == pytest.approx((1.0 - 0.9) / 1.0)
    assert main(["validate", "--perception", str(tmp_path / "p.toml")]) == 0
    assert "1 perception warning" in capsys.readouterr().out


def test_listed_contrasts_are_compared_relative_to_the_larger(tmp_path):
    """Contrasts 0.5 and 0.56 (mu_low 0.5 and 0.44): 0.06 / 0.56 = 10.7 %, under 0.11;
    over the smaller it read 12 % and was not flagged."""
    for name, low in (("a", 0.5), ("b", 0.44), ("c", 0.2)):  # c: contrast 0.8
        (tmp_path / f"{name}.toml").write_text(HEAD + GRATING.format(render="hybrid",
                                                                     period=5.0, low=low))
    (tmp_path / "l.toml").write_text(LISTED)
    found = protocol_findings(load_protocol(tmp_path / "l.toml"))
    assert [(f.kind, f.where) for f in found] == [("weber", 'stimuli "a" and "b"')]
    assert found[0].value == pytest.approx((0.56 - 0.5) / 0.56)


@pytest.mark.parametrize("b, flagged", [(5.69, True), (5.71, False)])
def test_a_period_difference_is_taken_relative_to_the_smaller_period(b, flagged):
    """dp/p of the reference, the smaller: 0.69 / 5 = 13.8 %, 0.71 / 5 = 14.2 %."""
    found = compare_values("period_mm", 5.0, b, "x")
    assert (found is not None) == flagged
    if flagged:
        assert found.value == pytest.approx((b - 5.0) / 5.0)


def test_a_short_clip_event_alone_is_not_flagged(tmp_path):
    """A 2.2 ms ramp was flagged as "below the shortest friction drop felt apart"; the
    2.3 ms of Gueorguiev et al. 2019 tells two drops' lengths apart, and bounds no one."""
    found = scene_findings(scene(tmp_path, RAMP.format(duration=0.0022)))
    assert [f for f in found if f.kind == "event"] == []
    assert "shortest" not in THRESHOLDS["event"].what
    assert "difference" in THRESHOLDS["event"].what
    assert "12(2):179-188" in THRESHOLDS["event"].source


@pytest.mark.parametrize("b_ms, flagged", [(11.5, True), (12.5, False)])
def test_listed_clips_are_compared_by_the_difference_of_their_events_lengths(tmp_path,
                                                                             b_ms, flagged):
    """Ramps of 10 ms and 11.5 ms differ by 1.5 ms, under the 2.3 ms discriminated
    (flagged); 10 and 12.5 ms by 2.5 ms (not). Before, events' lengths were not compared
    and equal contrasts read as no difference at all."""
    for name, ms in (("a", 10.0), ("b", b_ms), ("c", 40.0)):
        (tmp_path / f"{name}.toml").write_text(HEAD + RAMP.format(duration=ms / 1e3))
    (tmp_path / "l.toml").write_text(LISTED)
    found = protocol_findings(load_protocol(tmp_path / "l.toml"))
    pairs = [(f.kind, f.where) for f in found if f.where.startswith("stimuli")]
    assert pairs == ([("event", 'stimuli "a" and "b"')] if flagged else [])
    if flagged:
        assert found[-1].value == pytest.approx((b_ms - 10.0) / 1e3)
        assert "event 1 lengths 10 and 11.5 ms differ by 1.5 ms" in found[-1].message


@pytest.mark.parametrize("vary, a, b, match", [
    ("period_mm", 1.0, math.nan, "period_mm nan"),
    ("period_mm", 0.0, 0.1, "period_mm 0.0: expected a finite period above 0"),
    ("period_mm", 1.0, math.inf, "period_mm inf"),
    ("depth", 0.3, -0.1, "depth -0.1: expected a finite value of at least 0"),
    ("level", math.nan, 0.5, "level nan"),
])
def test_values_that_are_no_stimulus_are_refused_in_one_line(vary, a, b, match):
    """nan read "differ by nan %" and a period of 0 raised ZeroDivisionError."""
    with pytest.raises(InputError, match=match):
        compare_values(vary, a, b, "pair")
    assert issubclass(InputError, ValueError)


def test_a_depth_of_0_is_a_stimulus():
    assert compare_values("depth", 0.0, 0.5, "pair") is None  # mu' 1 -> 0.5: 50 %


def test_the_depth_staircases_floor_is_set_against_the_fraction_of_friction():
    """Its comment compared min 0.003 with 0.11 x depth 0.3 = 0.033 (11x); the fraction
    applies to friction: 0.11 x mu' 0.7 = 0.077, about 26x the floor."""
    path = ROOT / "app" / "experiment" / "protocols" / "depth-staircase.toml"
    text = path.read_text()
    doc = tomllib.loads(text)
    mu_reference = 1.0 - doc["stimuli"]["reference"]  # grating-5mm: mu_high 1
    step = THRESHOLDS["weber"].value * mu_reference
    assert f"{round(step / doc['staircase']['min']):d}x below the {step:.2g}" in text
    assert "0.033" not in text
