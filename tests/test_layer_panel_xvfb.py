"""The layer panel in the real demo window under Xvfb, driven by xdotool: L opens it, a
drag on the duty slider of a grating changes what the finger feels on the next stroke
and what the window shows, Ctrl+S saves the file with only the duty line changed.
Waits for the demo to confirm each step in events.csv (see test_demo)."""

import numpy as np
from PIL import Image

from frictex.app.live.layer_edit import LayerEdit, Slider, clamp
from frictex.rendering.visual.layer_panel import (ControlView, PanelView, panel_layout,
                                                  panel_width)
from frictex.rendering.visual.viewport import frame_layout
from frictex.textures.loader import load_scene
from test_demo import (drag, events_of, focus_window, grating_file, quit_demo,  # noqa: F401
                       read_csv, start_demo, wait_event, xdo, xdotool)  # (xdotool: a fixture)

KNOB_RGB = np.array([242, 191, 51])  # layer_panel.KNOB_RGBA in 8 bits
PERIOD_MM = 5.0


def knobs(shot: np.ndarray, width_px: int) -> list[tuple[float, float]]:
    """The sliders' knobs (x, y) px in a screenshot, top down, in the panel's column."""
    hit = np.all(np.abs(shot[:, :width_px].astype(int) - KNOB_RGB) <= 2, axis=-1)
    ys, xs = np.nonzero(hit)
    rows = np.unique(ys)
    runs = np.split(rows, np.flatnonzero(np.diff(rows) > 1) + 1) if rows.size else []
    return [(float(xs[np.isin(ys, run)].mean()), float(run.mean())) for run in runs]


def grating_mu(x_mm: np.ndarray, duty: float) -> np.ndarray:
    return np.where(np.mod(x_mm / PERIOD_MM, 1.0) < duty, 0.6, 1.0)


def off_edges(x_mm: np.ndarray, duty: float) -> np.ndarray:
    """Rows at positions 2e-4 mm or more from the grating's edges (friction.csv's x: 1e-4
    mm), on the band of the row before: a sample that moved across an edge plays both
    sides in proportion (``rendering.layers.band_limit``)."""
    phase_mm = np.mod(x_mm, PERIOD_MM)
    edges = np.array([0.0, duty * PERIOD_MM, PERIOD_MM])
    clear = np.min(np.abs(phase_mm[:, None] - edges[None, :]), axis=1) > 2e-4
    band = 2 * np.floor(x_mm / PERIOD_MM) + (phase_mm >= duty * PERIOD_MM)
    return clear & np.concatenate(([False], clear[:-1] & (band[1:] == band[:-1])))


