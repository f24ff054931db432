"""A simulated participant: feels what the pipeline outputs and answers as a Weber observer.

What it feels. For each stimulus the participant explores its area of the display with
one synthesized human-like stroke (``rendering.input.trace_synth``'s "human" motion:
minimum-jerk strokes with pauses, sampled at a 60 Hz touch rate), and the scene's haptic
pipeline (``rendering.pipeline``, 10 kHz, blocks of 50) turns the stroke into the friction
target under the finger, mu'(t). From mu'(t) along the finger's path it takes:

- ``contrast``: the friction depth felt, max - min of mu' while touching;
- ``period_mm``: the spatial period felt along the path (:func:`felt_period`): the path
  is cut into strokes where the finger rests or turns back, each stroke's mu' is read
  over distance travelled and given the period of its best-fitting sinusoid (a
  periodogram over distance, so neither the grating's phase where a stroke starts nor
  the stroke's speed profile counts: seed 003, section 6, found participants blind to
  the spatial phase of a periodic signal, only its period felt), and the period of the
  stroke covering the most periods is the one felt. A stroke across the lines at an
  angle feels them further apart (the period along its path); the same stroke over a
  grating a times coarser feels a times coarser, which is what a discrimination needs.
  The stroke lasts ``STROKE_S`` (2 s, some 60 mm: 10 periods of a 6 mm grating) or the
  presentation, whichever is shorter; over a grating its path has a stroke of at least
  ``ACROSS_MM`` across the lines (:func:`_motion`), so a short presentation still feels
  a period;
- ``fidelity``: how well mu'(t) reproduces the scene at the finger's true position
  (``rendering.compose.ideal_mu``), in [0, 1]: the cosine similarity of the two
  magnitude spectra, times their correlation for periods over 5 mm (seed 003 section 6:
  the plate changes the friction of the whole contact, so its stimulus cannot be placed
  under the fingerpad, and a phase error is not felt where two stimuli or more lie under
  it; its experiment found SHO and SHT alike at 5 mm and put the boundary there, above
  the 3-4 mm its section 4.4.3 cites for single objects); of finer features only their
  rhythm counts.

The stroke is the same for every stimulus whose lines run alike (its seed is the
participant's), so what differs between stimuli is what the pipeline made of them; the
features of a stimulus are computed once and kept (``feel`` is cached by scene text and
area), which keeps a simulated session to a few pipeline runs.

How it answers. The attribute judged follows ``vary``: period for ``period_mm``, contrast
for ``depth`` and ``level``, fidelity for a list of stimuli (seed 003's "accuracy of
reproduction"). Each presentation's percept is the attribute times exp(sigma e), e
standard normal; sigma = ln(1 + k) / (sqrt(2) z(0.75)) makes the Weber fraction k the
ratio a noise-free forced choice tells apart 75 % of the time. Two-interval trials: the
larger percept is chosen; same-different: "different" when the log percepts differ by
more than ln(1 + k). Magnitude: the percept placed on the scale (fidelity and contrast
directly, a period on a log scale from 0.1 to 100 mm). With probability ``lapse`` the
participant answers at random instead, whatever the trial. Draws come from the
participant's seed and the trial number, so a resumed session answers as an unbroken one.
The participant's seed is the spec's ``seed=`` or, without one, drawn from the session's
seed (:func:`participant_seed`): sessions of different seeds are independent observers,
a session run again with its seed answers alike; session.json records the one used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.special import ndtr, ndtri

from frictex.app.experiment.presenter import Presentation, Shown
from frictex.app.experiment.scheduler import Trial
from frictex.device.errors import InputError
from frictex.rendering.input.trace_file import Trace, make_trace

#: finger speed (mm/s), stroke duration (s), touch rate (Hz) of the synthesized strokes
SPEED_MM_S = 80.0
STROKE_S = 2.0
TOUCH_HZ = 60.0
RATE_HZ = 10_000.0
BLOCK = 50
#: periods (mm) up to this cannot be placed under the fingerpad (seed 003, section 6)
PLACEMENT_MM = 5.0
#: the finger moves (a stroke) above this speed (mm/s); mu' is read along a stroke every STEP_MM
MOVING_MM_S = 1.0
STEP_MM = 0.05
#: a stroke's period is read when its mu' shows this many periods (2 n midrange crossings)
MIN_PERIODS = 2.0
#: the participant's path has a stroke this long across the lines (mm: 4 periods of a 5 mm
#: grating), the first of this many draws of its seed that has one
ACROSS_MM = 20.0
PATH_DRAWS = 64
Z75 = float(ndtri(0.75))
#: the participant spec's keys: ``simulated:weber=0.11,lapse=0.02,seed=1``
SPEC_KEYS = {"weber": (0.001, 10.0), "lapse": (0.0, 1.0), "seed": (0, 2**63 - 1),
             "stroke_s": (0.05, 60.0)}
#: the spec's keys whose upper bound is excluded (``lapse=1`` would answer only at random)
OPEN_ABOVE = ("lapse",)
#: the stream tag of the participant's seed among the draws from the session's seed
_PARTICIPANT_STREAM = 0x0B5E


def participant_seed(session_seed: int) -> int:
    """The simulated participant's seed (0 to 2^63 - 1) when its spec gives none: drawn
    from the session's seed (a stream of its own, apart from the trial order's draws)."""
    rng = np.random.default_rng([int(session_seed), _PARTICIPANT_STREAM])
    return int(rng.integers(0, 2**63))


@dataclass(frozen=True)
class Felt:
    """What one stroke over a stimulus felt like (see the module docstring); ``trace``
    is the stroke (touch samples, mm and s)."""

    contrast: float
    period_mm: float
    fidelity: float
    trace: Trace


def sigma_of(weber: float) -> float:
    """The log-percept noise (natural log units) of a Weber fraction ``weber``."""
    return math.log1p(weber) / (math.sqrt(2.0) * Z75)


def p_choose_larger(ratio, weber: float, lapse: float):
    """Probability that the two-interval observer picks the stimulus whose attribute is
    ``ratio`` times the other's (ratio > 1: a correct answer)."""
    ratio = np.asarray(ratio, dtype=np.float64)
    d = np.log(ratio) / (sigma_of(weber) * math.sqrt(2.0))
    return 0.5 * lapse + (1.0 - lapse) * ndtr(d)


