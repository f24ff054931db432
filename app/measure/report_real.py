"""``frictex report --real DIR``: real touch recordings replayed through every renderer.

Every recording under DIR (recursively) is replayed: trace CSVs as they are, Android
``getevent -lt`` logs and evemu recordings through ``frictex trace import``. A log does
not record its screen's size, so it is imported onto the scene's display: its observed
range at one scale for both axes (``rendering.input.evdev_decode.screen_map``: a drag
keeps its shape), or a ``-lpt`` log's axis ranges each mapped to its side of the display
(a shape then stretched by the two sides' ratios). Positions and speeds are display
millimetres, each recording at its own scale (the phone drag of refdata: 19.9 mm on the
52 mm phone, 108 mm here, 5.4x): the rows compare how the tracker and the renderers
handle each gesture, not the gestures' real speeds. Each recording runs on each seed
003 grating of the report with every renderer, at its own touch rate (67-105 Hz for
refdata's logs), 10 kHz output, exact inversion.

No true path exists for a recording, so what is scored is what can be:

- continuity: the largest step of the output amplitude between two output samples
  (um) while a finger stays down (a grating's own edge is a full step), and chatter:
  edges felt twice, ``rendering.metrics.chatter`` (a step of mu' undone within
  ``CHATTER_S`` while the finger, as tracked, stayed within a quarter period and, as
  measured, did not turn back by ``REVERSAL_MEASURED_MM``), on gratings whose edges are
  events, not texture (period at least ``CHATTER_PERIOD_MM``: the 15 and 5 mm gratings);
- clamps: the friction inversion's guards that acted, and the tracker's jumps (a finger
  moving faster than a finger can) and dropped out-of-order samples;
- agreement between renderers: the spectral distance of each renderer's mu'(t) from the
  hybrid's (``rendering.metrics.spectral_error``, phase ignored), per finger;
- finger-role stability: with two or more fingers down, how often the positional
  selector ``left-most`` hands its role to another finger, per second, with the default
  hysteresis and without any (``rendering.tracking.finger_select``).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import tempfile
from pathlib import Path

import numpy as np

from frictex.app.measure.report_matrix import load, run_blocks, stack_fingers
from frictex.device.errors import InputError
from frictex.rendering.input.trace_file import TraceError, make_trace, read_trace
from frictex.rendering.input.trace_import import add_import_arguments, detect_format, run_import
from frictex.rendering.metrics import (CHATTER_PERIOD_MM, CHATTER_S, REVERSAL_MEASURED_MM,
                               MetricError, chatter, spectral_error)
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.renderers import RENDERERS, sho_variant_of
from frictex.rendering.tracking.finger_select import HYSTERESIS_MM, SelectionState, select_fingers
from frictex.rendering.tracking.tracks import TrackerConfig, TrackerState, track

OUTPUT_HZ = 10_000.0
#: recordings larger than this (bytes) are left out (a report is not a bulk converter)
MAX_BYTES = 8 << 20


def recordings(folder: Path) -> list[Path]:
    """The files under ``folder`` that look like touch recordings (sorted)."""
    if not folder.is_dir():
        raise InputError(f"--real {folder}: not a folder; expected a folder of touch "
                         "recordings (getevent logs, evemu recordings or trace CSVs)")
    found = []
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        if path.stat().st_size > MAX_BYTES:
            continue
        head = path.read_text(encoding="utf-8", errors="replace")[:4096]
        try:
            detect_format(path, head)
        except TraceError:
            continue
        found.append(path)
    if not found:
        raise InputError(f"--real {folder}: no touch recordings found (getevent logs, evemu "
                         "recordings or trace CSVs)")
    return found


def load_recording(path: Path, width_mm: float, height_mm: float):
    """The recording as a trace starting at t = 0 (logs mapped onto width x height mm)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "trace.csv"
        parser = argparse.ArgumentParser()
        add_import_arguments(parser)
        args = parser.parse_args([str(path), "-o", str(out), "--width-mm", str(width_mm),
                                  "--height-mm", str(height_mm)])
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            run_import(args, lambda to, text: Path(to).write_text(text, encoding="utf-8"))
        trace = read_trace(out)
    return make_trace(trace.t_s - trace.t_s[0], trace.finger, trace.x_mm, trace.y_mm,
                      trace.force_n, trace.event)


