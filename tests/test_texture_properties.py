"""Property tests: the key->line locator on generated TOML, and the parser on generated scenes."""

import math

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from frictex.textures.errors import Locator, field_name
from frictex.textures.loader import check_scene
from frictex.textures.model import auto_render_mode

# values whose text could fool a line scanner: brackets at the start of continuation
# lines, headers and "key = value" inside multi-line strings, '#' and '=' inside strings
VALUES = {
    "number": ["1.5"],
    "string": ['"a [b] = c # d"'],
    "literal": ["'x = [y]'"],
    "rows": ["[", "  [1, 2],", "  [3, 4],  # comment ]", "]"],
    "ml_string": ['"""', "[fake]", "x = 1", '\\"""still inside', '"""'],
    "ml_literal": ["'''", "[[fake]]", "'''"],
    "inline": ["{ a = 1, b = [2, 3] }"],
    "dotted": None,  # key.sub = 1
}


def emit(kind: str, key: str):
    """(lines, relative key path) for one key of the given kind."""
    if kind == "dotted":
        return [f"{key} . sub = 1"], (key, "sub")
    first, *rest = VALUES[kind]
    return [f"{key} = {first}"] + rest, (key,)


sections = st.lists(st.tuples(st.sampled_from(["table", "layer", "visual"]),
                              st.lists(st.sampled_from(sorted(VALUES)), max_size=4)), max_size=6)


@settings(max_examples=80, derandomize=True, deadline=None)
@given(top=st.lists(st.sampled_from(sorted(VALUES)), max_size=3), body=sections,
       blank=st.booleans())
def test_locator_finds_every_key(top, body, blank):
    import tomllib

    lines: list[str] = []
    expected = {}

    def add_keys(prefix, kinds):
        for i, kind in enumerate(kinds):
            text, rel = emit(kind, f"k{i}")
            expected[prefix + rel] = len(lines) + 1
            lines.extend(text)
            if blank:
                lines.append("")

    add_keys((), top)
    layers, visual_done = -1, set()
    for j, (kind, kinds) in enumerate(body):
        if kind == "table":
            prefix, header = (f"t{j}",), f"[ t{j} ]  # table"
        elif kind == "layer":
            layers += 1
            prefix, header = ("layer", layers), "[[layer]]"
        elif layers >= 0 and layers not in visual_done:
            visual_done.add(layers)
            prefix, header = ("layer", layers, "visual"), '[layer."visual"]'
        else:
            continue
        expected[prefix] = len(lines) + 1
        lines.append(header)
        add_keys(prefix, kinds)
    text = "\n".join(lines) + "\n"
    tomllib.loads(text)  # the generator writes valid TOML
    locator = Locator(text)
    for path, line in expected.items():
        assert locator.line(path) == line, (field_name(path), text)
    # keys inside values resolve to the line of the key holding them
    for path, line in expected.items():
        assert locator.line(path + ("inner", 3)) == line


HEAD = "format = 1\n[display]\nwidth_mm = 108.0\nheight_mm = 64.8\nwidth_px = 800\nheight_px = 480\n"
GRATING_LINES = {"period_mm": 9, "duty": 10, "mu_low": 11, "mu_high": 12, "angle_deg": 13, "offset_mm": 14}


def grating_text(values: dict) -> str:
    body = "".join(f"{key} = {values[key]!r}\n" for key in GRATING_LINES)
    return HEAD + '[[layer]]\ntype = "grating"\n' + body


grating_values = st.fixed_dictionaries({
    "period_mm": st.floats(0.01, 1e3),
    "duty": st.floats(0.0, 1.0, exclude_min=True, exclude_max=True),
    "mu_low": st.floats(0.0, 1.0, exclude_min=True),
    "mu_high": st.floats(0.0, 1.0, exclude_min=True),
    "angle_deg": st.floats(-360, 360),
    "offset_mm": st.floats(-1e3, 1e3),
}).map(lambda v: {**v, "mu_low": min(v["mu_low"], v["mu_high"]),
                  "mu_high": max(v["mu_low"], v["mu_high"])})


@settings(max_examples=60, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(values=grating_values)
def test_valid_gratings_load_exactly(tmp_path, values):
    path = tmp_path / "g.toml"
    path.write_text(grating_text(values), encoding="utf-8")
    scene, problems, _ = check_scene(path)
    assert problems == []
    g = scene.layers[0]
    assert {key: getattr(g, key) for key in GRATING_LINES} == values
    assert g.render == auto_render_mode(values["period_mm"])


bad_values = st.one_of(
    st.tuples(st.just("period_mm"), st.one_of(st.floats(max_value=0.01, exclude_max=True),
                                              st.floats(min_value=1e4, exclude_min=True))),
    st.tuples(st.just("angle_deg"), st.one_of(st.floats(max_value=-360, exclude_max=True),
                                              st.floats(min_value=360, exclude_min=True))),
    st.tuples(st.just("duty"), st.one_of(st.floats(max_value=0.0), st.floats(min_value=1.0))),
    st.tuples(st.just("mu_low"), st.one_of(st.floats(max_value=0.0), st.floats(min_value=1.0, exclude_min=True))),
    st.tuples(st.sampled_from(sorted(GRATING_LINES)), st.sampled_from([math.nan, math.inf, -math.inf])),
)


@settings(max_examples=60, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(values=grating_values, bad=bad_values)
def test_one_bad_value_gives_one_problem_at_its_line(tmp_path, values, bad):
    key, value = bad
    values = {**values, key: value}
    if key == "mu_low":
        values["mu_high"] = 1.0
    path = tmp_path / "g.toml"
    path.write_text(grating_text(values), encoding="utf-8")
    scene, problems, _ = check_scene(path)
    assert scene is None
    assert [(p.line, p.field) for p in problems] == [(GRATING_LINES[key], f"layer[1].{key}")]
