"""The GL overlay's own text layout: in frames of every kind of panel, at small and large
sizes, no text's box overlaps another's and none leaves the frame (the boxes are the
compositor's record of each text it drew, ``Compositor.text_boxes``)."""

import itertools

import numpy as np
import pytest

from frictex.app.live.demo_loop import KEYS_HELP
from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.device_panels import default_frame_size
from frictex.rendering.visual.modal_view import modal_envelope
from frictex.rendering.visual.overlay import OverlayState, record_from_output
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from test_visual_devices import run_pipeline

STATUS = ("two-finger-plate-seed001 (3/18) | renderer: file | force 0.50 N | link: sim, 1234 "
          "frames sent | clamps 0 | deadline misses 0",
          "input: mouse (drag: two fingers, the second 20 mm to the right; 2 touching)",
          KEYS_HELP)
BANNER = ("textures/plank.toml: layer 'grain': angle_deg 400 is out of range; expected -360 "
          "to 360 (the scene shown is the last good one)")
#: scene, finger positions (mm)
SCENES = [("grating-5mm", [(30.0, 30.0), (70.0, 40.0)]),
          ("keyclick-ring", [(40.0, 10.0), (120.0, 12.0)]),
          ("two-finger-beam-seed000", [(100.0, 3.0), (230.0, 3.0)]),
          ("two-finger-plate-seed001", [(30.0, 40.0), (95.0, 110.0)]),
          ("guidance-ring", [(60.0, 10.0), (150.0, 10.0)])]


def overlapping(a, b) -> bool:
    """Whether boxes (x, y, w, h) px share more than a sliver (0.5 px either way)."""
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    return (min(ax + aw, bx + bw) - max(ax, bx) > 0.5) and (min(ay + ah, by + bh) - max(ay, by) > 0.5)


@pytest.fixture(scope="module", params=SCENES, ids=[name for name, _ in SCENES])
def frame_input(request):
    name, fingers = request.param
    scene = load_scene(resolve_scene(name))
    pipe, out = run_pipeline(scene, fingers)
    overlay = OverlayState()
    overlay.add(record_from_output(out, stride=10))
    modal = modal_envelope(scene, pipe.actuation)
    env = None if modal is None else modal.at(overlay.commands, overlay.current())
    return scene, overlay, env


@pytest.mark.parametrize("size", ["default", (640, 400), (800, 480), (1920, 1080)])
@pytest.mark.parametrize("banner, scope", [(None, True), (BANNER, True), (BANNER, False)])
def test_no_text_overlaps_another_or_leaves_the_frame(gl, frame_input, size, banner, scope):
    scene, overlay, env = frame_input
    size = default_frame_size(scene) if size == "default" else size
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, scene, size)
    backend.use()
    comp.draw(FrameView(overlay=overlay, show_scope=scope, status=STATUS, banner=banner,
                        envelope=env, envelope_scale_um=1.0))
    boxes = list(comp.text_boxes)
    comp.release()
    backend.close()
    w, h = size
    assert len(boxes) >= 1 + (banner is not None) + 3 * scope  # status, banner, scope labels
    for box in boxes:
        x, y, bw, bh = box
        assert x >= -0.5 and y >= -0.5 and x + bw <= w + 0.5 and y + bh <= h + 0.5, (box, size)
    for a, b in itertools.combinations(boxes, 2):
        assert not overlapping(a, b), (a, b, size)


def test_the_overlap_check_sees_an_overlap():
    assert overlapping((0, 0, 10, 10), (9, 9, 10, 10))
    assert not overlapping((0, 0, 10, 10), (10, 0, 10, 10))  # touching edges
    assert not overlapping((0, 0, 10, 10), (9.7, 0, 10, 10))  # a sliver (rounding)


def test_a_full_text_atlas_starts_again_and_draws_the_same(gl):
    """Distinct status lines in every frame fill the atlas (about 30 frames' worth); the
    frame after it was emptied and packed again equals a fresh compositor's."""
    scene = load_scene(resolve_scene("grating-5mm"))
    overlay = OverlayState()
    size = (800, 480)
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, scene, size)
    backend.use()
    packed = []
    for k in range(60):
        view = FrameView(overlay=overlay, status=tuple(f"{line} [{k}]" for line in STATUS))
        comp.draw(view)
        packed.append(len(comp.atlas.entries))
    assert min(packed[1:]) < max(packed)  # it was emptied on the way
    long_run = backend.read_rgb()
    comp.release()
    fresh = Compositor(gl, scene, size)
    fresh.draw(view)
    assert np.array_equal(backend.read_rgb(), long_run)
    fresh.release()
    backend.close()


@pytest.mark.parametrize("width_px", [300.0, 560.0, 806.0 - 16.0, 1200.0])
def test_the_status_line_wraps_at_its_separators_only(width_px):
    """At 806 px the status line wrapped as 'deadline / misses 506' and 'emergency / stop'."""
    from frictex.rendering.visual.text import font, wrap
    from PIL import Image, ImageDraw
    probe = ImageDraw.Draw(Image.new("RGBA", (1, 1)))
    for status in (STATUS[0].replace("misses 0", "misses 506"), KEYS_HELP):
        lines = wrap(status, 14, width_px, " | ")
        phrases = status.split(" | ")
        assert " | ".join(lines) == status  # nothing lost, broken at separators only
        assert all(line.split(" | ")[0] in phrases and line.split(" | ")[-1] in phrases
                   for line in lines)
        assert all(probe.textlength(line, font=font(14)) <= width_px for line in lines)
    # a phrase wider than a line alone is broken between its words, nothing lost
    long = wrap("a | " + "word " * 40 + "| b", 14, 120.0, " | ")
    assert long[0] == "a" and long[-1] == "b" and " ".join(long[1:-1]).split() == ["word"] * 40
    assert len(long) > 3 and all(probe.textlength(line, font=font(14)) <= 120.0 for line in long)
