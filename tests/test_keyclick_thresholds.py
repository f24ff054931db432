"""A key-click's thresholds out of order (release_n < press_n < click_n) are reported at
the line of the key that breaks the order, not always at press_n's."""

import re

import pytest

from frictex.textures.format_examples import EXAMPLES
from frictex.textures.loader import check_scene

#: FORMAT.md's key-click example without its thresholds (each test writes its own)
SCENE = "".join(line for line in EXAMPLES["keyclick"].splitlines(keepends=True)
                if line.split(" = ")[0] not in ("press_n", "click_n", "release_n"))


def blamed_keys(tmp_path, thresholds: dict) -> list[str]:
    """The keys on the lines the problems name, in order."""
    text = SCENE + "".join(f"{k} = {v}\n" for k, v in thresholds.items())
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    _, problems, _ = check_scene(path)
    lines = text.splitlines()
    out = []
    for p in map(str, problems):
        assert "out of order" in p, p
        number = int(re.match(rf"{re.escape(str(path))}:(\d+): ", p).group(1))
        out.append(lines[number - 1].split(" = ")[0])
    return out


@pytest.mark.parametrize("thresholds, keys", [
    ({"press_n": 0.5, "click_n": 0.8, "release_n": 0.9}, ["release_n"]),
    ({"press_n": 0.5, "click_n": 0.45}, ["press_n", "click_n"]),  # either can move
    ({"press_n": 0.5, "click_n": 0.3}, ["click_n"]),  # below release_n 0.4 too
    ({"press_n": 0.9}, ["press_n"]),  # release_n 0.4 < 0.9, click_n 0.8 by default: press_n
    ({"press_n": 0.3}, ["press_n"]),  # below the default release_n: the written key
    ({"press_n": 0.5, "click_n": 0.8, "release_n": 0.6}, ["press_n", "release_n"]),
    ({"press_n": 0.5, "click_n": 0.3, "release_n": 0.9}, ["press_n", "click_n", "release_n"]),
])
def test_an_out_of_order_threshold_is_reported_at_its_own_line(tmp_path, thresholds, keys):
    assert blamed_keys(tmp_path, thresholds) == keys


def test_thresholds_in_order_are_accepted(tmp_path):
    assert blamed_keys(tmp_path, {"press_n": 0.5, "click_n": 0.8, "release_n": 0.4}) == []
