"""One measured figure of ``frictex bench``."""

from __future__ import annotations

from dataclasses import dataclass, replace


@dataclass(frozen=True)
class Figure:
    """One measured figure: what, how much, in which unit, and how many of the runs (or
    rounds) behind it failed and are left out of it (the label says so too:
    ``processes.failed_note``; the bench exits 1 where any did)."""

    section: str
    label: str
    value: float
    unit: str
    failed: int = 0

    def of_failed(self, failed: int) -> "Figure":
        """This figure, ``failed`` of its runs (or rounds) left out."""
        return replace(self, failed=failed)
