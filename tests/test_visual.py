"""The visual layer against the scene's own geometry: gratings, a disc, cursors, scope.

GL tests render small framebuffers on the shared EGL context (``gl`` fixture) and
compare pixels with expectations computed from the texture model and the haptic
pipeline, never with stored images.
"""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.input.trace_file import make_trace
from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.overlay import FINGER_RGB, BlockRecord, OverlayState, segment_triangles
from frictex.rendering.visual.scene_image import composed_rgb, from_srgb8, scene_rgb, to_srgb8
from frictex.rendering.visual.viewport import fit_viewport
from scenes import DISPLAY, disc_scene, grating_scene

ROW = 240  # the row measured (any row: the gratings are vertical lines)


def render(gl, scene, size=(800, 480), view=None):
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, scene, size)
    backend.use()
    comp.draw(view)
    rgb = backend.read_rgb()
    comp.release()
    backend.close()
    return rgb, comp.viewport


def crossings(row_linear: np.ndarray, level: float = 0.5):
    """Sub-pixel positions (px, frame coordinates) where a row crosses ``level``,
    rising and falling, by linear interpolation between pixel centres."""
    centres = np.arange(row_linear.size) + 0.5
    a, b = row_linear[:-1] - level, row_linear[1:] - level
    idx = np.flatnonzero((a < 0) != (b < 0))
    x = centres[idx] + a[idx] / (a[idx] - b[idx])
    rising = b[idx] > a[idx]
    return x[rising], x[~rising]


def sho_steps_mm(scene, y_mm: float, x_from: float, x_to: float) -> np.ndarray:
    """x (mm) where the haptic pipeline's SHO output steps, for a finger sliding along y_mm
    at 20 mm/s sampled at 100 Hz (the independent reference for the drawn edges). A
    sample straddling an edge plays both sides in proportion (``rendering.layers.band_limit``):
    one step is then two changes on consecutive samples, the edge within the first's."""
    speed, rate = 20.0, 100.0
    t = np.arange(0.0, (x_to - x_from) / speed, 1.0 / rate)
    trace = make_trace(t, np.zeros(t.size, int), x_from + speed * t, np.full(t.size, y_mm))
    pipe = build_pipeline(scene, render_override="sho-predicted", block_size=50)
    n_blocks = int(t[-1] * pipe.rate_hz / pipe.block_size)
    out, _ = pipe.process(0, trace, pipe.initial_state(), n_blocks=n_blocks)
    touching = out.contact[0]
    x, mu = out.x_mm[0][touching], out.mu_target[0][touching]
    k = np.flatnonzero(np.diff(mu) != 0)
    k = k[np.diff(k, prepend=-2) > 1]
    return 0.5 * (x[k] + x[k + 1])


@pytest.mark.parametrize("period_mm", [5.0, 0.6])
def test_rendered_grating_period_and_edges_match_the_haptic_map(gl, period_mm):
    scene = grating_scene(period_mm)
    rgb, vp = render(gl, scene)
    row = from_srgb8(rgb[ROW, :, 1])
    rising, falling = crossings(row)  # rising: low band (black) ends; falling: it starts
    sx = vp.px_per_mm[0]
    # period: least-squares slope of edge position against edge number, in mm
    for edges in (rising, falling):
        slope = np.polyfit(np.arange(edges.size), edges, 1)[0] / sx
        assert_allclose(slope, period_mm, rtol=0.01)
    # every drawn edge within one pixel of a step of the SHO output (pipeline, mm -> px)
    y_mm = (ROW + 0.5) / vp.px_per_mm[1]
    steps_px = vp.x0 + sho_steps_mm(scene, y_mm, 1.0, DISPLAY.width_mm - 1.0) * sx
    drawn = np.sort(np.concatenate((rising, falling)))
    drawn = drawn[(drawn > steps_px.min() - 1.0) & (drawn < steps_px.max() + 1.0)]
    assert drawn.size == steps_px.size > 10
    assert np.abs(drawn - steps_px).max() < 1.0


def test_fine_grating_has_no_moire_and_point_sampling_would():
    """Spectral content of a rendered row below half the 0.6 mm grating's frequency
    (where moire beats appear), relative to its fundamental."""
    scene = grating_scene(0.6)
    vp = fit_viewport(DISPLAY, 800, 480)
    f0 = 1.0 / (0.6 * vp.px_per_mm[0])  # cycles per pixel

    def beat_ratio(row):
        spec = np.abs(np.fft.rfft((row - row.mean()) * np.hanning(row.size)))
        f = np.fft.rfftfreq(row.size)
        fundamental = spec[np.abs(f - f0) < 3.0 / row.size].max()
        return spec[(f > 5.0 / row.size) & (f < 0.5 * f0)].max() / fundamental

    rendered = scene_rgb(scene, vp)[ROW, :, 0]
    centres = (np.arange(vp.width_px) + 0.5) / vp.px_per_mm[0]
    point = composed_rgb(scene, centres, np.full(vp.width_px, (ROW + 0.5) / vp.px_per_mm[1]))[:, 0]
    assert beat_ratio(rendered) < 0.01
    assert beat_ratio(point) > 0.05  # the check can fail: plain point sampling beats


