"""Protocol files: the bundled ones load, the reference page is the parser's tables, every
bad input is one ProtocolError line naming file, line and field, and the scene files a
session writes read back as written."""

import re
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from frictex.app.commands.cli import main
from frictex.app.experiment import protocol_doc
from frictex.app.experiment.protocol import ProtocolError, check_protocol, load_protocol
from frictex.app.experiment.toml_text import toml_text
from frictex.device.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "app" / "experiment" / "PROTOCOL_FORMAT.md"
BUNDLED = sorted((ROOT / "app" / "experiment" / "protocols").glob("*.toml"))

GOOD = """format = 1
method = "2afc"
repetitions = 2

[stimuli]
scene = "grating-5mm"
vary = "period_mm"
reference = 5.0
levels = [5.5, 6.0]
"""


def write(tmp_path, text, name="p.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_the_page_is_the_parsers_tables():
    assert PAGE.read_text(encoding="utf-8") == protocol_doc.render(), (
        "PROTOCOL_FORMAT.md is stale: .venv/bin/python -m frictex.app.experiment.protocol_doc "
        "> app/experiment/PROTOCOL_FORMAT.md")


def test_the_page_and_the_parser_agree_that_vary_needs_a_reference(tmp_path):
    row = next(line for line in PAGE.read_text(encoding="utf-8").splitlines()
               if line.startswith("| `reference` |"))
    assert row.endswith("| *required* with `vary` |")
    text = GOOD.replace('method = "2afc"', 'method = "magnitude"').replace("reference = 5.0\n", "")
    with pytest.raises(ProtocolError, match=r"stimuli.reference: missing \(required with vary"):
        load_protocol(write(tmp_path, text))


def test_every_key_of_the_bundled_protocols_is_on_the_page():
    page = PAGE.read_text(encoding="utf-8")
    tables = {"stimuli", "stimulus", "presentation", "staircase", "scale", "analysis"}
    for path in BUNDLED:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
        keys = {k for k in doc} | {k for v in doc.values() if isinstance(v, dict) for k in v}
        keys |= {k for v in doc.values() if isinstance(v, list) for item in v
                 if isinstance(item, dict) for k in item}
        missing = [k for k in keys - tables if f"| `{k}` |" not in page]
        assert missing == [], f"{path.name}: {missing}"


def test_the_bundled_protocols_load():
    assert {p.stem for p in BUNDLED} >= {"seed003-gratings", "period-2afc", "depth-staircase"}
    methods = {load_protocol(p).method for p in BUNDLED}
    assert methods == {"magnitude", "2afc", "staircase"}


def test_seed003_protocol_is_the_seeds_design():
    """Seed 003 section 5: three periods, each with both strategies, rated 1 to 10; its
    SHO the position map at the last touch sample (held between samples)."""
    p = load_protocol(ROOT / "app" / "experiment" / "protocols" / "seed003-gratings.toml")
    periods = sorted({s.scene.stem for s in p.stimuli.listed})
    assert periods == ["grating-0.6mm", "grating-15mm", "grating-5mm"]
    assert {(s.scene.stem, s.renderer) for s in p.stimuli.listed} == {
        (f"grating-{period}", r) for period in ("0.6mm", "5mm", "15mm") for r in ("sho-held", "sht")}
    assert p.scale == (1, 10) and p.presentation.exploration == "free"
    assert p.presentation.show_scene  # the grating was on the screen as well


def test_a_good_file_parses_to_its_values(tmp_path):
    p = load_protocol(write(tmp_path, GOOD))
    assert (p.method, p.stimuli.vary, p.stimuli.reference, p.stimuli.levels) == (
        "2afc", "period_mm", 5.0, (5.5, 6.0))
    assert p.target == 0.75 and p.guess_rate == 0.5 and p.name == "p"
    assert p.presentation.show_scene is False  # a haptic study shows no picture
    shown = load_protocol(write(tmp_path, GOOD + "[presentation]\nshow_scene = true\n"))
    assert shown.presentation.show_scene is True
    for samples in (0, 200):  # 0: no intervals; 200: the fewest that give one
        text = GOOD + f"[analysis]\nbootstrap = {samples}\n"
        assert load_protocol(write(tmp_path, text)).analysis.bootstrap == samples


@pytest.mark.parametrize("change, line, field, words", [
    (('levels = [5.5, 6.0]', 'levels = [5.5, 4.0]'), 9, "stimuli.levels[2]", "not above the reference"),
    (('vary = "period_mm"', 'vary = "periods"'), 7, "stimuli.vary", "did you mean period_mm"),
    (('repetitions = 2', 'repetitions = 0'), 3, "repetitions", "outside [1, 1000]"),
    (('scene = "grating-5mm"', 'scene = "no-such-scene"'), 6, "stimuli.scene", "no such file"),
    (('reference = 5.0', 'reference = 0.001'), 8, "stimuli.reference", "period_mm"),
    (('method = "2afc"', 'method = "2AFC"'), 2, "method", "not one of"),
    (('format = 1', 'format = 2'), 1, "format", "format = 1"),
    (('levels = [5.5, 6.0]', 'levels = [5.5, 5.5]'), 9, "stimuli.levels", "twice"),
    (('[stimuli]', '[stimuli]\nlayer = "nope"'), 6, "stimuli.layer", "no layer 'nope'"),
    (('repetitions = 2', 'repetitions = 2\n[scale]\nmin = 1'), 4, "scale", "only for method"),
    (('repetitions = 2', 'repetitions = 2\n[presentation]\nshow_scene = "yes"'), 5,
     "presentation.show_scene", "expected true or false"),
    (('repetitions = 2', 'repetitions = 2\n[analysis]\nbootstrap = 199'), 5,
     "analysis.bootstrap", "at least 200, or 0 for no intervals"),
])
def test_bad_values_are_one_line_with_file_line_and_field(tmp_path, change, line, field, words):
    path = write(tmp_path, GOOD.replace(*change))
    with pytest.raises(ProtocolError) as err:
        load_protocol(path)
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:{line}: {field}: "), message
    assert words in message


def test_a_default_threshold_reversals_is_named_as_the_default(tmp_path):
    """The file has no threshold_reversals: the message must not read as if it had 8."""
    text = GOOD.replace('method = "2afc"', 'method = "staircase"').replace(
        "levels = [5.5, 6.0]\n", "") + "\n[staircase]\nstart = 1.0\nreversals = 6\n"
    with pytest.raises(ProtocolError, match=r"staircase.threshold_reversals: not in the file "
                                            r"\(default 8\), and more than the 6 reversals "
                                            r"the staircase stops after; set it to 6 or fewer$"):
        load_protocol(write(tmp_path, text))


def test_staircase_checks_its_table(tmp_path):
    text = GOOD.replace('method = "2afc"', 'method = "staircase"').replace(
        "levels = [5.5, 6.0]\n", "") + "\n[staircase]\nstart = 1.0\nreversals = 4\nthreshold_reversals = 6\n"
    with pytest.raises(ProtocolError, match=r":13: staircase.threshold_reversals: 6 is more than"):
        load_protocol(write(tmp_path, text))
    no_table = GOOD.replace('method = "2afc"', 'method = "staircase"').replace("levels = [5.5, 6.0]\n", "")
    with pytest.raises(ProtocolError, match=r"staircase: missing \[staircase\] table"):
        load_protocol(write(tmp_path, no_table))
    too_far = no_table + "\n[staircase]\nstart = 1.0\nmax = 20000\n"
    with pytest.raises(ProtocolError, match=r":12: staircase.max: "):
        load_protocol(write(tmp_path, too_far))


@pytest.mark.parametrize("table, problem", [
    # 100 errors in a row at 5 log10 units a step: far past the period's 10000 mm
    ("start = 1.0\nsteps = [5.0]\n", r":12: staircase.steps: the difference can reach 1e\+06 "
                                      r"within 100 trials.*outside \[0.01, 10000\].*max"),
    # linear: 1 + 2 * 5000 mm
    ('start = 1.0\nsteps = [2.0]\nscale = "linear"\nmax_trials = 5000\n',
     r":12: staircase.steps: the difference can reach 10001 within 5000 trials"),
    ("start = 1.0\nsteps = [5.0]\nmax = 100\n", None),  # bounded: every level is valid
    ("start = 1.0\nsteps = [2.0]\nmax_trials = 1\n", None),  # one step: at most 100 mm
])
def test_a_staircase_whose_steps_can_leave_the_valid_range_is_refused(tmp_path, table, problem):
    """Every difference a staircase can reach within max_trials is a valid stimulus, or
    the file is refused (a level out of range would stop the session midway)."""
    text = (GOOD.replace('method = "2afc"', 'method = "staircase"')
            .replace("levels = [5.5, 6.0]\n", "") + "\n[staircase]\n" + table)
    path = write(tmp_path, text)
    if problem is None:
        assert load_protocol(path).staircase.start == 1.0
        return
    with pytest.raises(ProtocolError, match=problem) as err:
        load_protocol(path)
    assert "\n" not in str(err.value)


SECRET = "root:x:0:0:root:/root:/bin/bash\n"


@pytest.mark.parametrize("scene, words", [
    ("../secret", "leads out of the folder through '..'"),
    ("/etc/passwd", "is an absolute path"),
    ("link.toml", "passes through a symbolic link to"),
])
def test_a_scene_outside_the_protocols_folder_is_refused(tmp_path, monkeypatch, scene, words):
    """A protocol names scenes as a texture file names its files: in its folder or below
    unless allowed; and a file that is not a .toml file never has a line quoted."""
    monkeypatch.delenv("FRICTEX_ALLOW_OUTSIDE", raising=False)
    (tmp_path / "secret").write_text(SECRET, encoding="utf-8")
    folder = tmp_path / "study"
    folder.mkdir()
    (folder / "link.toml").symlink_to(tmp_path / "secret")
    path = write(folder, GOOD.replace('"grating-5mm"', f'"{scene}"'))
    with pytest.raises(ProtocolError, match=f":6: stimuli.scene: .*{words}.*--allow-outside"):
        load_protocol(path)
    monkeypatch.setenv("FRICTEX_ALLOW_OUTSIDE", "1")
    with pytest.raises(ProtocolError) as err:
        load_protocol(path)
    assert "stimuli.scene" in str(err.value) and "root:" not in str(err.value)


def test_unreadable_and_broken_files(tmp_path):
    with pytest.raises(ProtocolError, match="TOML syntax"):
        load_protocol(write(tmp_path, "format = 1\nmethod = \n"))
    with pytest.raises(ProtocolError, match="is empty"):
        load_protocol(write(tmp_path, "\n"))
    with pytest.raises(ProtocolError, match="expected a protocol file"):
        load_protocol(tmp_path / "missing.toml")
    (tmp_path / "bin.toml").write_bytes(b"format = 1\x00")
    with pytest.raises(ProtocolError, match="NUL"):
        load_protocol(tmp_path / "bin.toml")


def test_every_problem_is_listed(tmp_path):
    text = GOOD.replace("repetitions = 2", "repetitions = -1\npractice = 1000")
    _, problems = check_protocol(write(tmp_path, text))
    assert [p.field for p in problems] == ["repetitions", "practice"]


def test_check_prints_every_problem_one_line_each(tmp_path, capsys):
    """--check lists every problem with its file, line and field, as frictex validate
    does; a run names the first and points at --check for the rest."""
    bad = write(tmp_path, BAD_THREE)
    assert main(["experiment", str(bad), "--check"]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(": ")[2:4] for line in lines] == [
        [f"{bad}:3", "repetitions"], [f"{bad}:8", "stimuli.levels[1]"],
        [f"{bad}:10", "analysis.target"]]
    assert all(line.startswith("frictex: error: ") and "more problem" not in line
               for line in lines)
    with pytest.raises(ProtocolError, match=r"\(and 2 more problems; frictex experiment .*"
                                            r"p\.toml --check lists them all\)$"):
        load_protocol(bad)


BAD_THREE = """format = 1
method = "2afc"
repetitions = 0
[stimuli]
scene = "grating-5mm"
vary = "period_mm"
reference = 5.0
levels = [4.5, 5.5]
[analysis]
target = 1.2
"""


#: a value as TOML text: odd literals, and any finite value written by toml_text
_VALUES = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "1e400", '"5 mm"', "[1, 2]", "{a = 1}", "true",
                     '"grating-0.6mm"', '"staircase"', "[]", "0", "-0.0", '""']),
    st.one_of(st.integers(-10**20, 10**20), st.floats(allow_nan=False, allow_infinity=False),
              st.text(max_size=12), st.booleans(), st.lists(st.floats(-10, 10), max_size=3)
              ).map(lambda v: toml_text({"v": v}).split(" = ", 1)[1].strip()))
