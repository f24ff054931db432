"""The API's arguments checked as the command line checks its options: a bad value is one
:class:`~frictex.device.errors.InputError` line naming the argument, never a numpy or
type error from deep inside. The bounds are the command line's own (``app.engine.limits``,
``app.commands.trace.LIMITS``), read from there, not restated."""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Iterable

import numpy as np

from frictex.device.errors import InputError


def real(name: str, value: object, unit: str, bounds: tuple[float, float] | None = None, *,
         positive: bool = False) -> float:
    """``value`` as a finite float within ``bounds`` (inclusive; above the lower one when
    ``positive``), else an InputError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"{name}={_shown(value)}: expected a number{_unit(unit)}")
    try:
        number = float(value)
    except OverflowError:  # an int beyond float's range
        number = math.inf if value > 0 else -math.inf
    low, high = bounds if bounds is not None else (0.0 if positive else -math.inf, math.inf)
    if not (math.isfinite(number) and low <= number <= high and (number > 0 or not positive)):
        span = _span(low, high, unit, positive)
        if number == math.inf and math.isinf(high) and not span.startswith("a finite"):
            span = f"a finite number {span}"  # inf is "more than 0": say why it is refused
        raise InputError(f"{name}={number!r}: expected {span}")
    return number


def whole(name: str, value: object, unit: str, bounds: tuple[float, float]) -> int:
    """``value`` as an int (a Python or numpy integer, not a float) within ``bounds``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InputError(f"{name}={_shown(value)}: expected a whole number{_unit(unit)}")
    number = int(value)
    if not bounds[0] <= number <= bounds[1]:
        raise InputError(f"{name}={number}: expected {_span(*bounds, unit, False)}")
    return number


def choice(name: str, value: object, choices: Iterable[str], *, none: bool = False) -> str | None:
    """``value`` if it is one of ``choices`` (or None where ``none``)."""
    choices = tuple(choices)
    if (value is None and none) or (isinstance(value, str) and value in choices):
        return value
    raise InputError(f"{name}={_shown(value)}: expected one of {', '.join(choices)}"
                     f"{' or None' if none else ''}")


def flag(name: str, value: object) -> bool:
    """``value`` if it is True or False (a numpy bool too): ``strict="no"`` is an
    InputError, not a true string."""
    if not isinstance(value, bool | np.bool_):
        raise InputError(f"{name}={_shown(value)}: expected True or False")
    return bool(value)


def path_like(name: str, value: object, what: str) -> None:
    """An InputError unless ``value`` is a str or a path (``what`` says what it names),
    and not an empty one: ``Path("")`` would be the current folder, named ``.`` in the
    error that followed."""
    if not isinstance(value, str | os.PathLike):
        raise InputError(f"{name}={_shown(value)}: expected {what}")
    if not os.fspath(value):
        raise InputError(f"{name}='': the name is empty; expected {what}")


def _span(low: float, high: float, unit: str, positive: bool) -> str:
    if positive and low <= 0:
        start = "more than 0"
        return f"{start}{_unit(unit)}" if math.isinf(high) else f"{start} and at most {high:g} {unit}"
    if math.isinf(high):
        return f"at least {low:g} {unit}".strip() if not math.isinf(low) else "a finite number"
    return f"{low:g} to {high:g} {unit}".strip()


def _unit(unit: str) -> str:
    return f" ({unit})" if unit else ""


def _shown(value: object) -> str:
    """A value in an error: its repr where short and plain, else its type."""
    if isinstance(value, str | bytes | int | float | None):
        text = repr(value)
        if len(text) <= 40 and text.isprintable():
            return text
    return f"<{type(value).__name__}>"