def test_rendered_disc_centre_and_radius_match_the_file(gl):
    scene = disc_scene()
    disc = scene.layers[0].geometry
    rgb, vp = render(gl, scene, size=(400, 240))
    coverage = 1.0 - from_srgb8(rgb[..., 0])  # black inside (mu' = 0.7 -> color_low)
    yy, xx = np.mgrid[0:rgb.shape[0], 0:rgb.shape[1]] + 0.5
    cx_mm, cy_mm = vp.to_mm((coverage * xx).sum() / coverage.sum(),
                            (coverage * yy).sum() / coverage.sum())
    area_mm2 = coverage.sum() / (vp.px_per_mm[0] * vp.px_per_mm[1])
    mm_per_px = 1.0 / vp.px_per_mm[0]
    assert_allclose([cx_mm, cy_mm], [disc.cx_mm, disc.cy_mm], atol=0.05 * mm_per_px)
    assert_allclose(np.sqrt(area_mm2 / np.pi), disc.radius_mm, atol=0.1 * mm_per_px)


def test_letterboxed_frame_keeps_the_mm_scale_and_round_trips():
    vp = fit_viewport(DISPLAY, 1920, 1080)
    assert (vp.x0, vp.y0, vp.width_px, vp.height_px) == (60, 0, 1800, 1080)
    assert_allclose(vp.px_per_mm, (1800 / 108.0, 1080 / 64.8), rtol=1e-12)
    x, y = vp.to_mm(*vp.to_px(12.345, 6.789))
    assert_allclose([x, y], [12.345, 6.789], rtol=1e-12)
    with pytest.raises(ValueError, match="0x10 px"):
        fit_viewport(DISPLAY, 0, 10)


def test_srgb_encoding_round_trips_and_is_monotonic():
    levels = np.linspace(0, 1, 256)
    enc = to_srgb8(levels)
    assert (np.diff(enc.astype(int)) >= 0).all() and enc[0] == 0 and enc[-1] == 255
    assert_allclose(from_srgb8(enc), levels, atol=0.01)


def _record(t, x, y, contact, mu=None, amp=None, fid=0):
    one = lambda a: np.asarray(a, dtype=np.float64)[None, :]
    mu = np.ones_like(t) if mu is None else mu
    amp = np.zeros_like(t) if amp is None else amp
    return BlockRecord(np.asarray(t, float), (fid,), np.asarray(contact, bool)[None, :],
                       one(x), one(y), one(mu), one(amp))


def test_cursor_is_drawn_at_the_fractional_pixel_position(gl):
    """A filled cursor centred between pixels: its coloured pixels' centroid lands on the
    exact (not truncated) position."""
    scene = grating_scene(5.0, mu_low=1.0)  # plain white plate
    ov = OverlayState()
    x_mm, y_mm = 40.37, 21.81
    ov.add(_record([0.0, 0.01], [x_mm, x_mm], [y_mm, y_mm], [True, True]))
    rgb, vp = render(gl, scene, size=(400, 240), view=FrameView(overlay=ov, show_scope=False))
    lin = from_srgb8(rgb)
    # finger 0 is blue: weight by how far a pixel is from white towards the finger colour
    weight = np.clip(1.0 - lin[..., 0], 0, 1) * (lin[..., 2] > 0.5)
    yy, xx = np.mgrid[0:rgb.shape[0], 0:rgb.shape[1]] + 0.5
    cx, cy = (weight * xx).sum() / weight.sum(), (weight * yy).sum() / weight.sum()
    ex, ey = vp.to_px(x_mm, y_mm)
    assert_allclose([cx, cy], [ex, ey], atol=0.2)


def test_trail_only_joins_samples_in_contact():
    ov = OverlayState(trail_s=1.0)
    t = np.linspace(0, 0.5, 6)
    ov.add(_record(t, 10 + 10 * t, np.full(6, 5.0), [True, True, False, False, True, True]))
    tris = ov.trail_triangles(fit_viewport(DISPLAY, 800, 480))
    assert tris.shape == (2 * 2 * 6, 6)  # segments 0-1 and 4-5 only, outline and line
    assert (tris[:, 5] > 0).all() and (tris[:, 5] <= 0.9).all()


