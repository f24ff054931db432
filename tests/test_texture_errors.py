"""Bad texture files: every problem named with file, line and field, never a traceback."""

import re
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from frictex.device.safe_text import escape
from frictex.textures.loader import check_scene

GOOD = """\
format = 1
name = "t"

[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480

[device]
amplitude_limit_um = 2.5
normal_force_n = 0.5

[[layer]]
type = "grating"
period_mm = 5.0
duty = 0.5
mu_low = 0.6
mu_high = 1.0
edge = "square"
region = { x_mm = 0, y_mm = 0, width_mm = 50, height_mm = 20 }

[[layer]]
type = "disc"
cx_mm = 60
cy_mm = 30
radius_mm = 10
mu = 0.7
[layer.visual]
color_low = "#000000"
"""
LINES = GOOD.splitlines()


def line_of(text: str) -> int:
    """1-based line of the first line of GOOD starting with ``text``."""
    return next(i for i, line in enumerate(LINES, 1) if line.startswith(text))


def check(tmp_path, text: str):
    path = tmp_path / "t.toml"
    path.write_text(text, encoding="utf-8")
    return check_scene(path)


def test_the_base_file_is_good(tmp_path):
    scene, problems, warnings = check(tmp_path, GOOD)
    assert scene is not None and problems == [] and warnings == []


