"""A run's ``summary.json``: counts, clamps, warnings, per-finger errors and timings.

:class:`Totals` is a sink (``app.engine.sinks``) that counts over every block output;
:func:`summary` turns the counts into the document, :func:`timings` the run's seconds
into real-time factors. Real-time factors say what they count: ``x_realtime_end_to_end``
is output seconds over the wall time of reading the trace, computing and writing every
table (each closed in the staging folder), not writing ``summary.json`` itself nor
swapping the staging folder in (which deletes the previous run's outputs: 0.08-0.38 s
of system time for 90 MB, ``app.measure.bench_baseline``); ``x_realtime_with_setup`` over the whole run's wall time, start-up
too (loading the scene, loading the pipeline's compiled kernels: ``setup_s``);
``x_realtime_compute`` over the pipeline's compute alone.
"""

from __future__ import annotations

import math
import os

import numpy as np

from frictex.app.engine.finger_table import FingerTable
from frictex.app.engine.force_summary import ForceSummary
from frictex.device.friction import ClampCounts
from frictex.rendering.pipeline import STAGES

SUMMARY_VERSION = 7


class Totals:
    """What the summary counts over a run, block output by block output (a sink)."""

    def __init__(self):
        self.clamps = ClampCounts()
        self.errors = AmplitudeErrors()
        self.forces = ForceSummary()
        self.max_amplitude = 0.0
        self.contact_samples = 0
        self.touching = 0  # finger samples touching: the friction table's rows
        self.limited = 0
        self.modal_capped = 0
        self.off_structure = 0
        self.modal_unserved = 0
        self.layer_clipped: dict[str, int] = {}
        self.largest_time_s = 0.0  # the largest |t_s| of an output sample (s)

    def write(self, out, commands_um) -> None:
        self.clamps.add(out.clamps)
        self.errors.add(out)
        self.forces.add(out)
        self.max_amplitude = max(self.max_amplitude, float(commands_um.max(initial=0.0)))
        self.contact_samples += int(out.contact.any(axis=0).sum())
        self.touching += int(np.count_nonzero(out.contact))
        self.limited += out.limited
        self.modal_capped += out.capped
        self.off_structure += out.off_structure
        self.modal_unserved += out.unserved
        self.largest_time_s = max(self.largest_time_s, abs(float(out.t_s[0])),
                                  abs(float(out.t_s[-1])))
        for name, n in out.layer_clipped.items():
            self.layer_clipped[name] = self.layer_clipped.get(name, 0) + n

    def commit(self) -> None:
        """Counts are final as they are."""

    abort = commit


class AmplitudeErrors:
    """Per finger: how far the achieved amplitude was from the wanted one while touching
    (bounded in the ids it lists: ``app.engine.finger_table``)."""

    def __init__(self):
        # finger id -> [contact samples, sum of squares, max]
        self.table = FingerTable(("sum", "sum", "max"))

    def add(self, out) -> None:
        err = np.where(out.contact, out.amplitude_um - out.wanted_um, 0.0)
        segments = out.segments()
        for row, fid, lo, hi in segments:
            s = self.table.row(fid)
            s[0] += int(out.contact[row, lo:hi].sum())
            s[1] += float(np.sum(err[row, lo:hi] ** 2))
            s[2] = max(s[2], float(np.abs(err[row, lo:hi]).max(initial=0.0)))
        self.table.done_adding(fid for _, fid, _, _ in segments)

    @staticmethod
    def _entry(n, sq, mx) -> dict:
        """A finger's entry; its errors None (null) with no contact sample to measure."""
        return {"contact_samples": n, "amplitude_error_rms_um": (sq / n) ** 0.5 if n else None,
                "amplitude_error_max_um": float(mx) if n else None}

    def report(self) -> dict:
        """{finger: {contact_samples, amplitude_error_rms_um, amplitude_error_max_um}} for
        the listed fingers (at most ``MAX_LISTED``, those with the most contact samples)."""
        return {str(fid): self._entry(*row) for fid, row in self.table.report()[0].items()}

    def others(self) -> dict | None:
        """The fingers not listed, aggregated: ``fingers`` (how many ids) and the entry
        over all their samples; None when every finger is listed."""
        rest = self.table.report()[1]
        return None if rest is None else {"fingers": rest[0], **self._entry(*rest[1])}


