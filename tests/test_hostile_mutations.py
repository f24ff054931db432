"""Mutated bundled files through ``frictex validate`` and ``frictex replay``, in process.

The bundled scenes (``textures/library/*.toml``) and traces (``textures/library/traces/*.csv``)
are mutated (bytes flipped, truncated, lines duplicated or deleted, numbers replaced by
huge, tiny or non-finite ones) and run through the command as a user would. Whatever the
mutation: exit 0 or 2; on exit 2 every stderr line is ``frictex: error: ...`` (replay: exactly
one line); nothing else escapes (no traceback, no exception, no numpy overflow warning); on
exit 0 the outputs hold no NaN or infinity and ``summary.json`` is strict JSON.
"""

from __future__ import annotations

import contextlib
import io
import json
import re
import shutil
import tempfile
import warnings
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.app.commands.cli import main
from frictex.textures.library import LIBRARY_DIR, TRACES_DIR

SCENES = sorted(LIBRARY_DIR.glob("*.toml"))
TRACES = sorted(TRACES_DIR.glob("*.csv"))
NUMBER = re.compile(rb"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
HOSTILE_NUMBERS = [b"1e308", b"-1e308", b"1e-300", b"9" * 30, b"nan", b"inf", b"-inf", b"0",
                   b"-0.0", b"2147483648", b"9223372036854775807", b"1e20"]

# where a mutation lands: a fraction of the file (its bytes, lines or numbers), drawn
# uniformly (hypothesis favours small integers, which would keep every change at the start)
where = st.integers(0, 9999).map(lambda k: (k * 7919 % 10_000) / 10_000)
mutation = st.one_of(
    st.tuples(st.just("flip"), where, st.integers(1, 255)),
    st.tuples(st.just("truncate"), where, st.just(0)),
    st.tuples(st.just("duplicate"), where, st.integers(1, 50)),
    st.tuples(st.just("delete"), where, st.just(0)),
    st.tuples(st.just("number"), where, st.integers(0, len(HOSTILE_NUMBERS) - 1)),
    st.tuples(st.just("number"), where, st.integers(0, len(HOSTILE_NUMBERS) - 1)),
)


def mutate(data: bytes, kind: str, where: float, arg: int) -> bytes:
    """``data`` with one mutation at fraction ``where`` of it (of its bytes, lines, numbers)."""
    if not data:
        return data
    if kind == "flip":
        i = int(where * len(data))
        return data[:i] + bytes([data[i] ^ arg]) + data[i + 1:]
    if kind == "truncate":
        return data[:int(where * len(data))]
    lines = data.splitlines(keepends=True)
    k = int(where * len(lines))
    if kind == "duplicate":
        return b"".join(lines[:k + 1] + [lines[k]] * arg + lines[k + 1:])
    if kind == "delete":
        return b"".join(lines[:k] + lines[k + 1:])
    numbers = list(NUMBER.finditer(data))
    if not numbers:
        return data
    m = numbers[int(where * len(numbers))]
    return data[:m.start()] + HOSTILE_NUMBERS[arg] + data[m.end():]


def mutated(source: Path, changes) -> bytes:
    data = source.read_bytes()
    for change in changes:
        data = mutate(data, *change)
    return data


def run(argv: list[str]) -> tuple[int, list[str]]:
    """``frictex argv`` in process: (exit code, stderr lines); RuntimeWarnings fail."""
    err = io.StringIO()
    with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stderr(err), \
            contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("always")
        code = main(argv)
    numeric = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    assert not numeric, [str(w.message) for w in numeric]
    return code, err.getvalue().splitlines()


def _strict_json(text: str):
    def refuse(name):
        raise AssertionError(f"summary.json holds {name}, which is not JSON")
    return json.loads(text, parse_constant=refuse)


def check_replay(argv: list[str], out: Path) -> None:
    code, lines = run(argv)
    assert code in (0, 2), (code, lines)
    assert "Traceback" not in "\n".join(lines)
    if code == 2:
        assert len(lines) == 1 and lines[0].startswith("frictex: error: "), lines
        return
    assert all(line.startswith("frictex: warning: ") for line in lines), lines
    _strict_json((out / "summary.json").read_text())
    for table in ("commands.csv", "friction.csv"):
        text = (out / table).read_text().lower()
        assert "nan" not in text and "inf" not in text, table


@settings(max_examples=200, derandomize=True, deadline=None)
@given(index=st.integers(0, len(SCENES) - 1), changes=st.lists(mutation, min_size=1, max_size=3))
def test_mutated_scenes_validate_and_replay_cleanly(index, changes):
    source = SCENES[index]
    data = mutated(source, changes)
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        for image in LIBRARY_DIR.glob("*.png"):  # rasters are found next to the scene
            shutil.copy(image, folder)
        scene = folder / source.name
        scene.write_bytes(data)
        code, lines = run(["validate", str(scene)])
        assert code in (0, 2), (code, lines)
        errors = [line for line in lines if line.startswith("frictex: error: ")]
        assert all(line.startswith(("frictex: error: ", "frictex: warning: ")) for line in lines)
        assert (code == 2) == bool(errors), lines
        check_replay(["replay", str(scene), "swipe-40mms-50hz", "--out", str(folder / "out"),
                      "--rate", "1000", "--quiet"], folder / "out")


@settings(max_examples=200, derandomize=True, deadline=None)
@given(index=st.integers(0, len(TRACES) - 1), changes=st.lists(mutation, min_size=1, max_size=3))
def test_mutated_traces_replay_cleanly(index, changes):
    source = TRACES[index]
    data = mutated(source, changes)
    with tempfile.TemporaryDirectory() as folder:
        trace = Path(folder) / source.name
        trace.write_bytes(data)
        out = Path(folder) / "out"
        check_replay(["replay", "grating-5mm", str(trace), "--out", str(out), "--rate", "1000",
                      "--quiet"], out)


def test_mutate_does_what_it_says():
    data = b"a = 1.5\nb = 2\n"
    assert mutate(data, "flip", 0.0, 0x20) == b"A = 1.5\nb = 2\n"
    assert mutate(data, "truncate", 0.5, 0) == b"a = 1.5"
    assert mutate(data, "duplicate", 0.0, 2) == b"a = 1.5\na = 1.5\na = 1.5\nb = 2\n"
    assert mutate(data, "delete", 0.9, 0) == b"a = 1.5\n"
    assert mutate(data, "number", 0.6, 4) == b"a = 1.5\nb = nan\n"