def test_trail_breaks_where_the_finger_lifts_and_lands_within_a_block():
    """An up and a down handled in one block leave contact on throughout (the tracker
    restarts the touch): the 60 mm in 1 ms between them is not drawn as a stroke."""
    ov = OverlayState(trail_s=1.0)
    t = np.arange(6) * 1e-3
    x = np.array([90.0, 90.05, 90.1, 30.0, 30.05, 30.1])
    ov.add(_record(t, x, np.full(6, 5.0), [True] * 6))
    tris = ov.trail_triangles(fit_viewport(DISPLAY, 800, 480))
    width = np.ptp(tris[:, 0].reshape(-1, 3), axis=1)  # x extent of each triangle (px)
    assert len(tris) and width.max() < 5.0  # both strokes drawn (vertices 0.37 px apart, thinned), no jump
    assert tris[:, 0].min() < 250 < 600 < tris[:, 0].max()


def test_overlay_forgets_fingers_once_their_trail_has_faded():
    """1,000 one-touch ids, each seen in one record: the overlay holds the fingers whose
    samples are still within its window, not every id it has seen."""
    ov = OverlayState(trail_s=1.0, scope_s=1.0)
    for fid in range(1_000):
        t = 0.125 * fid + np.array([0.0, 0.0625])  # exact in binary
        ov.add(_record(t, [10.0, 11.0], [5.0, 5.0], [True, False], fid=fid))
        assert fid in ov.fingers and len(ov.fingers) <= 9  # 1 s of touches 0.125 s apart
    assert sorted(ov.fingers) == list(range(991, 1_000))  # ending within the last second


def test_segment_triangles_have_the_requested_width():
    tris = segment_triangles(np.array([[0.0, 0.0], [10.0, 0.0]]), np.ones((2, 4)), 3.0)
    assert_allclose(np.sort(np.unique(tris[:, 1])), [-1.5, 1.5])
    assert_allclose(np.sort(np.unique(tris[:, 0])), [0.0, 10.0])


def scope_layout(frame_h):
    """The scope's layout restated from its specification: a strip 22 % of the frame's
    height (100 to 220 px) at the bottom; two plots, each under a title row 1.25 label
    lines + 10 px high (labels 2 px under the status font, frame height / 45 within 11
    to 22 px); 1 px rules; values 4 px inside each plot's edges."""
    strip = min(max(round(0.22 * frame_h), 100), 220)
    label = max(10, int(min(max(frame_h / 45, 11), 22)) - 2)
    row = round(label * 1.25) + 10
    top = frame_h - strip
    plot_h = (strip - 2 * row - 3) / 2
    mu_plot = (top + 1 + row, plot_h)
    amp_plot = (top + 2 + 2 * row + plot_h, plot_h)
    return top, row, mu_plot, amp_plot


def value_row(plot, v):
    y, h = plot
    return y + 4 + (h - 8) * (1 - v)


def blue_rows(column):
    """Centres (px) of the runs of finger 0's blue in a column of linear RGB."""
    blue = np.flatnonzero((column[:, 2] > 0.6) & (column[:, 0] < 0.2))
    rows = np.split(blue, np.flatnonzero(np.diff(blue) > 1) + 1)
    return sorted(r.mean() + 0.5 for r in rows if r.size)


@pytest.mark.parametrize("mu, amp_um, frame_h", [(0.25, 2.0, 400), (1.0, 2.5, 615),
                                                  (0.0, 0.0, 1080)])
def test_scope_plots_mu_and_amplitude_at_their_scaled_heights(gl, mu, amp_um, frame_h):
    """Traces at their values, inside their plots (full scale and zero 4 px off the
    edges, so mu' = 1 is not on a rule); the scene fitted above the strip."""
    assert FINGER_RGB[0][2] > 0.6  # the colour the check looks for
    scene = grating_scene(5.0, mu_low=1.0)
    ov = OverlayState(scope_s=3.0)
    t = np.linspace(0.0, 3.0, 301)
    ov.add(_record(t, np.full(301, 10.0), np.full(301, 10.0), np.ones(301, bool),
                   mu=np.full(301, mu), amp=np.full(301, amp_um)))
    rgb, vp = render(gl, scene, size=(400, frame_h), view=FrameView(overlay=ov, amplitude_max_um=2.5))
    top, row, mu_plot, amp_plot = scope_layout(frame_h)
    assert vp.y0 + vp.height_px <= top  # the scene is above the strip, not under it
    centres = blue_rows(from_srgb8(rgb[:, 120, :]))  # left of the legend (finger 0 in blue)
    assert len(centres) == 2
    expect = [value_row(mu_plot, mu), value_row(amp_plot, amp_um / 2.5)]
    assert_allclose(centres, expect, atol=0.75)
    rules = [top + 0.5, mu_plot[0] - 0.5, amp_plot[0] - 0.5]  # the strip's and the plots' tops
    assert min(abs(c - r) for c in centres for r in rules) >= 3.0


