"""Extension points by registry: another package adds a renderer, an output device, or a
device profile and its actuation, with one module and one entry-point line each, and
frictex's command line, texture files and Python API take them.

The plugin is a real distribution (pyproject.toml and one module) built and installed by
pip into a folder of this test (``--target``, no network: ``--no-index
--no-build-isolation``); the runs that use it are subprocesses with that folder on their
path, so nothing of it reaches this process or any other test, and nothing is left to
uninstall. The registries themselves (``device.registry``) are tested in this process.
"""

import csv
import json
import os
import re
import subprocess
import sys
import textwrap
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import pytest

from frictex.device.registry import PluginError, Registry, UnknownName
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.renderers import LAYER_RENDERERS, RENDERERS, LayerRenderer, render_modes
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

#: the plugin's renderer: mu' = WOBBLE_MU under every finger, wherever the layer is
WOBBLE_MU = 0.625
PLUGIN = {
    "pyproject.toml": """
        [build-system]
        requires = ["setuptools>=70.1"]
        build-backend = "setuptools.build_meta"

        [project]
        name = "frictex-test-wobble"
        version = "1.0"

        [project.entry-points."frictex.renderers"]
        wobble = "frictex_test_wobble:Wobble"
        short = "frictex_test_wobble:Short"
        unset = "frictex_test_wobble:Unset"
        unbuilt = "frictex_test_wobble:Unbuilt"

        [project.entry-points."frictex.profiles"]
        wobble-plate = "frictex_test_wobble:PLATE"

        [project.entry-points."frictex.actuations"]
        wobble-channel = "frictex_test_wobble:one_channel"

        [project.entry-points."frictex.devices"]
        tally = "frictex_test_wobble:open_tally"

        [tool.setuptools]
        py-modules = ["frictex_test_wobble"]
        """,
    "frictex_test_wobble.py": f"""
        import numpy as np

        from frictex.device.actuation.base import SingleModeActuation
        from frictex.device.profile import ProfileSpec

        PLATE = ProfileSpec("a one-channel plate of a test plugin", "wobble-channel")


        class OneChannel(SingleModeActuation):
            channels = ("wobble",)


        def one_channel(device):
            return OneChannel()


        class Tally:
            # an output device that writes the sum of every amplitude it is sent to the
            # file its ARG names when it closes (the OutputDevice contract, no hardware)

            info = None

            def __init__(self, path, request):
                self.label = "tally"
                self.channels, self.rate_hz = request.channels, request.rate_hz
                self.paced, self.path = request.paced, path
                self.sent, self.total, self.next = 0, 0.0, 0

            def send(self, start_index, amplitudes_um, phases_rad=None):
                assert start_index == self.next  # in order, without gaps
                self.next += len(amplitudes_um)
                self.sent += len(amplitudes_um)
                self.total += float(np.sum(amplitudes_um))

            def wait_for_room(self, timeout_s):
                return True

            def status(self):
                return {{"state": "tally", "commanded_samples": self.sent,
                        "unplayed_samples": 0, "unplayed_by_cause": {{}}}}

            def unplayed_share(self):
                return 0.0

            def device_force_n(self):
                return None

            def force_report(self, index0=None, n=None):
                return None

            def forces_covered(self, index0, n):
                return np.zeros(0), np.zeros(0)

            def close(self):
                with open(self.path, "w") as fh:
                    fh.write(f"{{self.sent}} {{self.total!r}}")

            def __enter__(self):
                return self

            def __exit__(self, *exc):
                self.close()


        def open_tally(arg, request):
            return Tally(arg, request)


        class Wobble:
            def __init__(self, layer, rate_hz):
                self.layer = layer

            def initial_state(self):
                return 0

            def render(self, block, state):
                mu, covers = self.layer.mu_and_covers(block.x_pred, block.y_pred)
                return np.full(mu.shape, {WOBBLE_MU!r}), covers, state + 1


        class Short(Wobble):  # one sample short: frictex would fail broadcasting it
            def render(self, block, state):
                mu, covers, state = super().render(block, state)
                return mu[:, :-1], covers[:, :-1], state


        class Unset(Wobble):  # NaN, which frictex would write as the target
            def render(self, block, state):
                mu, covers, state = super().render(block, state)
                return mu * np.nan, covers, state


        class Unbuilt(Wobble):
            def __init__(self, layer, rate_hz):
                raise RuntimeError("no calibration table for this layer")
        """,
}
FRICTEX = Path(sys.executable).with_name("frictex")


