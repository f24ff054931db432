"""[device.friction] keys beside a [device.calibration] table: warned about, since the table
replaces seed 003's eq 2, unless a force layer's tangential force uses them."""

from frictex.textures.loader import check_scene

HEAD = ("format = 1\n[display]\nwidth_mm = 108.0\nheight_mm = 64.8\nwidth_px = 800\n"
        "height_px = 480\n")
FRICTION = "[device.friction]\nb_per_um = 2\nasymptote_per_n = 0.1\n"
TABLE = "[device.calibration]\namplitudes_um = [0.0, 1.0, 2.0]\nforces_n = [0.5]\nmu = [[1.0, 0.8, 0.7]]\n"
DISC = '[[layer]]\ntype = "disc"\ncx_mm = 10\ncy_mm = 10\nradius_mm = 3\nmu = 0.9\n'


def friction_warnings(tmp_path, device: str, layers: str = DISC):
    path = tmp_path / "scene.toml"
    path.write_text(HEAD + device + layers, encoding="utf-8")
    scene, problems, warnings = check_scene(path)
    assert scene is not None, problems
    return [w for w in warnings if w.field.startswith("device.friction")]


def test_friction_keys_beside_a_calibration_table_are_warned_about_at_their_lines(tmp_path):
    """Both tables: b_per_um = 2, asymptote_per_n = 0.1 were taken without a word and
    changed nothing (a replay's amplitude was 1.5 um either way)."""
    found = friction_warnings(tmp_path, "[device]\n" + FRICTION + TABLE)
    assert [(w.line, w.field) for w in found] == [(9, "device.friction.b_per_um"),
                                                  (10, "device.friction.asymptote_per_n")]
    assert all("has no effect: the [device.calibration] table replaces seed 003's eq 2"
               in w.message for w in found)


def test_either_table_alone_is_not_warned_about(tmp_path):
    assert friction_warnings(tmp_path, "[device]\n" + FRICTION) == []
    assert friction_warnings(tmp_path, "[device]\n" + TABLE) == []


def test_a_force_layer_uses_the_friction_keys_beside_the_table(tmp_path):
    device = '[device]\nprofile = "travelling-beam-seed002"\n' + FRICTION + TABLE
    push = '[[layer]]\ntype = "directional"\nmu_forward = 0.6\nmu_backward = 0.9\n'
    assert friction_warnings(tmp_path, device, push) == []