# (line of GOOD to replace, replacement, expected line, field, message pattern)
CASES = [
    ("period_mm", "period_mm = -5.0", "period_mm", "layer[1].period_mm", r"^-5\.0 is outside \[0\.01, 10000\] \(mm\)$"),
    ("period_mm", "period_mm = 0", "period_mm", "layer[1].period_mm", r"^0 is outside \[0\.01, 10000\] \(mm\)$"),
    ("period_mm", "period_mm = 1e308", "period_mm", "layer[1].period_mm",
     r"^1e\+308 is outside \[0\.01, 10000\] \(mm\)$"),
    ("period_mm", "period_mm = 1e-300", "period_mm", "layer[1].period_mm",
     r"^1e-300 is outside \[0\.01, 10000\] \(mm\)$"),
    ("period_mm", "period_mm = inf", "period_mm", "layer[1].period_mm", r"^inf is not a finite number"),
    ("period_mm", "period_mm = nan", "period_mm", "layer[1].period_mm", r"^nan is not a finite number"),
    ("period_mm", "period_mm = nan", "period_mm", "layer[1].period_mm", r"nan is not a finite number"),
    ("period_mm", "period_mm = inf", "period_mm", "layer[1].period_mm", r"inf is not a finite number"),
    ("period_mm", 'period_mm = "5 mm"', "period_mm", "layer[1].period_mm",
     r'got the string "5 mm"; write the number without quotes or units: period_mm = 5$'),
    ("period_mm", "period_cm = 0.5", "period_mm", "layer[1].period_cm",
     r"unknown key \(did you mean period_mm\?\)"),
    ("period_mm", "period_mm = true", "period_mm", "layer[1].period_mm", r"expected a number \(mm\), got the boolean true"),
    ("period_mm", "# no period", "[[layer]]", "layer[1].period_mm", r"^missing \(required\)$"),
    ("mu_low", "mu_low = 1.2", "mu_low", "layer[1].mu_low", r"1\.2 is outside \(0, 1\] \(relative friction mu'\)"),
    ("mu_low", "mu_low = 0", "mu_low", "layer[1].mu_low", r"0 is outside \(0, 1\]"),
    ("mu_high", "mu_high = 0.5", "mu_low", "layer[1].mu_low", r"0\.6 is above mu_high 0\.5"),
    ("duty", "duty = 1", "duty", "layer[1].duty", r"1 is outside \(0, 1\)"),
    ("edge =", 'edge = "round"', "edge =", "layer[1].edge", r'"round" is not one of square, smooth'),
    ("edge =", 'edge = "smooth"', "edge =", "layer[1].edge", r'edge = "smooth" needs edge_mm > 0 .*got 0$'),
    ("edge =", 'edge = "smooth"\nedge_mm = 3', "edge =", "layer[1].edge_mm", r"3 mm is wider than the narrower band "
                                                                           r"\(2\.5 mm = min\(duty, 1 - duty\) x period_mm\)"),
    ("edge =", 'edge = "square"\nedge_mm = 1', "edge =", "layer[1].edge_mm", r'not used with edge = "square"'),
    ("type = \"grating\"", 'type = "gratin"', "type = \"grating\"", "layer[1].type",
     r'"gratin" is not one of .* \(did you mean grating\?\)'),
    ("type = \"disc\"", 'type = "disc"\nrender = "sht"', "type = \"disc\"", "layer[2].render",
     r'"sht" needs a periodic layer'),
    ("type = \"disc\"", 'type = "disc"\nrender = "fast"', "type = \"disc\"", "layer[2].render",
     r'"fast" is not one of auto, sho, .*sht'),
    ("type = \"disc\"", 'type = "disc"\nblend = "add"', "type = \"disc\"", "layer[2].blend",
     r'"add" is not one of multiply, replace'),
    ("type = \"disc\"", 'type = "disc"\nname = "grating-1"', "type = \"disc\"", "layer[2].name",
     r'"grating-1" is already the name of layer\[1\]'),
    ("cx_mm", "cx_mm = 130", "cx_mm", "layer[2].cx_mm", r"disc at x 120 to 140 mm, y 20 to 40 mm lies wholly off "
                                                  r"the display \(x 0 to 108 mm, y 0 to 64\.8 mm\)"),
    ("radius_mm", "radius_mm = 10\nedge_mm = 25", "radius_mm", "layer[2].edge_mm", r"more than the diameter"),
    ("region", "region = { x_mm = 110, y_mm = 0, width_mm = 50, height_mm = 20 }", "region",
     "layer[1].region", r"region at x 110 to 160 mm.* lies wholly off the display"),
    ("region", "region = { x_mm = 0, y_mm = 0, width_mm = 50, radius_mm = 20 }", "region",
     "layer[1].region", r"mixes rectangle keys \(x_mm, y_mm, width_mm\) and disc keys \(radius_mm\)"),
    ("region", "region = { x_mm = 0, y_mm = 0, width_mm = 50 }", "region",
     "layer[1].region.height_mm", r"missing \(required\)"),
    ("region", "region = 5", "region", "layer[1].region", r"expected a table"),
    ("color_low", 'color_low = "black"', "color_low", "layer[2].visual.color_low", r'expected a colour "#rrggbb"'),
    ("color_low", 'colour_low = "#000"', "color_low", "layer[2].visual.colour_low", r"did you mean color_low\?"),
    ("width_px", "width_px = 800.5", "width_px", "display.width_px", r"expected an integer \(px\), got the number 800\.5"),
    ("width_px", "width_px = 0", "width_px", "display.width_px", r"0 is outside \[1, 8192\] \(px\)"),
    ("width_px", "width_px = 100000000000000000000000000", "width_px", "display.width_px",
     r"^100000000000000000000000000 is outside \[1, 8192\] \(px\)$"),
    ("width_px", "width_px = 1e26", "width_px", "display.width_px",
     r"expected an integer \(px\), got the number 1e\+26"),
    ("height_mm", "height_mm = -64.8", "height_mm", "display.height_mm", r"-64\.8 is outside \[0\.001, 10000\] \(mm\)"),
    ("amplitude_limit_um", "amplitude_limit_um = 0", "amplitude_limit_um", "device.amplitude_limit_um",
     r"0 is outside \(0, 100\] \(um zero-to-peak\)"),
    ("amplitude_limit_um", 'profile = "beam"', "amplitude_limit_um", "device.profile",
     r'"beam" is not one of plate-seed003'),
    ("normal_force_n", "normal_force = 0.5", "normal_force_n", "device.normal_force",
     r"did you mean normal_force_n\?"),
    ("format", "format = 2", "format", "format", r"2 is newer than this frictex reads; this frictex reads format = 1"),
    ("format", "format = 0", "format", "format", r"0 is not a format"),
    ("format", 'format = "1"', "format", "format", r'expected an integer \(format version\), got the string "1"'),
    ("name", "name = 3", "name", "name", r"expected a string, got the number 3"),
    ("name", r'name = "a\u0000b"', "name", "name",
     r"^holds the control character '\\x00' at character 2; expected one line of text$"),
    ("name", 'name = "' + "n" * 201 + '"', "name", "name", r"^is 201 characters long; expected at most 200$"),
    ("name", 'nmae = "x"', "name", "nmae", r"did you mean name\?"),
]


