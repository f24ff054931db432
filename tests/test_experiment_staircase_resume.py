"""A staircase session cut at any trial resumes to the table of the unbroken run: each
level is computed from an integer grid index, so a level revisited by another path is the
same float and finds the scene file it played (it was refused at the first revisit:
"this session played another scene under the name depth=0.3301426372")."""

import csv
import math
import re
import shutil
from pathlib import Path

import pytest

from frictex.app import experiment
from frictex.app.experiment.protocol import Staircase, load_protocol
from frictex.app.experiment.runner import make_presenter, run_session
from frictex.app.experiment.scheduler import StaircaseState, staircase_step
from frictex.app.experiment.stimuli import SAME_NUMBER_REL
from frictex.device.errors import InputError

PROTOCOLS = Path(experiment.__file__).parent / "protocols"

PARTICIPANT = "simulated:weber=0.11,lapse=0.02"
#: the columns a resumed run must reproduce (times and durations are measured anew)
SAME = ("trial", "practice", "stimuli", "value", "difference", "answer", "response", "correct")


def _run(out, resume=False):
    protocol = load_protocol(PROTOCOLS / "depth-staircase.toml")
    run_session(protocol, make_presenter(PARTICIPANT), out, seed=None if resume else 11,
                participant=PARTICIPANT, record="results", resume=resume)


def _table(out):
    with open(out / "results.csv", newline="", encoding="utf-8") as fh:
        return [tuple(row[c] for c in SAME) for row in csv.DictReader(fh)]


def _cut(source, target, rows):
    shutil.copytree(source, target)
    lines = (target / "results.csv").read_text().splitlines(keepends=True)
    (target / "results.csv").write_text("".join(lines[:rows + 1]))


@pytest.fixture(scope="module")
def unbroken(tmp_path_factory):
    out = tmp_path_factory.mktemp("stair") / "s"
    _run(out)
    return out


def test_the_seeded_staircase_revisits_levels(unbroken):
    values = [row[3] for row in _table(unbroken) if row[1] == "0"]
    assert len(set(values)) < len(values) / 2


@pytest.mark.parametrize("rows", [10, 15, 25, 35])
def test_a_cut_session_resumes_to_the_unbroken_table(unbroken, tmp_path, rows):
    _cut(unbroken, tmp_path / "k", rows)
    _run(tmp_path / "k", resume=True)
    assert _table(tmp_path / "k") == _table(unbroken)


def _mu_low(played):
    return float(re.search(r"^mu_low = (\S+)$", played.read_text(), re.M).group(1))


def _set_mu_low(played, value):
    played.write_text(re.sub(r"^mu_low = \S+$", f"mu_low = {value!r}", played.read_text(),
                             flags=re.M))


def test_a_played_file_from_a_path_dependent_level_is_played_again(unbroken, tmp_path):
    """A session written before the grid index holds numbers a last bit apart (mu_low
    0.669857362821885 against 0.6698573628218851): resumed, the played file kept."""
    _cut(unbroken, tmp_path / "old", 10)
    played = tmp_path / "old" / "stimuli" / "depth=0.3301426372.toml"
    _set_mu_low(played, math.nextafter(_mu_low(played), 0.0))
    kept = played.read_text()
    _run(tmp_path / "old", resume=True)
    assert _table(tmp_path / "old") == _table(unbroken)
    assert played.read_text() == kept


def test_a_played_file_with_another_value_is_still_refused(unbroken, tmp_path):
    _cut(unbroken, tmp_path / "other", 10)
    played = tmp_path / "other" / "stimuli" / "depth=0.3301426372.toml"
    _set_mu_low(played, _mu_low(played) * (1 + 100 * SAME_NUMBER_REL))
    with pytest.raises(InputError, match="played another scene under the name"):
        _run(tmp_path / "other", resume=True)


def _walk(sc, answers):
    state = StaircaseState(sc.start)
    for correct in answers:
        state = staircase_step(sc, state, correct)
    return state


@pytest.mark.parametrize("scale, steps", [("log", (0.2, 0.1)), ("linear", (0.02, 0.01))])
def test_a_level_reached_by_two_paths_is_bit_identical(scale, steps):
    """Two steps of 0.2 down, or 0.2 down, 0.1 up and three of 0.1 down: the same level,
    to the bit. Multiplying step by step gave 0.047772860466419674 and
    0.04777286046641968 on the log scale (a resumed session then refused its own
    stimulus file)."""
    sc = Staircase("1-up-2-down", 0.12, steps, scale, 14, 200, 8, None, None)
    straight = _walk(sc, [True] * 4)
    around = _walk(sc, [True, True, False] + [True] * 6)
    assert straight.index == around.index == -4
    assert straight.difference == around.difference
    big, small = steps
    expected = (0.12 * 10.0 ** -(2 * big) if scale == "log" else 0.12 - 2 * big)
    assert straight.difference == pytest.approx(expected, rel=1e-12)


def test_a_step_past_a_bound_stops_there_and_steps_back_onto_the_grid():
    sc = Staircase("1-up-2-down", 0.12, (0.2,), "log", 14, 200, 8, None, 0.15)
    up = staircase_step(sc, StaircaseState(sc.start), False)
    assert (up.difference, up.index) == (0.15, 1)
    held = staircase_step(sc, up, False)
    assert (held.difference, held.index) == (0.15, 1)
    down = staircase_step(sc, staircase_step(sc, held, True), True)
    assert (down.difference, down.index) == (0.12, 0)


def test_a_fine_grid_steps_onto_its_bound_by_the_closed_form():
    """Steps of 0.30103 and 0.1 make a grid of 1e-5: the step up to max lands on the
    first grid index at or past it (walking one unit at a time took 20 ms a step, and
    minutes at 1e-10)."""
    sc = Staircase("1-up-2-down", 0.1, (0.30103, 0.1), "log", 14, 200, 8, None, 0.15)
    up = staircase_step(sc, StaircaseState(sc.start), False)
    assert up.difference == 0.15
    assert up.index == math.ceil(math.log10(0.15 / 0.1) / 1e-5)  # 17610
    assert 0.1 * 10 ** ((up.index - 1) * 1e-5) < 0.15 <= 0.1 * 10 ** (up.index * 1e-5)


def test_the_linear_scale_stops_at_its_min_before_zero():
    """Start 0.5, steps of 0.4, min 0.05: down to 0.1, then to min (it was held at 0.1,
    the step to -0.3 taken as the floor at 0 though min lies above it)."""
    sc = Staircase("1-up-2-down", 0.5, (0.4,), "linear", 14, 200, 8, 0.05, None)
    once = _walk(sc, [True, True])
    assert once.difference == pytest.approx(0.1)
    assert _walk(sc, [True] * 4).difference == 0.05
