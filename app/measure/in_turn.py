"""Steps timed in this process in alternated rounds: one of each per round, the order
reversed every other round (A B, B A, ...), as ``processes.alternated`` runs commands,
so that neither step always runs after the other and a change in the machine's load
falls on every step alike."""

from __future__ import annotations

import time

import numpy as np


def timed_in_turn(steps: list[tuple], rounds: int,
                  warmup: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each ``(step, before)`` of ``steps`` run ``rounds`` times in alternated rounds
    (``before()``, untimed, just before its step; ``before`` may be None), after
    ``warmup`` untimed rounds (what a step does once, such as an import or a cache
    filled, then falls outside the times): per step its wall time and its CPU time of
    all this process's threads in each round, both s, in round order."""
    wall = np.zeros((len(steps), rounds))
    cpu = np.zeros((len(steps), rounds))
    order = list(range(len(steps)))
    for _ in range(warmup):
        for step, before in steps:
            if before is not None:
                before()
            step()
    for r in range(rounds):
        for k in (order if r % 2 == 0 else order[::-1]):
            step, before = steps[k]
            if before is not None:
                before()
            cpu0, t0 = time.process_time(), time.perf_counter()
            step()
            wall[k, r] = time.perf_counter() - t0
            cpu[k, r] = time.process_time() - cpu0
    return list(zip(wall, cpu))