def ratio_at(p: float, weber: float, lapse: float) -> float:
    """The attribute ratio the observer picks correctly with probability ``p``."""
    q = (p - 0.5 * lapse) / (1.0 - lapse)
    if not 0.5 < q < 1.0:
        raise ValueError(f"proportion {p} is out of reach with lapse rate {lapse}")
    return math.exp(float(ndtri(q)) * sigma_of(weber) * math.sqrt(2.0))


def _across(scene) -> tuple[float, float] | None:
    """The unit vector across the lines of ``scene``'s one periodic layer; None without
    exactly one."""
    axes = [layer.axis for layer in scene.layers if layer.is_periodic]
    return axes[0] if len(axes) == 1 else None


def _motion(area: tuple[float, float, float, float], duration_s: float, seed: int,
            across: tuple[float, float] | None):
    """The participant's exploration of ``area`` for ``duration_s`` s (positions relative
    to the area's corner, mm). Over a grating (``across``: the unit vector across its
    lines), the first of its seed's human paths (the seed's own, then draw d of it:
    seed + d 2^63) with a stroke that travels ``ACROSS_MM`` across the lines: a
    participant strokes across the lines it is asked about, and a path along them, or a
    first stroke that a short presentation ends before it went far, feels no period (every
    stimulus alike). Otherwise, or with no such path in ``PATH_DRAWS``, the seed's own."""
    from frictex.rendering.input.trace_synth import make_motion

    def path(draw):
        return make_motion("human", speed_mm_s=SPEED_MM_S, duration_s=duration_s,
                           area_mm=(area[2], area[3]), seed=seed + draw * 2**63)

    if across is not None:
        t = np.arange(0.0, duration_s, 1.0 / TOUCH_HZ)
        for draw in range(PATH_DRAWS):
            motion = path(draw)
            x, y = motion.position(t)
            if any(abs((x[i[-1]] - x[i[0]]) * across[0] + (y[i[-1]] - y[i[0]]) * across[1])
                   >= ACROSS_MM for i in strokes(t, x, y)):
                return motion
    return path(0)


