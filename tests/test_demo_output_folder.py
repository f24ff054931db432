"""The demo's ``--out`` / ``--record`` folder: replaced as a whole like a replay's, so a
``frames`` folder holding a file of the user's is refused before anything is written
(the demo once owned any folder named ``frames`` and deleted what was in it)."""

import subprocess
import sys

import pytest

from frictex.app.commands.demo import DEMO_OUTPUTS
from frictex.app.engine.staging import Staging
from frictex.device.errors import InputError


def test_a_frames_folder_holding_a_users_file_is_refused(tmp_path):
    (tmp_path / "frames").mkdir()
    (tmp_path / "frames" / "mine.txt").write_text("precious")
    with pytest.raises(InputError, match="holds the folder 'frames', not a run's output"):
        Staging(tmp_path, owned=DEMO_OUTPUTS).check()


def test_an_earlier_demos_frames_are_its_own(tmp_path):
    (tmp_path / "frames").mkdir()
    for k in range(3):
        (tmp_path / "frames" / f"frame-{k:05d}.png").write_bytes(b"")
    Staging(tmp_path, owned=DEMO_OUTPUTS, claimed_by_summary=False).check()  # frames' own --out
    with pytest.raises(InputError, match="holds 'frames' but no summary.json"):
        Staging(tmp_path, owned=DEMO_OUTPUTS).check()  # a recording's folder has its summary


def test_a_headless_demo_into_a_folder_of_the_users_deletes_nothing(tmp_path):
    """The command a stranger might give: one line, exit 2, the folder as it was."""
    out = tmp_path / "victim"
    (out / "frames").mkdir(parents=True)
    (out / "frames" / "mine.txt").write_text("precious")
    done = subprocess.run([sys.executable, "-m", "frictex", "demo", "grating-5mm", "--headless",
                           "--duration", "1", "--out", str(out)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and "not a run's output" in done.stderr
    assert sorted(p.relative_to(out).as_posix() for p in out.rglob("*")) == [
        "frames", "frames/mine.txt"]
    assert (out / "frames" / "mine.txt").read_text() == "precious"
