"""A recorded layer's model that cannot be played is refused where the file names it:
more vertices than are refitted (``textures.hatt.MAX_FIT_VERTICES``) at the 10 kHz output
rate when the scene is read, and at another ``replay --rate`` when the renderer is built."""

import math

from frictex.textures import hatt
from frictex.textures.loader import check_scene
from test_ar_texture_file import BODY, _grid_xml
from test_texture_loader import write

SIDE = math.isqrt(hatt.MAX_FIT_VERTICES) + 1  # SIDE^2 vertices: one grid more than refitted


def _scene(tmp_path, rate_hz: float):
    """A scene of one recorded layer whose model has SIDE^2 AR vertices made at ``rate_hz``."""
    xml = _grid_xml(SIDE, ma=False).replace("<modelSet>", f"<modelSet><SampleRate>{rate_hz:g}"
                                                          f"</SampleRate>", 1)
    (tmp_path / "wood.xml").write_text(xml, encoding="utf-8")
    return write(tmp_path, BODY)


def test_a_model_made_at_1_khz_with_too_many_vertices_is_a_problem_at_its_key(tmp_path):
    scene, problems, _ = check_scene(_scene(tmp_path, 1000.0))
    assert scene is None and len(problems) == 1, problems
    assert str(problems[0]).split(" \"wood")[0].endswith("scene.toml:9: layer[1].model:"), problems
    assert (f"{SIDE * SIDE} vertices made at 1000 Hz to play at 10000 Hz" in str(problems[0])
            and f"at most {hatt.MAX_FIT_VERTICES} are refitted" in str(problems[0])), problems


def test_a_model_made_at_10_khz_replayed_at_20_khz_names_the_texture_files_key(tmp_path, capsys):
    from frictex.app.commands.cli import main
    path = _scene(tmp_path, 10_000.0)
    assert check_scene(path)[1] == []  # plays at the default 10 kHz: nothing refitted
    assert main(["replay", str(path), "swipe-40mms-50hz", "--out", str(tmp_path / "r"), "--quiet",
                 "--rate", "20000"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"frictex: error: {path}:9: layer[1].model: "
                                               f'"wood.xml": '), err
    assert f"{SIDE * SIDE} vertices made at 10000 Hz to play at 20000 Hz" in err[0], err
