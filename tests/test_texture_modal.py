"""Texture files for modal devices: [device.structure], layer `fingers`, and their errors."""

import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.app.commands.cli import main
from frictex.device.structures.beam import FreeFreeBeam
from frictex.device.actuation.modal_actuation import ModalActuation
from frictex.rendering.pipeline import build_pipeline
from frictex.device import profile as profiles
from frictex.textures.library import resolve_scene
from frictex.textures.loader import check_scene, load_scene

BEAM = """\
format = 1
[display]
width_mm = 350.0
height_mm = 6.0
width_px = 1400
height_px = 24
[device]
profile = "beam-seed000"
amplitude_limit_um = 0.7
[device.structure]
{structure}
[[layer]]
type = "rectangle"
fingers = {fingers}
x_mm = 0
y_mm = 0
width_mm = 350
height_mm = 6
mu = 0.8
"""


def check(tmp_path, structure="", fingers='"1"', text=BEAM, files=()):
    for name, content in files:
        (tmp_path / name).write_text(content)
    path = tmp_path / "t.toml"
    path.write_text(text.format(structure=structure, fingers=fingers))
    return check_scene(path)


def only_problem(problems, field, pattern):
    assert len(problems) == 1, problems
    p = problems[0]
    assert p.field == field and re.search(pattern, p.message), p
    return p


def test_bundled_two_finger_scenes_load_with_the_papers_structures():
    beam = load_scene(resolve_scene("two-finger-beam-seed000"))
    assert beam.device.structure == profiles.BeamStructure()  # the file writes the defaults out
    assert [layer.fingers for layer in beam.layers] == ["1", "2"]
    plate = load_scene(resolve_scene("two-finger-plate-seed001"))
    assert plate.device.structure == profiles.PlateStructure()
    assert [layer.fingers for layer in plate.layers] == ["left-most", "right-most"]
    for scene in (beam, plate):
        assert isinstance(build_pipeline(scene).actuation, ModalActuation)


def test_validate_passes_on_the_new_scenes(capsys):
    assert main(["validate", "two-finger-beam-seed000", "two-finger-plate-seed001"]) == 0
    assert "warning" not in capsys.readouterr().out


def test_defaults_fill_an_empty_structure_table(tmp_path):
    scene, problems, warnings = check(tmp_path)
    assert problems == [] and warnings == []
    assert scene.device.structure == profiles.BeamStructure()
    assert scene.device.structure.orders == (16, 17) and scene.device.structure.channel_limit_um == 0.75


def test_author_overrides_and_timoshenko(tmp_path):
    scene, problems, _ = check(tmp_path, 'theory = "timoshenko"\nchannel_limit_um = 0.5\nmethod = "bounded"')
    assert problems == []
    s = scene.device.structure
    assert (s.theory, s.channel_limit_um, s.method) == ("timoshenko", 0.5, "bounded")


@pytest.mark.parametrize("value, stored", [('"any"', "any"), ('"2"', "2"), ("2", "2"), ('"02"', "2"),
                                           ('"bottom-most"', "bottom-most")])
def test_finger_selectors_accepted(tmp_path, value, stored):
    scene, problems, _ = check(tmp_path, fingers=value)
    assert problems == [] and scene.layers[0].fingers == stored


@pytest.mark.parametrize("value, pattern", [
    ('"leftmost"', r'"leftmost" is not one of any, left-most.*\(did you mean left-most\?\)'),
    ('"0"', r'finger numbers start at "1"'),
    ("true", r"got the boolean true"),
    ('"first"', r'or a finger number "1", "2"'),
])
def test_bad_finger_selectors(tmp_path, value, pattern):
    scene, problems, _ = check(tmp_path, fingers=value)
    p = only_problem(problems, "layer[1].fingers", pattern)
    assert scene is None and p.line == BEAM.splitlines().index("fingers = {fingers}") + 1


@pytest.mark.parametrize("structure, field, pattern", [
    ("lenght_mm = 300", "device.structure.lenght_mm", r"unknown key \(did you mean length_mm\?\)"),
    ("actuators_mm = [60]", "device.structure.actuators_mm", r"has 1 positions, expected one per mode \(2\)"),
    ("actuators_mm = [60, 400]", "device.structure.actuators_mm", r"400 mm is off the 350 mm beam"),
    ("orders = [16, 16.5]", "device.structure.orders", r"\[16, 16.5\]: 16.5 is not a whole mode order"),
    ("orders = [16, 16]", "device.structure.orders", r"\[16, 16\]: 16 is given twice"),
    ("length_mm = 300", "device.structure.x0_mm", r"display's width_mm \(0 to 350 mm\) must lie on the structure"),
    ("x0_mm = 5", "device.structure.x0_mm", r"spans 5 to 355 mm"),
    ('theory = "timoshenk"', "device.structure.theory", r"did you mean timoshenko"),
    ("rcond = 1.5", "device.structure.rcond", r"outside \(0, 1\)"),
    ("orders = [80, 81]\ntheory = \"timoshenko\"", "device.structure", r"above the Timoshenko cutoff"),
])
def test_bad_structures_name_the_field(tmp_path, structure, field, pattern):
    scene, problems, _ = check(tmp_path, structure)
    assert scene is None
    only_problem(problems, field, pattern)


def test_actuators_on_nodes_are_refused(tmp_path):
    nodes = FreeFreeBeam(350, 6, 6, 57, 2561).nodes_mm(16).tolist()
    scene, problems, _ = check(tmp_path, f"actuators_mm = [{nodes[2]!r}, {nodes[-3]!r}]")
    only_problem(problems, "device.structure", r"condition number .* actuator on a node")


