"""A recorded layer's model that cannot be played at a rate (more vertices than are
refitted there: ``textures.hatt.MAX_FIT_VERTICES``) is said where the file names it: a
warning when the scene is read, for the default 10 kHz output, and the error of a replay
at a rate that would refit it."""

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
    return write(tmp_path, BODY.replace("gain = 0.03", "gain = 0.001"))  # no clipping warning


def test_a_model_made_at_1_khz_with_too_many_vertices_is_a_warning_at_its_key(tmp_path, capsys):
    """validate said ok, and every replay at the default 10 kHz refused it. It warns at
    the model's key, a replay at 10 kHz fails naming that key, one at the model's own
    1 kHz (nothing refitted) plays it."""
    from frictex.app.commands.cli import main
    path = _scene(tmp_path, 1000.0)
    scene, problems, warnings = check_scene(path)
    assert scene is not None and problems == [] and len(warnings) == 1, (problems, warnings)
    said = str(warnings[0])
    assert said.split(' "wood')[0].endswith("scene.toml:9: layer[1].model:"), said
    assert ("cannot be played at 10000 Hz, the default output rate" in said
            and f"{SIDE * SIDE} vertices made at 1000 Hz to play at 10000 Hz" in said
            and said.endswith("it plays at --rate 1000")), said
    assert main(["replay", str(path), "swipe-40mms-50hz", "--out", str(tmp_path / "r"),
                 "--quiet"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[-1].startswith(f"frictex: error: {path}:9: layer[1].model: "), err
    assert main(["replay", str(path), "swipe-40mms-50hz", "--out", str(tmp_path / "r"),
                 "--quiet", "--rate", "1000"]) == 0


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
