"""A batch killed by SIGKILL leaves its staging folder beside --out; the next batch into
that --out clears it (its finished job folders deleted, none moved into --out) and runs."""

import csv
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

FRICTEX = str(Path(sys.executable).with_name("frictex"))
#: the longest the wait for the killed batch's job folders may take (s)
BOUND_S = 120

#: ``frictex batch`` whose replay of a trace named ``hang.csv`` never ends, so that the
#: batch can be killed while the jobs before it lie finished in its staging folder
HANGING_BATCH = textwrap.dedent("""
    import sys, time
    import frictex.app.engine.replay as replay
    from frictex.app.commands.cli import main

    real_replay = replay.run_replay

    def run_replay(scene, trace, *args, **kwargs):
        while str(trace).endswith("hang.csv"):
            time.sleep(1)
        return real_replay(scene, trace, *args, **kwargs)

    replay.run_replay = run_replay
    sys.exit(main(sys.argv[1:]))
""")


def batch(folder: Path, manifest: str) -> subprocess.CompletedProcess:
    return subprocess.run([FRICTEX, "batch", manifest, "--out", "out", "--quiet"],
                          cwd=folder, capture_output=True, text=True, timeout=BOUND_S)


def staged_jobs(folder: Path) -> set[str]:
    """The finished job folders in the batch's staging folders beside ``out``."""
    return {job.parent.name for job in folder.glob(".out.frictex-staging.*/*/summary.json")}


def test_a_batch_after_a_killed_one_clears_its_job_folders(tmp_path):
    (tmp_path / "one.csv").write_text("t_s,finger,x_mm,y_mm\n0,0,1,1\n0.1,0,2,1\n")
    (tmp_path / "hang.csv").write_text("t_s,finger,x_mm,y_mm\n0,0,1,1\n")
    (tmp_path / "first.csv").write_text("scene,trace,name\ngrating-5mm,one.csv,a\n")
    (tmp_path / "all.csv").write_text("scene,trace,name\ngrating-5mm,one.csv,a\n"
                                      "grating-5mm,one.csv,c\ngrating-5mm,hang.csv,d\n")
    (tmp_path / "hang.py").write_text(HANGING_BATCH)
    assert batch(tmp_path, "first.csv").returncode == 0

    killed = subprocess.Popen([sys.executable, "hang.py", "batch", "all.csv", "--out", "out",
                               "--jobs", "1", "--quiet"], cwd=tmp_path,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        end = time.monotonic() + BOUND_S
        while staged_jobs(tmp_path) != {"a", "c"}:
            assert killed.poll() is None and time.monotonic() < end, staged_jobs(tmp_path)
            time.sleep(0.05)
    finally:
        killed.send_signal(signal.SIGKILL)
        killed.wait()

    again = batch(tmp_path, "first.csv")
    assert again.returncode == 0, again.stderr
    assert sorted(os.listdir(tmp_path / "out")) == ["a", "batch.csv"]
    with open(tmp_path / "out" / "batch.csv", newline="") as fh:
        assert [row["name"] for row in csv.DictReader(fh)] == ["a"]
    assert not list(tmp_path.glob(".out.frictex-*"))
