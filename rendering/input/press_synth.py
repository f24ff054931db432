"""Synthetic presses: a still finger whose normal force rises and falls, with sensor noise.

Each press lands at ``touch_n``, rises to its peak over ``rise_s`` with a minimum-jerk
profile (Flash & Hogan 1985, as ``rendering.input.trace_synth``'s human strokes), holds, falls back
over the same time and lifts; a pause separates presses. Gaussian force noise of
``noise_n`` (standard deviation, N, clipped at 0) is added to every sample, as a force
sensor would report it. Deterministic for a given seed.

The bundled ``textures/library/traces/keyclick-press-100hz.csv`` is this module's
default output; its first line gives the ``frictex trace synth press`` command that
makes it again.
"""

from __future__ import annotations

import numpy as np

from frictex.device.errors import InputError
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, Trace, make_trace
from frictex.rendering.input.trace_synth import sample_times


#: where the finger presses (mm): on keyclick-ring's button (50-90 x 5-25 mm)
PRESS_MM = (70.0, 15.0)
#: the force sensor's report rate (Hz)
PRESS_RATE_HZ = 100.0
#: normal force at touch-down (N)
TOUCH_N = 0.1


def press_trace(peaks_n=(1.0, 0.95, 1.1), x_mm: float = PRESS_MM[0], y_mm: float = PRESS_MM[1],
                rate_hz: float = PRESS_RATE_HZ, touch_n: float = TOUCH_N, rise_s: float = 0.6,
                hold_s: float = 0.1, pause_s: float = 0.3, noise_n: float = 0.03,
                seed: int = 0) -> Trace:
    """Presses of a still finger at (x_mm, y_mm), one per peak force (N).

    Returns a trace with finger 0 touching down at the start of each press and lifting at
    its end; times in s from 0, forces in N.
    """
    if rate_hz <= 0 or rise_s <= 0 or noise_n < 0:
        raise InputError(f"rate {rate_hz} Hz and rise {rise_s} s must be > 0, noise {noise_n} N >= 0")
    rng = np.random.default_rng(seed)
    t_all, f_all, ev_all = [], [], []
    start = 0.0
    for peak in peaks_n:
        duration = 2 * rise_s + hold_s
        t = sample_times(duration, rate_hz)
        up = np.clip(t / rise_s, 0.0, 1.0)
        down = np.clip((duration - t) / rise_s, 0.0, 1.0)
        s = np.minimum(_min_jerk(up), _min_jerk(down))
        force = touch_n + (peak - touch_n) * s + rng.normal(0.0, noise_n, t.size)
        event = np.full(t.size, MOVE, dtype=np.int8)
        event[0], event[-1] = DOWN, UP
        t_all.append(start + t)
        f_all.append(np.maximum(force, 0.0))
        ev_all.append(event)
        start += duration + pause_s
    t = np.concatenate(t_all)
    n = t.size
    return make_trace(t, np.zeros(n, dtype=np.int64), np.full(n, x_mm), np.full(n, y_mm),
                      np.concatenate(f_all), np.concatenate(ev_all))


def _min_jerk(u: np.ndarray) -> np.ndarray:
    return 10 * u**3 - 15 * u**4 + 6 * u**5
