"""The API reference builds from the docstrings (.ci/api-docs, pdoc), warnings failing it."""

import subprocess
from pathlib import Path

import pytest

pytest.importorskip("pdoc")

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / ".ci" / "api-docs"


def build(out: Path, **env) -> subprocess.CompletedProcess:
    import os
    return subprocess.run(["bash", str(SCRIPT), str(out)], capture_output=True, text=True,
                          timeout=120, env={**os.environ, **env})


def test_the_reference_documents_every_public_name(tmp_path):
    import frictex
    done = build(tmp_path / "docs")
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "docs" / "frictex.html").read_text(encoding="utf-8")
    missing = [name for name in frictex.__all__ if f'id="{name}"' not in page]
    assert missing == []
    assert "Output sample rate (Hz)" in page  # a parameter's numpydoc text, rendered
    assert not (tmp_path / "docs" / "frictex" / "app").exists()  # internals left out


def test_a_docstring_pdoc_cannot_resolve_fails_the_build(tmp_path):
    fake = tmp_path / "src" / "frictex"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text('"""A package."""\n\n\ndef f(x: "NoSuchType") -> None:\n'
                                      '    """F."""\n', encoding="utf-8")
    done = build(tmp_path / "docs", PYTHONPATH=str(tmp_path / "src"))
    assert done.returncode == 1
    assert done.stderr.splitlines() == [
        "api-docs: warning: Error parsing type annotation NoSuchType for frictex.f. Import of "
        "NoSuchType failed: name 'NoSuchType' is not defined"]
