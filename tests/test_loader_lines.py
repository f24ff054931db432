"""Problems about the [[layer]] array as a whole name the line of the header at fault."""

from frictex.textures.keys import MAX_LAYERS
from frictex.textures.loader import check_scene

HEAD = ("format = 1\n[display]\nwidth_mm = 108.0\nheight_mm = 64.8\nwidth_px = 800\n"
        "height_px = 480\n")
DISC = '[[layer]]\ntype = "disc"\ncx_mm = 10\ncy_mm = 10\nradius_mm = 3\nmu = 0.9\n'


def only_problem(tmp_path, text: str):
    path = tmp_path / "scene.toml"
    path.write_text(text, encoding="utf-8")
    scene, problems, _ = check_scene(path)
    assert scene is None and len(problems) == 1, problems
    return problems[0]


def test_a_layer_sub_table_before_any_layer_names_its_header_line(tmp_path):
    """'[layer.visual]' on line 2, no [[layer]]: the problem had no line."""
    problem = only_problem(tmp_path, 'format = 1\n[layer.visual]\noutline = true\n'
                                     + HEAD.removeprefix("format = 1\n"))
    assert problem.line == 2 and problem.field == "layer"
    assert "expected [[layer]] tables" in problem.message


def test_one_layer_too_many_names_the_header_past_the_limit(tmp_path):
    """33 [[layer]] tables: the problem had no line; it names the 33rd header."""
    problem = only_problem(tmp_path, HEAD + DISC * (MAX_LAYERS + 1))
    header = len(HEAD.splitlines()) + MAX_LAYERS * len(DISC.splitlines()) + 1
    assert problem.line == header
    assert problem.field == f"layer[{MAX_LAYERS + 1}]"
    assert problem.message.startswith(f"{MAX_LAYERS + 1} [[layer]] tables; a scene holds at "
                                      f"most {MAX_LAYERS}")