def warnings_of(pipeline, tracker, totals: Totals) -> list[str]:
    """One sentence per thing the pipeline changed or could not do."""
    clamps = totals.clamps.as_dict()
    warnings = []
    if clamps["unreachable"] and pipeline.forces is not None:
        n = clamps["unreachable"]
        warnings.append(f"{counted(n, 'sample')} asked for a tangential force out of the "
                        f"wave's reach and {were(n)} clamped to the nearest reachable force")
    elif clamps["unreachable"]:
        n = clamps["unreachable"]
        warnings.append(f"{counted(n, 'target sample')} {were(n)} below the lowest reachable "
                        f"mu' and {were(n)} clamped to the amplitude limit")
    if clamps["nonfinite_target"]:
        n = clamps["nonfinite_target"]
        warnings.append(f"{counted(n, 'target sample')} {were(n)} not finite (NaN or inf) "
                        f"and {were(n)} commanded 0 um")
    if clamps["force_beyond_model"]:
        warnings.append(f"{counted(clamps['force_beyond_model'], 'sample')} had a normal force "
                        + pipeline.friction.beyond_model(forces=pipeline.forces is not None))
    if tracker.jumps:
        warnings.append(f"{counted(tracker.jumps, 'finger jump')} {were(tracker.jumps)} "
                        "treated as lift and touch")
    if tracker.out_of_order:
        warnings.append(f"{counted(tracker.out_of_order, 'out-of-order touch sample')} "
                        f"{were(tracker.out_of_order)} dropped")
    if totals.limited:
        warnings.append(f"{counted(totals.limited, 'sample')} hit an actuator limit "
                        "(achieved amplitude differs from the wanted one; see fingers)")
    if totals.modal_capped:
        warnings.append(f"{counted(totals.modal_capped, 'sample')}: the fingers could not be "
                        "given independent amplitudes (seed 001 eq 8): where their mode-shape "
                        "matrix is singular (det ~ 0; on a beam e.g. fingers a multiple of half "
                        "a wavelength apart, coincident or on a shared node) the modal gain was "
                        "capped, so fingers asking for different friction may feel the same "
                        "(see fingers)")
    if totals.off_structure:
        n = totals.off_structure
        warnings.append(f"{counted(n, 'finger sample')} {were(n)} off the vibrating "
                        f"structure and {were(n)} held at its edge")
    if totals.modal_unserved:
        warnings.append(_unserved_warning(totals.modal_unserved, pipeline.actuation.n_modes))
    clipped = {name: n for name, n in totals.layer_clipped.items() if n}
    if clipped:
        layers = {layer.name: layer for layer in pipeline.scene.layers}
        warnings += [_clipped_warning(layers[name], n, totals.touching)
                     for name, n in clipped.items()]
    return warnings


def _unserved_warning(n: int, modes: int) -> str:
    """The sentence for ``n`` finger samples touching beyond the ``modes`` fingers a
    modal scene serves at a time."""
    return (f"{counted(n, 'finger sample')} {were(n)} not served: the scene's "
            f"{counted(modes, 'mode')} serve only {counted(modes, 'finger')} at a time (those "
            "touching longest), so a further finger gets no control of its own and feels the vibration the served ones get "
            "(|Phi(x) W_M|, its achieved amplitude in fingers) whatever its target")


def _within_a_block(trace_report: dict) -> list[str]:
    """The sentence for touches that began and lifted within one output block."""
    n = trace_report.get("touches_within_a_block", 0)
    if not n:
        return []
    them, their = ("it", "its") if n == 1 else ("them", "their")
    return [f"{counted(n, 'touch', 'touches')} began and lifted within one output block, so "
            f"no output sample is in contact for {them} (none of {their} rows in the friction "
            "table); a smaller --block keeps shorter touches"]


def _clipped_warning(layer, n: int, touching: int) -> str:
    """The sentence for ``n`` finger samples (of ``touching``) that ``layer``'s own
    limits clipped: a clip's level sum past 1, a recorded texture's mu_min/mu_max, a
    periodic layer's texture past the output's Nyquist frequency
    (``rendering.layers.band_limit``)."""
    share = f"{n} of {touching} touching samples ({100.0 * n / max(touching, 1):.1f} %)"
    kind = getattr(layer, "renderer_kind", None)
    if getattr(layer, "is_periodic", False):
        return (f"layer {layer.name!r}: {share} moved its texture past the output's Nyquist "
                f"frequency (|v . axis| / period above half the output rate) and {were(n)} played "
                f"as its mean mu', not an alias; raise --rate to play "
                f"{'it' if n == 1 else 'them'}")
    if kind == "clip":
        return (f"layer {layer.name!r} (clip): {share} played where its events' levels added "
                f"past 1 and {were(n)} held at mu' = 1 - depth = {1.0 - layer.clip.depth:.4g}; "
                "lower the events' intensities to keep their shape")
    lo, hi = layer.mu_range
    said = (f"layer {layer.name!r}: {share} {were(n)} clipped to its mu' limits "
            f"[{lo:.4g}, {hi:.4g}]")
    if kind == "ar":
        said += ("; lower its gain or widen mu_min/mu_max to keep the recorded texture's "
                 "spectrum")
    return said


