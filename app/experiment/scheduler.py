"""The methods as pure trial logic: a scheduler with explicit state.

    scheduler = Scheduler(protocol, seed)
    state = scheduler.initial_state()
    while (trial := scheduler.next_trial(state)) is not None:
        response = ...                      # the presenter's
        state = scheduler.answer(state, trial, response)

Nothing here reads a clock or a file, and every random draw comes from ``seed`` (and the
trial's position), so a session is rebuilt exactly by answering the recorded responses
again (:meth:`Scheduler.replay`): that is how ``--resume`` continues with no trial lost
or repeated.

Constant methods (2afc, same-different, magnitude) draw their whole list of main trials
when the scheduler is made: every level in every order ``repetitions`` times (2afc: the
comparison first and second; same-different: AB, BA, AA, BB; magnitude: each stimulus),
shuffled. The staircase draws the order of the two intervals in pairs of trials (one
comparison-first and one comparison-second in each pair, in random order), and sets the
comparison from the answers (Levitt 1971's transformed up-down rules: down a step after
``n`` correct in a row, up a step after an error; a 1-up-2-down staircase converges on
the difference answered correctly 70.7 % of the time, p^2 = 1/2, a 1-up-3-down on 79.4 %).
A reversal is a change of direction; its level is the difference of the trial before
the change. Steps shrink with the reversals (``steps[i]`` after ``i`` reversals) and on
the log scale are factors 10^step. Each level is computed from an integer index on a
grid (the largest unit every step is a whole number of): start * 10^(index * unit), or
start + index * unit, so a level is the same float however it was reached. A step past
``min`` or ``max`` stops at that bound, and the next step back lands on the grid; on the
linear scale without ``min``, a step that would reach 0 or below is held. The
staircase stops after ``reversals`` reversals or ``max_trials`` main trials.

Practice trials come first (the easiest comparison, or random stimuli for magnitude
estimation), answered but neither adapting a staircase nor analysed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from fractions import Fraction
from functools import lru_cache
from typing import Iterable

import numpy as np

from frictex.app.experiment.protocol import MAX_DECADES, Protocol, Staircase, Stimulus
from frictex.app.experiment.stimuli import name_of
from frictex.device.errors import InputError

INTERVALS = ("1", "2")
SAME_DIFFERENT = ("same", "different")
#: a session's seed is an integer from 0 to SEED_LIMIT - 1 (2^63 - 1)
SEED_LIMIT = 2**63
#: stream tags of the draws from the seed (so that each kind of draw is independent)
_PLAN, _PRACTICE, _ORDER = 1, 2, 3


@dataclass(frozen=True)
class Trial:
    """One trial.

    number : 1-based position in the session, practice included.
    practice : a practice trial (not analysed, does not adapt a staircase).
    stimuli : the stimulus names in presentation order (first/left, second/right).
    value : the comparison's value of ``vary`` (None for magnitude estimation).
    difference : ``value`` minus the reference (units of ``vary``); 0 for an AA/BB pair.
    answer : the correct response (None where no answer is correct: magnitude).
    responses : the responses a participant may give.
    break_before : a break is due before this trial.
    """

    number: int
    practice: bool
    stimuli: tuple[str, ...]
    value: float | None
    difference: float | None
    answer: str | None
    responses: tuple[str, ...]
    break_before: bool = False


@dataclass(frozen=True)
class StaircaseState:
    """difference : the next comparison's difference from the reference.
    run : correct answers in a row since the last step.
    direction : +1 after a step up, -1 after a step down, 0 before any step.
    reversals : the difference at each reversal so far.
    index : the difference's place on the staircase's grid, in grid units from the start
    (:func:`staircase_level`); 0 for a state made at the start."""

    difference: float
    run: int = 0
    direction: int = 0
    reversals: tuple[float, ...] = ()
    index: int = 0


@dataclass(frozen=True)
class SchedulerState:
    """done : trials answered (practice included). main : main trials answered.
    staircase : the staircase's state (staircase protocols only)."""

    done: int = 0
    main: int = 0
    staircase: StaircaseState | None = None


@dataclass(frozen=True)
class _Planned:
    """A constant-method trial before it is numbered: stimuli, value, difference, answer."""

    stimuli: tuple[str, ...]
    value: float | None
    difference: float | None
    answer: str | None


