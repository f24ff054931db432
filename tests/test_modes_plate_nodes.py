"""modes plate --plot with the first finger on a node of both modes: det Phi (seed 001,
eq 8) is 0 for every second finger; the plot says so and a warning too."""

import matplotlib
import pytest

from frictex.app.commands import modes_plate
from frictex.app.commands.cli import main

PLATE = ["modes", "plate", "--youngs-gpa", "69", "--density", "2700"]


@pytest.fixture
def figures(monkeypatch):
    """The figures the command would write, kept instead."""
    kept = []
    monkeypatch.setattr(modes_plate, "save_figure", lambda fig, path: kept.append(fig))
    yield kept
    matplotlib.pyplot.close("all")


def panel_texts(fig):
    return [t.get_text() for t in fig.axes[2].texts]


# (0, 0) is a corner; (16.47, 16.47) mm the first interior node of both order-8 modes
@pytest.mark.parametrize("finger", [("0", "0"), ("16.470588235294116", "16.470588235294116")])
def test_a_finger_on_a_node_of_both_modes_is_annotated_and_warned(capsys, tmp_path, figures, finger):
    assert main([*PLATE, "--finger", *finger, "--plot", str(tmp_path / "p0.png")]) == 0
    err = capsys.readouterr().err
    assert "frictex: warning: --finger" in err and "on a node of both modes" in err
    assert panel_texts(figures[0]) == ["det Phi = 0 everywhere:\nfinger 1 is on a node\nof both modes"]


def test_a_finger_off_the_nodes_is_neither(capsys, tmp_path, figures):
    assert main([*PLATE, "--finger", "20", "70", "--plot", str(tmp_path / "p.png")]) == 0
    assert "warning" not in capsys.readouterr().err
    assert panel_texts(figures[0]) == []