@pytest.fixture(scope="module")
def plugin_path(tmp_path_factory) -> Path:
    """A folder holding the installed plugin (its module and its dist-info)."""
    source = tmp_path_factory.mktemp("plugin-source")
    for name, text in PLUGIN.items():
        (source / name).write_text(textwrap.dedent(text).lstrip(), encoding="utf-8")
    target = tmp_path_factory.mktemp("plugin-installed")
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                           "--no-index", "--no-build-isolation", "--disable-pip-version-check",
                           "--target", str(target), str(source)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (target / "frictex_test_wobble.py").is_file()
    return target


def run(args: list[str], plugin: Path | None, cwd: Path, timeout: float = 300):
    """``args`` in a fresh process, with the plugin's folder on its path if given."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if plugin is not None:
        env["PYTHONPATH"] = str(plugin)
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout, cwd=cwd,
                          env=env)


def mu_targets(folder: Path) -> list[float]:
    with open(folder / "friction.csv", newline="", encoding="utf-8") as fh:
        return [float(row["mu_target"]) for row in csv.DictReader(fh)]


def test_replay_renders_with_a_plugins_renderer(plugin_path, tmp_path):
    listed = run([str(FRICTEX), "replay", "--help"], plugin_path, tmp_path)
    assert listed.returncode == 0 and "wobble" in listed.stdout
    out = tmp_path / "wobble"
    done = run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out),
                "--renderer", "wobble", "--quiet"], plugin_path, tmp_path)
    assert done.returncode == 0, done.stderr
    mu = mu_targets(out)
    assert len(mu) > 1000 and set(mu) == {WOBBLE_MU}
    # the same replay with frictex's own renderer is not the plugin's
    own = tmp_path / "sht"
    assert run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(own),
                "--renderer", "sht", "--quiet"], plugin_path, tmp_path).returncode == 0
    assert WOBBLE_MU not in set(mu_targets(own))


@pytest.mark.parametrize("name, message", [
    ("short", "returned mu' of shape (1, 99) on layer 'lines'; expected (1, 100) (1 finger(s) "
              "x 100 samples)"),
    ("unset", "returned 100 mu' values that are not finite (NaN or inf) on layer 'lines', "
              "where it covers"),
    ("unbuilt", "failed building layer 'lines': RuntimeError: no calibration table for this "
                "layer"),
])
def test_a_plugins_renderer_that_breaks_its_contract_is_named_not_frictex(plugin_path,
                                                                        tmp_path, name,
                                                                        message):
    """A plugin's renderer raising, or returning what frictex would fail on (a short
    block) or write (NaN), fails the run naming the plugin and the layer: exit 1, one
    line, no outputs; never frictex's internal error (exit 70) or NaN in friction.csv."""
    out = tmp_path / name
    done = run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out),
                "--renderer", name, "--quiet"], plugin_path, tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"frictex: error: renderer {name!r} of frictex-test-wobble (frictex_test_wobble:"
        f"{name.capitalize()}) {message}"]
    assert not out.exists()


def test_without_the_plugin_its_name_is_an_error_listing_the_known(tmp_path):
    done = run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out",
                str(tmp_path / "o"), "--renderer", "wobble"], None, tmp_path)
    assert done.returncode == 2
    assert "invalid choice: 'wobble'" in done.stderr and "'sho-held'" in done.stderr
    assert not (tmp_path / "o").exists()


PYTHON_USE = """
import json, sys
import numpy as np
import frictex
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.renderers import RENDERERS

run = frictex.replay("grating-5mm", "swipe-40mms-50hz", renderer="wobble")
mu = run.friction.column("mu_target").to_numpy()
scene = frictex.load_scene(sys.argv[1])  # a texture file whose layer names the plugin's
pipeline = build_pipeline(scene)               # renderer
print(json.dumps({"origin": RENDERERS.origin("wobble"), "rows": int(mu.size),
                  "values": sorted(set(mu.tolist())),
                  "renderer": [type(r).__name__ for r in (pipeline.renderers[0],
                                                          pipeline.renderers[0].inner)]}))
"""