_LINES = GOOD.splitlines()


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(index=st.integers(0, len(_LINES) - 1), value=_VALUES, drop=st.booleans())
def test_any_mutation_is_a_protocol_or_an_input_error(tmp_path, index, value, drop):
    """A line's value replaced by any value, or the line dropped: a protocol, or one error
    line naming the file."""
    lines = list(_LINES)
    key = lines[index].split("=")[0].strip() if "=" in lines[index] else "extra"
    lines[index] = "" if drop else f"{key} = {value}"
    path = write(tmp_path, "\n".join(lines) + "\n")
    try:
        load_protocol(path)
    except InputError as exc:
        assert "\n" not in str(exc) and str(exc).startswith(str(path))


_KEYS = st.text(st.characters(codec="utf-8", exclude_categories=("Cs",)), min_size=1, max_size=8)
_SCALARS = st.one_of(st.booleans(), st.integers(-2**63, 2**63 - 1),
                     st.floats(allow_nan=False, allow_infinity=False),
                     st.text(st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=10))
_DOCS = st.recursive(st.dictionaries(_KEYS, _SCALARS, max_size=4),
                     lambda inner: st.dictionaries(_KEYS, st.one_of(
                         _SCALARS, inner, st.lists(_SCALARS, max_size=3),
                         st.lists(inner, min_size=1, max_size=2)), max_size=4), max_leaves=12)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(_DOCS)
