"""The README's Python example runs as printed and prints what it says."""

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_the_python_example_runs(tmp_path):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), re.S)
    assert len(blocks) == 1
    done = subprocess.run([sys.executable, "-c", blocks[0]], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("(10050, 1) [")
    assert lines[1] == "10000 friction rows, 10000 touching"
    assert lines[2].startswith("('commands.parquet', 'friction.parquet') ")
    assert lines[3] == "['t_s', 'ch0_um']"
    assert sorted(p.name for p in (tmp_path / "out-python").iterdir()) == [
        "commands.parquet", "friction.parquet", "summary.json"]
