"""The example files of the format page (``textures/FORMAT.md``): the walk-through's wood
plank, as first written and corrected, and a complete file per layer type.

``textures.format_doc`` prints them on the page; ``tests/test_format_doc.py`` reads them
back *from the page*, validates and replays each.
"""

from __future__ import annotations

_HEAD = """format = 1
name = "{name}"

[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480
"""

_PLANK_HEAD = """format = 1
name = "wood-plank"
description = "A wood plank: grain, growth rings and a knot"

[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480

[[layer]]
type = "waveform"
name = "grain"
shape = "triangle"
period_mm = 1.5
angle_deg = 95.0          # lines running 5 deg below horizontal, to the right
mu_min = {grain}

[[layer]]
type = "grating"
name = "rings"
period_mm = 9.0
angle_deg = 95.0          # along the grain
duty = 0.15
mu_low = {rings}

[[layer]]
type = "height"
name = "knot"
shape = "bump"
cx_mm = 70.0
cy_mm = 32.0
sigma_mm = 4.0
rise_mm = 0.6
rendering = "magnitude"   # rougher where steeper, whichever way the finger crosses
"""

#: the walk-through's plank: as first written (below the floor, a step at the disc) and fixed
PLANK = {
    "plank-first": _PLANK_HEAD.format(grain=0.72, rings=0.6) + """mu_min = 0.8
[layer.region]            # confine the knot to a disc
cx_mm = 70.0
cy_mm = 32.0
radius_mm = 12.0
""",
    "plank": _PLANK_HEAD.format(grain=0.9, rings=0.85) + """mu_rest = 0.85
mu_min = 0.85
""",
}

#: one complete file per layer type
EXAMPLES = {
    "grating": _HEAD.format(name="grating") + """
[[layer]]
type = "grating"
period_mm = 5.0
angle_deg = 0.0           # vertical lines
duty = 0.5
mu_low = 0.6
edge = "smooth"
edge_mm = 0.5
[layer.visual]
color_low = "#202020"
color_high = "#fff"
""",
    "waveform": _HEAD.format(name="waveform") + """
[[layer]]
type = "waveform"
shape = "samples"         # one period of your own: mu' at evenly spaced phases
period_mm = 2.0
angle_deg = 90.0          # horizontal lines
samples = [1.0, 0.8, 0.7, 0.8]
""",
    "rectangle": _HEAD.format(name="rectangle") + """
[[layer]]
type = "rectangle"
x_mm = 30.0
y_mm = 20.0
width_mm = 40.0
height_mm = 20.0
angle_deg = 15.0          # turned clockwise about its centre
mu = 0.7
edge_mm = 2.0
""",
    "disc": _HEAD.format(name="disc") + """
[[layer]]
type = "disc"
cx_mm = 54.0
cy_mm = 32.4
radius_mm = 10.0
mu = 0.65
edge_mm = 1.0
""",
    "edge": _HEAD.format(name="edge") + """
[[layer]]
type = "edge"
x_mm = 54.0
y_mm = 32.4
angle_deg = 0.0           # a vertical edge, slippery to its right
mu = 0.7
edge_mm = 1.0
""",
    "bump": _HEAD.format(name="bump") + """
[[layer]]
type = "bump"
cx_mm = 54.0
cy_mm = 32.4
sigma_mm = 6.0
mu = 0.65
""",
    "line": _HEAD.format(name="line") + """
[[layer]]
type = "line"
x0_mm = 20.0
y0_mm = 50.0
x1_mm = 90.0
y1_mm = 15.0
width_mm = 3.0
mu = 0.7
""",
    "raster": _HEAD.format(name="raster") + """
[[layer]]
type = "raster"
image = "raster-map.png"  # grey: black mu_black, white mu_white
mode = "tile"
x_mm = 4.0
y_mm = 2.4
width_mm = 100.0
height_mm = 60.0
tile_width_mm = 25.0
tile_height_mm = 15.0
mu_black = 0.65
""",
    "directional": """format = 1
name = "directional"

[display]
width_mm = 140.0
height_mm = 30.0
width_px = 700
height_px = 150

[device]
profile = "ring-seed004"  # force layers need a travelling-wave profile
amplitude_limit_um = 3.0

[[layer]]
type = "directional"
angle_deg = 0.0           # forward is +x
force_forward_n = 0.03
force_backward_n = 0.2
""",
    "guidance": """format = 1
name = "guidance"

[display]
width_mm = 140.0
height_mm = 30.0
width_px = 700
height_px = 150

[device]
profile = "ring-seed004"
amplitude_limit_um = 3.0

[[layer]]
type = "guidance"
x_mm = 70.0
y_mm = 15.0
line = true
line_angle_deg = 90.0     # pulled towards the vertical line x = 70 mm
gain_n_per_mm = 0.002
max_force_n = 0.02
""",
    "keyclick": """format = 1
name = "keyclick"

[display]
width_mm = 140.0
height_mm = 30.0
width_px = 700
height_px = 150

[device]
profile = "ring-seed004"
amplitude_limit_um = 3.0

[[layer]]
type = "keyclick"
x_mm = 50.0
y_mm = 5.0
width_mm = 40.0
height_mm = 20.0
press_n = 0.5
click_n = 0.8
release_n = 0.4
""",
    "height": _HEAD.format(name="height") + """
[[layer]]
type = "height"
shape = "ridge"
x_mm = 54.0               # a point on the crest
y_mm = 32.4
angle_deg = 90.0          # the crest runs vertically
width_mm = 12.0
rise_mm = 1.0
rendering = "slope"       # climbing raises mu', descending lowers it
gain = 2.0
mu_rest = 0.8
mu_min = 0.6
""",
    "recorded": _HEAD.format(name="recorded") + """
[[layer]]
type = "recorded"
model = "wood.xml"        # a HaTT texture model
mu_mean = 0.8
gain = 0.015
""",
    "clip": _HEAD.format(name="clip") + """
[[layer]]
type = "clip"
trigger = "edge"          # crossing the vertical line x = 90 mm, either way
x_mm = 90.0
y_mm = 32.4
angle_deg = 0.0
clip = "ahap"
file = "clips/tick-then-buzz.ahap"
depth = 0.4

[[layer]]
type = "clip"
trigger = "down"          # every touch starts with a tick
clip = "tick"
intensity = 0.8
""",
}
