"""The grammar of session.json (``session`` writes it), checked once where it is read
(``session.read_info``): every key a reader uses, with the bounds the protocol loader
applies to the protocol key it records (``protocol.TOP``, ``STIMULI``, ``ANALYSIS``,
``STAIRCASE``, ``SCALE`` and the checks across them), so that a session.json a person
edited, or a stranger wrote, is one line naming the file, the key and what was expected,
before any trial runs or any fit starts.
::

    seed                  required; the trial order's seed (as the protocol's seed)
    protocol, participant required; one line of text each
    method                required; one of the protocol's methods
    participant_seed      null or a seed (as seed); participant_id: null or a plain name
    record                all | traces | results
    protocol_sha256       64 hexadecimal digits; scene_sha256: {name: 64 hex digits}
    started_utc           an ISO 8601 time; ended_utc: null or one
    parts                 a list of {started_utc, ended_utc (null or a time), first_trial
                          (1 or more), trials (0 or more), ended (null or a line)}
    design                required: {vary (null or a protocol's vary), reference (null
                          or a protocol's number), guess (the method's guess rate, null
                          for a method without one), target (the threshold's proportion
                          correct, below 1 - lapse_max; null without a guess rate),
                          analysis (the protocol's [analysis]), staircase (its
                          [staircase]; null unless method is staircase), scale ([min,
                          max] of its [scale]; null or absent unless method is magnitude)}

Keys not listed here (versions, vary_unit, question) are not read, so not checked; a
missing key of ``analysis`` or ``staircase`` takes the protocol's default, as in a
protocol file.
"""

from __future__ import annotations

import re
import sys
from dataclasses import asdict, dataclass
from datetime import datetime
from typing import Any

from frictex.app.experiment.protocol import (ANALYSIS, GUESS_RATES, STAIRCASE, STIMULI, TOP,
                                             check_method_fits, check_scale, check_staircase)
from frictex.app.engine.batch import NAME
from frictex.device.errors import InputError
from frictex.textures.schema import BAD, Choice, Int, Reader, Text, kind

#: what a session keeps per trial (``--record``): every stimulus's files, the touch traces,
#: or the results only
RECORDS = ("all", "traces", "results")
#: a sha256 as session.json records it (``hashlib``'s hexdigest)
SHA256 = re.compile(r"[0-9a-f]{64}")


@dataclass(frozen=True)
class Line:
    """One line of text of any length, as :class:`~frictex.textures.schema.Text` checks
    one (no control or format character), and no unpaired surrogate (a JSON escape such
    as \\ud800, which no output can encode): a name printed in reports."""

    def check(self, r: Reader, value, path):
        value = Text(max_len=sys.maxsize).check(r, value, path)
        if value is not BAD and any("\ud800" <= c <= "\udfff" for c in value):
            return r.report(path, "holds an unpaired surrogate (a \\ud800-\\udfff escape); "
                                  "expected text")
        return value


@dataclass(frozen=True)
class Matching:
    """A string that ``pattern`` matches whole; ``what`` it is, for the message."""

    pattern: re.Pattern
    what: str

    def check(self, r: Reader, value, path):
        if not isinstance(value, str) or self.pattern.fullmatch(value) is None:
            return r.report(path, f"expected {self.what}, got {kind(value)}")
        return value


@dataclass(frozen=True)
class Time:
    """A time as session.json records one: ISO 8601 text (``session._now``)."""

    def check(self, r: Reader, value, path):
        try:
            datetime.fromisoformat(value)
        except (TypeError, ValueError):
            return r.report(path, f"expected a time (ISO 8601, such as "
                                  f"2026-01-31T12:00:00+00:00), got {kind(value)}")
        return value


@dataclass(frozen=True)
class OrNull:
    """null, or a value ``spec`` checks."""

    spec: Any

    def check(self, r: Reader, value, path):
        return None if value is None else self.spec.check(r, value, path)


@dataclass(frozen=True)
class Fields:
    """A JSON object: each key of ``specs`` it holds checked (the ``required`` ones must
    be there); other keys are kept unchecked (no reader uses them)."""

    specs: dict
    required: tuple = ()

    def check(self, r: Reader, value, path):
        if not isinstance(value, dict):
            return r.report(path, f"expected a table {{...}}, got {kind(value)}")
        out = dict(value)
        for key in self.required:
            if key not in value:
                out[key] = r.report(path + (key,), "missing (required)")
        for key, spec in self.specs.items():
            if key in value:
                out[key] = spec.check(r, value[key], path + (key,))
        return out


@dataclass(frozen=True)
class Each:
    """A JSON list (``what``: of what, for the message), each item checked by ``item``;
    or with ``by_name``, an object whose every value is."""

    item: Any
    what: str
    by_name: bool = False

    def check(self, r: Reader, value, path):
        if not isinstance(value, dict if self.by_name else list):
            return r.report(path, f"expected {self.what}, got {kind(value)}")
        if self.by_name:
            return {k: self.item.check(r, v, path + (k,)) for k, v in value.items()}
        return [self.item.check(r, v, path + (i,)) for i, v in enumerate(value)]