def _stroke(motion, area: tuple[float, float, float, float], seed: int) -> Trace:
    """``motion`` as the touch screen reports it, moved to ``area``'s corner (mm)."""
    from frictex.rendering.input.trace_synth import sample
    t = sample(motion, TOUCH_HZ, seed=seed)
    return make_trace(t.t_s, t.finger, t.x_mm + area[0], t.y_mm + area[1], t.force_n, t.event)


def strokes(t: np.ndarray, x: np.ndarray, y: np.ndarray) -> list[np.ndarray]:
    """The finger's strokes: index arrays of the samples (times ``t`` s, positions
    ``x``, ``y`` mm) where it moves faster than ``MOVING_MM_S`` without turning back
    (two steps more than 90 degrees apart start a new stroke)."""
    dx, dy, dt = np.diff(x), np.diff(y), np.diff(t)
    moving = np.hypot(dx, dy) > MOVING_MM_S * np.where(dt > 0, dt, 0.0)
    turned = np.concatenate([[False], dx[1:] * dx[:-1] + dy[1:] * dy[:-1] < 0.0])
    keep = moving & ~turned
    edges = np.flatnonzero(np.diff(np.concatenate([[0], keep.astype(np.int8), [0]])))
    # step i joins samples i and i + 1: a run of steps [a, b) covers samples a to b
    return [np.arange(a, b + 1) for a, b in zip(edges[::2], edges[1::2])]


def _fit_power(freq: np.ndarray, s: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The variance of ``v`` (mu' at distances ``s``, mm) that a least-squares fit of
    offset + cos + sin at each spatial frequency of ``freq`` (1/mm) explains."""
    v = v - v.mean()
    power = np.empty(freq.size)
    for part in np.array_split(np.arange(freq.size), max(1, freq.size * s.size // 2_000_000)):
        phase = 2.0 * np.pi * np.outer(freq[part], s)
        basis = np.stack([np.ones_like(phase), np.cos(phase), np.sin(phase)], axis=1)
        gram = np.einsum("fin,fjn->fij", basis, basis)
        proj = basis @ v
        coef = np.linalg.solve(gram + 1e-9 * s.size * np.eye(3), proj[..., None])[..., 0]
        power[part] = np.einsum("fi,fi->f", coef, proj)
    return power


def stroke_period(s: np.ndarray, v: np.ndarray) -> float:
    """The period (mm) of the sinusoid whose least-squares fit explains most of ``v``
    (mu' every ``STEP_MM`` of distance ``s``, mm, along one stroke), searched from 4 steps
    to the stroke's length (that length when nothing shorter fits better)."""
    length = float(s[-1])
    freq = np.arange(1.0 / length, 1.0 / (4.0 * STEP_MM), 0.25 / length)
    if freq.size < 2 or not np.ptp(v) > 0:
        return length
    power = _fit_power(freq, s, v)
    best = int(np.argmax(power))
    if best == 0:
        return length
    low, high = freq[best - 1], freq[min(best + 1, freq.size - 1)]
    found = minimize_scalar(lambda f: -_fit_power(np.array([f]), s, v)[0],
                            bounds=(low, high), method="bounded",
                            options={"xatol": 1e-6 / length})
    return float(1.0 / found.x)


def felt_period(mu: np.ndarray, t: np.ndarray, x: np.ndarray, y: np.ndarray) -> float:
    """The spatial period (mm) of mu' along the finger's path: mu' at samples ``t`` (s)
    taken at finger positions ``x``, ``y`` (mm), cut into strokes (:func:`strokes`), each
    read on an even grid of distance travelled (``STEP_MM``) and given its period p
    (:func:`stroke_period`). The felt period is the p of the stroke covering the most
    periods, n = length / p (the best-resolved reading: a frequency estimate's variance
    falls as the cube of the cycles it spans, Rife & Boorstyn 1974), among the strokes
    whose mu' crosses its midrange at least 2 ``MIN_PERIODS`` times (a stroke over one
    line fits a sinusoid of any period). Every stroke's n scales alike when the
    grating does, so the same stroke is read for a grating a times coarser, which is felt
    a times coarser; a stroke at an angle feels the lines further apart, and the stroke
    most across them covers the most. (Averaging the strokes, weighted n^3 over those with
    n >= ``MIN_PERIODS``, let a stroke at another angle count for one grating and not for
    one 11 % coarser: a 2 s path felt 5 mm as 7.04 mm and 5.55 mm as 8.49, 1.21 times.)
    With no such stroke: the longest stroke's length (a period at least that long; the
    whole path when the finger never moved)."""
    found = []
    for index in strokes(t, x, y):
        s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x[index]), np.diff(y[index])))])
        if s[-1] >= 4.0 * STEP_MM:
            grid = np.arange(0.0, s[-1], STEP_MM)
            v = np.interp(grid, s, mu[index])
            side = np.sign(v - 0.5 * (v.max() + v.min()))
            side = side[side != 0]
            found.append((float(s[-1]), stroke_period(grid, v),
                          np.count_nonzero(side[1:] != side[:-1])))
    if not found:
        return float(max(np.sum(np.hypot(np.diff(x), np.diff(y))), STEP_MM))
    length, period, crossings = np.array(found).T
    read = crossings >= 2.0 * MIN_PERIODS
    if not np.any(read):
        return float(length.max())
    return float(period[read][np.argmax(length[read] / period[read])])


