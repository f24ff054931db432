"""The window's key names: a typed rating (an experiment's 0-100 scale) is corrected
with Backspace and signed with minus, which the window did not pass on."""

import pytest

from frictex.rendering.visual.context import _key_names


def test_backspace_and_minus_reach_the_window_s_readers():
    glfw = pytest.importorskip("glfw", reason="glfw (Python package) not installed")
    names = _key_names(glfw)
    assert names[glfw.KEY_BACKSPACE] == "backspace"
    assert names[glfw.KEY_MINUS] == names[glfw.KEY_KP_SUBTRACT] == "minus"
    assert names[glfw.KEY_KP_7] == "7" and names[glfw.KEY_ENTER] == "enter"
