"""``frictex experiment analyse``: sessions of a study, summarised, fitted and plotted.

Sessions are grouped into studies by protocol name (sessions of one name must have run
the same protocol file: session.json's ``protocol_sha256``). Practice trials are left out.
Per study, by method:

- ``2afc`` and ``staircase``: the psychometric function (``psychometric``) fitted to the
  proportion correct against the comparison's difference from the reference, pooled over
  the study's sessions and per session; threshold and slope with their 95 % bootstrap
  intervals (for a staircase, the bootstrap runs the staircase again with the fitted
  function as the observer, and the threshold's interval is a Bayesian credible interval
  with the slope integrated out: ``psychometric.fit_adaptive``); each fit names its
  threshold interval's method (``threshold_ci_method``, also printed). A staircase is
  also summarised by its reversals (the same rules as the run, ``scheduler.staircase_step``,
  replayed from the answers): the mean of its last ``threshold_reversals`` reversal levels (geometric on the log scale), per session and
  their mean over sessions.
- ``same-different``: per level, the hit rate (saying "different" to AB and BA), the
  false-alarm rate (to AA and BB) and d' = z(H) - z(F) with each rate taken as
  (k + 0.5) / (n + 1) (the yes-no formula: for a same-different task under the
  differencing model it underestimates the sensitivity; Macmillan & Creelman 2005, ch. 9).
- ``magnitude``: per stimulus, the ratings' mean, standard deviation, count and the 95 %
  interval of the mean: Student's t (2 ratings or more; none below), clipped to the
  rating scale and marked so (``ci95_clipped``). The mean cannot leave the scale, so
  clipping removes no value the t-interval covers and keeps its coverage; with few
  ratings near an end of the scale the t-interval is wide (n 3: the mean +- 2.5 sd).

Writes ``analysis.json`` (every number above) and ``analysis.png`` (one panel per study)
into the output folder.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import stats

from frictex.app.experiment import psychometric
from frictex.app.experiment.protocol import Staircase
from frictex.app.experiment.scheduler import StaircaseState, staircase_step, staircase_threshold
from frictex.app.experiment.session import read_info, read_rows
from frictex.device.errors import InputError


@dataclass(frozen=True)
class SessionData:
    folder: Path
    info: dict
    rows: list[dict]

    @property
    def design(self) -> dict:
        return self.info["design"]

    def main(self) -> list[dict]:
        """The main (not practice) trials."""
        return [row for row in self.rows if row["practice"] == "0"]


def read_session(folder: str | Path) -> SessionData:
    """A session folder's session.json and results (InputError when it is none)."""
    folder = Path(folder)
    info = read_info(folder)
    if not isinstance(info.get("design"), dict) or not isinstance(info.get("protocol"), str):
        raise InputError(f"{folder / 'session.json'}: has no design; not a session of this "
                         f"frictex")
    return SessionData(folder, info, read_rows(folder))


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


def _float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"results: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise InputError(f"results: {text!r} is not a finite number")
    return value