def _fidelity(felt: np.ndarray, ideal: np.ndarray, period_mm: float | None) -> float:
    a, b = felt - felt.mean(), ideal - ideal.mean()
    if not np.any(b) or not np.any(a):
        return 1.0 if not np.any(a) and not np.any(b) else 0.0
    fa, fb = np.abs(np.fft.rfft(a)), np.abs(np.fft.rfft(b))
    spectral = float(fa @ fb / (np.linalg.norm(fa) * np.linalg.norm(fb)))
    if period_mm is not None and period_mm <= PLACEMENT_MM:
        return max(0.0, spectral)
    placed = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
    return max(0.0, spectral * max(0.0, placed))


def feel_scene(scene, area, duration_s: float, seed: int) -> Felt:
    """Run ``scene``'s pipeline on the participant's stroke over ``area`` (x, y, width,
    height in mm; :func:`_motion`, across the lines of its grating if it has one) and
    take the features the module docstring lists."""
    from frictex.rendering.compose import ideal_mu
    from frictex.rendering.pipeline import build_pipeline
    motion = _motion(area, duration_s, seed, _across(scene))
    trace = _stroke(motion, area, seed)
    pipeline = build_pipeline(scene, rate_hz=RATE_HZ, block_size=BLOCK, t0_s=float(trace.t_s[0]))
    blocks = int(math.ceil(trace.duration_s * RATE_HZ / BLOCK)) + 1
    out, _ = pipeline.process(0, trace, pipeline.initial_state(), n_blocks=blocks)
    touching = out.contact[0]
    mu = out.mu_target[0][touching]
    if mu.size < 2:
        raise InputError(f"the simulated stroke never touched scene {scene.name!r}")
    t = out.t_s[touching]
    tx, ty = motion.position(t - trace.t_s[0])
    ideal = ideal_mu(scene, tx + area[0], ty + area[1])
    return Felt(contrast=float(mu.max() - mu.min()),
                period_mm=felt_period(mu, t, tx, ty),
                fidelity=_fidelity(mu, ideal, scene.grating_period_mm), trace=trace)


