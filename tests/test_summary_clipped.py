"""Samples a layer's own limits clip reach summary.json (``layer_clipped``) and the warnings:
the counts equal a count made from the friction table the same replay wrote."""

import json

import numpy as np
import pytest

from frictex.app.commands.cli import main
from test_ar_texture import _xml
from test_texture_loader import write

TWO_OVERLAPPING = json.dumps({"Version": 1, "Pattern": [
    {"Event": {"Time": t, "EventType": "HapticContinuous", "EventDuration": 0.06,
               "EventParameters": [{"ParameterID": "HapticIntensity", "ParameterValue": 0.7},
                                   {"ParameterID": "HapticSharpness", "ParameterValue": 0.0}]}}
    for t in (0.0, 0.03)]})  # levels 0.7 + 0.7 over 30 ms: held at 1


def _replay(tmp_path, capsys, body):
    out = tmp_path / "out"
    assert main(["replay", str(write(tmp_path, body)), "swipe-40mms-50hz", "--out", str(out),
                 "--format", "npz"]) == 0
    doc = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    mu = np.load(out / "friction.npz")["mu_target"]  # one row per touching finger sample
    printed = capsys.readouterr()
    clipped = sum(doc["layer_clipped"].values())
    assert (f"0 clamped by the friction inversion, {clipped} clipped by the layers' own limits;" in printed.out) == (
        clipped > 0)
    return doc, mu, printed.err


def test_a_recorded_texture_clipped_at_its_limits_is_counted_and_warned(tmp_path, capsys):
    (tmp_path / "tex.xml").write_text(_xml(), encoding="utf-8")
    doc, mu, err = _replay(tmp_path, capsys, '[[layer]]\ntype = "recorded"\nname = "tex"\n'
                           'model = "tex.xml"\ngain = 0.05\nmu_min = 0.79\nmu_max = 0.81\n')
    at_limits = int(np.count_nonzero((mu == 0.79) | (mu == 0.81)))
    assert 0 < at_limits < mu.size
    assert doc["layer_clipped"] == {"tex": at_limits}
    line = (f"layer 'tex': {at_limits} of {mu.size} touching samples "
            f"({100 * at_limits / mu.size:.1f} %) were clipped to its mu' limits [0.79, 0.81]")
    assert any(w.startswith(line) for w in doc["warnings"])
    assert f"frictex: warning: {line}" in err


def test_a_clip_whose_levels_add_past_1_is_counted_and_warned(tmp_path, capsys):
    (tmp_path / "two.ahap").write_text(TWO_OVERLAPPING, encoding="utf-8")
    doc, mu, err = _replay(tmp_path, capsys, '[[layer]]\ntype = "clip"\nname = "knock"\n'
                           'trigger = "down"\nclip = "ahap"\nfile = "two.ahap"\ndepth = 0.4\n')
    held = int(np.count_nonzero(mu == 1.0 - 0.4))
    assert held == 300  # 30 ms at 10 kHz
    assert np.count_nonzero(mu == 1.0 - 0.4 * 0.7) == 600  # each event alone: not clipped
    assert doc["layer_clipped"] == {"knock": held}
    assert f"frictex: warning: layer 'knock' (clip): {held} of {mu.size} touching samples" in err
    assert "held at mu' = 1 - depth = 0.6" in err


@pytest.mark.parametrize("body", [
    '[[layer]]\ntype = "recorded"\nname = "tex"\nmodel = "tex.xml"\ngain = 0.001\n',
    '[[layer]]\ntype = "clip"\nname = "knock"\ntrigger = "down"\nclip = "tick"\n',
    '[[layer]]\ntype = "grating"\nname = "g"\nperiod_mm = 5.0\nmu_low = 0.6\nmu_high = 1.0\n',
])
def test_nothing_clipped_gives_zero_and_no_warning(tmp_path, capsys, body):
    (tmp_path / "tex.xml").write_text(_xml(), encoding="utf-8")
    doc, _, err = _replay(tmp_path, capsys, body)
    # a grating's renderer (the hybrid here) counts samples past the Nyquist frequency
    expected = {doc["scene"]["layers"][0]["name"]: 0}
    assert doc["layer_clipped"] == expected and "clipped" not in err