def _largest_step(amplitude: np.ndarray, contact: np.ndarray) -> float:
    """The largest amplitude step (um) between output samples while a finger stays down."""
    both = contact[:, 1:] & contact[:, :-1]
    return float(np.abs(np.where(both, np.diff(amplitude, axis=1), 0.0)).max(initial=0.0))


def _measured(trace, ids: list[int], n: int):
    """Each finger's tracks on the output grid (a FingerBlock) and its rows in the
    order of ``ids``."""
    fingers, _ = track(0, n, trace, TrackerState(), TrackerConfig(rate_hz=OUTPUT_HZ))
    return fingers, [fingers.ids.index(fid) for fid in ids]


def _chatter(mu: np.ndarray, contact: np.ndarray, measured, layer) -> int:
    """Edges felt twice over every finger (``rendering.metrics.chatter``): where the
    steps are, the tracker's predicted position; its reversals, in the measured one."""
    fingers, rows = measured
    (ax, ay), t = layer.axis, np.arange(mu.shape[1]) / OUTPUT_HZ
    return sum(chatter(mu[k], t, ax * fingers.x_pred[row] + ay * fingers.y_pred[row],
                       contact[k], layer.period_mm, REVERSAL_MEASURED_MM,
                       turning_mm=ax * fingers.x_held[row] + ay * fingers.y_held[row])
               for k, row in enumerate(rows))


def _role_swaps(trace, hysteresis_mm: float) -> tuple[int, float]:
    """Hand-overs of ``left-most`` while two or more fingers are down, and that time (s)."""
    cfg = TrackerConfig(rate_hz=OUTPUT_HZ)
    fingers, _ = track(0, int((trace.duration_s + 0.05) * OUTPUT_HZ) + 1, trace, TrackerState(), cfg)
    many = fingers.contact.sum(axis=0) >= 2
    if not many.any():
        return 0, 0.0
    left = select_fingers(["left-most"], fingers, SelectionState(), hysteresis_mm)[0][0]
    holder = np.argmax(left, axis=0)[many]
    runs = np.flatnonzero(np.diff(np.flatnonzero(many)) > 1)  # separate stretches of many
    changes = np.diff(holder) != 0
    changes[runs] = False
    return int(np.count_nonzero(changes)), float(many.sum() / OUTPUT_HZ)


def replay(path: Path, scene_name: str) -> dict:
    """The figures of the module docstring for one recording on one scene."""
    scene = load(scene_name)
    trace = load_recording(path, scene.display.width_mm, scene.display.height_mm)
    duration = trace.duration_s + 0.05
    out: dict = {"recording": path.name, "scene": scene_name, "samples": len(trace),
                 "fingers": len(trace.fingers), "duration_s": trace.duration_s, "renderers": {}}
    mu_by = {}
    layer = next((lay for lay in scene.layers if lay.is_periodic), None)
    measured = None
    for renderer in RENDERERS.names():
        pipeline = build_pipeline(scene, rate_hz=OUTPUT_HZ, block_size=50,
                                  render_override=renderer,
                                  sho_variant=sho_variant_of(renderer))
        outs, _ = run_blocks(pipeline, trace, 200, duration)
        ids, contact = stack_fingers(outs, "contact", False)
        amplitude = stack_fingers(outs, "amplitude_um", 0.0)[1]
        mu = stack_fingers(outs, "mu_target", 1.0)[1]
        mu_by[renderer] = (mu, contact)
        if measured is None:
            measured = _measured(trace, ids, mu.shape[1])
        doubled = (_chatter(mu, contact, measured, layer)
                   if layer is not None and layer.period_mm >= CHATTER_PERIOD_MM else None)
        clamps = None
        for o in outs:
            clamps = o.clamps if clamps is None else (clamps.add(o.clamps) or clamps)
        out["renderers"][renderer] = {
            "largest_step_um": _largest_step(amplitude, contact), "chatter": doubled,
            "clamps": clamps.total, "finite": bool(np.isfinite(amplitude).all())}
    for renderer in RENDERERS.names():
        out["renderers"][renderer]["spectral_distance_from_hybrid"] = _agreement(
            *mu_by[renderer], mu_by["hybrid"][0])
    tracker = TrackerConfig(rate_hz=OUTPUT_HZ)
    _, state = track(0, int(duration * OUTPUT_HZ), trace, TrackerState(), tracker)
    out["tracker"] = {"jumps": state.jumps, "out_of_order": state.out_of_order}
    swaps, many_s = _role_swaps(trace, HYSTERESIS_MM)
    plain, _ = _role_swaps(trace, 0.0)
    out["roles"] = {"two_or_more_s": many_s, "left_most_swaps": swaps,
                    "left_most_swaps_without_hysteresis": plain}
    return out


