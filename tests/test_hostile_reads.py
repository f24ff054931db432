"""Hostile files where frictex reads before its checks: a protocol guessed for
``validate --perception``, a resumed session's protocol.toml, ``experiment analyse``'s
session folders and --out, a texture's named file that is a link loop. Each ends in exit
2 and one line naming the file.

Cases that blew up or hung run ``frictex`` in a child process under an address-space
limit of 1 GiB and a wall-clock timeout, so that a regression fails instead of hanging;
the timeout is a guard, not a speed claim.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from frictex.app.commands.cli import main
import test_experiment_resume_parts as resume_parts

ROOT = Path(__file__).resolve().parents[1]
ADDRESS_SPACE = 1 << 30
TIMEOUT_S = 60.0
RUN = "import sys; from frictex.app.commands.cli import main; sys.exit(main(sys.argv[1:]))"
LOOP = "is a symbolic link loop"
PROTOCOL = resume_parts.PROTOCOL.replace("repetitions = 2", "repetitions = 1")
PARTICIPANT = resume_parts.PARTICIPANT


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def frictex(*args, cwd: Path) -> subprocess.CompletedProcess:
    """``frictex args`` in a child under the memory limit and the timeout."""
    return subprocess.run([sys.executable, "-c", RUN, *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=TIMEOUT_S,
                          preexec_fn=_limit_memory, env={**os.environ, "PYTHONPATH": str(ROOT)})


def one_error(done: subprocess.CompletedProcess, *words: str) -> None:
    """Exit 2 and one ``frictex: error:`` line holding ``words``."""
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1 and lines[0].startswith("frictex: error: "), done.stderr
    for word in words:
        assert word in lines[0], lines[0]


def loop(folder: Path, name: str = "l1") -> Path:
    """``name`` in ``folder``: a link to a link back to it."""
    (folder / "l2").symlink_to(name)
    (folder / name).symlink_to("l2")
    return folder / name


def test_perception_guess_of_a_deep_file_is_the_loaders_syntax_error(tmp_path):
    (tmp_path / "p.toml").write_text('method = "2afc"\nx = ' + "[" * 1000 + "]" * 1000 + "\n")
    one_error(frictex("validate", "--perception", "p.toml", cwd=tmp_path),
              "p.toml:2: TOML syntax", "nested more than 16 deep")


@pytest.mark.parametrize("make, words", [
    (lambda d: "/dev/zero", ("/dev/zero", "is a character device")),
    (lambda d: os.mkfifo(d / "f.toml") or "f.toml", ("f.toml", "is a FIFO")),
])
def test_perception_guess_reads_no_device_or_fifo(tmp_path, make, words):
    one_error(frictex("validate", "--perception", make(tmp_path), cwd=tmp_path), *words)


@pytest.fixture
def session(tmp_path):
    """A finished two-trial session in ``tmp_path / "s"`` of ``tmp_path / "p.toml"``."""
    (tmp_path / "p.toml").write_text(PROTOCOL, encoding="utf-8")
    assert main(["experiment", str(tmp_path / "p.toml"), "--out", str(tmp_path / "s"),
                 "--participant", PARTICIPANT, "--quiet"]) == 0
    return tmp_path / "s"


@pytest.mark.parametrize("swap, words", [
    (lambda p: p.symlink_to("/dev/zero"), ("is a character device",)),
    (lambda p: os.mkfifo(p), ("is a FIFO",)),
])
def test_resume_reads_no_device_or_fifo_as_the_sessions_protocol(session, swap, words):
    (session / "protocol.toml").unlink()
    swap(session / "protocol.toml")
    done = frictex("experiment", "p.toml", "--resume", "--out", "s", "--participant",
                   PARTICIPANT, "--quiet", cwd=session.parent)
    one_error(done, "s: the session's protocol.toml cannot be read", *words)


def test_analyse_of_a_link_loop_says_so(tmp_path, capsys):
    assert main(["experiment", "analyse", str(loop(tmp_path))]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"frictex: error: {tmp_path / 'l1'}: {LOOP} (a link that leads back to itself)"


@pytest.mark.parametrize("out, words", [
    (lambda d: (d / "afile").touch() or d / "afile", ("afile: exists and is not a folder",)),
    (lambda d: "/proc/x", ("/proc/x: cannot be made as the output folder",)),
])
def test_analyse_refuses_a_bad_out_before_analysing(session, capsys, monkeypatch, out, words):
    from frictex.app.experiment import analysis

    def never(group):
        raise AssertionError("analysed before --out was checked")

    monkeypatch.setattr(analysis, "analyse_study", never)
    assert main(["experiment", "analyse", str(session), "--out",
                 str(out(session.parent))]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(word in err[0] for word in words), err


def test_a_named_file_in_a_link_loop_is_called_a_loop_not_a_race(tmp_path, capsys):
    text = (ROOT / "textures" / "library" / "raster-map.toml").read_text(encoding="utf-8")
    (tmp_path / "t.toml").write_text(text.replace('image = "raster-map.png"', 'image = "l1"'))
    loop(tmp_path)
    assert main(["validate", str(tmp_path / "t.toml")]) == 2
    err = capsys.readouterr().err
    assert LOOP in err and "after it was checked" not in err, err
