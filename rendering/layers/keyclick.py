"""The key-click button of seed 004 (Fig. 5) as a state machine on the finger's normal force.

Seed 004 turns the travelling wave on (pushing one way) when the normal force reaches
0.5 N and reverses its phase when it reaches 0.8 N; lifting the finger ends the click.
Per finger and button, with F_n the normal force (N) and "inside" meaning touching the
button::

    idle (0) --[inside, F_n >= press_n]--> on (1) --[inside, F_n >= click_n]--> clicked (2)
    on, clicked --[outside or F_n < release_n]--> idle

Against force noise: release_n < press_n is a hysteresis band (a press ends only below
where it began); clicked can only be left by a release, so the phase flips at most once
per press; and each condition must hold for ``dwell`` consecutive output samples before
it acts. A touch sample's force holds until the next, so a single noisy sample does not
count only where the dwell is longer than the touch screen's sample period (the bundled
scenes: 15 ms against 100 Hz's 10 ms). The band stops on/idle flicker only where the
sensor's noise is well under its half-width: a finger held at 0.45 N, inside the bundled
scenes' 0.4-0.5 N band, with noise of 0.05 N standard deviation at 100 Hz turned the wave
on and off 40 times in 30 s (at 0.03 N, once).

Vectorised over a block: each condition's run length (consecutive samples it has held,
carried between blocks) comes from a cumulative maximum of the indices where it failed;
"pressed" and "clicked" are then set/reset flip-flops, forward-filled from their last
event the same way. The state carried is a few integers per finger, so any split of a
trace into blocks gives the same states.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

IDLE, ON, CLICKED = 0, 1, 2


@dataclass(frozen=True)
class ButtonState:
    """One finger on one button between blocks: flip-flops and run lengths (samples)."""

    pressed: bool = False
    clicked: bool = False
    runs: tuple[int, int, int] = (0, 0, 0)  # press, click, release conditions


def _runs(condition: np.ndarray, carried: int) -> np.ndarray:
    """Consecutive samples (n,) that ``condition`` has held up to each sample, inclusive."""
    idx = np.arange(condition.size)
    last_fail = np.maximum.accumulate(np.where(condition, -1, idx))
    return np.where(last_fail >= 0, idx - last_fail, idx + 1 + carried)


def _flip_flop(set_: np.ndarray, reset: np.ndarray, initial: bool) -> np.ndarray:
    """bool (n,): True from each set event, False from each reset event (never both at once)."""
    event = np.where(set_, 1, np.where(reset, 0, -1))
    idx = np.where(event >= 0, np.arange(event.size), -1)
    last = np.maximum.accumulate(idx)
    return np.where(last >= 0, event[np.maximum(last, 0)] == 1, initial)


def button_states(force_n: np.ndarray, inside: np.ndarray, press_n: float, click_n: float,
                  release_n: float, dwell: int, state: ButtonState | None = None
                  ) -> tuple[np.ndarray, np.ndarray, ButtonState]:
    """States (0 idle, 1 on, 2 clicked) of one finger on one button over a block.

    Parameters
    ----------
    force_n : (n,) normal force (N); NaN counts as no press.
    inside : (n,) bool, the finger touches the button.
    press_n, click_n, release_n : thresholds (N), release_n < press_n < click_n.
    dwell : samples each condition must hold before it acts (>= 1).
    state : from the previous block (default: idle).

    Returns
    -------
    states : int8 (n,). clicks : bool (n,), an idle/on -> clicked transition at the sample.
    new_state : to pass to the next block.
    """
    state = state or ButtonState()
    f = np.asarray(force_n, dtype=np.float64)
    inside = np.asarray(inside, dtype=bool)
    with np.errstate(invalid="ignore"):
        press = inside & (f >= press_n)
        click = inside & (f >= click_n)
        release = ~inside | ~(f >= release_n)
    runs = [_runs(c, r) for c, r in zip((press, click, release), state.runs)]
    held = [r >= dwell for r in runs]
    pressed = _flip_flop(held[0], held[2], state.pressed)
    clicked = _flip_flop(held[1], held[2], state.clicked)
    states = np.where(clicked, CLICKED, np.where(pressed, ON, IDLE)).astype(np.int8)
    rising = np.diff(np.concatenate(([state.clicked], clicked)).astype(np.int8)) > 0
    if f.size == 0:
        return states, rising, state
    new = ButtonState(bool(pressed[-1]), bool(clicked[-1]),
                      tuple(int(min(r[-1], dwell)) for r in runs))
    return states, rising, new
