"""AUTHORING.md's worked step bound is the bundled bump's: its sigma and rise, its
largest |h''| along a line through the crest, and gain max|h''| |v| / rate per sample."""

import re
import tomllib
from pathlib import Path

import numpy as np

TEXTURES = Path(__file__).resolve().parents[1] / "textures"
WORKED = re.compile(r"bundled bump \((?P<rise>[\d.]+) mm high, sigma (?P<sigma>[\d.]+) mm: max "
                    r"\|h''\| = (?:[\d/]+ = )?(?P<curv>[\d.]+) /mm.*?at (?P<speed>\d+) mm/s and "
                    r"(?P<khz>\d+) kHz with gain (?P<gain>[\d.]+): (?P<step>[\d.e-]+) per sample")


def test_the_step_bound_is_worked_out_for_the_bundled_bump():
    text = " ".join((TEXTURES / "AUTHORING.md").read_text(encoding="utf-8").split())
    worked = WORKED.search(text)
    assert worked, "AUTHORING.md's step bound example was not found"
    layer = tomllib.loads((TEXTURES / "library" / "height-bump.toml").read_text())["layer"][0]
    assert float(worked["rise"]) == layer["rise_mm"] and float(worked["sigma"]) == layer["sigma_mm"]
    u = np.linspace(-5 * layer["sigma_mm"], 5 * layer["sigma_mm"], 200_001)
    h = layer["rise_mm"] * np.exp(-u ** 2 / (2 * layer["sigma_mm"] ** 2))
    curvature = np.abs(np.gradient(np.gradient(h, u), u)).max()  # /mm
    assert abs(float(worked["curv"]) - curvature) < 0.0005 * 2  # as written, 3 digits
    step = float(worked["gain"]) * curvature * float(worked["speed"]) / (float(worked["khz"]) * 1e3)
    assert float(worked["gain"]) == layer["gain"]
    assert abs(float(worked["step"]) - step) <= 0.05e-4, (worked["step"], step)
