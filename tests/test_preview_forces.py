"""frictex preview says what its friction map leaves out: force layers (directional,
guidance, keyclick) are mu' 1 there, so the title and a printed line give what each does
and where; and an output 'folder' that is a file is named so."""

import pytest

from frictex.app.commands.cli import main
from frictex.app.commands.preview import preview_figure
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

#: what each bundled force scene's layer does, as its file gives it
BUNDLED = {
    "directional-beam": "one-way (directional",
    "guidance-beam": "mid-span (guidance",
    "keyclick-ring": "button (keyclick",
}
EFFECTS = {
    "directional-beam": "mu' 0.3 moving +x, 0.9 moving -x, within x 230-370 mm",
    "guidance-beam": "a pull towards the line x = 300 mm, 0.002 N/mm up to 0.05 N, "
                     "within x 230-370 mm",
    "keyclick-ring": "a push of 0.1 N towards +x from a press of 0.5 N, reversed at 0.8 N, "
                     "released below 0.4 N, within x 50-90, y 5-25 mm",
}


@pytest.mark.parametrize("name", sorted(BUNDLED))
def test_a_force_layer_is_titled_and_printed_with_what_it_does(tmp_path, capsys, name):
    """directional-beam printed only "mu' ... 1.000 to 1.000" and titled its layer
    'one-way (directional, sho)': nothing of 0.3 forward, 0.9 backward."""
    assert main(["preview", name, "-o", str(tmp_path / "p.png")]) == 0
    printed = capsys.readouterr().out
    assert (f"force layer {BUNDLED[name]}, not in the friction map): {EFFECTS[name]}\n"
            in printed)
    fig, _ = preview_figure(load_scene(resolve_scene(name)), size=(600, 60))
    title = fig.get_suptitle().replace("\n", " ")
    assert f"{BUNDLED[name]}: {EFFECTS[name]}; not in the map)" in title


def test_a_backward_force_target_over_the_whole_display(tmp_path):
    text = resolve_scene("directional-beam").read_text(encoding="utf-8")
    region = text[text.index("region = "):text.index("\n", text.index("region = ")) + 1]
    text = (text.replace(region, "").replace("angle_deg = 0 ", "angle_deg = 180 ")
            .replace("mu_forward = 0.3", "force_forward_n = 0.05")
            .replace("mu_backward = 0.9", "force_backward_n = -0.02"))
    path = tmp_path / "force.toml"
    path.write_text(text, encoding="utf-8")
    fig, info = preview_figure(load_scene(path), size=(600, 60))
    effect = ("a net tangential force of 0.05 N moving -x, -0.02 N moving +x (positive resists "
              "the finger), over the whole display")
    assert info["forces"] == [f"one-way (directional, not in the friction map): {effect}"]
    assert effect in fig.get_suptitle().replace("\n", " ")


def test_an_output_folder_that_is_a_file_is_named_so(tmp_path, monkeypatch, capsys):
    """`touch f; frictex preview grating-5mm -o f/a.png` said "output folder 'f' does not exist"."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f").touch()
    assert main(["preview", "grating-5mm", "-o", "f/a.png"]) == 2
    err = capsys.readouterr().err
    assert err == "frictex: error: output folder 'f' exists but is not a folder\n"
