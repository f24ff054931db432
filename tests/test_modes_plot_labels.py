"""modes plots say what they mark: the beam's travelling-wave thresholds and spans, and
the ring's degenerate L/R over the table's whole window."""

import matplotlib
import pytest

from frictex.app.commands import modes_beam, modes_ring
from frictex.app.commands.cli import main


@pytest.fixture
def figures(monkeypatch):
    """The figures the commands would write, kept instead."""
    kept = []
    for module in (modes_beam, modes_ring):
        monkeypatch.setattr(module, "save_figure", lambda fig, path: kept.append(fig))
    yield kept
    matplotlib.pyplot.close("all")


def legend_texts(ax):
    legend = ax.get_legend()
    return [] if legend is None else [t.get_text() for t in legend.get_texts()]


def test_the_travelling_plot_names_its_thresholds_and_spans(capsys, tmp_path, figures):
    # it shaded two green spans and drew dashed lines naming neither 0.68 nor 0.9
    assert main(["modes", "beam", "--travelling", "--plot", str(tmp_path / "b.png")]) == 0
    texts = legend_texts(figures[0].axes[1])
    for threshold in ("0.68", "0.9"):
        assert f"threshold {threshold}" in texts and f"ratio >= {threshold} (shaded)" in texts


def test_the_ring_plot_covers_every_crossing_the_table_lists(capsys, tmp_path, figures):
    # the table listed a crossing at L/R 1.9178 for order 2; the plot spanned 2.24-3.5
    assert main(["modes", "ring", "--orders", "2", "3", "--json", "--plot",
                 str(tmp_path / "r.png")]) == 0
    import json
    pairs = json.loads(capsys.readouterr().out)["pairs"]
    listed = [c for p in pairs for c in p["degenerate_l_over_r"]]
    assert listed and min(listed) < 2.0
    for ax, pair in zip(figures[0].axes, pairs):
        lo, hi = ax.get_xlim()
        for crossing in pair["degenerate_l_over_r"]:
            assert lo <= crossing <= hi
        if pair["degenerate_l_over_r"]:
            assert "degenerate (split 0)" in legend_texts(ax)
