"""What a presenter is: the interface between the runner and whoever shows the trials.

A :class:`Presenter` shows a trial's stimuli (:class:`Shown`, one per interval) and
returns the participant's answer (:class:`Presentation`). The simulated participant
(``observer``) is one; the demo window's is another. The runner
(``runner.run_session``) owns everything else.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence

from frictex.app.experiment.protocol import Protocol as ExperimentProtocol
from frictex.app.experiment.scheduler import Trial
from frictex.textures.model import Scene


@dataclass(frozen=True)
class Shown:
    """One interval of a trial as the presenter shows it.

    name : the stimulus (side by side: the pair, ``LEFT+RIGHT``).
    scene : the scene to play; text : its texture file's text (what the session records).
    area : (x, y, width, height) mm of the display the participant explores.
    seconds : exploration time (s): fixed, or the most allowed when ``free``.
    """

    name: str
    scene: Scene
    text: str
    area: tuple[float, float, float, float]
    seconds: float
    free: bool


@dataclass(frozen=True)
class Presentation:
    """What a presenter returns: the ``response`` (one of the trial's), the response
    time ``rt_s`` (s, from the end of the trial's last interval to the answer: the
    exploration's own length is not in it) and one touch trace per interval."""

    response: str
    rt_s: float
    traces: tuple


class Presenter(Protocol):
    """Shows trials to a participant (the simulated one, or the demo window)."""

    def begin(self, protocol: ExperimentProtocol) -> None:
        """Called once before the first trial (instructions)."""

    def rest(self, trial: Trial) -> None:
        """A break is due before ``trial``; return when the participant is ready."""

    def present(self, trial: Trial, shown: Sequence[Shown]) -> Presentation:
        """Show ``shown`` (one per interval, in order) and return the answer."""
