"""A log staircase without min, answered correctly, halves its difference on and on
(depth-staircase reached 1.9e-13 by trial 121, both stimuli named depth=0.3): --check
and a run warn of it; a min the names resolve is not warned of."""

import pytest

from frictex.app.commands.cli import main

PROTOCOL = """format = 1
method = "staircase"
[stimuli]
scene = "grating-5mm"
vary = "depth"
reference = 0.3
[presentation]
exploration_s = 0.3
[staircase]
rule = "1-up-2-down"
start = 0.12
steps = [0.2, 0.1]
scale = "log"
reversals = 6
threshold_reversals = 4
max_trials = 120
max = 0.6
{floor}
"""


@pytest.mark.parametrize("floor, warned", [("", True), ("min = 0.003", False)])
def test_check_warns_of_a_floor_the_names_cannot_show(tmp_path, capsys, floor, warned):
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL.format(floor=floor), encoding="utf-8")
    assert main(["experiment", str(path), "--check"]) == 0
    err = capsys.readouterr().err
    assert ("staircase.min: none, and within 120 trials the difference can fall to 1.2e-13, "
            "where the comparison is named as the reference (depth=0.3)" in err) is warned
    assert err.count("\n") == int(warned)
