"""One measured figure of ``frictex bench``."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Figure:
    """One measured figure: what, how much, in which unit."""

    section: str
    label: str
    value: float
    unit: str
