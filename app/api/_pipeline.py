"""The haptic pipeline of a scene, run over a whole trace in one call."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from frictex._args import choice, real, whole
from frictex._inputs import checked, scene_of
from frictex.app.engine.finger_slots import FingerSlots
from frictex.app.engine.limits import BLOCK_SIZES, OUTPUT_RATES_HZ
from frictex.app.engine.tables import check_memory
from frictex.rendering.input.trace_file import Trace
from frictex.rendering.pipeline import INVERSIONS, BlockOutput
from frictex.rendering.pipeline import build_pipeline as build
from frictex.rendering.tracking.tracks import apply_index
from frictex.textures.model import CONTROL_MODES, Scene, render_modes


def run_settings(rate_hz: float, block_size: int | np.integer | None, renderer: str | None,
                 control: str | None) -> tuple[float, int | None]:
    """The output rate (Hz) and block size (samples; None: 5 ms of samples) checked
    against the command line's bounds (``app.engine.limits``), the renderer and control
    mode against those known."""
    choice("renderer", renderer, render_modes(), none=True)
    choice("control", control, CONTROL_MODES, none=True)
    return (real("rate_hz", rate_hz, "Hz", OUTPUT_RATES_HZ),
            None if block_size is None
            else whole("block_size", block_size, "samples", BLOCK_SIZES))


#: values per finger and output sample in a :class:`BlockOutput`: ``contact``, ``x_mm``,
#: ``y_mm``, ``mu_target``, ``wanted_um``, ``amplitude_um``
OUTPUT_VALUES_PER_FINGER = 6

#: the computation's peak memory over its output's (the stages' working arrays beside
#: the output): measured 2.7 at one finger (172 bytes a sample against 64), 2.3 at two
PEAK_PER_OUTPUT = 3


class Pipeline:
    """The stages a scene needs (tracker, renderers, composition, friction inversion,
    actuation), built once; :meth:`process` runs a trace through them.

    Made by :func:`build_pipeline`. The live demo and ``frictex replay`` run the same
    stages block by block with the state carried over; one call over a whole trace gives
    the same output (a touch sample takes effect at the block boundary after it).
    """

    def __init__(self, scene: Scene | str | Path, *, rate_hz: float = 10_000.0,
                 block_size: int | np.integer | None = None, renderer: str | None = None,
                 control: str | None = None,
                 inversion: str = "exact"):
        scene = scene_of(scene)
        rate_hz, block_size = run_settings(rate_hz, block_size, renderer, control)
        choice("inversion", inversion, INVERSIONS)
        self._stages = build(scene, rate_hz=rate_hz, block_size=block_size,
                             render_override=renderer, control=control, inversion=inversion)

    @property
    def scene(self) -> Scene:
        """The scene the pipeline renders."""
        return self._stages.scene

    @property
    def rate_hz(self) -> float:
        """Output sample rate (Hz)."""
        return self._stages.rate_hz

    @property
    def block_size(self) -> int:
        """Output samples per block."""
        return self._stages.block_size

    @property
    def channels(self) -> tuple[str, ...]:
        """The actuator channels, in the order of ``BlockOutput.commands_um``'s columns."""
        return self._stages.channels

    def process(self, trace: Trace) -> BlockOutput:
        """Run a whole trace through the pipeline, from a fresh state.

        The output clock starts at the trace's first sample (output sample k at
        ``t0 + k / rate_hz``) and runs, without a break, to the end of the block after
        its last sample: every output sample of that span, long pauses included. That is
        where it differs from :func:`replay`, which takes a pause longer than its
        ``max_gap_s`` (5 s by default) as a lift and skips its silence, keeping 0.1 s on
        each side, and lifts every finger touching where the pause starts: at 10 kHz a
        2 s stroke, a 20 s pause and a 2 s stroke give 240,050 output samples here and
        42,050 from :func:`replay`, the same up to the pause's start. For a replay's
        output, use :func:`replay`.

        Parameters
        ----------
        trace : Trace
            Touch samples (:func:`read_trace`, :func:`synth_trace`, :func:`make_trace`), at
            least one; checked as :func:`make_trace` checks arrays.

        Returns
        -------
        BlockOutput
            For n output samples and F rows: ``t_s`` (n,) s; per row (F, n):
            ``contact``, ``x_mm``, ``y_mm`` (mm), ``mu_target`` (mu'), ``wanted_um`` and
            ``amplitude_um`` (um zero-to-peak); ``commands_um`` (n, channels) um;
            ``phases_rad`` (n, channels) rad or None; ``clamps``, the friction
            inversion's guard counts. The rows are the trace's fingers as :func:`replay`
            maps them (a row per finger touching at once, handed on from a lifted
            finger to the next touch): ``finger_ids`` names each row's finger, and
            ``sample_ids`` (F, n) each sample's where a row carries more than one
            (``segments()`` lists them). So a finger's state, a recorded texture's
            noise included, is what :func:`replay` gives it, up to the first pause
            longer than replay's ``max_gap_s``: this renders the pause (``max_gap_s``
            does not apply here: the finger stays touching, held where it was
            extrapolated to), where replay lifts every finger and skips it, so the
            rows line up with replay's only for a trace without such a pause.

        Raises
        ------
        InputError
            A trace :func:`make_trace` refuses (no samples, a NaN, a value out of range,
            time going back, ...); the message names the field and the first bad sample.
            Or an output too big for memory, refused before anything is computed: its
            values (8 bytes each: ``t_s``, six per finger, ``commands_um`` and
            ``phases_rad``) times 3 (the stages' working arrays beside them) may take
            at most half the memory available (Linux's ``MemAvailable``): with one
            finger and one channel 192 bytes a sample, at 10 kHz 1.9 GB per 1,000 s of
            trace, pauses included.
        PluginError
            A ``RuntimeError``, not an InputError: another package's renderer (or one
            registered from your code) that raises or returns what its contract does
            not allow; the message names it and its package.
        """
        trace = checked(trace)
        stages = self._stages
        config = dataclasses.replace(stages.tracker_config, t0_s=float(trace.t_s[0]))
        applied = apply_index(trace.t_s, config)
        n_blocks = int(applied[-1]) // stages.block_size + 1
        slots = FingerSlots()  # the pipeline's rows, as replay's: see app.engine.finger_slots
        slotted = slots.assign(trace, applied)
        self._check_memory(slotted, n_blocks * stages.block_size)
        stages.tracker_config = config
        out, _ = stages.process(0, slotted, stages.initial_state(), n_blocks=n_blocks)
        return slots.label(out)

    def _check_memory(self, trace: Trace, samples: int) -> None:
        """Refuse an output of ``samples`` samples (of every finger in ``trace``) whose
        computation would not fit the memory available (``tables.check_memory``)."""
        fingers = max(1, len(np.unique(trace.finger)))
        phases = 2 if self._stages.actuation.has_phases else 1
        values = 1 + OUTPUT_VALUES_PER_FINGER * fingers + phases * len(self.channels)
        seconds = samples / self.rate_hz
        check_memory(samples * values * 8 * PEAK_PER_OUTPUT,
                     f"the output of this {seconds:.6g} s trace ({samples} samples at "
                     f"{self.rate_hz:g} Hz, {fingers} finger{'s' * (fingers > 1)}, pauses included)",
                     "replay(out=...) skips long pauses and writes its tables a chunk at a time")