def test_toml_text_reads_back_as_written(doc):
    assert tomllib.loads(toml_text(doc)) == doc


@pytest.mark.parametrize("table, problem", [
    # 1.0 - 0.5 per two correct answers reaches 0 on the second down step
    ('start = 1.0\nsteps = [0.5]\nscale = "linear"\n',
     r":12: staircase.steps: the difference can reach -24 within 100 trials \(steps up to "
     r"0.5\): not above 0.*\[staircase\] min"),
    ('start = 1.0\nsteps = [0.5]\nscale = "linear"\nmin = 0.1\n', None),
    ('start = 1.0\nsteps = [0.5]\nscale = "linear"\nmax_trials = 3\n', None),  # one down step
])
def test_a_linear_staircase_that_can_step_to_zero_is_refused(tmp_path, table, problem):
    """A linear staircase without min that can step to a difference of 0 or below is
    refused at load (and --check) with file:line: field, not left to sit at a floor."""
    text = (GOOD.replace('method = "2afc"', 'method = "staircase"')
            .replace("levels = [5.5, 6.0]\n", "") + "\n[staircase]\n" + table)
    path = write(tmp_path, text)
    if problem is None:
        assert load_protocol(path).staircase.scale == "linear"
        return
    with pytest.raises(ProtocolError, match=problem):
        load_protocol(path)
    _, problems = check_protocol(path)
    assert len(problems) == 1 and re.search(problem, str(problems[0]))


def test_a_scene_name_missing_beside_the_protocol_never_reads_the_current_folders_file(
        tmp_path, monkeypatch):
    """A stranger's protocol naming secret.toml, which is not in its folder: a scene file
    of that name where frictex runs is not read (it was, and the check passed)."""
    study, here = tmp_path / "study", tmp_path / "here"
    study.mkdir()
    here.mkdir()
    (here / "secret.toml").write_text((ROOT / "textures" / "library" / "grating-5mm.toml")
                                      .read_text(encoding="utf-8"), encoding="utf-8")
    protocol = study / "p.toml"
    protocol.write_text('format = 1\nmethod = "2afc"\n[stimuli]\nscene = "secret.toml"\n'
                        'vary = "period_mm"\nreference = 5.0\nlevels = [5.5, 6.5]\n',
                        encoding="utf-8")
    monkeypatch.chdir(here)
    found, problems = check_protocol(protocol)
    assert found is None and [str(p) for p in problems] == [
        f"{protocol}:4: stimuli.scene: secret.toml: no such file, and no bundled scene of "
        "that name (frictex library lists them)"]