class Scheduler:
    """The trials of ``protocol`` drawn from ``seed`` (see the module docstring)."""

    def __init__(self, protocol: Protocol, seed: int):
        if not 0 <= seed < SEED_LIMIT:
            raise InputError(f"seed {seed}: expected an integer from 0 to 2^63 - 1")
        self.protocol = protocol
        self.seed = int(seed)
        s = protocol.stimuli
        self.reference = name_of(s.vary, s.reference, None) if s.vary else None
        if protocol.method == "magnitude":
            self.responses = tuple(str(i) for i in range(protocol.scale[0], protocol.scale[1] + 1))
        elif protocol.method == "same-different":
            self.responses = SAME_DIFFERENT
        else:
            self.responses = INTERVALS
        self.plan = self._main_plan() if protocol.method != "staircase" else None
        self.practice = self._practice_plan()

    # -- plans -------------------------------------------------------------------------

    def _rng(self, *tags: int) -> np.random.Generator:
        return np.random.default_rng([self.seed, *tags])

    def stimuli_list(self) -> tuple[Stimulus, ...]:
        """Every stimulus the constant methods show (the staircase's are made as it goes)."""
        s = self.protocol.stimuli
        if s.listed:
            return s.listed
        values = (s.reference, *s.levels)
        return tuple(Stimulus(name_of(s.vary, v, None), s.scene, v, None) for v in values)

    def _pair(self, value: float, comparison_first: bool) -> _Planned:
        s = self.protocol.stimuli
        names = (name_of(s.vary, value, None), self.reference)
        if not comparison_first:
            names = names[::-1]
        return _Planned(names, value, value - s.reference, "1" if comparison_first else "2")

    def _main_plan(self) -> tuple[_Planned, ...]:
        p, s = self.protocol, self.protocol.stimuli
        plan: list[_Planned] = []
        for _ in range(p.repetitions):
            if p.method == "magnitude":
                plan += [_Planned((st.name,), st.value, None, None) for st in self.stimuli_list()]
                continue
            for value in s.levels:
                if p.method == "2afc":
                    plan += [self._pair(value, True), self._pair(value, False)]
                    continue
                a, b = self.reference, name_of(s.vary, value, None)
                diff = value - s.reference
                plan += [_Planned((a, b), value, diff, "different"),
                         _Planned((b, a), value, diff, "different"),
                         _Planned((a, a), value, 0.0, "same"),
                         _Planned((b, b), value, 0.0, "same")]
        order = self._rng(_PLAN).permutation(len(plan))
        return tuple(plan[i] for i in order)

    def _practice_plan(self) -> tuple[_Planned, ...]:
        p, s = self.protocol, self.protocol.stimuli
        rng = self._rng(_PRACTICE)
        out = []
        for i in range(p.practice):
            first = bool(rng.integers(2))
            if p.method == "magnitude":
                st = self.stimuli_list()[rng.integers(len(self.stimuli_list()))]
                out.append(_Planned((st.name,), st.value, None, None))
            elif p.method == "staircase":
                out.append(self._pair(self._value(p.staircase.start), first))
            elif p.method == "2afc":
                out.append(self._pair(max(s.levels), first))
            else:
                planned = self._pair(max(s.levels), first)
                out.append(replace(planned, answer="different"))
        return tuple(out)

    def _value(self, difference: float) -> float:
        return self.protocol.stimuli.reference + difference

    # -- the state machine ---------------------------------------------------------------

    def initial_state(self) -> SchedulerState:
        sc = self.protocol.staircase
        return SchedulerState(staircase=StaircaseState(sc.start) if sc is not None else None)

    def finished(self, state: SchedulerState) -> bool:
        if state.done < len(self.practice):
            return False
        if self.plan is not None:
            return state.main >= len(self.plan)
        sc = self.protocol.staircase
        return (len(state.staircase.reversals) >= sc.reversals or state.main >= sc.max_trials)

    def next_trial(self, state: SchedulerState) -> Trial | None:
        """The trial to run in ``state``, or None when the session is complete."""
        if self.finished(state):
            return None
        number = state.done + 1
        if state.done < len(self.practice):
            planned, practice = self.practice[state.done], True
        elif self.plan is not None:
            planned, practice = self.plan[state.main], False
        else:
            pair, second = divmod(state.main, 2)
            first = bool(self._rng(_ORDER, pair).permutation(2)[second])
            planned, practice = self._pair(self._value(state.staircase.difference), first), False
        due = not practice and ((state.main == 0 and len(self.practice) > 0) or (
            self.protocol.break_every and state.main > 0
            and state.main % self.protocol.break_every == 0))
        return Trial(number, practice, planned.stimuli, planned.value, planned.difference,
                     planned.answer, self.responses, bool(due))

    def answer(self, state: SchedulerState, trial: Trial, response: str) -> SchedulerState:
        """The state after ``trial`` was answered with ``response`` (one of its responses)."""
        if trial.number != state.done + 1:
            raise ValueError(f"trial {trial.number} answered in the state before trial "
                             f"{state.done + 1}")
        if response not in trial.responses:
            raise InputError(f"trial {trial.number}: response {response!r} is not one of "
                             f"{', '.join(trial.responses)}")
        done, main = state.done + 1, state.main + (not trial.practice)
        staircase = state.staircase
        if staircase is not None and not trial.practice:
            staircase = staircase_step(self.protocol.staircase, staircase,
                                       response == trial.answer)
        return SchedulerState(done, main, staircase)

    def replay(self, responses: Iterable[tuple[tuple[str, ...], str]]) -> SchedulerState:
        """The state after the recorded trials ``(stimuli, response)``, in order; an
        InputError at the first that does not match the trial this scheduler draws (a
        session recorded with another protocol or seed)."""
        state = self.initial_state()
        for i, (stimuli, response) in enumerate(responses, start=1):
            trial = self.next_trial(state)
            if trial is None:
                raise InputError(f"trial {i}: recorded after the end of the session")
            if tuple(stimuli) != trial.stimuli:
                raise InputError(f"trial {i}: recorded {' vs '.join(stimuli)}, but the protocol "
                                 f"and seed give {' vs '.join(trial.stimuli)}")
            state = self.answer(state, trial, response)
        return state