def build_pipeline(scene: Scene | str | Path, *, rate_hz: float = 10_000.0,
                   block_size: int | np.integer | None = None,
                   renderer: str | None = None, control: str | None = None,
                   inversion: str = "exact") -> Pipeline:
    """Build the haptic pipeline of a scene.

    Parameters
    ----------
    scene : Scene, str or Path
        A scene (:func:`load_scene`), a texture file or a bundled scene's name. A
        :class:`Scene` built or changed in code (``dataclasses.replace``) is checked by
        the rules of the texture file's keys, as a file is when read.
    rate_hz : float, optional
        Output sample rate (Hz), 100 Hz to 1 MHz as ``frictex replay --rate``; 10 kHz is
        the seed 003 device's link.
    block_size : int or None, optional
        Output samples per block, 1 to 100,000 as ``--block``: touch samples take effect
        at block boundaries, as live. None (the default): 5 ms of samples (50 at 10 kHz,
        1 at 100 Hz).
    renderer : str or None, optional
        Render every periodic layer this way (``sho``, ``sho-held``, ``sho-predicted``,
        ``sht``, ``hybrid``) instead of as its file says.
    control : str or None, optional
        The friction loop (``open``, ``closed``, ``adaptive``) instead of the scene file's.
    inversion : str, optional
        The friction inversion: ``exact`` (seed 003's eq 3) or ``lut`` (a table).

    Returns
    -------
    Pipeline
        Built and warmed (its compiled kernels loaded).

    Raises
    ------
    InputError
        A bad scene (a value of a :class:`Scene` breaking its key's rule: the message
        names the layer and field), or a rate, block size, renderer or control mode that
        is not one the command line accepts, or an inversion other than ``exact`` and
        ``lut`` (the message names the argument).
    PluginError
        A ``RuntimeError``, not an InputError: another package's renderer or device
        profile the scene names (or one registered from your code) that cannot be
        loaded, fails when built, or is not what frictex expects; the message names it
        and its package.
    """
    return Pipeline(scene, rate_hz=rate_hz, block_size=block_size, renderer=renderer,
                    control=control, inversion=inversion)
