"""A plugin whose import raises SystemExit (a script turned plugin: ``sys.exit()`` or argparse
at module level) is left out with one warning, as one with a missing import is; it ended
every replay, which imports every renderer for --renderer's choices, with its status and
not a word (exit 3). A SystemExit of a signal's (app.engine.driver.Terminated) still ends
the run."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from frictex.app.engine.driver import Terminated
from frictex.device.registry import PluginError, Registry

FRICTEX = Path(sys.executable).with_name("frictex")


def distribution(site: Path, group: str, modules: dict[str, str]) -> Path:
    """``site`` holding the distribution frictex-exit-test: each module of ``modules``
    (name: source), its ``X`` an entry point of ``group`` under the module's name."""
    dist = site / "frictex_exit_test-1.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: frictex-exit-test\n"
                                   "Version: 1.0\n", encoding="utf-8")
    points = "".join(f"{name} = {name}:X\n" for name in modules)
    (dist / "entry_points.txt").write_text(f"[{group}]\n{points}", encoding="utf-8")
    for name, source in modules.items():
        (site / f"{name}.py").write_text(textwrap.dedent(source), encoding="utf-8")
    return site


def test_replay_leaves_out_a_renderer_whose_import_exits(tmp_path):
    site = distribution(tmp_path / "site", "frictex.renderers",
                        {"exits_on_import": "import sys\nsys.exit(3)\n"})
    done = subprocess.run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out",
                           str(tmp_path / "o"), "--quiet"], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(site)})
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip().splitlines() == [
        "frictex: warning: renderer 'exits_on_import' of frictex-exit-test "
        "(exits_on_import:X) cannot be loaded: SystemExit: 3; left out"]
    assert (tmp_path / "o" / "summary.json").exists()


def test_an_import_ended_by_a_signal_is_not_the_plugins_fault(tmp_path, monkeypatch):
    site = distribution(tmp_path / "site", "frictex.test-gadgets-exit", {
        "gadget_exits": "import argparse\nargparse.ArgumentParser().parse_args(['-x'])\n",
        "gadget_terminated": """
            import signal
            from frictex.app.engine.driver import Terminated
            raise Terminated(signal.SIGTERM)
            """})
    monkeypatch.syspath_prepend(str(site))
    registry = Registry("gadget", "frictex.test-gadgets-exit")
    with pytest.raises(PluginError, match=r"^gadget 'gadget_exits' of frictex-exit-test "
                                          r"\(gadget_exits:X\) cannot be loaded: SystemExit: 2$"):
        registry.get("gadget_exits")
    with pytest.raises(Terminated):
        registry.get("gadget_terminated")