@pytest.mark.parametrize("target, replacement, at, field, pattern", CASES,
                         ids=[f"{c[3]}:{c[1][:24]}" for c in CASES])
def test_bad_value_is_reported_at_its_line(tmp_path, target, replacement, at, field, pattern):
    index = line_of(target) - 1
    text = "\n".join(LINES[:index] + [replacement] + LINES[index + 1:]) + "\n"
    scene, problems, _ = check(tmp_path, text)
    assert scene is None
    matching = [p for p in problems if p.field == field]
    assert matching, [str(p) for p in problems]
    # the problem is on the replacement's line that sets the field, else on line ``at``
    key = field.split(".")[-1]
    added = [k for k, new in enumerate(replacement.split("\n")) if new.startswith(key + " ")]
    line = line_of(target) + added[0] if added else line_of(at)
    assert matching[0].line == line
    assert re.search(pattern, matching[0].message), matching[0].message
    assert str(matching[0]).startswith(f"{tmp_path / 't.toml'}:{line}: {field}: ")


def test_every_problem_is_collected(tmp_path):
    text = (GOOD.replace("period_mm = 5.0", "period_mm = -5.0")
            .replace("width_px = 800", "width_px = 0")
            .replace("mu = 0.7", "mu = 7"))
    scene, problems, _ = check(tmp_path, text)
    assert scene is None
    assert [(p.line, p.field) for p in problems] == [
        (line_of("width_px"), "display.width_px"), (line_of("period_mm"), "layer[1].period_mm"),
        (line_of("mu = 0.7"), "layer[2].mu")]


