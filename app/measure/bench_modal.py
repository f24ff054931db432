"""Bench section "modal": speed and error of each modal inversion method (device.actuation.modal).

Seed 000's beam (modes 16 and 17, actuators 60 mm from each end), wanted amplitudes
uniform in 0..0.5 um under two fingers (seed 000 eq 14 asks 0.4 um under one finger and
a node under the other), actuator limit 0.75 um zero-to-peak (seed 001's amplifiers stop
at 300 V peak-to-peak; taking seed 000's 160 V peak-to-peak of Fig. 11 to have driven
exactly eq 14's actuator A amplitude, 0.41 um, which the paper does not say). Finger pairs:
random over the beam, and near-singular (finger b within 0.5 mm of finger a). For each
method: wall time per sample in blocks of 50 (one batched call each), the median of
``REPEATS`` passes over the samples (one pass of the quick run's 500 takes about 1 ms,
which one load spike can multiply), mean and worst error under the fingers, the share
of samples that met a limit, and the largest command step when finger b crosses finger
a in 1 um steps (continuity across a singular locus). Then the
whole modal actuation of the bundled beam scene (``ModalActuation.command``: positions,
shapes, touch order, inversion, commands, achieved amplitudes) on two fingers, one
sweeping across the other, in blocks of ``ACTUATION_BLOCK`` samples as replay batches them.
"""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np

from frictex.app.measure.figure import Figure
from frictex.device.actuation.factory import make_actuation
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from frictex.device.structures.beam import FreeFreeBeam
from frictex.device.actuation.modal import DEFAULT_RCOND, METHODS, solve

ORDERS = (16, 17)
LIMIT_UM = 0.75
BLOCK = 50
#: samples per ModalActuation.command call (replay runs up to 500 blocks of 50 at once)
ACTUATION_BLOCK = 25_000
#: timed passes over the samples per method and case; the figure is their median
REPEATS = 7


def mean_wall_unit(samples: int) -> str:
    """The unit of a time per sample: wall time over ``samples`` samples, divided."""
    return f"us (wall time, mean of {samples:,} samples)"


def median_wall_unit(samples: int, repeats: int) -> str:
    """The unit of a time per sample: the median over ``repeats`` passes of each pass's
    wall time over ``samples`` samples, divided."""
    return f"us (wall time, median of {repeats} passes of {samples:,} samples)"


def error_figures(label: str, err_um: np.ndarray, limited: np.ndarray) -> list[Figure]:
    """Mean and worst error (um) under the fingers over the samples (``err_um``: one per
    finger and sample) and the share of samples that met a limit (``limited``), each
    label counting the samples."""
    of = f"({limited.shape[0]:,} samples)"
    return [Figure("modal", f"{label}: mean error {of}", float(np.mean(err_um)), "um"),
            Figure("modal", f"{label}: worst error {of}", float(np.max(err_um)), "um"),
            Figure("modal", f"{label}: samples at a limit {of}",
                   100 * float(np.mean(limited)), "%")]


def _phi(beam, xa, xb):
    return np.stack([beam.phi(ORDERS, xa), beam.phi(ORDERS, xb)], axis=-2)


def run(quick: bool) -> list[Figure]:
    beam = FreeFreeBeam(350, 6, 6, 57, 2561)
    act = beam.phi(ORDERS, np.array([60.0, 290.0]))
    rng = np.random.default_rng(0)
    n = 500 if quick else 5000
    xa = rng.uniform(0, 350, n)
    cases = {"random": (xa, rng.uniform(0, 350, n)),
             "near-singular": (xa, np.clip(xa + rng.uniform(-0.5, 0.5, n), 0, 350))}
    wanted = rng.uniform(0, 0.5, (n, 2)).astype(np.complex128)
    sweep_b = np.linspace(115.0, 125.0, 10001)
    sweep_phi = _phi(beam, np.full_like(sweep_b, 120.0), sweep_b)
    figures = []
    for method in METHODS:
        kwargs = dict(actuators=act, limits_um=LIMIT_UM)
        for case, (a, b) in cases.items():
            phi = _phi(beam, a, b)
            solve(phi[:BLOCK], wanted[:BLOCK], method, **kwargs)  # compiled kernels loaded
            per_sample, sols = _timed_passes(phi, wanted, method, kwargs)
            err = np.concatenate([s.error_um for s in sols])
            limited = np.concatenate([s.limited for s in sols])
            figures.append(Figure("modal", f"{method} {case}: time per sample (blocks of {BLOCK})",
                                  per_sample * 1e6, median_wall_unit(n, REPEATS)))
            figures += error_figures(f"{method} {case}", err, limited)
        steps = solve(sweep_phi, [0.4, 0.0], method, **kwargs).commands_um
        figures.append(Figure("modal", f"{method}: largest command step, finger b crossing a "
                                       f"in 1 um steps", float(np.max(np.abs(np.diff(steps, axis=0)))), "um"))
    for rcond in (0.03, DEFAULT_RCOND, 0.3):
        a, b = cases["random"]
        sol = solve(_phi(beam, a, b), wanted, "regularised", rcond=rcond, actuators=act, limits_um=LIMIT_UM)
        figures.append(Figure("modal", f"regularised rcond={rcond:g} random: mean error ({n:,} samples)",
                              float(np.mean(sol.error_um)), "um"))
    return figures + [_actuation_time(4 if quick else 40)]


def _timed_passes(phi: np.ndarray, wanted: np.ndarray, method: str, kwargs: dict):
    """The median over ``REPEATS`` passes of ``solve`` over all the samples (``phi``:
    (n, 2, modes), ``wanted``: (n, 2) um) in blocks of ``BLOCK`` of each pass's wall time
    per sample (s), and the last pass's solutions (the passes solve the same samples)."""
    n = len(wanted)
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        sols = [solve(phi[i:i + BLOCK], wanted[i:i + BLOCK], method, **kwargs)
                for i in range(0, n, BLOCK)]
        times.append((time.perf_counter() - start) / n)
    return float(np.median(times)), sols


def _actuation_time(blocks: int) -> Figure:
    """Wall time per output sample (the mean) of the bundled beam scene's ModalActuation.command over
    ``blocks`` blocks: finger a from 100 to 120 mm, finger b from 260 to 100 mm across it
    (and the singular loci on the way), both lifted for 2 % of each block, wanted
    amplitudes 0.15 um and 0.1 +- 0.1 um (about a quarter of the samples meet a limit)."""
    actuation = make_actuation(load_scene(resolve_scene("two-finger-beam-seed000")).device)
    t = np.linspace(0.0, 1.0, ACTUATION_BLOCK)
    contact = np.ones((2, t.size), dtype=bool)
    contact[:, 9000:9500] = False
    fingers = SimpleNamespace(contact=contact, touch_start=np.array([[0.0], [0.2]]) * np.ones((2, t.size)),
                              x_pred=np.stack([100.0 + 20 * t, 260.0 - 160 * t]), y_pred=np.full((2, t.size), 3.0))
    wanted = np.stack([np.full(t.size, 0.15), 0.1 + 0.1 * np.sin(40 * t)])
    actuation.command(wanted, fingers)  # compiled kernels loaded
    start = time.perf_counter()
    for _ in range(blocks):
        actuation.command(wanted, fingers)
    per_sample = (time.perf_counter() - start) / (blocks * t.size)
    return Figure("modal", f"actuation (ModalActuation.command), two fingers on the beam scene: "
                           f"time per sample (blocks of {ACTUATION_BLOCK})", per_sample * 1e6,
                  mean_wall_unit(blocks * t.size))
