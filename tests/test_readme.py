"""The README's Python example runs as written and prints what it says."""

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
    assert lines[0].startswith("(10100, 1) [")
    assert lines[1].startswith("['commands.parquet', 'friction.parquet']")
    assert lines[2].endswith("friction rows") and int(lines[2].split()[0]) > 9000
    assert (tmp_path / "out-python" / "summary.json").exists()
