"""``frictex experiment analyse``: sessions of a study, summarised, fitted and plotted.

Sessions are grouped into studies by protocol name (sessions of one name must have run
the same protocol file: session.json's ``protocol_sha256``). Practice trials are left out.
Per study, by method:

- ``2afc`` and ``staircase``: the psychometric function (``psychometric``) fitted to the
  proportion correct against the comparison's difference from the reference, pooled over
  the study's sessions and per session; threshold and slope (d psi / dx at the
  threshold: proportion correct per unit of ``vary``) with their 95 % bootstrap
  intervals, each bootstrap seeded from its data (equal data, equal intervals); for a
  staircase, the bootstrap runs the staircase again with the fitted function as the
  observer, and the threshold's interval is a Bayesian credible interval with the slope
  integrated out (``psychometric.fit_adaptive``). Each fit names its intervals' methods
  (``threshold_ci_method``, ``slope_ci_method``, also printed; None and "no interval"
  for ``bootstrap = 0``, except a staircase's threshold, whose interval draws nothing).
  The pooled fit treats the sessions' trials as one observer's (its interval is not a
  between-participant one) and says so; with 2 or more sessions, the sessions' own
  thresholds and their mean and standard error across sessions are given too
  (``session_thresholds``).
  No fit (``fit``/``pooled`` None, ``no_fit`` says why) below :data:`MIN_LEVELS`
  distinct differences or, for a staircase, :data:`MIN_REVERSALS` reversals. A
  threshold outside the differences tested is flagged (``threshold_in_tested_range``):
  the fit extrapolates there. A staircase is also summarised by its reversals (the same
  rules as the run, ``scheduler.staircase_step``, replayed from the answers): the mean
  of its last ``threshold_reversals`` reversal levels (geometric on the log scale), per
  session and their mean over sessions (geometric on the log scale too); and by the steps its floor or ceiling held (a
  down step that would cross the linear scale's floor or ``min``, an up step past
  ``max``: the level stays), which bias its reversal mean. Each session's share of
  answers per interval (``response_shares``) is printed, and one interval answered in
  more than :data:`BIAS_SHARE` of its main trials is warned of (``response_bias``).
- ``same-different``: per level, the counts of hits (saying "different" to AB and BA)
  and false alarms (to AA and BB), their raw rates and the rates d' is computed from,
  log-linear corrected ((k + 0.5) / (n + 1), ``rate_correction``), and d' under the
  differencing model with its bootstrap interval (``same_different``); a level whose
  hits are not above its false alarms says that its d' 0 means no discrimination shown
  (``d_prime_note``).
- ``magnitude``: per stimulus (by its value of ``vary``, then by name), the ratings'
  mean, standard deviation, count and the 95 % interval of the mean: Student's t (2
  ratings or more; none below), clipped to the rating scale and marked so
  (``ci95_clipped``). The mean cannot leave the scale, so clipping removes no value the
  t-interval covers and keeps its coverage; with few ratings near an end of the scale
  the t-interval is wide (n 3: the mean +- 2.5 sd).

A slope interval's method quotes its measured coverage only for one complete session of
the bundled protocol it was measured on (:func:`measured_coverage`), and says otherwise
that it is not measured for the design. A fitted lapse rate on its bound ``lapse_max`` is
flagged (``lapse_at_bound``).

An interval the data cannot settle is flagged (``*_ci95_unsettled``: why, else None;
printed after it): one whose fit the data cannot settle (``fit_unsettled``, from
``psychometric.Fit.unsettled``: every trial correct, or a threshold its profile
likelihood does not bound), a slope only bounded below (``slope_unsettled``: a step fits
as well), a staircase's slope interval (its measured coverage is far below 95 %,
``psychometric.RERUN_SHORT``, where :func:`measured_coverage` quotes it; elsewhere
``RERUN_LOOSE``, without the figure), one of zero width, one that spans more than a
factor of :data:`UNSETTLED_RATIO` or reaches 0 (a threshold or slope), a d' interval
at a raw rate of 0 or 1 (``d_prime_ci95_unsettled``), or a magnitude mean's from fewer
than 2 distinct ratings (its zero width says nothing of the uncertainty). With every
trial correct a fit gives no threshold, only its one-sided 95 % upper bound
(``threshold_below``; ``psychometric.ALL_CORRECT_P``), or that the trials are too few to
bound it.

Each session's end is recorded (``session_ends``: "complete", "stopped (...)" or
"killed", its main trials, the rows read from results.csv, the trials session.json
records and whether a torn last line was skipped); one that did not run to its end is
warned of, and so is a results.csv with fewer rows than the trials recorded or a torn
last line (a table cut short). A row whose response is not one of its trial's responses,
or whose ``correct`` is not whether the response is the answer (a table edited by hand),
is warned of by its file and line (``row_problems``): the analysis counts ``correct`` as
written. A ``practice`` other than 0 or 1, a ``correct`` other than 0 or 1 where the
trial has an answer, a cell the analysis reads as a number (``difference``, a
same-different ``value``, a rating) that is not a finite number, or a forced choice's
``difference`` not above 0 or not its ``value`` minus the reference, is refused by its
file and line (``check_cells``). A session folder given twice is refused (it would count
twice), and so is one session in two folders (a copy: the same start, seeds and trials,
``distinct_sessions``).

Writes ``analysis.json`` (every number above) and ``analysis.png`` (one panel per study)
into the output folder.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import stats

from frictex.app.experiment import psychometric, same_different
from frictex.app.experiment.protocol import Staircase, bundled_protocol
from frictex.app.experiment.scheduler import (INTERVALS, SAME_DIFFERENT, StaircaseState,
                                              staircase_step, staircase_threshold)
from frictex.app.experiment.session import read_info, read_rows, torn_last_line
from frictex.device.errors import InputError
from frictex.device.safe_files import file_problem
from frictex.device.numbers import ascii_float


#: the fewest distinct differences a psychometric fit needs (one leaves the slope free)
MIN_LEVELS = 2
#: the fewest reversals (in all the sessions fitted together) a staircase's fit needs
MIN_REVERSALS = 4
#: a threshold's or slope's interval wider than this factor (high / low) is flagged
UNSETTLED_RATIO = 100.0


#: a forced-choice session answering one interval in more than this share of its main
#: trials is warned of (``response_bias``): the comparison is in each interval in half
#: the trials (the scheduler balances the orders), so an observer answering from the
#: stimuli splits about evenly at any level, and a fit to answers that follow the
#: interval gives a threshold that says nothing
BIAS_SHARE = 0.8
#: the fewest main trials for that warning: an unbiased observer at chance answers one
#: interval in more than 80 % of 20 trials with probability 0.0013 (binomial), of 10
#: with 0.011
BIAS_MIN_TRIALS = 20


#: why an interval of zero width is flagged
ZERO_WIDTH = ("unsettled: the interval has zero width (every resampling gave the same "
              "value): the likelihood is flat there, not the estimate exact")


def unsettled(ci, fit_problem: str | None = None) -> str | None:
    """Why the interval ``ci`` (low, high) of a positive quantity cannot be settled by
    its data (its fit's ``fit_problem``, ``psychometric.Fit.unsettled``; zero width; it
    reaches 0 or below, or spans more than :data:`UNSETTLED_RATIO`), or None (settled,
    or no interval)."""
    low, high = ci
    if low is None or high is None or not (math.isfinite(low) and math.isfinite(high)):
        return None
    if fit_problem:
        return f"unsettled: {fit_problem}"
    if high == low:
        return ZERO_WIDTH
    if low <= 0.0:
        return "unsettled: the interval reaches 0, the data cannot bound it from below"
    if high / low > UNSETTLED_RATIO:
        return (f"unsettled: the interval spans a factor of {high / low:.3g} (more than "
                f"{UNSETTLED_RATIO:g}); the data cannot settle it")
    return None


@dataclass(frozen=True)
class SessionData:
    """A session: its folder, session.json, results rows, and whether results.csv's
    last line was torn (written without its line end, and skipped)."""

    folder: Path
    info: dict
    rows: list[dict]
    torn: bool = False

    @property
    def recorded(self) -> int | None:
        """The trials session.json records (its runs' ``trials``), None where none."""
        counts = [p.get("trials") for p in self.info.get("parts") or []]
        return sum(counts) if counts and all(isinstance(c, int) for c in counts) else None

    @property
    def short(self) -> bool:
        """Whether results.csv holds fewer rows than session.json records trials."""
        return self.recorded is not None and len(self.rows) < self.recorded

    @property
    def design(self) -> dict:
        return self.info["design"]

    def main(self) -> list[dict]:
        """The main (not practice) trials."""
        return [row for row in self.rows if row["practice"] == "0"]


#: the results column each method's analysis reads as a number
NUMBER_COLUMN = {"2afc": "difference", "staircase": "difference", "same-different": "value",
                 "magnitude": "response"}


def read_session(folder: str | Path) -> SessionData:
    """A session folder's session.json (checked by ``session.read_info``) and results
    (InputError when it is none, when a key of session.json is malformed, or when a cell
    the analysis counts is: :func:`check_cells`)."""
    folder = Path(folder)
    info = read_info(folder)
    rows = read_rows(folder)
    check_cells(folder / "results.csv", info["method"], rows, info["design"].get("reference"))
    return SessionData(folder, info, rows, torn_last_line(folder))


def _cell_number(cell: str) -> float | None:
    """The number a results cell holds; None where it holds no finite number."""
    try:
        value = ascii_float(cell)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _difference_problem(row: dict, reference: float | None) -> str | None:
    """Why a forced choice's row (its ``difference`` a finite number) cannot be counted:
    a ``difference`` not above 0 (its comparisons lie above the reference), or not its
    ``value`` minus ``reference`` (a fit would count it as a level of its own); None where
    it can, or where session.json keeps no reference. Both cells are written to 12
    significant digits (``session``), so they may disagree by a few units of the 12th."""
    difference = ascii_float(row["difference"])
    if difference <= 0.0:
        return (f"difference {row['difference']!r}: expected a number above 0 (a comparison "
                f"above the reference)")
    if reference is None:
        return None
    value = _cell_number(row["value"])
    if value is None:
        return f"value {row['value']!r}: expected a finite number"
    if abs(difference - (value - reference)) > 1e-10 * max(abs(value), abs(reference)):
        return (f"difference {row['difference']!r} is not value {row['value']!r} minus the "
                f"reference {reference:.12g} ({value - reference:.12g})")
    return None


def check_cells(table: Path, method: str, rows: list[dict],
                reference: float | None = None) -> None:
    """InputError (one line, ``FILE:LINE``) for the first of ``rows`` (of the results
    table ``table``, a session of ``method`` whose design's reference is ``reference``,
    units of ``vary``) whose cell the analysis reads as a number (:data:`NUMBER_COLUMN`)
    is not a finite number, whose ``difference`` a forced choice fits is not above 0 or
    not its ``value`` minus ``reference`` (:func:`_difference_problem`), whose
    ``practice`` is neither 0 nor 1, or whose ``correct`` is neither 0 nor 1 where its
    trial has an answer: the analysis could not count it as written."""
    column = NUMBER_COLUMN[method]
    for line, row in enumerate(rows, start=2):  # line 1 is the header
        if row["practice"] not in ("0", "1"):
            raise InputError(f"{table}:{line}: practice {row['practice']!r}: expected 0 or 1 "
                             f"(whether the trial is a practice one)")
        if _cell_number(row[column]) is None:
            raise InputError(f"{table}:{line}: {column} {row[column]!r}: expected a finite "
                             f"number")
        problem = _difference_problem(row, reference) if column == "difference" else None
        if problem is not None:
            raise InputError(f"{table}:{line}: {problem}")
        if row["answer"] and row["correct"] not in ("0", "1"):
            raise InputError(f"{table}:{line}: correct {row['correct']!r}: expected 0 or 1 "
                             f"(whether response is answer)")


def _responses(info: dict) -> tuple[str, ...] | None:
    """The responses a trial of the session (its session.json ``info``) may be given;
    None where the design does not say (a rating scale not recorded)."""
    if info["method"] != "magnitude":
        return SAME_DIFFERENT if info["method"] == "same-different" else INTERVALS
    scale = info["design"].get("scale")
    return tuple(str(i) for i in range(scale[0], scale[1] + 1)) if scale else None


def row_problems(session: SessionData) -> list[str]:
    """``FILE:LINE: why`` for each row of the session's results.csv whose response is not
    one its trials may be given, or whose ``correct`` is not whether the response is the
    answer (blank where the trial has none). Rows without those columns are not checked."""
    options, table = _responses(session.info), session.folder / "results.csv"
    out = []
    for line, row in enumerate(session.rows, start=2):  # line 1 is the header
        if not {"response", "answer", "correct"} <= row.keys():
            continue
        expected = "" if not row["answer"] else str(int(row["response"] == row["answer"]))
        if options is not None and row["response"] not in options:
            out.append(f"{table}:{line}: response {row['response']!r} is not one of "
                       f"{', '.join(options)}")
        elif row["correct"] != expected:
            out.append(f"{table}:{line}: correct is {row['correct']!r}, but response "
                       f"{row['response']!r} against answer {row['answer']!r} makes it "
                       f"{expected!r}")
    return out


def distinct_folders(folders: list[str | Path]) -> list[Path]:
    """``folders`` as paths; InputError (one line) when two name the same folder, which
    would count its session twice."""
    seen: dict[Path, Path] = {}
    for folder in map(Path, folders):
        try:
            real = folder.resolve()
        except (OSError, RuntimeError) as exc:  # RuntimeError: a link loop, before Python 3.13
            raise InputError(f"{folder}: {file_problem(folder) or exc}") from None
        first = seen.setdefault(real, folder)
        if first is not folder:
            raise InputError(f"analyse: {folder} is given twice (also as {first}); each "
                             f"session counts once")
    return list(seen.values())


def distinct_sessions(sessions: list[SessionData]) -> list[SessionData]:
    """``sessions``; InputError (one line) when two are one session in two folders (a
    copy, or a copy taken before the session was resumed): the same start, seed and
    participant seed, and the rows of one the first rows of the other. It would count
    twice."""
    runs: dict[tuple, list[SessionData]] = {}
    for s in sessions:
        key = tuple(s.info.get(k) for k in ("started_utc", "seed", "participant_seed"))
        for other in runs.setdefault(key, []):
            shared = min(len(other.rows), len(s.rows))
            if other.rows[:shared] == s.rows[:shared]:
                raise InputError(f"analyse: {s.folder} holds the same session as "
                                 f"{other.folder} (started {key[0]}, seed {key[1]}, its "
                                 f"first {shared} trials alike); each session counts once")
        runs[key].append(s)
    return sessions


def ended(info: dict) -> str | None:
    """How a session (its session.json ``info``) ended: "complete", its last run's
    ``ended`` ("stopped (...)"), "killed" (a run without an end), or None where no run
    is recorded."""
    if info.get("ended_utc") is not None:
        return "complete"
    parts = info.get("parts")
    return (parts[-1].get("ended") or "killed") if parts else None


def studies(sessions: list[SessionData]) -> dict[str, list[SessionData]]:
    """Sessions grouped by protocol name, in the order given."""
    out: dict[str, list[SessionData]] = {}
    for s in sessions:
        group = out.setdefault(s.info["protocol"], [])
        if group and group[0].info.get("protocol_sha256") != s.info.get("protocol_sha256"):
            raise InputError(f"{s.folder}: study {s.info['protocol']!r} ran another protocol "
                             f"file than {group[0].folder} (protocol_sha256 differs); give the "
                             f"variants different names")
        group.append(s)
    return out


def _counts(rows: list[dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(difference, trials, correct) per distinct difference of two-interval trials."""
    if not rows:
        return np.empty(0), np.empty(0), np.empty(0)
    x = np.array([float(r["difference"]) for r in rows])
    c = np.array([r["correct"] == "1" for r in rows], dtype=np.float64)
    xs, inverse = np.unique(x, return_inverse=True)
    return xs, np.bincount(inverse, minlength=xs.size).astype(np.float64), np.bincount(
        inverse, c, xs.size)


#: the bundled protocols each interval's coverage was measured on (name: its coverage
#: sentence for the slope's interval), and with how many sessions per fit
MEASURED_ON = {"period-2afc": psychometric.SLOPE_BCA_COVERAGE,
               "depth-staircase": psychometric.RERUN_COVERAGE}
#: what a slope interval's method says where its design is not one measured
NOT_MEASURED = ("its coverage is not measured for this design (only for the bundled "
                "period-2afc and depth-staircase, one session each)")


def measured_coverage(sessions: list[SessionData]) -> str | None:
    """The slope interval's measured coverage where ``sessions`` are one complete session
    of a bundled protocol it was measured on, run unchanged (its protocol_sha256 that of
    the bundled file), else None."""
    if len(sessions) != 1 or ended(sessions[0].info) != "complete" or sessions[0].short:
        return None
    info = sessions[0].info
    bundled = bundled_protocol(info["protocol"])
    if info["protocol"] not in MEASURED_ON or bundled is None:
        return None
    if hashlib.sha256(bundled.read_bytes()).hexdigest() != info.get("protocol_sha256"):
        return None
    return MEASURED_ON[info["protocol"]]


#: why a lapse rate on its upper bound is flagged
LAPSE_AT_BOUND = ("on its bound lapse_max: the data ask for more lapses than allowed, which "
                  "biases the threshold and slope (Wichmann & Hill 2001a)")


def _fit_dict(f: psychometric.Fit, coverage: str | None, staircase: bool) -> dict:
    """A fit as analysis.json records it; ``coverage``: its slope interval's measured
    coverage (:func:`measured_coverage`), None where it is not measured; ``staircase``:
    a staircase's fit, whose slope interval is flagged as falling short of 95 % (with the
    coverage measured where ``coverage`` is quoted)."""
    short = None
    if staircase:
        short = psychometric.RERUN_SHORT if coverage else psychometric.RERUN_LOOSE
    slope_flag = unsettled(f.slope_ci, f.slope_unsettled) or short
    return {"function": f.function, "guess": f.guess, "lapse_max": f.lapse_max,
            "target": f.target, "alpha": f.alpha, "beta": f.beta, "lapse": f.lapse,
            "lapse_at_bound": (LAPSE_AT_BOUND if f.lapse_max > 0.0
                               and f.lapse >= f.lapse_max * (1.0 - 1e-6) else None),
            "threshold": f.threshold, "threshold_below": f.threshold_below,
            "fit_unsettled": f.unsettled, "slope_unsettled": f.slope_unsettled,
            "threshold_ci95": list(f.threshold_ci),
            "threshold_ci_method": f.threshold_ci_method,
            "threshold_ci95_unsettled": (unsettled(f.threshold_ci, f.unsettled)
                                         if f.threshold_ci_method else None),
            "threshold_in_tested_range": bool(f.x[0] <= f.threshold <= f.x[-1]),
            "slope": f.slope, "slope_definition": psychometric.SLOPE,
            "slope_ci95": list(f.slope_ci),
            "slope_ci_method": (f"{f.slope_ci_method}; {coverage or NOT_MEASURED}"
                                if f.slope_ci_method else None),
            "slope_ci95_unsettled": slope_flag if f.slope_ci_method else None,
            "levels": [{"difference": float(x), "trials": int(n), "correct": int(k)}
                       for x, n, k in zip(f.x, f.n, f.k)]}


def _too_few(x: np.ndarray, reversals: int | None) -> str | None:
    """Why trials at differences ``x`` (and a staircase's ``reversals``) get no fit."""
    if x.size == 0:
        return "no main trials"
    levels = np.unique(x).size
    if levels < MIN_LEVELS:
        return (f"{x.size} trial{'s' * (x.size != 1)} at {levels} difference: a fit needs "
                f"at least {MIN_LEVELS}")
    if reversals is not None and reversals < MIN_REVERSALS:
        return (f"{x.size} trials, {reversals} reversal{'s' * (reversals != 1)}: a "
                f"staircase's fit needs at least {MIN_REVERSALS}")
    return None


def _fit(design: dict, x, n, k) -> psychometric.Fit:
    a = design["analysis"]
    return psychometric.fit(x, n, k, function=a["function"], guess=design["guess"],
                            lapse_max=a["lapse_max"], target=design["target"],
                            bootstrap=a["bootstrap"], seed=psychometric.data_seed(x, n, k))


def _play(sc: Staircase, p, rng) -> tuple[list[float], list[bool], StaircaseState]:
    """One staircase run to its stopping rule by an observer correct with probability
    ``p(difference)``: its differences, answers and final state."""
    state, xs, cs = StaircaseState(sc.start), [], []
    while len(state.reversals) < sc.reversals and len(xs) < sc.max_trials:
        correct = bool(rng.random() < p(state.difference))
        xs.append(state.difference)
        cs.append(correct)
        state = staircase_step(sc, state, correct)
    return xs, cs, state


def _staircase_plays(sc: Staircase, sessions: int):
    """``simulate`` for ``psychometric.fit_adaptive``: ``sessions`` staircases."""
    def play(p, rng):
        runs = [_play(sc, p, rng) for _ in range(sessions)]
        return (np.concatenate([r[0] for r in runs]),
                np.concatenate([r[1] for r in runs]).astype(bool))
    return play


def _fit_staircase(design: dict, rows: list[dict], sessions: int) -> psychometric.Fit:
    a = design["analysis"]
    x = np.array([float(r["difference"]) for r in rows])
    correct = np.array([r["correct"] == "1" for r in rows])
    return psychometric.fit_adaptive(x, correct, _staircase_plays(
        Staircase(**design["staircase"]), sessions), function=a["function"],
        guess=design["guess"], lapse_max=a["lapse_max"], target=design["target"],
        bootstrap=a["bootstrap"], seed=psychometric.data_seed(*_counts(rows)))


def _fitted(design: dict, rows: list[dict], sessions: list[SessionData],
            reversals: int | None) -> dict:
    """``{"fit": ...}`` for ``rows`` (of ``sessions``), or ``fit`` None and ``no_fit``
    saying why."""
    reason = _too_few(np.array([float(r["difference"]) for r in rows]), reversals)
    if reason:
        return {"fit": None, "no_fit": reason}
    found = (_fit_staircase(design, rows, len(sessions)) if design["staircase"]
             else _fit(design, *_counts(rows)))
    return {"fit": _fit_dict(found, measured_coverage(sessions), bool(design["staircase"]))}


def staircase_summary(design: dict, rows: list[dict]) -> dict:
    """A staircase session's reversals and threshold, replayed from its answers."""
    sc = Staircase(**design["staircase"])
    state = StaircaseState(sc.start)
    held = {-1: 0, +1: 0}  # steps down and up that left the level where it was
    for row in rows:
        after = staircase_step(sc, state, row["correct"] == "1")
        if after.run == 0 and after.difference == state.difference:
            held[after.direction] += 1
        state = after
    threshold = staircase_threshold(state.reversals, sc.threshold_reversals, sc.scale)
    return {"reversals": list(state.reversals), "threshold": threshold,
            "threshold_reversals": sc.threshold_reversals, "rule": sc.rule, "scale": sc.scale,
            "held_at_floor": held[-1], "held_at_ceiling": held[+1]}


def response_shares(rows: list[dict]) -> dict[str, float | None]:
    """The share of ``rows`` (main trials of a forced choice) answering each interval
    (None where no row records an answer)."""
    answered = [row.get("response") for row in rows]
    return {interval: answered.count(interval) / len(answered) if any(answered) else None
            for interval in INTERVALS}


def response_bias(shares: dict[str, float | None], trials: int) -> str | None:
    """Why a session's answers follow the interval rather than the stimulus
    (:data:`BIAS_SHARE` of :data:`BIAS_MIN_TRIALS` or more), or None."""
    if trials < BIAS_MIN_TRIALS or None in shares.values():
        return None
    for interval, share in shares.items():
        if share > BIAS_SHARE:
            return (f"answered interval {interval} in {share:.0%} of {trials} main trials "
                    f"(an observer answering from the stimuli splits about evenly): its "
                    f"threshold reflects the bias, not the stimuli")
    return None


def session_thresholds(per_session: list[dict]) -> dict | None:
    """The sessions' own fitted thresholds (units of ``vary``) and their mean and standard
    error across sessions (the spread between participants, which the pooled fit's
    interval is not); None for fewer than 2 sessions with a threshold."""
    values = [e["fit"]["threshold"] for e in per_session
              if e["fit"] is not None and e["fit"]["threshold"] is not None]
    if len(values) < 2:
        return None
    return {"thresholds": values, "sessions": len(values), "of_sessions": len(per_session),
            "mean": float(np.mean(values)),
            "se": float(np.std(values, ddof=1) / math.sqrt(len(values)))}


def _forced_choice(design: dict, sessions: list[SessionData]) -> dict:
    per = []
    pooled_rows = []
    for s in sessions:
        rows = s.main()
        pooled_rows += rows
        shares = response_shares(rows)
        entry = {"session": str(s.folder), "trials": len(rows), "response_shares": shares,
                 "response_bias": response_bias(shares, len(rows))}
        reversals = None
        if design["staircase"]:
            entry["staircase"] = staircase_summary(design, rows)
            reversals = len(entry["staircase"]["reversals"])
        per.append({**entry, **_fitted(design, rows, [s], reversals)})
    reversals = (sum(len(e["staircase"]["reversals"]) for e in per) if design["staircase"]
                 else None)
    pooled = _fitted(design, pooled_rows, sessions, reversals)
    out = {"per_session": per, "pooled": pooled.pop("fit"), **pooled,
           "session_thresholds": session_thresholds(per)}
    if design["staircase"]:
        values = [e["staircase"]["threshold"] for e in per if e["staircase"]["threshold"] is not None]
        # over sessions as within one: geometric on the log scale
        out["staircase_threshold_mean"] = (staircase_threshold(
            tuple(values), len(values), design["staircase"]["scale"]) if values else None)
        out["staircase_scale"] = design["staircase"]["scale"]
        for end in ("held_at_floor", "held_at_ceiling"):
            out[end] = sum(e["staircase"][end] for e in per)
    return out


def _same_different(design: dict, sessions: list[SessionData]) -> dict:
    levels: dict[float, dict[str, float]] = {}
    for s in sessions:
        for row in s.main():
            level = levels.setdefault(float(row["value"]), {"hits": 0, "different": 0,
                                                             "false_alarms": 0, "same": 0})
            said = row["response"] == "different"
            if row["answer"] == "different":
                level["different"] += 1
                level["hits"] += said
            else:
                level["same"] += 1
                level["false_alarms"] += said
    out = []
    bootstrap = design["analysis"]["bootstrap"]
    for value in sorted(levels):
        c = levels[value]
        h = float(same_different.rate(c["hits"], c["different"]))
        f = float(same_different.rate(c["false_alarms"], c["same"]))
        ci = same_different.d_prime_interval(c["hits"], c["different"], c["false_alarms"],
                                             c["same"], bootstrap)
        out.append({"value": value, **{k: int(v) for k, v in c.items()},
                    "d_prime_ci95_unsettled": same_different.ceiling(
                        c["hits"], c["different"], c["false_alarms"], c["same"]) if ci else None,
                    "hit_rate_raw": c["hits"] / c["different"] if c["different"] else None,
                    "false_alarm_rate_raw": (c["false_alarms"] / c["same"] if c["same"]
                                             else None),
                    "hit_rate": h, "false_alarm_rate": f,
                    "d_prime": float(same_different.d_prime(h, f)),
                    "d_prime_note": None if h > f else same_different.NO_DISCRIMINATION,
                    "d_prime_ci95": list(ci) if ci else None})
    return {"d_prime_model": same_different.MODEL, "rate_correction": same_different.CORRECTION,
            "d_prime_ci_method": same_different.INTERVAL if bootstrap else None,
            "levels": out}


#: how a magnitude study's interval of a mean rating is computed (printed and recorded)
MEAN_CI_METHOD = ("Student's t on the ratings (n >= 2), clipped to the rating scale: the "
                  "mean lies on the scale, so clipping drops no mean the interval covers")


def mean_interval(ratings: np.ndarray, scale: tuple[float, float] | None):
    """The 95 % interval of the mean of ``ratings`` (:data:`MEAN_CI_METHOD`) and whether
    the scale ``(min, max)`` clipped it; ``(nan, nan), False`` below 2 ratings."""
    if ratings.size < 2:
        return (math.nan, math.nan), False
    mean = float(ratings.mean())
    half = float(stats.t.ppf(0.975, ratings.size - 1) * ratings.std(ddof=1)
                 / math.sqrt(ratings.size))
    low, high = mean - half, mean + half
    if scale is None:
        return (low, high), False
    clipped = (max(low, float(scale[0])), min(high, float(scale[1])))
    return clipped, clipped != (low, high)


def _stimulus_order(name: str, value: str) -> tuple:
    """Sort key of a magnitude stimulus: by its ``value`` of ``vary`` where that is a
    number (period_mm=2 before period_mm=10), then by ``name``; a stimulus without one
    (a list of scenes) by name, after those with one."""
    try:
        return (0, ascii_float(value), name)
    except ValueError:
        return (1, 0.0, name)


def _magnitude(design: dict, sessions: list[SessionData]) -> dict:
    ratings: dict[str, list[float]] = {}
    order: dict[str, tuple] = {}
    for s in sessions:
        for row in s.main():
            ratings.setdefault(row["stimuli"], []).append(float(row["response"]))
            order.setdefault(row["stimuli"], _stimulus_order(row["stimuli"], row["value"]))
    scale = design.get("scale")
    out = []
    for name in sorted(ratings, key=order.__getitem__):
        r = np.asarray(ratings[name])
        sd = float(r.std(ddof=1)) if r.size > 1 else math.nan
        ci, clipped = mean_interval(r, scale)
        flat = (f"unsettled: from {np.unique(r).size} distinct rating"
                f"{'s' * (np.unique(r).size != 1)} (fewer than 2), the interval's width "
                f"says nothing of the uncertainty" if r.size > 1 and np.unique(r).size < 2
                else None)
        out.append({"stimulus": name, "n": int(r.size), "mean": float(r.mean()), "sd": sd,
                    "ci95": list(ci), "ci95_clipped": clipped, "ci95_unsettled": flat})
    return {"scale": scale, "ci95_method": MEAN_CI_METHOD, "stimuli": out}


def analyse_study(sessions: list[SessionData]) -> dict:
    """The summary of one study (see the module docstring)."""
    first = sessions[0]
    design, method = first.design, first.info["method"]
    out = {"study": first.info["protocol"], "method": method, "sessions": len(sessions),
           "vary": design["vary"], "reference": design["reference"],
           "session_ends": [{"session": str(s.folder), "ended": ended(s.info),
                             "main_trials": len(s.main()), "rows": len(s.rows),
                             "trials_recorded": s.recorded, "torn_last_line": s.torn,
                             "row_problems": row_problems(s)}
                            for s in sessions]}
    if method in ("2afc", "staircase"):
        out.update(_forced_choice(design, sessions))
    elif method == "same-different":
        out.update(_same_different(design, sessions))
    else:
        out.update(_magnitude(design, sessions))
    return out


def _finite(value):
    """NaN and infinities as None, for JSON."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


def _made_folder(out_dir: Path) -> Path:
    """``out_dir``, made where missing; InputError (one line) where it cannot be."""
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"{out_dir}: exists and is not a folder")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{out_dir}: cannot be made as the output folder "
                         f"({exc.strerror or exc})") from None
    return out_dir


def analyse(folders: list[str | Path], out_dir: str | Path, plot: bool = True) -> list[dict]:
    """Analyse the sessions in ``folders``; write analysis.json (and analysis.png) into
    ``out_dir``; return the studies' summaries."""
    sessions = distinct_sessions([read_session(f) for f in distinct_folders(folders)])
    out_dir = _made_folder(Path(out_dir))  # before the bootstrap: a bad --out fails at once
    summaries = [analyse_study(group) for group in studies(sessions).values()]
    text = json.dumps(_finite({"studies": summaries}), indent=2, allow_nan=False) + "\n"
    (out_dir / "analysis.json").write_text(text, encoding="utf-8")
    if plot:
        from frictex.app.experiment.plot import plot_studies
        plot_studies(summaries, out_dir / "analysis.png")
    return summaries


def _interval(ci: list, method: str | None, flag: str | None = None) -> str:
    """An interval as printed: its ends (and why the data cannot settle it), or that
    there is none."""
    if method is None:
        return "no interval (bootstrap = 0)"
    return f"95 % [{ci[0]:.4g}, {ci[1]:.4g}]" + (f"; {flag}" if flag else "")


def _ci(fit: dict, name: str) -> tuple:
    """The interval of ``name`` (threshold, slope) in ``fit``, its method and its flag."""
    return fit[f"{name}_ci95"], fit[f"{name}_ci_method"], fit[f"{name}_ci95_unsettled"]


def _pooled_over(summary: dict) -> str:
    """What the threshold line's fit is, where it pools sessions: " of N sessions'
    trials pooled (...)"; empty for one session."""
    if summary["sessions"] < 2:
        return ""
    return (f" of {summary['sessions']} sessions' trials pooled (one fit, as one observer; "
            f"its interval is not a between-participant interval)")


def _session_thresholds_line(each: dict, unit: str) -> str:
    """The sessions' own thresholds and their mean +- SE across sessions."""
    values = ", ".join(f"{v:.4g}" for v in each["thresholds"])
    missing = each["of_sessions"] - each["sessions"]
    return (f"  per session: thresholds {values} {unit}; mean {each['mean']:.4g} ± "
            f"{each['se']:.2g} {unit} (SE across {each['sessions']} sessions"
            + (f"; {missing} without a threshold" if missing else "") + ")")


def _forced_choice_lines(summary: dict, unit: str) -> list[str]:
    """The pooled fit's lines (or why there is none) and the staircases'."""
    lines = [_shares_line(entry) for entry in summary["per_session"]
             if None not in entry["response_shares"].values()]
    pooled = summary["pooled"]
    if pooled is None:
        lines.append(f"  no threshold: {summary['no_fit']}")
    elif pooled["threshold_below"] is not None:
        bound = pooled["threshold_below"]
        lines.append(f"  threshold ({pooled['target']:.3g} correct, {pooled['function']}): "
                     + (f"below {bound:.4g} {unit} difference" if math.isfinite(bound)
                        else "not bounded")
                     + f" (no threshold, slope or interval): {pooled['fit_unsettled']}")
    else:
        lo, hi = pooled["levels"][0]["difference"], pooled["levels"][-1]["difference"]
        where = ("" if pooled["threshold_in_tested_range"] else
                 f" (outside the differences tested, {lo:.4g} to {hi:.4g}: extrapolated)")
        lines += [f"  threshold{_pooled_over(summary)} ({pooled['target']:.3g} correct, "
                  f"{pooled['function']}): {pooled['threshold']:.4g} {unit} difference{where}, "
                 f"{_interval(*_ci(pooled, 'threshold'))}; lapse {pooled['lapse']:.3f}"
                 + (f" ({pooled['lapse_at_bound']})" if pooled["lapse_at_bound"] else ""),
                 f"  slope {pooled['slope']:.4g} per {unit} "
                 f"({_interval(*_ci(pooled, 'slope'))}): "
                 f"{psychometric.SLOPE}"]
        for name in ("threshold", "slope"):
            if pooled[f"{name}_ci_method"]:
                lines.append(f"  {name} interval: {pooled[f'{name}_ci_method']}")
        if pooled["fit_unsettled"] and pooled["threshold_ci_method"] is None:
            lines.append(f"  fit unsettled: {pooled['fit_unsettled']}")
    if summary.get("session_thresholds"):
        lines.append(_session_thresholds_line(summary["session_thresholds"], unit))
    if summary.get("staircase_threshold_mean") is not None:
        mean = "geometric mean" if summary["staircase_scale"] == "log" else "mean"
        lines.append(f"  staircases: {mean} of the sessions' reversal {mean}s "
                     f"{summary['staircase_threshold_mean']:.4g} {unit}")
    for end, way in (("floor", "down"), ("ceiling", "up")):
        if summary.get(f"held_at_{end}"):
            lines.append(f"  staircases: {summary[f'held_at_{end}']} {way} step(s) held at "
                         f"the {end} (the level stayed; reversals there bias the "
                         f"reversal mean)")
    return lines


def _shares_line(entry: dict) -> str:
    """A session's answers per interval, and the warning of a bias."""
    shares = ", ".join(f"interval {interval} {share:.0%}"
                       for interval, share in entry["response_shares"].items())
    bias = entry["response_bias"]
    return (f"  {'warning: ' if bias else ''}{entry['session']}: answers {shares}"
            + (f"; {bias}" if bias else ""))


def _table_warning(end: dict) -> list[str]:
    """The warning (one line, or none) for a session whose results.csv was cut short:
    fewer rows than session.json records, or a torn last line."""
    torn = "; its torn last line was skipped" if end["torn_last_line"] else ""
    if end["trials_recorded"] is not None and end["rows"] < end["trials_recorded"]:
        return [f"  warning: {end['session']}: results.csv holds {end['rows']} of the "
                f"{end['trials_recorded']} trials session.json records{torn}: the table was "
                f"cut short and the missing trials are not analysed"]
    return [f"  warning: {end['session']}: results.csv's last line was torn (written "
            f"without its line end) and skipped"] if torn else []


def report_lines(summary: dict) -> list[str]:
    """The one-screen text summary of a study."""
    head = (f"{summary['study']}: {summary['method']}, {summary['sessions']} session"
            f"{'s' * (summary['sessions'] != 1)}")
    lines = [head]
    lines += [f"  warning: {end['session']} did not run to its end ({end['ended']}, "
              f"{end['main_trials']} main trials): its planned trials are not all here"
              for end in summary["session_ends"] if end["ended"] not in ("complete", None)]
    lines += [line for end in summary["session_ends"] for line in _table_warning(end)]
    lines += [f"  warning: {problem}; counted as written" for end in summary["session_ends"]
              for problem in end["row_problems"]]
    unit = summary["vary"] or ""
    if summary["method"] in ("2afc", "staircase"):
        lines += _forced_choice_lines(summary, unit)
    elif not summary.get("levels") and not summary.get("stimuli"):
        lines.append("  no main trials")
    if summary.get("levels"):
        lines.append(f"  d': {summary['d_prime_model']}; interval: "
                     f"{summary['d_prime_ci_method'] or 'none (bootstrap = 0)'}")
        lines.append(f"  rates: {summary['rate_correction']}")
    for level in summary.get("levels", []):
        ci = level["d_prime_ci95"]
        note = level["d_prime_note"]
        lines.append(f"  {unit} {level['value']:.4g}: hits {level['hits']} of "
                     f"{level['different']}, false alarms {level['false_alarms']} of "
                     f"{level['same']} (corrected rates {level['hit_rate']:.3f} and "
                     f"{level['false_alarm_rate']:.3f}), d' {level['d_prime']:.3f}"
                     + (f", 95 % [{ci[0]:.3f}, {ci[1]:.3f}]" if ci else "")
                     + (f"; {level['d_prime_ci95_unsettled']}"
                        if level["d_prime_ci95_unsettled"] else "")
                     + (f" ({note})" if note else ""))
    for st in summary.get("stimuli", []):
        low, high = (math.nan if v is None else v for v in st["ci95"])
        lines.append(f"  {st['stimulus']}: mean {st['mean']:.3g} (n {st['n']}, 95 % "
                     f"[{low:.3g}, {high:.3g}]{', clipped to the scale' * st['ci95_clipped']}"
                     f"{'; ' + st['ci95_unsettled'] if st['ci95_unsettled'] else ''})")
    if summary.get("stimuli"):
        lines.append(f"  intervals: {summary['ci95_method']}")
    return lines
