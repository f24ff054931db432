"""``frictex validate`` loads the plugin renderers a file's layers name, as a replay does:
one that cannot be loaded is a problem of that layer (exit 2), not ``ok`` and then a
replay's failure."""

from test_plugins import FRICTEX, fake_distribution, run

GRATING = """format = 1
name = "{name}"

[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480

[[layer]]
type = "grating"
period_mm = 2.0
mu_low = 0.9

[[layer]]
name = "lines"
type = "grating"
period_mm = 5.0
mu_low = 0.9
render = "{render}"
"""


def test_a_layer_naming_a_renderer_that_cannot_be_loaded_is_a_problem(tmp_path):
    """The entry point's module is there but not its object (AttributeError), or the
    module is not there (ModuleNotFoundError)."""
    site = fake_distribution(tmp_path / "site", "frictex-test-gone", """
        [frictex.renderers]
        no-object = frictex_test_gone:Nope
        no-module = frictex_test_no_such_module:Nope
        """)
    (site / "frictex_test_gone.py").write_text("WOBBLE = 1\n", encoding="utf-8")
    good = tmp_path / "good.toml"
    good.write_text(GRATING.format(name="good", render="sht"), encoding="utf-8")
    files = [str(good)]
    for render in ("no-object", "no-module"):
        files.append(str(tmp_path / f"{render}.toml"))
        (tmp_path / f"{render}.toml").write_text(GRATING.format(name=render, render=render),
                                                 encoding="utf-8")
    done = run([str(FRICTEX), "validate", *files], site, tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stdout.splitlines() == [f"ok {good} (2 layers)"]
    assert done.stderr.splitlines() == [
        f'frictex: error: {files[1]}:20: layer[2].render: "lines": renderer \'no-object\' of '
        "frictex-test-gone (frictex_test_gone:Nope) cannot be loaded: AttributeError: module "
        "'frictex_test_gone' has no attribute 'Nope'",
        f'frictex: error: {files[2]}:20: layer[2].render: "lines": renderer \'no-module\' of '
        "frictex-test-gone (frictex_test_no_such_module:Nope) cannot be loaded: "
        "ModuleNotFoundError: No module named 'frictex_test_no_such_module'",
        "frictex: error: 2 of 3 files have problems"]
