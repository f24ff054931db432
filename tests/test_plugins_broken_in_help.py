"""``frictex replay --help`` leaves out a package's renderer, sink or clock whose entry
point cannot be loaded, with one warning each, as the README says of every whole list."""

import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

FRICTEX = Path(sys.executable).with_name("frictex")


def broken_distribution(folder: Path) -> Path:
    """A distribution's metadata only, whose entry points name a module that is not there."""
    dist = folder / "frictex_wobble_missing-1.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: frictex-wobble-missing\n"
                                   "Version: 1.0\n", encoding="utf-8")
    (dist / "entry_points.txt").write_text(textwrap.dedent("""
        [frictex.renderers]
        ghost = frictex_wobble_missing:Ghost
        [frictex.sinks]
        ghost-sink = frictex_wobble_missing:sink
        [frictex.clocks]
        ghost-clock = frictex_wobble_missing:clock
        """), encoding="utf-8")
    return folder


def help_with_broken_plugins(tmp_path, command: str) -> tuple[str, list[str]]:
    """``frictex COMMAND --help`` beside :func:`broken_distribution`: its help (whitespace
    folded) and its warning lines, once it exits 0 offering frictex's own renderers."""
    env = {**os.environ, "PYTHONPATH": str(broken_distribution(tmp_path / "site"))}
    done = subprocess.run([str(FRICTEX), command, "--help"], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path, env=env)
    assert done.returncode == 0, done.stderr
    helped = " ".join(done.stdout.split())
    assert "sho-held" in helped
    return helped, done.stderr.strip().splitlines()


def cannot_be_loaded(name: str, line: str) -> bool:
    """Whether ``line`` is the warning that entry ``name`` is left out."""
    return re.fullmatch(rf"frictex: warning: \w+( \w+)? '{name}' of frictex-wobble-missing "
                        r"\(.*\) cannot be loaded: ModuleNotFoundError: .*; left out",
                        line) is not None


def test_replay_help_leaves_out_entries_that_cannot_be_loaded(tmp_path):
    helped, warnings = help_with_broken_plugins(tmp_path, "replay")
    assert "ghost" not in helped
    assert len(warnings) == 3 and len(set(warnings)) == 3
    for name in ("ghost", "ghost-sink", "ghost-clock"):
        assert sum(cannot_be_loaded(name, w) for w in warnings) == 1, warnings


def test_demo_help_leaves_out_a_renderer_that_cannot_be_loaded(tmp_path):
    helped, warnings = help_with_broken_plugins(tmp_path, "demo")
    assert "ghost" not in helped
    assert len(warnings) == 1 and cannot_be_loaded("ghost", warnings[0]), warnings