def test_structure_on_a_single_mode_plate_is_refused(tmp_path):
    text = BEAM.replace('profile = "beam-seed000"', 'profile = "plate-seed003"')
    scene, problems, _ = check(tmp_path, "length_mm = 350", text=text)
    only_problem(problems, "device.structure", r'not used with profile "plate-seed003"; only the modal profiles.*beam-seed000')


def test_plate_display_must_lie_on_the_plate(tmp_path):
    text = BEAM.replace('"beam-seed000"', '"plate-seed001"').replace("width_mm = 350.0", "width_mm = 150.0")
    scene, problems, _ = check(tmp_path, "x0_mm = 0", text=text.replace("width_mm = 350\n", "width_mm = 150\n"))
    only_problem(problems, "device.structure.x0_mm", r"display's width_mm \(0 to 150 mm\).*spans 0 to 140 mm")


def test_a_per_finger_layer_on_a_one_channel_device_warns(tmp_path):
    text = BEAM.replace('profile = "beam-seed000"', 'profile = "plate-seed003"').replace("[device.structure]\n", "")
    scene, problems, warnings = check(tmp_path, text=text)
    assert problems == [] and scene is not None
    assert len(warnings) == 1 and warnings[0].field == "layer[1].fingers"
    assert "serves only the finger touching longest" in warnings[0].message


def modes_csv():
    beam = FreeFreeBeam(350, 6, 6, 57, 2561)
    x = np.linspace(0, 350, 701)
    shapes = beam.phi((16, 17), x)
    return "x_mm,A,B\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, (b, c) in zip(x.tolist(), shapes.tolist()))


def test_measured_mode_table_replaces_the_model(tmp_path):
    scene, problems, _ = check(tmp_path, 'modes_file = "modes.csv"', files=[("modes.csv", modes_csv())])
    assert problems == []
    s = scene.device.structure
    assert s.modes_path == (tmp_path / "modes.csv").resolve() and s.modes.names == ("A", "B")
    act = build_pipeline(scene).actuation
    model_act = build_pipeline(load_scene(resolve_scene("two-finger-beam-seed000"))).actuation
    x = np.array([[120.0], [250.0]])
    # a 0.5 mm table of the model's own shapes (scaled to 1 at its largest, 2 at the free
    # ends): the spline matches the model closely
    np.testing.assert_allclose(2.0 * act.shapes(x, x * 0), model_act.shapes(x, x * 0), atol=2e-3)


def test_a_table_of_1e_100_drives_the_beam_as_the_same_table_in_um(tmp_path):
    """Its modal solve overflowed to NaN (80,000 of 80,050 command rows, exit 0, nothing
    counted); the unit of a table cancels, so the commands are the same."""
    import frictex
    bundled = resolve_scene("two-finger-beam-seed000").read_text(encoding="utf-8")
    trace = frictex.read_trace("back-and-forth-beam-60mms-60hz")
    commands = []
    for unit in (1.0, 1e-100):
        folder = tmp_path / f"u{unit:g}"
        folder.mkdir()
        table = modes_csv().splitlines()
        (folder / "modes.csv").write_text("\n".join(
            [table[0]] + [",".join([row.split(",")[0]] + [repr(float(v) * unit) for v in
                                                        row.split(",")[1:]]) for row in table[1:]])
            + "\n")
        text = re.sub(r"^orders = \[16, 17\]$", 'modes_file = "modes.csv"', bundled, count=1,
                      flags=re.M)
        assert "modes.csv" in text
        (folder / "s.toml").write_text(text, encoding="utf-8")
        run = frictex.replay(str(folder / "s.toml"), trace)
        commands.append(np.column_stack([c.to_numpy() for c in run.commands.columns[1:]]))
    assert np.isfinite(commands[1]).all()
    np.testing.assert_allclose(commands[1], commands[0], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("structure, files, pattern", [
    ('modes_file = "nope.csv"', [], r'"nope.csv": .*nope.csv: No such file'),
    ('modes_file = "m.csv"', [("m.csv", "x_mm,A\n0,1\n1,2\n")], r"need at least 4 positions"),
])
def test_bad_mode_tables(tmp_path, structure, files, pattern):
    scene, problems, _ = check(tmp_path, structure, files=files)
    only_problem(problems, "device.structure.modes_file", pattern)


def test_orders_and_modes_file_together_are_refused(tmp_path):
    scene, problems, _ = check(tmp_path, 'modes_file = "modes.csv"\norders = [16, 17]',
                               files=[("modes.csv", modes_csv())])
    only_problem(problems, "device.structure.orders", r"not used with modes_file")


@settings(max_examples=200, deadline=None, derandomize=True)
@given(text=st.lists(st.sampled_from(list("x_mA,0123456789.e-+ \n#\"\x1b\x07٢") + ["inf", "nan"]),
                    max_size=80).map("".join))
def test_any_mode_table_text_is_a_table_or_one_escaped_line(text):
    """Whatever a mode table holds, reading it gives a table or a ModesError whose message
    is one printable line showing no cell longer than MAX_CELL_SHOWN."""
    from frictex.device.structures.beam import ModesError
    from frictex.device.structures.measured_modes import MAX_CELL_SHOWN, MeasuredModes
    try:
        with np.errstate(all="raise"):
            MeasuredModes.from_text("x_mm,A\n" + text, "m.csv")
    except (ModesError, ValueError, FloatingPointError) as exc:
        message = str(exc)
        assert message.isprintable() and "m.csv" in message
        for shown in re.findall(r'"([^"]*)"', message):
            assert len(shown) <= MAX_CELL_SHOWN
