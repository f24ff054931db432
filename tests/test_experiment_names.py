"""Bundled protocols given by name (``frictex experiment NAME``, ``frictex validate
--perception NAME``), and the names and descriptions of the scene files a session
writes for its stimuli."""

import tomllib

import pytest

from frictex.app.commands.cli import main
from frictex.app.experiment.protocol import (PROTOCOLS_DIR, Stimulus, load_protocol,
                                             resolve_protocol)
from frictex.app.experiment.stimuli import NAME_LIMIT, StimulusBank
from frictex.textures.loader import load_scene


@pytest.fixture(autouse=True)
def elsewhere(tmp_path, monkeypatch):
    """Run where no protocol file lies, as a user of an installed frictex does."""
    monkeypatch.chdir(tmp_path)


def test_experiment_runs_a_bundled_protocol_by_name(capsys):
    assert main(["experiment", "period-2afc", "--check"]) == 0
    assert "period-2afc, 2afc: 4 practice and 120 main trials" in capsys.readouterr().out
    assert resolve_protocol("period-2afc.toml") == PROTOCOLS_DIR / "period-2afc.toml"


def test_a_file_or_a_path_is_never_taken_for_a_bundled_name(tmp_path):
    (tmp_path / "period-2afc").write_text("")
    assert str(resolve_protocol("period-2afc")) == "period-2afc"
    assert str(resolve_protocol("missing/period-2afc")) == "missing/period-2afc"


def test_an_unknown_protocol_name_suggests_the_closest_protocol(capsys):
    assert main(["experiment", "period-2afx", "--check"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert ("period-2afx: no such file, and no bundled protocol of that name (did you mean "
            "period-2afc? the bundled protocols: depth-staircase, period-2afc, "
            "seed003-gratings)") in err


def test_help_names_the_bundled_protocols(capsys):
    for command in (["experiment", "--help"], ["validate", "--help"]):
        with pytest.raises(SystemExit):
            main(command)
    out = " ".join(capsys.readouterr().out.split())
    assert "or the name of a bundled protocol (depth-staircase, period-2afc, seed003-gratings" in out
    assert "a bundled protocol's name (a name is looked up among the scenes first" in out


def test_validate_perception_takes_a_bundled_protocol_name(capsys):
    assert main(["validate", "--perception", "seed003-gratings", "grating-5mm"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"ok {PROTOCOLS_DIR / 'seed003-gratings.toml'} (protocol, ")
    assert out[1].endswith("grating-5mm.toml (1 layer)")


def test_validate_says_which_kinds_of_name_it_searched(capsys):
    assert main(["validate", "--perception", "seed003-gratngs"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: seed003-gratngs: no such file, and no bundled scene "
                          "or protocol of that name (did you mean seed003-gratings? frictex "
                          "library lists the scenes; the bundled protocols: ")
    assert main(["validate", "seed003-gratings"]) == 2
    assert "but a bundled protocol: frictex validate --perception checks protocols" in \
        capsys.readouterr().err


def _written(tmp_path, stimulus, vary="period_mm", layer=0):
    scene, text = StimulusBank(tmp_path / "stimuli").get(stimulus, vary, layer)
    return scene, tomllib.loads(text)


def test_a_stimulus_scene_is_named_and_described_as_the_base_changed(tmp_path):
    base = load_protocol(PROTOCOLS_DIR / "period-2afc.toml").stimuli.scene
    scene, doc = _written(tmp_path, Stimulus("period_mm=6.6", base, 6.6))
    assert scene.name == doc["name"] == "grating-5mm-period_mm=6.6"
    assert doc["description"] == ('An experiment stimulus: the scene grating-5mm with '
                                  'period_mm = 6.6 on layer "lines".')
    assert doc["layer"][0]["period_mm"] == 6.6
    _, doc = _written(tmp_path, Stimulus("depth=0.25-sht", base, 0.25, "sht"), "depth")
    assert doc["name"] == "grating-5mm-depth=0.25-sht"
    assert doc["description"].endswith('depth = 0.25 on layer "lines" (mu_low = mu_high - '
                                       'depth) and its periodic layers rendered sht.')
    unchanged = load_scene(base)
    scene, _ = _written(tmp_path, Stimulus("as-is", base))
    assert (scene.name, scene.description) == (unchanged.name, unchanged.description)


def test_a_long_base_name_still_makes_a_valid_scene_name(tmp_path):
    base = tmp_path / "long.toml"
    text = (PROTOCOLS_DIR.parents[2] / "textures" / "library" / "grating-5mm.toml").read_text()
    base.write_text(text.replace('name = "grating-5mm"', f'name = "{"g" * NAME_LIMIT}"', 1))
    scene, _ = _written(tmp_path, Stimulus("period_mm=6.6", base, 6.6))
    assert len(scene.name) == NAME_LIMIT and scene.name.endswith("g-period_mm=6.6")
