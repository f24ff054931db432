"""--resume plays the scenes the session started with: a changed scene file is refused,
the session folder keeps its own copies of the protocol's scenes, and a stimulus file a
session played is never overwritten."""

import json
import shutil

import pytest

from frictex.app.commands.cli import main
from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import make_presenter, run_session
from frictex.device.errors import InputError
from frictex.textures.library import bundled_file

PROTOCOL = """format = 1
method = "2afc"
repetitions = 2
[stimuli]
scene = "myg.toml"
vary = "period_mm"
reference = 5.0
levels = [5.5, 6.5]
[presentation]
exploration_s = 0.3
"""
PARTICIPANT = "simulated:weber=0.11,seed=3"


@pytest.fixture
def study(tmp_path):
    """A protocol naming a scene of its own folder, and a session of it cut to 4 trials."""
    folder = tmp_path / "q"
    folder.mkdir()
    shutil.copyfile(bundled_file("grating-5mm", "scene"), folder / "myg.toml")
    (folder / "my.toml").write_text(PROTOCOL, encoding="utf-8")
    out = tmp_path / "q1"
    run_session(load_protocol(folder / "my.toml"), make_presenter(PARTICIPANT), out, seed=2,
                participant=PARTICIPANT, record="results")
    lines = (out / "results.csv").read_text().splitlines(keepends=True)
    (out / "results.csv").write_text("".join(lines[:5]))
    return folder, out


def resume(protocol_path, out):
    return run_session(load_protocol(protocol_path), make_presenter(PARTICIPANT), out,
                       participant=PARTICIPANT, record="results", resume=True)


def test_a_scene_edited_since_the_start_is_refused(study):
    folder, out = study
    assert set(json.loads((out / "session.json").read_text())["scene_sha256"]) == {"myg.toml"}
    scene = folder / "myg.toml"
    scene.write_text(scene.read_text().replace("mu_low = 0.6", "mu_low = 0.95"))
    played = (out / "stimuli" / "period_mm=5.toml").read_text()
    with pytest.raises(InputError, match=r"myg.toml: not the scene .* started with"):
        resume(folder / "my.toml", out)
    assert (out / "stimuli" / "period_mm=5.toml").read_text() == played
    assert (out / "results.csv").read_text().count("\n") == 5


def test_a_session_resumes_from_its_own_folder(study):
    folder, out = study
    assert (out / "myg.toml").read_bytes() == (folder / "myg.toml").read_bytes()
    shutil.rmtree(folder)
    assert main(["experiment", str(out / "protocol.toml"), "--out", str(out), "--resume",
                 "--participant", PARTICIPANT, "--record", "results", "--quiet"]) == 0
    assert (out / "results.csv").read_text().count("\n") == 1 + 2 * 2 * 2


def test_a_stimulus_file_played_is_never_overwritten(study):
    folder, out = study
    stimulus = out / "stimuli" / "period_mm=5.toml"
    stimulus.write_text(stimulus.read_text().replace("mu_low = 0.6", "mu_low = 0.7"))
    kept = stimulus.read_text()
    with pytest.raises(InputError, match="period_mm=5.toml: this session played another"):
        resume(folder / "my.toml", out)
    assert stimulus.read_text() == kept
