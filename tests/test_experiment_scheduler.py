"""The scheduler: counterbalanced, seeded trial lists; the staircase rules; a session
rebuilt from its recorded answers is the same session."""

from collections import Counter

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.app.experiment.protocol import Staircase, load_protocol
from frictex.app.experiment.scheduler import (Scheduler, StaircaseState, staircase_step,
                                              staircase_threshold)
from frictex.device.errors import InputError

HEAD = 'format = 1\nmethod = "{method}"\nrepetitions = {reps}\npractice = {practice}\nbreak_every = {breaks}\n'
PARAMETRIC = '[stimuli]\nscene = "grating-5mm"\nvary = "depth"\nreference = 0.3\n'


def protocol(tmp_path, method="2afc", reps=3, practice=0, breaks=0, extra=""):
    text = HEAD.format(method=method, reps=reps, practice=practice, breaks=breaks) + PARAMETRIC
    if method == "staircase":
        text += extra or "[staircase]\nstart = 0.2\nsteps = [0.2, 0.1]\nreversals = 6\nthreshold_reversals = 4\nmax = 0.6\n"
    elif method == "magnitude":
        text += "levels = [0.4, 0.5]\n" + extra
    else:
        text += "levels = [0.33, 0.36, 0.4]\n" + extra
    path = tmp_path / f"{method}.toml"
    path.write_text(text, encoding="utf-8")
    return load_protocol(path)


def run(scheduler, answer):
    """Every trial and response of a session whose responses come from ``answer(trial)``."""
    state, out = scheduler.initial_state(), []
    while (trial := scheduler.next_trial(state)) is not None:
        response = answer(trial)
        out.append((trial, response))
        state = scheduler.answer(state, trial, response)
    return out, state


def test_2afc_shows_each_level_in_each_order_equally(tmp_path):
    p = protocol(tmp_path, reps=3)
    trials, _ = run(Scheduler(p, 5), lambda t: "1")
    assert len(trials) == 3 * 2 * 3
    counts = Counter((t.value, t.answer) for t, _ in trials)
    assert set(counts.values()) == {3} and len(counts) == 6
    for t, _ in trials:  # the comparison is in the interval the answer names
        assert t.stimuli[int(t.answer) - 1] == f"depth={t.value:.10g}"
        assert t.stimuli[2 - int(t.answer)] == "depth=0.3"
        assert t.difference == pytest.approx(t.value - 0.3, abs=1e-15)


def test_order_follows_the_seed(tmp_path):
    p = protocol(tmp_path, reps=4)
    order = lambda seed: [t.stimuli for t, _ in run(Scheduler(p, seed), lambda t: "1")[0]]
    assert order(11) == order(11)
    assert order(11) != order(12)
    assert sorted(order(11)) == sorted(order(12))


def test_same_different_pairs(tmp_path):
    p = protocol(tmp_path, method="same-different", reps=2)
    trials, _ = run(Scheduler(p, 1), lambda t: "same")
    per_level = Counter((t.value, t.stimuli[0] == t.stimuli[1], t.answer) for t, _ in trials)
    for value in (0.33, 0.36, 0.4):
        assert per_level[(value, False, "different")] == 4   # AB and BA, twice each
        assert per_level[(value, True, "same")] == 4         # AA and BB, twice each
    assert Counter(t.stimuli for t, _ in trials)[("depth=0.3", "depth=0.3")] == 6


def test_magnitude_rates_each_stimulus_on_the_scale(tmp_path):
    p = protocol(tmp_path, method="magnitude", reps=2, extra="\n[scale]\nmin = 0\nmax = 4\n")
    trials, _ = run(Scheduler(p, 1), lambda t: "3")
    assert Counter(t.stimuli for t, _ in trials) == {("depth=0.3",): 2, ("depth=0.4",): 2,
                                                     ("depth=0.5",): 2}
    assert trials[0][0].responses == ("0", "1", "2", "3", "4") and trials[0][0].answer is None
    with pytest.raises(InputError, match="response '5' is not one of"):
        Scheduler(p, 1).answer(Scheduler(p, 1).initial_state(), trials[0][0], "5")


def test_practice_first_then_breaks(tmp_path):
    p = protocol(tmp_path, reps=3, practice=2, breaks=5)
    trials, _ = run(Scheduler(p, 3), lambda t: "2")
    assert [t.practice for t, _ in trials[:3]] == [True, True, False]
    assert all(t.value == 0.4 for t, _ in trials[:2])  # practice: the easiest comparison
    breaks = [t.number for t, _ in trials if t.break_before]
    assert breaks == [3, 8, 13, 18]  # the first main trial, then every 5 main trials


def test_one_up_two_down_rules(tmp_path):
    p = protocol(tmp_path, method="staircase")
    sc = p.staircase
    st0 = StaircaseState(0.2)
    one = staircase_step(sc, st0, True)
    assert one.difference == 0.2 and one.run == 1
    down = staircase_step(sc, one, True)
    assert down.difference == pytest.approx(0.2 / 10 ** 0.2) and down.direction == -1
    up = staircase_step(sc, down, False)  # a reversal: the step after it is the second
    assert up.reversals == (down.difference,)
    assert up.difference == pytest.approx(down.difference * 10 ** 0.1)
    assert staircase_threshold((1.0, 4.0, 2.0), 2, "log") == pytest.approx(np.sqrt(8.0))
    assert staircase_threshold((1.0, 4.0, 2.0), 2, "linear") == 3.0
    assert staircase_threshold((1.0,), 2, "log") is None