def test_the_python_api_and_texture_files_take_a_plugins_renderer(plugin_path, tmp_path):
    text = Path(resolve_scene("grating-5mm")).read_text(encoding="utf-8")
    assert text.count('render = "auto"') == 1
    scene = tmp_path / "wobbly.toml"
    scene.write_text(text.replace('render = "auto"', 'render = "wobble"'), encoding="utf-8")
    done = run([sys.executable, "-c", PYTHON_USE, str(scene)], plugin_path, tmp_path)
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout.splitlines()[-1])
    assert got["origin"] == "frictex-test-wobble (frictex_test_wobble:Wobble)"
    assert got["rows"] > 1000 and got["values"] == [WOBBLE_MU]
    assert got["renderer"] == ["PluginRenderer", "Wobble"]  # wrapped: its errors name it


DEVICE_USE = """
import sys
import frictex
run = frictex.replay("grating-5mm", "swipe-40mms-50hz", device="tally:" + sys.argv[1])
print(run.summary.to_dict()["device"]["state"], run.commands.num_rows)
"""


def test_replay_and_the_python_api_stream_to_a_plugins_output_device(plugin_path, tmp_path):
    own = tmp_path / "own"
    assert run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(own),
                "--quiet"], None, tmp_path).returncode == 0
    with open(own / "commands.csv", newline="", encoding="utf-8") as fh:
        commanded = [float(row[1]) for row in list(csv.reader(fh))[1:]]
    tally = tmp_path / "tally.txt"
    done = run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out",
                str(tmp_path / "out"), "--device", f"tally:{tally}", "--quiet"],
               plugin_path, tmp_path)
    assert done.returncode == 0, done.stderr
    sent, total = tally.read_text().split()
    # every commanded sample reached the plugin's device, the same amplitudes (the CSV
    # prints 6 decimals: each sample within 0.5e-6 um)
    assert int(sent) == len(commanded)
    assert float(total) == pytest.approx(sum(commanded), abs=0.5e-6 * len(commanded))
    tally.unlink()
    done = run([sys.executable, "-c", DEVICE_USE, str(tally)], plugin_path, tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["tally", str(len(commanded))]
    assert int(tally.read_text().split()[0]) == len(commanded)
    refused = run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out",
                   str(tmp_path / "o2"), "--device", f"tally:{tally}"], None, tmp_path)
    assert refused.returncode == 2 and "sim" in refused.stderr


def test_a_plugins_device_profile_drives_its_actuation(plugin_path, tmp_path):
    text = Path(resolve_scene("grating-5mm")).read_text(encoding="utf-8")
    assert text.count('profile = "plate-seed003"') == 1
    scene = tmp_path / "wobble-plate.toml"
    scene.write_text(text.replace('profile = "plate-seed003"', 'profile = "wobble-plate"'),
                     encoding="utf-8")
    assert run([str(FRICTEX), "validate", str(scene)], plugin_path, tmp_path).returncode == 0
    out = tmp_path / "out"
    done = run([str(FRICTEX), "replay", str(scene), "swipe-40mms-50hz", "--out", str(out),
                "--quiet"], plugin_path, tmp_path)
    assert done.returncode == 0, done.stderr
    own = tmp_path / "own"
    assert run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(own),
                "--quiet"], None, tmp_path).returncode == 0
    lines = (out / "commands.csv").read_text(encoding="utf-8").splitlines()
    assert lines[0] == "t_s,wobble_um"  # the plugin's channel, the same commands
    assert lines[1:] == (own / "commands.csv").read_text(encoding="utf-8").splitlines()[1:]
    refused = run([str(FRICTEX), "validate", str(scene)], None, tmp_path)
    assert refused.returncode == 2 and "is not one of plate-seed003" in refused.stderr


