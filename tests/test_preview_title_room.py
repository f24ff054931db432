"""The friction map's title stays whole: no line of it runs under the colour bar beside
the panel or off the figure."""

import pytest

from frictex.app.commands.preview import preview_figure
from frictex.textures.format_doc import example_files
from frictex.textures.loader import load_scene
from test_preview_fingers import FINGER_LAYERS


def map_title_flaws(fig) -> list[str]:
    """Where the friction map's title (the second panel's) meets another axes or leaves
    the figure, as words."""
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    panel = fig.axes[1]
    box = panel.title.get_window_extent(renderer)
    width, height = fig.canvas.get_width_height()
    flaws = [] if 0 <= box.x0 and box.x1 <= width and 0 <= box.y0 and box.y1 <= height \
        else ["leaves the figure"]
    for ax in fig.axes:
        other = ax.get_window_extent(renderer)
        if ax is not panel and box.overlaps(other):
            flaws.append(f"meets the axes at x {other.x0:.0f} to {other.x1:.0f} px")
    return flaws


@pytest.mark.parametrize("text", [example_files()["plank-first"], FINGER_LAYERS],
                         ids=["plank-below-the-floor", "layers-left-out"])
def test_the_map_title_is_clear_of_the_colour_bar(tmp_path, text):
    """The walk-through's first plank at the CLI's size: '...; hatched: below the floor
    (13...' ran under the colour bar, its share unreadable."""
    path = tmp_path / "scene.toml"
    path.write_text(text, encoding="utf-8")
    fig, info = preview_figure(load_scene(path))
    assert map_title_flaws(fig) == []
    title = fig.axes[1].get_title().replace("\n", " ")
    if info["below"]:
        assert f"hatched: below the floor ({info['below']:.1%} of the display)" in title
    else:
        assert 'left out of the map: sheet (fingers = "2": only with 2 or more fingers down)' \
            in title