class SimulatedParticipant:
    """A presenter that is its own participant (``presenter.Presenter``); see the module
    docstring. ``weber``: Weber fraction k; ``lapse``: share of random answers;
    ``seed``: its stroke and its draws (None: the session's, :meth:`settle_seed`);
    ``stroke_s``: the longest stroke per stimulus (s)."""

    def __init__(self, weber: float = 0.11, lapse: float = 0.02, seed: int | None = None,
                 stroke_s: float = STROKE_S):
        self.weber, self.lapse, self.stroke_s = weber, lapse, stroke_s
        self.seed = None if seed is None else int(seed)
        self.sigma = sigma_of(weber)
        self.attribute = "fidelity"
        self.scale: tuple[int, int] | None = None
        self._felt: dict[tuple, Felt] = {}

    def settle_seed(self, session_seed: int, recorded: int | None = None) -> int:
        """The seed this participant answers with, fixed now if its spec gave none: the
        one a resumed session ``recorded``, else :func:`participant_seed` of the
        session's seed."""
        if self.seed is None:
            self.seed = participant_seed(session_seed) if recorded is None else int(recorded)
        return self.seed

    def begin(self, protocol) -> None:
        if self.seed is None:
            raise RuntimeError("the simulated participant's seed is not settled: "
                               "call settle_seed first (run_session does)")
        vary = protocol.stimuli.vary
        self.attribute = {"period_mm": "period_mm", "depth": "contrast", "level": "contrast",
                          None: "fidelity"}[vary]
        self.scale = protocol.scale

    def feel(self, shown: Shown) -> Felt:
        """The features of ``shown`` (cached: the same stroke on the same scene)."""
        duration = min(self.stroke_s, shown.seconds)
        key = (shown.text, shown.area, duration)
        if key not in self._felt:
            self._felt[key] = feel_scene(shown.scene, shown.area, duration, self.seed)
        return self._felt[key]

    def value(self, felt: Felt) -> float:
        """The attribute this participant judges, as felt."""
        return getattr(felt, self.attribute)

    def rest(self, trial: Trial) -> None:
        """A break: a simulated participant needs none."""

    def present(self, trial: Trial, shown: Sequence[Shown]) -> Presentation:
        felts = [self.feel(s) for s in shown]
        rng = np.random.default_rng([self.seed, trial.number])
        percepts = [max(self.value(f), 1e-12) * math.exp(self.sigma * rng.standard_normal())
                    for f in felts]
        lapsed = rng.random() < self.lapse
        guess = trial.responses[int(rng.integers(len(trial.responses)))]
        if lapsed:
            response = guess
        elif len(trial.responses) == 2 and trial.responses == ("1", "2"):
            response = "1" if percepts[0] > percepts[1] else "2"
        elif trial.responses == ("same", "different"):
            apart = abs(math.log(percepts[0] / percepts[1])) > math.log1p(self.weber)
            response = "different" if apart else "same"
        else:
            response = self._rating(percepts[0], trial.responses)
        rt = float(rng.lognormal(math.log(0.8), 0.3))  # from the last interval's end
        return Presentation(response, rt, tuple(f.trace for f in felts))

    def _rating(self, percept: float, responses: tuple[str, ...]) -> str:
        if self.attribute == "period_mm":
            where = math.log10(percept / 0.1) / 3.0
        else:
            where = percept
        index = int(round(min(max(where, 0.0), 1.0) * (len(responses) - 1)))
        return responses[index]


def parse_spec(text: str) -> SimulatedParticipant:
    """``weber=0.11,lapse=0.02[,seed=N][,stroke_s=S]`` -> a participant (InputError naming
    the bad part, or a key given twice)."""
    values: dict[str, float] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        key, sep, raw = part.partition("=")
        if not sep or key not in SPEC_KEYS:
            raise InputError(f"simulated participant: {part!r}: expected key=value with a key "
                             f"of {', '.join(SPEC_KEYS)}")
        if key in values:
            raise InputError(f"simulated participant: {key} is given twice; give each key "
                             f"once")
        low, high = SPEC_KEYS[key]
        try:
            value = int(raw) if key == "seed" else float(raw)
            if math.isnan(value):  # float() reads "nan", which no range check refuses
                raise ValueError(raw)
        except ValueError:
            raise InputError(f"simulated participant: {key}={raw!r} is not a number") from None
        open_above = key in OPEN_ABOVE
        if not (low <= value <= high) or (open_above and value >= high):
            raise InputError(f"simulated participant: {key}={raw} is outside [{low:g}, "
                             f"{high:g}{')' if open_above else ']'}")
        values[key] = value
    return SimulatedParticipant(**values)