def test_one_up_three_down_and_linear_steps(tmp_path):
    p = protocol(tmp_path, method="staircase", extra="[staircase]\nrule = \"1-up-3-down\"\n"
                 "start = 0.2\nsteps = [0.05]\nscale = \"linear\"\nmin = 0.05\nmax = 0.6\n")
    sc, state = p.staircase, StaircaseState(0.2)
    for _ in range(2):
        state = staircase_step(sc, state, True)
    assert state.difference == 0.2
    state = staircase_step(sc, state, True)
    assert state.difference == pytest.approx(0.15)
    for _ in range(9):
        state = staircase_step(sc, state, True)
    assert state.difference == pytest.approx(0.05)  # held at min


def test_a_step_of_a_million_decades_goes_to_min_and_max():
    """10^(1e6 x the index) overflowed (OverflowError: an internal error on the third
    trial) though min and max bound what is presented."""
    sc = Staircase("1-up-2-down", 0.12, (1e6,), "log", 14, 120, 10, 0.003, 0.6)
    up = staircase_step(sc, StaircaseState(0.12), False)
    assert up.difference == 0.6
    state = up
    for expected in (0.12, 0.003):  # a step down from max lands on the grid: the start
        state = staircase_step(sc, staircase_step(sc, state, True), True)
        assert state.difference == expected
    assert staircase_step(sc, state, False).difference == 0.12


def test_a_grid_unit_below_the_floats_resolution_finds_the_bound():
    """Steps of 2.2345678901234567e-16 and 1.2345678901234567e-16 decades (17 digits
    each) each move 0.12, but their grid unit is 1e-32 decades, far below float64's
    resolution there: the walk of one unit at a time that corrected the bound's
    closed-form index never ended."""
    step = 2.2345678901234567e-16
    sc = Staircase("1-up-2-down", 0.12, (step, 1.2345678901234567e-16), "log", 14, 120, 10,
                   0.119999999999999, 0.120000000000001)
    up = staircase_step(sc, StaircaseState(0.12), False)
    assert up.difference == 0.12 * 10 ** step  # one step up: below max
    state = StaircaseState(0.12)
    for _ in range(200):  # down past min (some 16 steps): held there
        state = staircase_step(sc, state, True)
    assert state.difference == 0.119999999999999
    assert 0.119999999999999 < staircase_step(sc, state, False).difference < 0.12


@pytest.mark.parametrize("steps, scale", [("[1e-300]", "log"), ("[0.2, 1e-17]", "log"),
                                          ("[1e-18]", "linear")])
def test_steps_that_leave_the_start_where_it_is_are_refused(tmp_path, steps, scale):
    with pytest.raises(InputError, match="leaves the start .* where it is in float64"):
        protocol(tmp_path, method="staircase", extra=f"[staircase]\nstart = 0.2\nsteps = "
                 f"{steps}\nscale = \"{scale}\"\nmin = 0.05\nmax = 0.6\n")


def test_staircase_stops_after_its_reversals_and_counterbalances(tmp_path):
    p = protocol(tmp_path, method="staircase")
    rng = np.random.default_rng(0)
    trials, state = run(Scheduler(p, 9), lambda t: t.answer if rng.random() < 0.8 else
                        ("1" if t.answer == "2" else "2"))
    assert len(state.staircase.reversals) == 6
    firsts = [t.answer for t, _ in trials]
    for i in range(0, len(firsts) - 1, 2):  # one comparison-first, one second, per pair
        assert sorted(firsts[i:i + 2]) == ["1", "2"]


@settings(max_examples=40, deadline=None, derandomize=True)
@given(method=st.sampled_from(["2afc", "staircase", "same-different"]),
       seed=st.integers(0, 2**63 - 1), answers=st.lists(st.booleans(), min_size=1, max_size=60),
       cut=st.integers(0, 60))
def test_a_resumed_session_is_the_same_session(tmp_path_factory, method, seed, answers, cut):
    """Replaying the first rows (what --resume does) and going on gives the trials and
    the state of a session never interrupted."""
    p = protocol(tmp_path_factory.mktemp("p"), method=method, reps=2, practice=1)
    scheduler = Scheduler(p, seed)
    pick = lambda t: t.responses[answers[t.number % len(answers)]]
    whole, final = run(scheduler, pick)
    cut = min(cut, len(whole))
    state = scheduler.replay((t.stimuli, r) for t, r in whole[:cut])
    rest = []
    while (trial := scheduler.next_trial(state)) is not None:
        rest.append(trial)
        state = scheduler.answer(state, trial, pick(trial))
    assert [t for t, _ in whole[cut:]] == rest
    assert state == final


def test_replaying_another_sessions_rows_is_refused(tmp_path):
    p = protocol(tmp_path, reps=3)
    trials, _ = run(Scheduler(p, 1), lambda t: "1")
    rows = [(t.stimuli, r) for t, r in trials]
    other = [(t.stimuli, r) for t, r in run(Scheduler(p, 2), lambda t: "1")[0]]
    mismatch = next(i for i, (a, b) in enumerate(zip(rows, other)) if a[0] != b[0])
    with pytest.raises(InputError, match=f"trial {mismatch + 1}: recorded"):
        Scheduler(p, 1).replay(other)
    with pytest.raises(InputError, match="after the end of the session"):
        Scheduler(p, 1).replay(rows + rows[:1])