def test_frictexs_own_renderers_come_from_its_entry_points():
    """The installed metadata lists what pyproject.toml declares (a stale editable install
    would not), each loads, and each is frictex's own."""
    import tomllib
    root = Path(__file__).resolve().parents[1]
    declared = tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))
    points = declared["project"]["entry-points"]
    for registry in (RENDERERS, LAYER_RENDERERS):
        names = sorted(points[registry.group])
        assert sorted(n for n in registry.names() if registry.origin(n) == "frictex") == names
        for name in names:
            assert callable(registry.get(name))
    grating = load_scene(resolve_scene("grating-5mm")).layers[0]
    for name in RENDERERS.names():
        assert isinstance(RENDERERS.get(name)(grating, 10_000.0), LayerRenderer)
    assert render_modes()[0] == "sho" and set(render_modes()[1:]) >= {"sho-held", "sht"}


def test_an_unknown_renderer_lists_the_known():
    scene = load_scene(resolve_scene("grating-5mm"))
    with pytest.raises(UnknownName, match=r"unknown renderer 'wobble'; expected one of sho, "
                                          r".*sho-held.*sht"):
        build_pipeline(scene, render_override="wobble")
    with pytest.raises(UnknownName, match="SHO variant|unknown renderer"):
        build_pipeline(scene, sho_variant="nope")
    with pytest.raises(ValueError, match="expected a renderer of any layer, one of "
                                         "sho-held, sho-predicted"):
        build_pipeline(scene, sho_variant="sht")


def test_an_unknown_dynamic_layer_kind_is_an_error_not_a_clip():
    """A layer whose renderer_kind nobody registered became a clip renderer, silently."""
    scene = load_scene(resolve_scene("grating-5mm"))
    stranger = SimpleNamespace(name="stranger", renderer_kind="ripple", is_periodic=False,
                               blend="multiply", fingers="any")
    with pytest.raises(UnknownName, match="unknown dynamic layer kind 'ripple'; expected one "
                                          "of ar, clip, height"):
        build_pipeline(replace(scene, layers=(stranger,)))


def test_a_registry_refuses_a_second_entry_under_a_name_and_bad_names():
    registry: Registry = Registry("gadget", "frictex.test-gadgets-none")
    registry.register("one", len)

    @registry.register("two")
    def two(x):
        return x

    assert registry.names() == ("one", "two") and registry.get("two") is two
    registry.register("one", len)  # the same entry again: no clash
    with pytest.raises(PluginError, match="gadget 'one' from frictex is already registered by "
                                          "frictex"):
        registry.register("one", abs)
    for bad in ("", " x", "a:b", 3):
        with pytest.raises(PluginError, match="expected a non-empty name"):
            registry.register(bad, abs)
    with pytest.raises(UnknownName, match="unknown gadget 'three'; expected one of one, two"):
        registry.get("three")
    assert "one" in registry and "three" not in registry and 3 not in registry
    assert registry.origin("two") == "frictex" and list(registry) == ["one", "two"]


def test_a_broken_plugin_names_itself(tmp_path):
    """An entry point that cannot be imported is a PluginError naming the distribution."""
    dist = tmp_path / "frictex_test_broken-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: frictex-test-broken\n"
                                   "Version: 1.0\n", encoding="utf-8")
    (dist / "entry_points.txt").write_text("[frictex.test-broken]\nbad = no_such_module_x:Thing\n",
                                           encoding="utf-8")
    sys.path.insert(0, str(tmp_path))
    try:
        registry: Registry = Registry("gadget", "frictex.test-broken")
        assert "bad" in registry  # installed after the metadata was first read: read again
        assert registry.names() == ("bad",)  # listed without importing it
        with pytest.raises(PluginError, match=r"gadget 'bad' of frictex-test-broken "
                                              r"\(no_such_module_x:Thing\) cannot be loaded: "
                                              r"ModuleNotFoundError"):
            registry.get("bad")
    finally:
        sys.path.remove(str(tmp_path))


def fake_distribution(folder: Path, name: str, entry_points: str) -> Path:
    """An installed distribution's metadata only (``<name>-1.0.dist-info``) in ``folder``."""
    dist = folder / f"{name.replace('-', '_')}-1.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.0\n",
                                   encoding="utf-8")
    (dist / "entry_points.txt").write_text(textwrap.dedent(entry_points), encoding="utf-8")
    return folder


