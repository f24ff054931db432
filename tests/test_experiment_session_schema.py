"""session.json read as a stranger's file: every key a reader uses is checked where the file
is read, with the protocol's bounds, into one line naming the file, the key and what was
expected (before, one field changed in a period-2afc session gave a traceback, exit 70,
or a wrong analysis with exit 0)."""

import json
import math
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.app.commands.cli import main
from frictex.app.experiment import psychometric, same_different
from frictex.app.experiment.analysis import analyse
from frictex.device.errors import InputError
from test_experiment_analysis import BUNDLED, SAME_DIFFERENT, SIM

DELETED = object()  # the field left out


@pytest.fixture(scope="module")
def bases(tmp_path_factory):
    """A session of each method, as this frictex writes it (results only)."""
    root = tmp_path_factory.mktemp("bases")
    (root / "sd.toml").write_text(SAME_DIFFERENT)
    out = {}
    for name, protocol in (("2afc", BUNDLED / "period-2afc.toml"),
                           ("staircase", BUNDLED / "depth-staircase.toml"),
                           ("magnitude", BUNDLED / "seed003-gratings.toml"),
                           ("same-different", root / "sd.toml")):
        out[name] = root / name
        assert main(["experiment", str(protocol), "--participant", f"{SIM},seed=1", "--seed", "1",
                     "--out", str(out[name]), "--record", "results", "--quiet"]) == 0
    return out


def changed(base: Path, folder: Path, path: tuple, value) -> Path:
    """A copy of the session ``base`` in ``folder`` with session.json's field at ``path``
    set to ``value`` (or left out: :data:`DELETED`)."""
    shutil.copytree(base, folder)
    info = json.loads((base / "session.json").read_text())
    inner = info
    for key in path[:-1]:
        inner = inner[key]
    if value is DELETED:
        del inner[path[-1]]
    else:
        inner[path[-1]] = value
    (folder / "session.json").write_text(json.dumps(info))
    return folder