def counted(n: int, noun: str, nouns: str | None = None) -> str:
    """``n`` and ``noun``, in the plural (``nouns``; default ``noun`` + "s") unless ``n``
    is 1: "1 finger jump", "3 finger jumps"."""
    return f"{n} {noun if n == 1 else nouns or noun + 's'}"


def were(n: int) -> str:
    """The verb for ``n`` things: "was" for 1, else "were"."""
    return "was" if n == 1 else "were"


def _real_path(path) -> str | None:
    """A scene's or trace's file as ``summary.json`` gives it: absolute, links and ``..``
    resolved, so that the same run started from another folder says the same; None for
    none (a trace given as a Trace object)."""
    return os.path.realpath(path) if path else None


def summary(scene, trace_report: dict, pipeline, tracker, totals: Totals, fmt: str,
            files: list[str], blocks: int) -> dict:
    """The summary document (without ``timings``, ``device`` and run-level warnings)."""
    n_out = blocks * pipeline.block_size
    doc = {
        "summary_version": SUMMARY_VERSION,
        "scene": {"name": scene.name,
                  "path": _real_path(scene.source),
                  "device": scene.device.profile,
                  "layers": [{"name": layer.name, "type": layer.file_type,
                              "renderer": mode}
                             for layer, mode in zip(scene.layers, pipeline.layer_modes)]},
        "trace": {**trace_report, "path": _real_path(trace_report.get("path"))},
        "output": {"rate_hz": pipeline.rate_hz, "block_size": pipeline.block_size,
                   "samples": n_out, "duration_s": n_out / pipeline.rate_hz,
                   "channels": list(pipeline.channels), "format": fmt, "files": files},
        "counts": {"blocks": blocks, "contact_samples": totals.contact_samples,
                   "jumps": tracker.jumps, "out_of_order": tracker.out_of_order,
                   "max_amplitude_um": totals.max_amplitude,
                   "actuator_limited": totals.limited, "modal_capped": totals.modal_capped,
                   "off_structure": totals.off_structure,
                   "modal_unserved": totals.modal_unserved},
        "clamps": totals.clamps.as_dict(),
        "layer_clipped": dict(totals.layer_clipped),
        "warnings": warnings_of(pipeline, tracker, totals) + _within_a_block(trace_report),
        "fingers": totals.errors.report(),
    }
    others = totals.errors.others()
    if others is not None:
        force_others = totals.forces.others()
        doc["fingers_others"] = others if force_others is None else {**others, "forces": force_others}
    forces = totals.forces.report()
    if forces is not None:
        doc["forces"] = forces
    return doc


def timings(pipeline, output_s: float, loop_seconds: dict, wall_s: float,
            setup_s: float = 0.0) -> dict:
    """``timings``: wall, start-up and compute seconds and the real-time factors (see the
    module doc)."""
    stages = dict(pipeline.timer.seconds)
    compute = sum(stages.values())
    run_s = wall_s - setup_s
    return {"wall_s": wall_s, "setup_s": setup_s, "compute_s": compute,
            "x_realtime_end_to_end": output_s / run_s if run_s > 0 else None,
            "x_realtime_with_setup": output_s / wall_s if wall_s > 0 else None,
            "x_realtime_compute": output_s / compute if compute > 0 else None,
            "loop_s": dict(loop_seconds),
            "stages_s": {s: stages[s] for s in STAGES},
            "layers_s": dict(pipeline.timer.layer_seconds)}


def finite_json(value):
    """``value`` with every non-finite float replaced by None (JSON has no inf or NaN)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_json(v) for v in value]
    return value


def control_line(control: dict) -> str:
    """One line of a summary's ``control`` section (``rendering.control.loop``'s
    ``report``), as ``frictex replay`` and ``frictex demo`` print it. Two gains, each
    named: the depth gain c (the reduction of friction asked is c times the texture's;
    the integrator moves it) and the integrator's step ki (how far one block's
    measurement moves log c, scheduled on the force reports' delay)."""
    measured = control.get("measured") or {}
    if measured.get("reports", 1):
        reports = f"force reports up to {control['report_delay_blocks']} blocks late"
    else:  # no report the loop could use: no delay to give
        rejected = sum((control.get("reports_rejected") or {}).values())
        reports = (f"no usable force report ({rejected} rejected, "
                   f"{measured.get('reports_missed', 0)} missed)")
    return (f"{control['mode']} loop: {reports}; depth gain c {control['gain']:.3f} at the end (reduction asked = "
            f"c x the texture's; {control['updates']} updates), integrator step ki "
            f"{control['ki']:.3g} per block at the end (scheduled for reports "
            f"{control['scheduled_delay_blocks']} blocks late); {control['fallbacks']} "
            f"fallbacks to open loop ({control['fallback_samples']} samples)")
