"""``app.measure.figure_check``: texts that overlap or leave the canvas are found, and the
closed-loop plot's title fits however few scenes it has."""

import pytest

from frictex.app.measure.figure_check import text_flaws
from frictex.app.measure.report_output import pyplot


@pytest.fixture
def plt():
    plt = pyplot()
    yield plt
    plt.close("all")


def test_a_legible_figure_has_no_flaws(plt):
    fig, ax = plt.subplots(figsize=(4, 3), constrained_layout=True)
    ax.plot([1, 2, 3], [3, 1, 2], label="a line")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title("a title")
    ax.legend()
    assert text_flaws(fig) == []


def test_overlapping_texts_are_found(plt):
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.annotate("first label", (0.5, 0.5))
    ax.annotate("second label", (0.5, 0.5), xytext=(4, 2), textcoords="offset points")
    flaws = text_flaws(fig)
    assert [(f.kind, f.text, f.other) for f in flaws] == [
        ("overlap", "first label", "second label")]
    assert str(flaws[0]) == "'first label' overlaps 'second label'"


def test_a_text_off_the_canvas_is_found(plt):
    fig = plt.figure(figsize=(3, 2))
    fig.suptitle("a title far too long for a figure three inches wide, cut at both ends")
    fig.text(0.5, 1.02, "above")
    found = {(f.kind, f.text) for f in text_flaws(fig)}
    assert found == {("clipped", "a title far too long for a figure three inches wide, "
                                 "cut at both ends"), ("clipped", "above")}


def test_unused_tick_labels_are_not_counted(plt):
    """An axis keeps tick labels it does not draw (outside the view) for reuse: only
    the drawn ones count."""
    fig, ax = plt.subplots(figsize=(4, 3), constrained_layout=True)
    ax.plot([0, 100], [0, 1])
    fig.draw_without_rendering()
    ax.set_xlim(0, 1)  # the ticks at 20..100 go out of view, their labels stay
    assert text_flaws(fig) == []