def _counts(rows: list[dict]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(difference, trials, correct) per distinct difference of two-interval trials."""
    if not rows:
        return np.empty(0), np.empty(0), np.empty(0)
    x = np.array([_float(r["difference"]) for r in rows])
    c = np.array([r["correct"] == "1" for r in rows], dtype=np.float64)
    xs, inverse = np.unique(x, return_inverse=True)
    return xs, np.bincount(inverse, minlength=xs.size).astype(np.float64), np.bincount(
        inverse, c, xs.size)


def _fit_dict(f: psychometric.Fit) -> dict:
    return {"function": f.function, "guess": f.guess, "lapse_max": f.lapse_max,
            "target": f.target, "alpha": f.alpha, "beta": f.beta, "lapse": f.lapse,
            "threshold": f.threshold, "threshold_ci95": list(f.threshold_ci),
            "threshold_ci_method": f.threshold_ci_method,
            "slope": f.slope, "slope_ci95": list(f.slope_ci), "bootstrap": f.bootstrap,
            "levels": [{"difference": float(x), "trials": int(n), "correct": int(k)}
                       for x, n, k in zip(f.x, f.n, f.k)]}


def _fit(design: dict, x, n, k, seed: int) -> psychometric.Fit | None:
    if x.size == 0:
        return None
    a = design["analysis"]
    return psychometric.fit(x, n, k, function=a["function"], guess=design["guess"],
                            lapse_max=a["lapse_max"], target=design["target"],
                            bootstrap=a["bootstrap"], seed=seed)


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


def _fit_staircase(design: dict, rows: list[dict], sessions: int, seed: int):
    if not rows:
        return None
    a = design["analysis"]
    x = np.array([_float(r["difference"]) for r in rows])
    correct = np.array([r["correct"] == "1" for r in rows])
    return psychometric.fit_adaptive(x, correct, _staircase_plays(
        Staircase(**design["staircase"]), sessions), function=a["function"],
        guess=design["guess"], lapse_max=a["lapse_max"], target=design["target"],
        bootstrap=a["bootstrap"], seed=seed)


def staircase_summary(design: dict, rows: list[dict]) -> dict:
    """A staircase session's reversals and threshold, replayed from its answers."""
    sc = Staircase(**design["staircase"])
    state = StaircaseState(sc.start)
    for row in rows:
        state = staircase_step(sc, state, row["correct"] == "1")
    threshold = staircase_threshold(state.reversals, sc.threshold_reversals, sc.scale)
    return {"reversals": list(state.reversals), "threshold": threshold,
            "threshold_reversals": sc.threshold_reversals, "rule": sc.rule, "scale": sc.scale}


def _forced_choice(design: dict, sessions: list[SessionData]) -> dict:
    per = []
    pooled_rows = []
    for i, s in enumerate(sessions):
        rows = s.main()
        pooled_rows += rows
        entry = {"session": str(s.folder), "trials": len(rows)}
        fitted = (_fit_staircase(design, rows, 1, seed=i + 1) if design["staircase"]
                  else _fit(design, *_counts(rows), seed=i + 1))
        entry["fit"] = _fit_dict(fitted) if fitted else None
        if design["staircase"]:
            entry["staircase"] = staircase_summary(design, rows)
        per.append(entry)
    pooled = (_fit_staircase(design, pooled_rows, len(sessions), seed=0) if design["staircase"]
              else _fit(design, *_counts(pooled_rows), seed=0))
    out = {"per_session": per, "pooled": _fit_dict(pooled) if pooled else None}
    if design["staircase"]:
        values = [e["staircase"]["threshold"] for e in per if e["staircase"]["threshold"] is not None]
        out["staircase_threshold_mean"] = float(np.mean(values)) if values else None
    return out


def _rate(k: float, n: float) -> float:
    return (k + 0.5) / (n + 1.0)


def _same_different(sessions: list[SessionData]) -> dict:
    levels: dict[float, dict[str, float]] = {}
    for s in sessions:
        for row in s.main():
            level = levels.setdefault(_float(row["value"]), {"hits": 0, "different": 0,
                                                             "false_alarms": 0, "same": 0})
            said = row["response"] == "different"
            if row["answer"] == "different":
                level["different"] += 1
                level["hits"] += said
            else:
                level["same"] += 1
                level["false_alarms"] += said
    out = []
    for value in sorted(levels):
        c = levels[value]
        h, f = _rate(c["hits"], c["different"]), _rate(c["false_alarms"], c["same"])
        out.append({"value": value, **{k: int(v) for k, v in c.items()},
                    "hit_rate": h, "false_alarm_rate": f,
                    "d_prime": float(stats.norm.ppf(h) - stats.norm.ppf(f))})
    return {"levels": out}


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


def _magnitude(design: dict, sessions: list[SessionData]) -> dict:
    ratings: dict[str, list[float]] = {}
    for s in sessions:
        for row in s.main():
            ratings.setdefault(row["stimuli"], []).append(_float(row["response"]))
    scale = design.get("scale")
    out = []
    for name in sorted(ratings):
        r = np.asarray(ratings[name])
        sd = float(r.std(ddof=1)) if r.size > 1 else math.nan
        ci, clipped = mean_interval(r, scale)
        out.append({"stimulus": name, "n": int(r.size), "mean": float(r.mean()), "sd": sd,
                    "ci95": list(ci), "ci95_clipped": clipped})
    return {"scale": scale, "ci95_method": MEAN_CI_METHOD, "stimuli": out}


def analyse_study(sessions: list[SessionData]) -> dict:
    """The summary of one study (see the module docstring)."""
    first = sessions[0]
    design, method = first.design, first.info["method"]
    out = {"study": first.info["protocol"], "method": method, "sessions": len(sessions),
           "vary": design["vary"], "reference": design["reference"]}
    if method in ("2afc", "staircase"):
        out.update(_forced_choice(design, sessions))
    elif method == "same-different":
        out.update(_same_different(sessions))
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


def analyse(folders: list[str | Path], out_dir: str | Path, plot: bool = True) -> list[dict]:
    """Analyse the sessions in ``folders``; write analysis.json (and analysis.png) into
    ``out_dir``; return the studies' summaries."""
    sessions = [read_session(f) for f in folders]
    summaries = [analyse_study(group) for group in studies(sessions).values()]
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    text = json.dumps(_finite({"studies": summaries}), indent=2, allow_nan=False) + "\n"
    (out_dir / "analysis.json").write_text(text, encoding="utf-8")
    if plot:
        from frictex.app.experiment.plot import plot_studies
        plot_studies(summaries, out_dir / "analysis.png")
    return summaries


def report_lines(summary: dict) -> list[str]:
    """The one-screen text summary of a study."""
    head = (f"{summary['study']}: {summary['method']}, {summary['sessions']} session"
            f"{'s' * (summary['sessions'] != 1)}")
    lines = [head]
    unit = summary["vary"] or ""
    pooled = summary.get("pooled")
    if pooled:
        lo, hi = pooled["threshold_ci95"]
        lines.append(f"  threshold ({pooled['target']:.3g} correct, {pooled['function']}): "
                     f"{pooled['threshold']:.4g} {unit} difference, 95 % [{lo:.4g}, {hi:.4g}]; "
                     f"slope {pooled['slope']:.4g} per {unit}, lapse {pooled['lapse']:.3f}")
        lines.append(f"  threshold interval: {pooled['threshold_ci_method']}")
    if summary.get("staircase_threshold_mean") is not None:
        lines.append(f"  staircases: mean of the sessions' reversal means "
                     f"{summary['staircase_threshold_mean']:.4g} {unit}")
    for level in summary.get("levels", []):
        lines.append(f"  {unit} {level['value']:.4g}: hits {level['hit_rate']:.3f}, false "
                     f"alarms {level['false_alarm_rate']:.3f}, d' {level['d_prime']:.3f}")
    for st in summary.get("stimuli", []):
        low, high = (math.nan if v is None else v for v in st["ci95"])
        lines.append(f"  {st['stimulus']}: mean {st['mean']:.3g} (n {st['n']}, 95 % "
                     f"[{low:.3g}, {high:.3g}]{', clipped to the scale' * st['ci95_clipped']})")
    if summary.get("stimuli"):
        lines.append(f"  intervals: {summary['ci95_method']}")
    return lines