def _exact(step: float) -> Fraction:
    """A step as the decimal it was written as (0.1 is 1/10, not the float's binary)."""
    return Fraction(repr(float(step)))


@lru_cache(maxsize=64)
def _grid_unit(steps: tuple[float, ...]) -> Fraction:
    """The largest exact unit every step is a whole number of (0.05 for [0.2, 0.1, 0.05])."""
    exact = [_exact(step) for step in steps]
    denominator = math.lcm(*(f.denominator for f in exact))
    return Fraction(math.gcd(*(int(f * denominator) for f in exact)), denominator)


def staircase_level(sc: Staircase, index: int) -> float:
    """The difference (units of ``vary``) ``index`` grid units from the start, within
    ``min`` and ``max``: start * 10^(index * unit) on the log scale, start + index * unit
    on the linear one. Computed from the index alone, so a level reached by different
    paths is the same float (a resumed session finds the scene file it played)."""
    offset = float(index * _grid_unit(tuple(sc.steps)))
    if sc.scale == "log":  # within float64's range however far the index (min/max clamp)
        level = sc.start * 10.0 ** min(max(offset, -MAX_DECADES), MAX_DECADES)
    else:
        level = sc.start + offset
    if sc.min is not None:
        level = max(level, sc.min)
    if sc.max is not None:
        level = min(level, sc.max)
    return level


def _grid_level(sc: Staircase, index: int) -> float:
    """``staircase_level`` before the ``min``/``max`` clamp."""
    return staircase_level(replace(sc, min=None, max=None), index)


def _first_index_reaching(sc: Staircase, bound: float, upward: bool) -> int:
    """The first grid index whose unclamped level is at or past ``bound`` going up
    (``upward``: level >= bound) or down (level <= bound): from its closed form,
    corrected for the float's rounding by a search that doubles its stride, then halves
    it (a walk of one unit at a time took minutes at a unit of 1e-10, and never ended
    where one unit moves the level by less than the float's resolution)."""
    unit = float(_grid_unit(tuple(sc.steps)))
    span = math.log10(bound / sc.start) if sc.scale == "log" else bound - sc.start
    sign = 1 if upward else -1  # levels rise with the index: going down, search mirrored

    def past(k: int) -> bool:  # the level at index sign * k is at or past the bound
        level = _grid_level(sc, sign * k)
        return level >= bound if upward else level <= bound

    guess = math.ceil(sign * span / unit)
    stride = 1
    if past(guess):
        inside, reached = guess - 1, guess
        while past(inside):
            reached, inside, stride = inside, guess - 2 * stride, 2 * stride
    else:
        inside, reached = guess, guess + 1
        while not past(reached):
            inside, reached, stride = reached, guess + 2 * stride, 2 * stride
    while reached - inside > 1:  # not past at inside, past at reached
        middle = (inside + reached) // 2
        inside, reached = (inside, middle) if past(middle) else (middle, reached)
    return sign * reached


def _bounded_index(sc: Staircase, before: int, after: int) -> int:
    """The index a step from ``before`` to ``after`` ends on: no further than the first
    index at or past ``max`` (``min``), so that a step back from a bound lands on the
    grid; on the linear scale without ``min``, held where the step would reach 0 or
    below (never the reference itself)."""
    if after > before and sc.max is not None:
        return max(before, min(after, _first_index_reaching(sc, sc.max, upward=True)))
    if after < before and sc.min is not None:
        return min(before, max(after, _first_index_reaching(sc, sc.min, upward=False)))
    if sc.scale == "linear" and sc.min is None and _grid_level(sc, after) <= 0.0:
        return before
    return after


def staircase_step(sc: Staircase, st: StaircaseState, correct: bool) -> StaircaseState:
    """The staircase ``sc``'s state after a main trial answered ``correct`` (or not) in
    state ``st`` (the module docstring's rules)."""
    run = st.run + 1 if correct else 0
    if correct and run < sc.down_after:
        return replace(st, run=run)
    direction = -1 if correct else +1
    reversals = st.reversals
    if st.direction and direction != st.direction:
        reversals = reversals + (st.difference,)
    step = sc.steps[min(len(reversals), len(sc.steps) - 1)]
    units = int(_exact(step) / _grid_unit(tuple(sc.steps)))
    index = _bounded_index(sc, st.index, st.index + direction * units)
    return StaircaseState(staircase_level(sc, index), 0, direction, reversals, index)


def staircase_threshold(reversals: tuple[float, ...], last: int, scale: str) -> float | None:
    """The staircase's threshold: the mean of the last ``last`` reversal levels (the
    geometric mean on the log scale); None before there are that many."""
    if len(reversals) < last:
        return None
    tail = np.asarray(reversals[-last:], dtype=np.float64)
    return float(np.exp(np.log(tail).mean()) if scale == "log" else tail.mean())
