"""results.csv's columns are documented with their units (PROTOCOL_FORMAT.md), and a
session records the unit of the parameter it varies (session.json's design.vary_unit)."""

import json
from pathlib import Path

import pytest

from frictex.app import experiment
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