@pytest.mark.parametrize("text, line, field, pattern", [
    ("", None, "", r"^is empty; expected a texture file \(format = 1, \[display\], \[\[layer\]\]\)$"),
    ("# only a comment\n", None, "format", r"missing \(required\)"),
    ("format = 1\n", None, "display", r"missing \[display\] table"),
    ("format = 1\n[display\n", 2, "TOML syntax", r"Expected '\]' at the end of a table declaration \(column \d+\)"),
    ("format = 1\nx = \n", 2, "TOML syntax", r"Invalid value \(column 5\)"),
    # tomllib's messages with the line's number and text: a duplicate key, a value the
    # file ends in (tomllib: "at end of document"), an unclosed string (its '\n' escaped
    # once), a line with a terminal escape (shown escaped)
    ("format = 1\nformat = 1\n", 2, "TOML syntax", r"^Cannot overwrite a value \(column 11\): format = 1$"),
    ("format = 1\ngarbage = [", 2, "TOML syntax", r"^Invalid value \(at the end of the file\): garbage = \[$"),
    ("format = 1\n\ngarbage = [\n\n", 3, "TOML syntax", r"^Invalid value \(at the end of the file\): garbage = \[$"),
    ('format = 1\nname = "abc\n', 2, "TOML syntax", r"""^Illegal character '\\n' \(column 12\): name = "abc$"""),
    ('format = 1\nname = "\x1b[2J\n', 2, "TOML syntax", r"""^Illegal character '\\x1b' \(column 9\): name = "\\x1b\[2J$"""),
    # an array left open: placed where it opened (a bracket in a comment is no bracket),
    # with tomllib's stop (the line where the file went on, or its end) in the message
    ("format = 1\nsize = [80, 48\n\n[[layer]]\n", 2, "TOML syntax",
     r"^Unclosed array \(opened here; still open at line 4, column 1\): size = \[80, 48$"),
    ("format = 1\nrows = [[1, 2],\n  [3, 4] # ]\nb = 1\n", 2, "TOML syntax",
     r"^Unclosed array \(opened here; still open at line 4, column 1\): rows = \[\[1, 2\],$"),
    ("format = 1\na = [\n  1,\n  2\n", 2, "TOML syntax",
     r"^Unclosed array \(opened here; still open at the end of the file\): a = \[$"),
    ("format = 1\na = [1, 2\n", 2, "TOML syntax", r"^Unclosed array \(at the end of the file\): a = \[1, 2$"),
    ("format = 1\n[display]\nwidth_mm = 1\nheight_mm = 1\nwidth_px = 1\nheight_px = 1\n", None, "layer",
     r"no \[\[layer\]\] tables"),
    ("format = 1\n[display]\nwidth_mm = 1\nheight_mm = 1\nwidth_px = 1\nheight_px = 1\n[layer]\ntype = \"bump\"\n",
     7, "layer", r"expected \[\[layer\]\] tables \(an array of tables\), got a table"),
    ("format = 1\nlayer = 5\n", 2, "layer", r"expected \[\[layer\]\] tables"),
    ("format = 1\ndisplay = [1, 2]\n", 2, "display", r"expected a table, got the list \[1, 2\]"),
    ("format = 1\n[device]\n[device.calibration]\namplitudes_um = [0.5, 1]\nforces_n = [0.5]\nmu = [[1, 0.8]]\n",
     4, "device.calibration.amplitudes_um", r"starts at 0\.5, expected 0"),
    ("format = 1\n[device.calibration]\namplitudes_um = [0, 1]\nforces_n = [0.5, 0.4]\nmu = [[1, 0.8], [1, 0.9]]\n",
     4, "device.calibration.forces_n", r"\[0\.5, 0\.4\] is not strictly increasing"),
    ("format = 1\n[device.calibration]\namplitudes_um = [0, 1]\nforces_n = [0.5]\nmu = [[1, 0.8], [1, 0.9]]\n",
     5, "device.calibration.mu", r"has 2 rows, expected one per force \(1\)"),
    ("format = 1\n[device.calibration]\namplitudes_um = [0, 1]\nforces_n = [0.5]\nmu = [\n  [0.9, 0.8],\n]\n",
     5, "device.calibration.mu", r"row 1 starts at 0\.9, expected 1"),
    ("format = 1\n[device.calibration]\namplitudes_um = [0, 1]\nforces_n = [0.5]\nmu = [[1, 1.5]]\n",
     5, "device.calibration.mu[1][2]", r"1\.5 is outside \(0, 1\]"),
])
def test_file_level_problems(tmp_path, text, line, field, pattern):
    scene, problems, _ = check(tmp_path, text)
    assert scene is None
    matching = [p for p in problems if p.field == field]
    assert matching, [str(p) for p in problems]
    assert matching[0].line == line
    assert re.search(pattern, matching[0].message), matching[0].message


def test_unreadable_files(tmp_path):
    missing = tmp_path / "nope.toml"
    assert [str(p) for p in check_scene(missing)[1]] == [
        f"{missing}: No such file or directory; expected a .toml texture file"]
    assert [p.message for p in check_scene(tmp_path)[1]] == [
        "is a folder, not a file; expected a .toml texture file"]
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"format = 1\n\xff\xfe")
    assert [p.message for p in check_scene(binary)[1]] == [
        "not UTF-8 text (byte 0xff at offset 11); expected a .toml texture file"]


@pytest.mark.parametrize("content, pattern", [
    (b"not a png", r"9 bytes that do not start with the PNG signature, not a PNG"),
    (None, r"map\.png: No such file or directory; expected 8- or 16-bit greyscale PNG"),
])
def test_bad_raster_image(tmp_path, content, pattern):
    if content is not None:
        (tmp_path / "map.png").write_bytes(content)
    text = GOOD + '\n[[layer]]\ntype = "raster"\nimage = "map.png"\nwidth_mm = 10\nheight_mm = 10\nmu_black = 0.7\n'
    scene, problems, _ = check(tmp_path, text)
    assert scene is None
    assert [p.field for p in problems] == ["layer[3].image"]
    assert problems[0].line == len(LINES) + 4
    assert re.search(pattern, problems[0].message)