@pytest.mark.parametrize("path, value, said", [
    (("parts",), [None], "parts[1]: expected a table {...}, got None"),
    (("method",), ["2afc"], 'method: expected one of 2afc, staircase, same-different, '
                            'magnitude, got the list ["2afc"]'),
    (("design", "analysis", "lapse_max"), None,
     "design.analysis.lapse_max: expected a number (proportion), got None"),
    (("design", "reference"), {}, "design.reference: expected a number (units of `vary`), "
                                  "got a table"),
    (("design", "analysis"), 5.0, "design.analysis: expected a table, got the number 5.0"),
    (("design", "vary"), DELETED, "design.vary: missing (required)"),
    (("participant_id",), [1], "participant_id: expected a plain name"),
    (("started_utc",), {}, "started_utc: expected a time (ISO 8601"),
    (("design", "analysis", "lapse_max"), -1, "design.analysis.lapse_max: -1 is outside "
                                              "[0, 0.2] (proportion)"),
    (("design", "analysis", "bootstrap"), 100_000_000,
     "design.analysis.bootstrap: 100000000 is outside [0, 100000]"),
    (("design", "analysis", "bootstrap"), 1e9, "design.analysis.bootstrap: expected an integer"),
    (("design", "analysis", "bootstrap"), -5, "design.analysis.bootstrap: -5 is outside "
                                              "[0, 100000]"),
    (("design", "analysis", "bootstrap"), 50, "design.analysis.bootstrap: 50 samples are too "
                                              "few"),
    (("design", "reference"), math.nan, "design.reference: nan is not a finite number"),
    (("design", "staircase"), {"start": 1.0}, 'design.staircase: only for method "staircase"'),
    (("design", "target"), 0.95, "design.target: 0.95 is not below 1 - lapse_max (0.94)"),
    (("participant_seed",), -1, "participant_seed: -1 is outside [0, 9223372036854775807]"),
])
def test_a_bad_field_is_one_line_naming_it(bases, tmp_path, capsys, path, value, said):
    """The fuzzed period-2afc session of each case: a traceback (parts, method,
    lapse_max null, reference {}, analysis 5.0, no vary, participant_id, started_utc) or
    a wrong analysis (lapse_max -1: 'lapse -0.500' fitted; bootstrap 1e8: unbounded, -5:
    'no interval'; reference NaN: no check of difference == value - reference)."""
    folder = changed(bases["2afc"], tmp_path / "s", path, value)
    assert main(["experiment", "analyse", str(folder), "--no-plot"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{folder / 'session.json'}: {said}" in err, err
    assert not (folder / "analysis").exists()  # refused before any work


def test_a_resumed_session_with_a_bad_participant_seed_is_one_line(bases, tmp_path, capsys):
    """--resume of the session cut to 59 trials, its participant_seed [1]: a TypeError in
    the simulated participant before."""
    folder = changed(bases["2afc"], tmp_path / "s", ("participant_seed",), [1])
    lines = (folder / "results.csv").read_text().splitlines(keepends=True)
    (folder / "results.csv").write_text("".join(lines[:1 + 59]))
    assert main(["experiment", "period-2afc", "--out", str(folder), "--resume", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and (f"{folder / 'session.json'}: participant_seed: expected "
                                     f"an integer (random seed), got the list [1]") in err
    assert len((folder / "results.csv").read_text().splitlines()) == 1 + 59


def test_a_session_this_frictex_wrote_is_analysed(bases, tmp_path):
    summaries = analyse(list(bases.values()), tmp_path / "out", plot=False)
    assert sorted(s["method"] for s in summaries) == sorted(bases)


def _fields(value, path=()):
    """The path of every field under ``value`` (a JSON object or list)."""
    items = value.items() if isinstance(value, dict) else enumerate(value)
    for key, inner in items:
        yield path + (key,)
        if isinstance(inner, (dict, list)):
            yield from _fields(inner, path + (key,))


SCALARS = (st.none() | st.booleans() | st.integers() | st.floats()
           | st.text(st.characters(exclude_categories=()), max_size=8))
JSON = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=3)
                    | st.dictionaries(st.text(max_size=4), inner, max_size=3), max_leaves=6)


def _no_draws(monkeypatch):
    """The fits and d' intervals with no bootstrap draws, whatever count session.json
    gives (a valid count up to 100,000 only costs time; what is read does not change)."""
    for module, name in ((psychometric, "fit"), (psychometric, "fit_adaptive"),
                         (same_different, "d_prime_interval")):
        real = getattr(module, name)
        if name == "d_prime_interval":
            monkeypatch.setattr(module, name, lambda *a, real=real: real(*a[:-1], 0))
        else:
            monkeypatch.setattr(module, name, lambda *a, real=real, **k: real(
                *a, **{**k, "bootstrap": 0}))


@pytest.fixture(scope="module")
def infos(bases):
    return {method: json.loads((folder / "session.json").read_text())
            for method, folder in bases.items()}


@settings(max_examples=150)
@given(data=st.data())
def test_any_value_in_any_field_is_an_analysis_or_one_line(bases, infos, data):
    """Any JSON value (or none) in any one field of a valid session.json: a normal
    analysis or an InputError of one line, never another exception."""
    method = data.draw(st.sampled_from(sorted(bases)), label="method")
    path = data.draw(st.sampled_from(list(_fields(infos[method]))), label="field")
    value = data.draw(JSON | st.just(DELETED) if isinstance(path[-1], str) else JSON,
                      label="value")
    with tempfile.TemporaryDirectory() as tmp, pytest.MonkeyPatch.context() as mp:
        _no_draws(mp)
        folder = changed(bases[method], Path(tmp) / "s", path, value)
        try:
            analyse([folder], Path(tmp) / "out", plot=False)
        except InputError as exc:
            assert "\n" not in str(exc)