def test_slider_drag_under_xvfb_changes_the_next_stroke_and_the_picture_and_saves(
        xvfb_display, xdotool, tmp_path):
    scene_file, text = grating_file(tmp_path)
    scene = load_scene(scene_file)
    ed = LayerEdit(scene_file)
    ed.select(0)
    sliders = [c for c in ed.controls() if isinstance(c, Slider)]
    duty_k = [c.key for c in sliders].index("duty")
    rec, shots = tmp_path / "rec", tmp_path / "shots"
    proc = start_demo(xvfb_display, tmp_path, scene_file, rec, "--screenshots", str(shots))
    try:
        win = focus_window(xvfb_display)
        wait_event(proc, rec)
        drag(xvfb_display, win, proc, rec, [(x, 240) for x in np.linspace(100, 700, 25)], 0)
        xdo(xvfb_display, "key", "l")
        wait_event(proc, rec, "panel")
        xdo(xvfb_display, "key", "p")
        wait_event(proc, rec, "screenshot")
        before = np.asarray(Image.open(sorted(shots.glob("*.png"))[0]).convert("RGB"))
        h, w = before.shape[:2]
        column = panel_width(w)
        found = knobs(before, column)
        assert len(found) == len(sliders)  # the panel drawn, one knob per number key
        # the track's span, from the panel's own layout (it does not depend on the row)
        row = panel_layout(PanelView((), None, (ControlView("slider", "k", "k"),)),
                           (0.0, 0.0, float(column), 1000.0), 24.0)[1]
        tx, _, tw, _ = row.track
        kx, ky = found[duty_k]
        target_x = int(round(tx + 0.2 * tw))
        xdo(xvfb_display, "mousemove", "--window", win, str(int(round(kx))), str(int(round(ky))))
        xdo(xvfb_display, "mousedown", "1")
        for x in np.linspace(kx, target_x, 6)[1:]:
            xdo(xvfb_display, "mousemove", "--window", win, str(int(round(x))), str(int(round(ky))))
        xdo(xvfb_display, "mouseup", "1")
        duty_slider = sliders[duty_k]
        duty = clamp(duty_slider, duty_slider.value_at((target_x - tx) / tw))
        assert 0.15 < duty < 0.25
        edits = events_of(rec, "edit")
        for _ in range(8):  # the edit of the drag's last position (at most one a move)
            if edits and edits[-1]["detail"].endswith(f"duty = {duty}"):
                break
            wait_event(proc, rec, "edit", len(edits) + 1)
            edits = events_of(rec, "edit")
        assert edits[-1]["detail"] == f"lines (grating) duty = {duty}"
        xdo(xvfb_display, "key", "p")
        wait_event(proc, rec, "screenshot", 2)
        after = np.asarray(Image.open(sorted(shots.glob("*.png"))[1]).convert("RGB"))
        vp = frame_layout(scene.display, w, h, True, 0, left_px=column)[0]
        py = vp.y0 + vp.height_px // 2
        drag(xvfb_display, win, proc, rec,
             [(x, py) for x in np.linspace(vp.x0 + 10, vp.x0 + vp.width_px - 10, 25)], 1)
        # the haptic side takes only the latest of the edits queued at a block (a late one
        # switches fewer times than there were edits), and the order of the window's log
        # lines is not that of the haptic side: the last edit, made before the stroke
        # began, was taken at or before the stroke's first block
        switches = events_of(rec, "output-switch")
        assert 1 <= len(switches) <= len(edits), f"{len(switches)} switches for {len(edits)} edits"
        stroke_t = float(events_of(rec, "finger-down")[1]["t_s"])
        assert float(switches[-1]["t_s"]) <= stroke_t, "the edit reached the output after the stroke began"
        xdo(xvfb_display, "key", "ctrl+s")
        wait_event(proc, rec, "save")
    finally:
        quit_demo(xvfb_display, proc)

    # the picture: the scene's area changed (lines of another width), the panel beside it
    area = (slice(vp.y0, vp.y0 + vp.height_px), slice(vp.x0, vp.x0 + vp.width_px))
    assert np.any(before[area] != after[area], axis=-1).mean() > 0.1

    # the output: the first stroke felt duty 0.5, the one after the edit's switch the new duty
    t_switch = float(events_of(rec, "output-switch")[-1]["t_s"])
    rows = read_csv(rec / "friction.csv")
    t = np.array([float(r["t_s"]) for r in rows])
    x = np.array([float(r["x_mm"]) for r in rows])
    mu = np.array([float(r["mu_target"]) for r in rows])
    first = (t < float(events_of(rec, "panel")[0]["t_s"])) & off_edges(x, 0.5)
    second = (t >= t_switch) & off_edges(x, duty)
    assert first.sum() > 500 and second.sum() > 500
    np.testing.assert_array_equal(mu[first], grating_mu(x[first], 0.5))
    np.testing.assert_array_equal(mu[second], grating_mu(x[second], duty))

    # the file: only the duty line changed, its comment kept
    saved = scene_file.read_text().splitlines(keepends=True)
    changed = [(a, b) for a, b in zip(text.splitlines(keepends=True), saved) if a != b]
    assert len(saved) == len(text.splitlines()) and len(changed) == 1
    assert changed[0][0].startswith("duty = 0.5 ") and changed[0][1].startswith(f"duty = {duty} ")
    assert changed[0][1].endswith("# the black line is the first half of each period\n")
    assert load_scene(scene_file).layers[0].duty == duty