# ---------------------------------------------------------------------------
# Fuzz: mutate the good file; whatever happens, a result and never an exception

toml_values = st.one_of(
    st.integers(-10**6, 10**6).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(
        lambda f: {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(f), repr(f))),
    st.sampled_from(['"square"', '"sht"', '"#fff"', '"5 mm"', "true", "false", "[]", "[1, 2]",
                     "{ x_mm = 1 }", "[[1, 0.5]]", '""', "1979-05-27", '"map.png"']),
)


def _assert_well_formed(path, result):
    scene, problems, warnings = result
    assert (scene is None) == bool(problems)
    n_lines = len(path.read_bytes().splitlines())
    for p in problems + warnings:
        assert p.file == str(path) and p.message and "\n" not in str(p)
        assert p.line is None or 1 <= p.line <= max(n_lines, 1)


@settings(max_examples=150, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(index=st.integers(0, len(LINES) - 1), value=toml_values, delete=st.booleans())
def test_fuzz_one_value(tmp_path, index, value, delete):
    line = LINES[index]
    if delete:
        new = ""
    elif "=" in line and not line.startswith("region"):
        new = line.split("=")[0] + "= " + value
    else:
        new = line + " " + value
    path = tmp_path / "f.toml"
    path.write_text("\n".join(LINES[:index] + [new] + LINES[index + 1:]) + "\n", encoding="utf-8")
    _assert_well_formed(path, check_scene(path))


@settings(max_examples=100, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cut=st.integers(0, len(GOOD)), junk=st.binary(max_size=20))
def test_fuzz_truncated_and_junk(tmp_path, cut, junk):
    path = tmp_path / "g.toml"
    path.write_bytes(GOOD.encode()[:cut] + junk)
    _assert_well_formed(path, check_scene(path))


def test_problems_listed_per_file_are_bounded(tmp_path):
    text = GOOD + "".join(f"[t{i}]\n" for i in range(150))
    _, problems, _ = check(tmp_path, text)
    assert len(problems) == 101
    assert [p.field for p in problems[1:]] == [f"t{i}" for i in range(100)]
    assert str(problems[0]) == f"{tmp_path / 't.toml'}: more than 100 problems; the rest are not listed"


def test_dotted_keys_nest_at_most_16_deep(tmp_path):
    _, problems, _ = check(tmp_path, "a" + ".b" * 16 + " = 1\n" + GOOD)
    assert [(p.line, p.field) for p in problems] == [(1, "TOML syntax")]
    assert problems[0].message.startswith("arrays, inline tables or dotted keys nested more than 16")
    _, problems, _ = check(tmp_path, "a" + ".b" * 15 + " = 1\n" + GOOD)
    assert [(p.line, p.field) for p in problems] == [(1, "a")]  # 16 parts: only unknown


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.lists(st.sampled_from(['format = 1', 'a = [', 'b = "x', 'c = 1', 'c = 2', '[t]', '[t]',
                                 '[[u]', 'd = {', '"\x1b" = 3', 'e = 1e', '', '  ', 'f = "\\q"',
                                 "g = '\t\x07'"]), min_size=1, max_size=8))
def test_every_toml_syntax_error_is_one_printable_line_at_a_line_of_the_file(parts):
    """Whatever tomllib refuses: a line of the file (1 .. its last), the message one
    printable line ending with that line's text when it is not blank."""
    from frictex.textures.toml_safe import syntax_problem
    text = "\n".join(parts)
    try:
        tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        line, message = syntax_problem(str(exc), text)
    else:
        return
    lines = text.splitlines()
    assert line is not None and 1 <= line <= max(1, len(lines))
    assert message.isprintable()
    head = message.split(" (")[0]  # tomllib's own words: a character it quotes escaped once
    assert not re.search(r"\\\\[nrtx]|\\\\\\\\", head), head
    if line <= len(lines) and lines[line - 1].strip():
        assert message.endswith(": " + escape(lines[line - 1].strip()))
