"""SHT phase integration: exact over hours, restart on touch, independent of block splits."""

import math

import numpy as np
from numpy.testing import assert_allclose

from frictex.rendering.layers.sht import integrate_phase


def test_one_hour_phase_stays_within_1e_6_period():
    """1 h at 10 kHz with the speed changing every 20 ms (a 50 Hz screen): the carried,
    wrapped phase equals the exact integral (math.fsum of rate x duration) to 1e-6 cycle."""
    rate_hz, period_mm = 10_000.0, 0.6
    seg = 200  # output samples per touch sample
    n_seg = 3600 * 50
    rng = np.random.default_rng(1)
    speeds = rng.uniform(-150.0, 150.0, n_seg)  # mm/s, with reversals
    rates = speeds / period_mm  # cycles/s
    exact = math.fsum((rates * (seg / rate_hz)).tolist())  # exact integral to ~1e-16 relative
    carry = None
    chunk = 2000  # segments per call: 400 000 samples
    touch = np.zeros(chunk * seg, dtype=np.int64)
    for k in range(0, n_seg, chunk):
        r = np.repeat(rates[k:k + chunk], seg)
        _, end = integrate_phase(r, 1 / rate_hz, touch[:r.size], carry)
        carry = (0, end)
    error = (carry[1] - exact) % 1.0
    assert min(error, 1.0 - error) < 1e-6


def test_restart_at_each_new_touch():
    rate = np.full(10, 100.0)
    touch = np.array([1, 1, 1, 2, 2, 2, 2, 3, 3, 3])
    phase, _ = integrate_phase(rate, 1e-3, touch, (1, 0.25))
    assert_allclose(phase, [0.25, 0.35, 0.45, 0.0, 0.1, 0.2, 0.3, 0.0, 0.1, 0.2], atol=1e-12)


def test_split_equals_one_call():
    rng = np.random.default_rng(3)
    rate = rng.normal(0, 200, 1000)
    touch = np.repeat([4, 5], 500)
    whole, end_whole = integrate_phase(rate, 1e-4, touch, None)
    parts, carry = [], None
    for lo, hi in ((0, 137), (137, 500), (500, 999), (999, 1000)):
        p, end = integrate_phase(rate[lo:hi], 1e-4, touch[lo:hi], carry)
        parts.append(p)
        carry = (int(touch[hi - 1]), end)
    # the same operations whatever the split: bit for bit
    assert np.array_equal(np.concatenate(parts), whole)
    assert carry[1] == end_whole


def test_a_replay_does_not_depend_on_its_chunk_size(tmp_path):
    """SHT on grating-5mm over a 40 mm/s swipe: one block per pipeline call, seven, and the
    default give the same tables bit for bit (a sum restarted at each call flipped 13 of
    20,050 samples at the grating's edges between one block per call and the default)."""
    from frictex.app.engine.replay import run_replay
    from frictex.app.engine.tables import read_table
    from frictex.rendering.input.trace_file import read_trace
    from frictex.textures.library import resolve_scene, resolve_trace
    from frictex.textures.loader import load_scene
    scene = load_scene(resolve_scene("grating-5mm"))
    trace = read_trace(resolve_trace("swipe-40mms-50hz"))
    tables = []
    for chunk_blocks in (None, 1, 7):
        out = tmp_path / f"chunks-{chunk_blocks}"
        run_replay(scene, trace, out, fmt="npz", chunk_blocks=chunk_blocks, progress=False,
                   render_override="sht")
        tables.append(read_table(out / "friction.npz"))
    assert tables[0].num_rows == 20_000  # one row per touching sample
    assert all(t.equals(tables[0]) for t in tables[1:])
