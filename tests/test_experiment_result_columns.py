"""results.csv's columns are documented with their units (PROTOCOL_FORMAT.md), and a
session records the unit of the parameter it varies (session.json's design.vary_unit)."""

import json
import shutil
from pathlib import Path

import pytest

from frictex.app import experiment
from frictex.app.commands.cli import main
from frictex.app.experiment import protocol_doc
from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.session import RESULT_COLUMNS, create

PROTOCOLS = Path(experiment.__file__).parent / "protocols"
PARTICIPANT = "simulated:weber=0.11,seed=3"


def test_every_results_column_is_described_in_order():
    assert tuple(protocol_doc.RESULT_COLUMNS) == RESULT_COLUMNS
    page = (Path(experiment.__file__).parent / "PROTOCOL_FORMAT.md").read_text()
    for name in RESULT_COLUMNS:
        assert f"| `{name}` |" in page
    assert "`period_mm`: mm" in page and "`depth`: unitless" in page


@pytest.mark.parametrize("name, unit", [("period-2afc", "mm"), ("depth-staircase", "unitless")])
def test_session_json_keeps_the_unit_of_the_varied_parameter(tmp_path, name, unit):
    protocol = load_protocol(PROTOCOLS / f"{name}.toml")
    out = tmp_path / "s"
    create(out, protocol, 1, PARTICIPANT)
    design = json.loads((out / "session.json").read_text())["design"]
    assert design["vary_unit"].split(" ")[0] == unit


TWO_AFC = """format = 1
name = "depth-2afc"
method = "2afc"
repetitions = 2
[stimuli]
scene = "grating-5mm"
vary = "depth"
reference = 0.3
levels = [0.32, 0.36, 0.42]
[presentation]
exploration_s = 0.3
[analysis]
bootstrap = 200
"""


@pytest.fixture(scope="module")
def session_2afc(tmp_path_factory):
    root = tmp_path_factory.mktemp("afc")
    (root / "afc.toml").write_text(TWO_AFC)
    assert main(["experiment", str(root / "afc.toml"), "--participant", PARTICIPANT, "--out",
                 str(root / "s"), "--seed", "4", "--record", "results", "--quiet"]) == 0
    return root / "s"


def _edit_row(folder, line, **values):
    """Set columns of line ``line`` (1: the header) of ``folder``'s results.csv."""
    table = folder / "results.csv"
    lines = table.read_text().splitlines(keepends=True)
    header = lines[0].rstrip("\n").split(",")
    cells = lines[line - 1].rstrip("\n").split(",")
    for name, value in values.items():
        cells[header.index(name)] = value
    lines[line - 1] = ",".join(cells) + "\n"
    table.write_text("".join(lines))


def _analyse(folder, tmp_path, capsys):
    capsys.readouterr()
    assert main(["experiment", "analyse", str(folder), "--out", str(tmp_path / "a")]) == 0
    return capsys.readouterr().out


def test_a_consistent_table_is_not_warned_of(session_2afc, tmp_path, capsys):
    assert "results.csv:" not in _analyse(session_2afc, tmp_path, capsys)


def test_a_response_outside_the_trials_responses_is_warned_of(session_2afc, tmp_path,
                                                                 capsys):
    edited = tmp_path / "s"
    shutil.copytree(session_2afc, edited)
    _edit_row(edited, 4, response="7", correct="1")
    printed = _analyse(edited, tmp_path, capsys)
    assert (f"warning: {edited / 'results.csv'}:4: response '7' is not one of 1, 2; counted "
            f"as written") in printed


def test_a_correct_that_is_not_response_equals_answer_is_warned_of(session_2afc, tmp_path,
                                                                    capsys):
    edited = tmp_path / "s"
    shutil.copytree(session_2afc, edited)
    rows = (edited / "results.csv").read_text().splitlines()
    header = rows[0].split(",")
    cells = rows[5].split(",")
    answer = cells[header.index("answer")]
    wrong = "2" if answer == "1" else "1"
    _edit_row(edited, 6, response=wrong, correct="1")
    printed = [line for line in _analyse(edited, tmp_path, capsys).splitlines()
               if "results.csv:" in line]
    assert printed == [f"  warning: {edited / 'results.csv'}:6: correct is '1', but response "
                       f"'{wrong}' against answer '{answer}' makes it '0'; counted as written"]