def test_a_legend_of_many_fingers_stops_short_of_the_title(gl):
    """A log with a new id per touch (1,000 ids over a session) can have dozens in the
    scope's window: the legend names the latest that fit, sums up the rest as "+k more"
    in white, and never runs over the mu' title."""
    from frictex.rendering.visual.text import text_rgba
    scene = grating_scene(5.0, mu_low=1.0)
    ov = OverlayState(scope_s=3.0)
    for fid in range(100, 140):
        ov.add(_record([0.0, 0.01], [10.0, 10.0], [10.0, 10.0], [True, True], fid=fid))
    rgb, _ = render(gl, scene, size=(800, 480), view=FrameView(overlay=ov))
    top, row, _, _ = scope_layout(480)
    label = max(10, int(min(max(480 / 45, 11), 22)) - 2)
    title_right = 4 + text_rgba(("mu' target (0 to 1)",), label, (255, 255, 255),
                                (0, 0, 0, 0)).shape[1]
    band = from_srgb8(rgb)[int(top + 1):int(top + row)]
    coloured = band.max(axis=2) - band.min(axis=2) > 0.3   # a finger's colour, not grey
    white = band.min(axis=2) > 0.6
    columns = np.flatnonzero(coloured.any(axis=0))
    assert columns.size and columns.min() > title_right + 4   # labels, all right of the title
    more = np.flatnonzero(white[:, title_right + 4:columns.min()].any(axis=0))
    assert more.size > 10   # the "+k more" label between the title and the legend


def test_scope_labels_sit_in_title_rows_no_trace_crosses(gl):
    """Traces over the whole range (a sweep of mu' and amplitude from 0 to full scale
    and past it) never enter the title rows, where the labels are."""
    scene = grating_scene(5.0, mu_low=1.0)
    ov = OverlayState(scope_s=3.0)
    t = np.linspace(0.0, 3.0, 601)
    sweep = np.abs(np.sin(t * 7.0)) * 1.3  # past full scale: clipped to it
    ov.add(_record(t, np.full(601, 10.0), np.full(601, 10.0), np.ones(601, bool),
                   mu=sweep, amp=sweep * 2.5))
    rgb, _ = render(gl, scene, size=(800, 480), view=FrameView(overlay=ov, amplitude_max_um=2.5))
    top, row, mu_plot, amp_plot = scope_layout(480)
    lin = from_srgb8(rgb)
    blue = ((lin[..., 2] > 0.6) & (lin[..., 0] < 0.2))[:, :400]  # left of the legend
    for title_top in (top + 1, mu_plot[0] + mu_plot[1] + 1):
        assert not blue[int(title_top):int(title_top + row - 1)].any()
    plots = blue[int(mu_plot[0]):].any(axis=1)
    assert plots.sum() > 2 * 0.5 * mu_plot[1]  # the traces are drawn, over both plots
    white = (lin[..., 0] > 0.6) & (lin[..., 1] > 0.6) & (lin[..., 2] > 0.6)
    for title_top in (top + 1, mu_plot[0] + mu_plot[1] + 1):  # the labels are there
        assert white[int(title_top):int(title_top + row - 1), :200].sum() > 50


class _FirstSizeScreen:
    """A window's default framebuffer as moderngl gives it: its size is the window's when
    the context was made, and a read without a viewport reads that much."""

    def __init__(self, fbo, first_size):
        self.fbo, self.first_size = fbo, first_size

    def read(self, viewport=None, **options):
        return self.fbo.read(viewport=viewport or (0, 0, *self.first_size), **options)


def test_pixels_are_read_over_the_size_asked_whatever_size_the_framebuffer_was_made_at(gl):
    """After the window grew from 80 x 60 to 120 x 90, P read the old size's pixels and
    the demo ended on a reshape error (a recorded session's record lost)."""
    from frictex.rendering.visual.context import _read
    backend = OffscreenBackend((120, 90), ctx=gl)
    backend.use()
    backend.fbo.clear(0.0, 0.0, 1.0, 1.0)
    rgb = _read(_FirstSizeScreen(backend.fbo, (80, 60)), (120, 90))
    backend.close()
    assert rgb.shape == (90, 120, 3) and (rgb == [0, 0, 255]).all()