def _agreement(mu: np.ndarray, contact: np.ndarray, reference: np.ndarray) -> float | None:
    """Mean over fingers of the spectral distance of ``mu`` from ``reference`` (None where
    no finger has enough contact or texture to compare)."""
    values = []
    for row in range(mu.shape[0]):
        try:
            values.append(spectral_error(mu[row], reference[row], contact[row], OUTPUT_HZ))
        except MetricError:
            continue
    return float(np.mean(values)) if values else None


def real_section(folder: Path, scenes) -> dict:
    """Every recording under ``folder`` on every scene: ``{"folder", "runs": [...],
    "skipped": [{"recording", "reason"}]}`` (a recording that cannot be imported, e.g. a
    single touch whose log does not show the axis ranges, is listed with the reason)."""
    runs, skipped = [], []
    for path in recordings(folder):
        try:
            runs += [replay(path, scene) for scene in scenes]
        except TraceError as exc:
            skipped.append({"recording": path.name, "reason": str(exc).splitlines()[0]})
    return {"folder": str(folder), "runs": runs, "skipped": skipped}


def summary_lines(doc: dict) -> list[str]:
    """The report.md section for :func:`real_section`."""
    lines = [f"## Real recordings ({doc['folder']})", "",
             "Each recording replayed on each grating by every renderer (10 kHz, exact "
             "inversion); logs mapped onto the scene's display. No true path exists, so: the "
             "largest step of the output amplitude while a finger stays down (um; a grating "
             f"edge is a full step), chatter (a step of mu' undone within {CHATTER_S * 1e3:g} ms "
             "while the finger, as tracked, stayed within a quarter period and did not turn "
             f"back by {REVERSAL_MEASURED_MM:g} mm: an edge felt twice; rendering/metrics.py), "
             "clamps counted by the inversion, the spectral distance of mu'(t) "
             "from the hybrid's (phase ignored; 0 = the same texture), and how often "
             f"'left-most' changed finger with two or more down ({HYSTERESIS_MM:g} mm "
             "hysteresis / none).", "",
             "| recording | scene | renderer | largest step um | chatter | clamps | "
             "distance from hybrid |", "|---|---|---|---|---|---|---|"]
    for run in doc["runs"]:
        for renderer, r in run["renderers"].items():
            dist = r["spectral_distance_from_hybrid"]
            lines.append(f"| {run['recording']} | {run['scene']} | {renderer} | "
                         f"{r['largest_step_um']:.3f} | {'-' if r['chatter'] is None else r['chatter']} | "
                         f"{r['clamps']} | "
                         f"{'-' if dist is None else f'{dist:.3f}'} |")
    lines += ["", "| recording | fingers | s with 2+ down | left-most swaps | without hysteresis "
              "| tracker jumps | out of order |", "|---|---|---|---|---|---|---|"]
    seen = set()
    for run in doc["runs"]:
        if run["recording"] in seen:
            continue
        seen.add(run["recording"])
        roles, tr = run["roles"], run["tracker"]
        lines.append(f"| {run['recording']} | {run['fingers']} | {roles['two_or_more_s']:.2f} | "
                     f"{roles['left_most_swaps']} | {roles['left_most_swaps_without_hysteresis']} "
                     f"| {tr['jumps']} | {tr['out_of_order']} |")
    if doc["skipped"]:
        lines += ["", "Not replayed: " + "; ".join(f"{s['recording']} ({s['reason']})"
                                                   for s in doc["skipped"]) + "."]
    return lines + [""]