TIME = Time()
LINE = Line()
SEED = TOP["seed"]
PART = Fields({"started_utc": TIME, "ended_utc": OrNull(TIME),
               "first_trial": Int("trial number", ge=1), "trials": Int("trials", ge=0),
               "ended": OrNull(LINE)})
INFO = Fields({"seed": SEED, "protocol": LINE, "method": TOP["method"], "participant": LINE,
               "participant_seed": OrNull(SEED),
               "participant_id": OrNull(Matching(NAME, "a plain name (--participant-id, "
                                                       "such as P07)")),
               "record": Choice(RECORDS),
               "protocol_sha256": Matching(SHA256, "a sha256 (64 hexadecimal digits)"),
               "scene_sha256": Each(Matching(SHA256, "a sha256 (64 hexadecimal digits)"),
                                    "an object of each scene's sha256 by its name",
                                    by_name=True),
               "started_utc": TIME, "ended_utc": OrNull(TIME),
               "parts": Each(PART, "a list of the session's runs")},
              required=("seed", "protocol", "method", "participant", "design"))
DESIGN = Fields({"vary": OrNull(STIMULI["vary"]), "reference": OrNull(STIMULI["reference"])},
                required=("vary", "reference", "guess", "target", "analysis", "staircase"))


class _Under(Reader):
    """A reader of the part of session.json under ``prefix``, each problem named by its
    whole path; it is its own ``_Check`` (``.r``, ``.report``), so that the protocol's
    checks of its tables check the design's."""

    def __init__(self, label: str, prefix: tuple):
        super().__init__(label, None)
        self.prefix = prefix

    @property
    def r(self) -> Reader:
        return self

    def problem(self, path, message: str, warning: bool = False):
        return super().problem(self.prefix + tuple(path), message, warning)


def _nulls_unset(value, spec: dict):
    """A JSON object of a protocol table with its nulls of keys whose default is None
    left out (session.json writes ``null`` where the protocol file had no key)."""
    if not isinstance(value, dict):
        return value
    return {k: v for k, v in value.items()
            if not (v is None and getattr(spec.get(k), "default", BAD) is None)}


def _target(d: _Under, value, method: str, analysis: dict | None):
    """``design.target``: for a method with a guess rate, the threshold's proportion
    correct (``[analysis] target``'s bounds), below 1 - lapse_max (where the fitted
    function tops out); else null."""
    if GUESS_RATES.get(method) is None:
        return None if value is None else d.report(
            ("target",), f"expected null: method {method} fits no psychometric function")
    target = ANALYSIS["target"].check(d, value, ("target",))
    if target is BAD or analysis is None or analysis["lapse_max"] is BAD:
        return target
    if not target < 1.0 - analysis["lapse_max"]:
        return d.report(("target",), f"{target:g} is not below 1 - lapse_max "
                                     f"({1.0 - analysis['lapse_max']:g}): the fitted "
                                     f"function never reaches it")
    return target


def _rating_scale(d: _Under, value, method: str):
    """``design.scale``: a magnitude estimation's [min, max] (``[scale]``); null for
    other methods."""
    if value is None and method != "magnitude":
        return None
    if not isinstance(value, list) or len(value) != 2:
        return d.report(("scale",), f"expected [min, max] (the rating scale), got "
                                    f"{kind(value)}")
    scale = check_scale(d, {"scale": dict(zip(("min", "max"), value))}, method)
    return BAD if scale is None else list(scale)


def _design(label: str, value, method: str) -> tuple[dict | object, list]:
    """``design`` checked against ``method`` (the protocol's own checks of its tables and
    across them): the checked object (``analysis`` and ``staircase`` with their
    defaults) and its problems."""
    d = _Under(label, ("design",))
    design = DESIGN.check(d, value, ())
    if design is BAD or d.problems:
        return design, d.problems
    guess = GUESS_RATES.get(method)
    if design["guess"] != guess:
        d.report(("guess",), f"expected {'null' if guess is None else guess} (method "
                             f"{method}'s guess rate), got {kind(design['guess'])}")
    analysis = d.table(_nulls_unset(design["analysis"], ANALYSIS), ("analysis",), ANALYSIS)
    check_method_fits(d, method, None, analysis)
    design["analysis"] = analysis
    design["target"] = _target(d, design["target"], method, analysis)
    given = design["staircase"]
    staircase = check_staircase(d, {} if given is None else
                           {"staircase": _nulls_unset(given, STAIRCASE)}, method)
    design["staircase"] = asdict(staircase) if staircase not in (None, BAD) else staircase
    design["scale"] = _rating_scale(d, design.get("scale"), method)
    return design, d.problems


def check_info(info: dict, label: str) -> dict:
    """session.json's object ``info`` (of the file ``label``) checked (see the module
    docstring): a copy with ``design``'s ``analysis`` and ``staircase`` as the protocol
    reads them (defaults filled in). InputError: the first problem, one line."""
    r = Reader(label, None)
    checked = INFO.check(r, info, ())
    problems = list(r.problems)
    if "design" in info and checked["method"] is not BAD:
        checked["design"], found = _design(label, info["design"], checked["method"])
        problems += found
    if problems:
        more = len(problems) - 1
        raise InputError(str(problems[0]) + (f" (and {more} more problem{'s' * (more > 1)})"
                                             if more else ""))
    return checked
