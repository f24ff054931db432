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
from frictex.app.experiment.scheduler import StaircaseState, staircase_level, staircase_step
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


@pytest.mark.parametrize("scale, steps", [("log", (0.2, 0.1)), ("linear", (0.02, 0.01))])
def test_a_level_reached_by_two_paths_is_bit_identical(scale, steps):
    """Down a first step, then up and down the second: back on the first level."""
    sc = Staircase("1-up-2-down", 0.12, steps, scale, 14, 200, 8, None, None)
    state = StaircaseState(sc.start)
    states = []
    for correct in (True, True, False, True, True, False, True, True, False, True, True):
        state = staircase_step(sc, state, correct)
        states.append(state)
    by_index = {}
    for st in states:
        by_index.setdefault(st.index, set()).add(st.difference)
    revisited = [i for i in by_index if sum(s.index == i for s in states if s.run == 0) > 1]
    assert revisited
    assert all(len(by_index[i]) == 1 for i in by_index)
    assert staircase_level(sc, -2) == states[1].difference


def test_a_step_past_a_bound_stops_there_and_steps_back_onto_the_grid():
    sc = Staircase("1-up-2-down", 0.12, (0.2,), "log", 14, 200, 8, None, 0.15)
    up = staircase_step(sc, StaircaseState(sc.start), False)
    assert (up.difference, up.index) == (0.15, 1)
    held = staircase_step(sc, up, False)
    assert (held.difference, held.index) == (0.15, 1)
    down = staircase_step(sc, staircase_step(sc, held, True), True)
    assert (down.difference, down.index) == (0.12, 0)