def test_a_clashing_or_broken_plugin_is_refused_on_its_own(tmp_path):
    """A plugin registering a built-in's name, the reserved 'sho', a broken profile and a
    broken touch input: every command still runs, each refusal one warning line (once),
    and a broken entry is an error only where its name is used."""
    plugin = fake_distribution(tmp_path / "site", "frictex-test-clash", """
        [frictex.renderers]
        sho = frictex_nothing:Sho
        sht = frictex_nothing:Sht
        [frictex.profiles]
        broken-plate = no_such_module_y:PLATE
        [frictex.inputs]
        broken-pen = no_such_module_y:PEN
        """)
    done = run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out",
                str(tmp_path / "out"), "--quiet", "--renderer", "sht"], plugin, tmp_path)
    assert done.returncode == 0, done.stderr
    warnings = done.stderr.strip().splitlines()
    assert "Traceback" not in done.stderr and len(warnings) == len(set(warnings))
    assert any("renderer 'sho' from frictex-test-clash" in w and "reserved" in w
               for w in warnings)
    assert any("renderer 'sht' from frictex-test-clash" in w and "already registered by "
               "frictex" in w for w in warnings)
    assert all(w.startswith("frictex: warning: ") for w in warnings)
    helped = run([str(FRICTEX), "replay", "--help"], plugin, tmp_path)
    assert helped.returncode == 0
    choices = re.findall(r"\{([^{}]*sho-held[^{}]*)\}", " ".join(helped.stdout.split()))
    assert choices and all(sorted(set(c.split(","))) == sorted(c.split(",")) for c in choices)
    assert all(c.split(",").count("sho") == 1 for c in choices)
    demo = run([str(FRICTEX), "demo", "--help"], plugin, tmp_path)
    assert demo.returncode == 0, demo.stderr
    assert "broken-pen" in demo.stderr and "cannot be loaded" in demo.stderr
    scene = tmp_path / "broken.toml"
    scene.write_text(resolve_scene("grating-5mm").read_text(encoding="utf-8")
                     .replace("[device]", '[device]\nprofile = "broken-plate"', 1)
                     if "[device]" in resolve_scene("grating-5mm").read_text(encoding="utf-8")
                     else resolve_scene("grating-5mm").read_text(encoding="utf-8")
                     + '\n[device]\nprofile = "broken-plate"\n', encoding="utf-8")
    named = run([str(FRICTEX), "validate", str(scene)], plugin, tmp_path)
    assert named.returncode in (1, 2) and "Traceback" not in named.stderr
    assert "broken-plate" in named.stderr


def test_a_missing_extra_before_the_command_runs_is_the_pip_hint(tmp_path):
    """The demo's module imports OpenGL: without the gui extra that import is the one-line
    pip hint (exit 1), not a traceback; a bug in a command's import is exit 70."""
    code = ("import sys; sys.modules['moderngl'] = sys.modules['glfw'] = None\n"
            "from frictex.app.commands.cli import main; sys.exit(main(['demo', '--headless']))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip().splitlines() == [
        "frictex: error: OpenGL drawing needs frictex's 'gui' extra (moderngl is not "
        "installed): pip install 'frictex[gui]'"] or "pip install 'frictex[gui]'" in done.stderr
    assert "Traceback" not in done.stderr
    code = ("import sys; from frictex.app.commands import cli\n"
            "cli.COMMANDS['library'] = ('frictex_no_such_module_z', 'x')\n"
            "sys.exit(cli.main(['library']))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, cwd=tmp_path)
    assert done.returncode == 70 and "internal error" in done.stderr


def test_a_registry_gives_a_builtin_its_name_back_and_refuses_reserved_names(capsys):
    registry: Registry = Registry("gadget", "frictex.test-gadgets-none", reserved=("any",))
    registry._add("late", abs, "frictex-test-x (m:abs)")  # a plugin, scanned first
    registry.register("late", len)  # then frictex's own: its name
    assert registry.get("late") is len and registry.origin("late") == "frictex"
    assert "gadget 'late' from frictex-test-x (m:abs) is refused" in capsys.readouterr().err
    with pytest.raises(PluginError, match="the name is reserved"):
        registry._add("any", abs, "frictex-test-x (m:abs)")
    registry.register("any", abs)  # frictex's own may
