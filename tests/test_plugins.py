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

import numpy as np
import pytest

from frictex.device.registry import Expect, PluginError, Registry, UnknownName
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.renderers import LAYER_RENDERERS, RENDERERS, LayerRenderer, render_modes
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from flat_renderer import FlatRenderer

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
        methodless = "frictex_test_wobble:Methodless"

        [project.entry-points."frictex.profiles"]
        wobble-plate = "frictex_test_wobble:PLATE"

        [project.entry-points."frictex.actuations"]
        wobble-channel = "frictex_test_wobble:one_channel"

        [project.entry-points."frictex.devices"]
        tally = "frictex_test_wobble:open_tally"
        numbered = "frictex_test_wobble:NUMBER"
        unplugged = "frictex_test_wobble:open_unplugged"
        jammed = "frictex_test_wobble:open_jammed"

        [project.entry-points."frictex.sinks"]
        ledger = "frictex_test_wobble:Ledger"
        leaky = "frictex_test_wobble:Leaky"

        [project.entry-points."frictex.clocks"]
        metronome = "frictex_test_wobble:Metronome"
        stuck = "frictex_test_wobble:Stuck"

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


        class Methodless:  # neither initial_state nor render
            def __init__(self, layer, rate_hz):
                pass


        NUMBER = 42  # not a device's factory


        def open_unplugged(arg, request):
            raise RuntimeError("USB interface 3 not found")


        class Jammed(Tally):
            def send(self, start_index, amplitudes_um, phases_rad=None):
                raise ValueError("amplitude buffer overflow in driver")


        def open_jammed(arg, request):
            return Jammed(arg, request)


        class Ledger:
            # a sink (factory(arg, request)): at commit, the calls, rows and sum of every
            # command (um) it was given, its channels and rate, into the file ARG names
            def __init__(self, arg, request):
                self.path, self.request = arg, request
                self.calls, self.rows, self.total = 0, 0, 0.0

            def write(self, out, commands_um):
                assert commands_um.shape == (out.t_s.size, len(self.request.channels))
                self.calls += 1
                self.rows += commands_um.shape[0]
                self.total += float(np.sum(commands_um))

            def commit(self):
                with open(self.path, "w") as fh:
                    fh.write(f"{{self.calls}} {{self.rows}} {{self.total!r}} "
                             f"{{','.join(self.request.channels)}} {{self.request.rate_hz!r}}")

            def abort(self):
                pass


        class Leaky(Ledger):
            def write(self, out, commands_um):
                raise RuntimeError("the lab server's disk is full")


        class Metronome:
            # a clock: how many calls and blocks it was told of, and its block (s), into
            # the file ARG names after each call
            def __init__(self, arg, request):
                self.path, self.block_s = arg, request.block_s
                self.calls = self.blocks = 0

            def wait(self, k):
                assert k == self.blocks  # no gap: the trace has none

            def finished(self, k, n):
                self.calls += 1
                self.blocks += n
                with open(self.path, "w") as fh:
                    fh.write(f"{{self.calls}} {{self.blocks}} {{self.block_s!r}}")


        class Stuck(Metronome):
            def wait(self, k):
                raise RuntimeError("no sync pulse from the lab's clock")
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


#: ``registry.register(*args)`` called from a module of frictex's own (its frame's
#: module name is under ``frictex.``), as frictex's own registrations are
register_as_frictex = eval("lambda registry, *args: registry.register(*args)",
                           {"__name__": "frictex.tests_own"})


def test_a_registry_refuses_a_second_entry_under_a_name_and_bad_names():
    registry: Registry = Registry("gadget", "frictex.test-gadgets-none")
    register_as_frictex(registry, "one", len)

    def two(x):
        return x
    register_as_frictex(registry, "two")(two)  # as a decorator

    assert registry.names() == ("one", "two") and registry.get("two") is two
    register_as_frictex(registry, "one", len)  # the same entry again: no clash
    with pytest.raises(PluginError, match="gadget 'one' from frictex is already registered by "
                                          "frictex"):
        register_as_frictex(registry, "one", abs)
    for bad in ("", " x", "a:b", 3):
        with pytest.raises(PluginError, match="expected a non-empty name"):
            register_as_frictex(registry, bad, abs)
    with pytest.raises(UnknownName, match="unknown gadget 'three'; expected one of one, two"):
        registry.get("three")
    assert "one" in registry and "three" not in registry and 3 not in registry
    assert registry.origin("two") == "frictex" and list(registry) == ["one", "two"]


def test_code_outside_frictex_registers_as_a_plugin():
    """``register`` from a notebook or another package was frictex's own: a reserved name
    and an entry of the wrong type were taken."""
    registry: Registry = Registry("gadget", "frictex.test-gadgets-none", reserved=("any",),
                                  expect=Expect.factory("a gadget factory"))
    registry.register("one", len)

    @registry.register("two")
    def two(x):
        return x

    assert registry.origin("one") == "test_plugins (len)"
    assert registry.origin("two") == "test_plugins (two)" and registry.get("two") is two
    with pytest.raises(PluginError, match=r"^gadget 'any' from test_plugins \(abs\): the name "
                                          "is reserved$"):
        registry.register("any", abs)
    with pytest.raises(PluginError, match=r"^gadget 'num' from test_plugins \(int\) is the int "
                                          "42; expected a gadget factory$"):
        registry.register("num", 42)
    with pytest.raises(PluginError, match=r"already registered by test_plugins \(len\)"):
        # another module's register (a module may replace its own entry)
        eval("lambda r: r.register('one', abs)", {"__name__": "other_module"})(registry)
    assert registry.names() == ("one", "two")


def test_a_registry_lists_its_entry_points_before_first_use():
    """Its repr listed [] until a name was asked for."""
    assert "'sht'" in repr(Registry("renderer", "frictex.renderers"))


class _NotFinite(FlatRenderer):
    def render(self, block, state):
        mu, covers, state = super().render(block, state)
        return mu * np.nan, covers, state


class _Flattened(FlatRenderer):
    def render(self, block, state):
        return np.full(3, 0.5), np.ones(3, bool), state


def test_a_renderer_registered_in_process_is_checked_as_a_plugins(in_process_renderers):
    """``RENDERERS.register`` in a notebook skipped every check a plugin's renderer gets:
    a NaN renderer wrote 5000 NaN mu_target rows, a wrong shape was a numpy traceback from
    compose.py, ``sho`` was taken (render_modes() then listed it twice), and 42 was."""
    import frictex
    scene, trace = frictex.load_scene("grating-5mm"), frictex.synth_trace("swipe",
                                                                          duration_s=0.2)
    RENDERERS.register("test-flat", FlatRenderer)
    assert set(frictex.replay(scene, trace, renderer="test-flat").friction.column(
        "mu_target").to_numpy()) <= {0.5}
    RENDERERS.register("test-nan", _NotFinite)
    with pytest.raises(PluginError, match=r"^renderer 'test-nan' of test_plugins \(_NotFinite\)"
                                          r" returned \d+ mu' values that are not finite"):
        frictex.replay(scene, trace, renderer="test-nan")
    RENDERERS.register("test-flattened", _Flattened)
    with pytest.raises(PluginError, match=r"returned mu' of shape \(3,\) on layer"):
        frictex.replay(scene, trace, renderer="test-flattened")
    modes = render_modes()
    with pytest.raises(PluginError, match="'sho' from test_plugins .*: the name is reserved"):
        RENDERERS.register("sho", FlatRenderer)
    assert render_modes() == modes and modes.count("sho") == 1
    with pytest.raises(PluginError, match="is the int 42; expected a renderer class"):
        LAYER_RENDERERS.register("num", 42)


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
    grating = resolve_scene("grating-5mm").read_text(encoding="utf-8")
    assert 'profile = "plate-seed003"' in grating
    scene.write_text(grating.replace('profile = "plate-seed003"', 'profile = "broken-plate"'),
                     encoding="utf-8")
    named = run([str(FRICTEX), "validate", str(scene)], plugin, tmp_path)
    assert named.returncode == 1 and "Traceback" not in named.stderr
    assert "error: device profile 'broken-plate' of frictex-test-clash" in named.stderr


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
    register_as_frictex(registry, "late", len)  # then frictex's own: its name
    assert registry.get("late") is len and registry.origin("late") == "frictex"
    assert "gadget 'late' from frictex-test-x (m:abs) is refused" in capsys.readouterr().err
    with pytest.raises(PluginError, match="the name is reserved"):
        registry._add("any", abs, "frictex-test-x (m:abs)")
    register_as_frictex(registry, "any", abs)  # frictex's own may


def commanded(folder: Path) -> list[float]:
    """The one channel's commands (um) of a replay's commands.csv."""
    with open(folder / "commands.csv", newline="", encoding="utf-8") as fh:
        return [float(row[1]) for row in list(csv.reader(fh))[1:]]


SINK_USE = """
import sys
import frictex
run = frictex.replay("grating-5mm", "swipe-40mms-50hz", sinks=["ledger:" + sys.argv[1]],
                     clock="metronome:" + sys.argv[2], renderer="sho-held")
print(run.commands.num_rows)
"""


def test_replay_and_the_python_api_feed_a_plugins_sink_on_a_plugins_clock(plugin_path,
                                                                          tmp_path):
    """--sink NAME:ARG and --clock NAME:ARG build the plugin's by its factory with ARG;
    the sink gets every command (um, the channels' order), the clock every block."""
    # sho-held: the same commands however many blocks a pipeline call runs (a pacing
    # clock runs one; sht's differ at a few grating edges, in the last bit of the phase)
    own = tmp_path / "own"
    args = [str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--quiet",
            "--renderer", "sho-held", "--out"]
    assert run(args + [str(own)], None, tmp_path).returncode == 0
    commands = commanded(own)
    ledger, metronome = tmp_path / "ledger.txt", tmp_path / "metronome.txt"
    done = run(args + [str(tmp_path / "out"), "--sink", f"ledger:{ledger}", "--clock",
                       f"metronome:{metronome}"], plugin_path, tmp_path)
    assert done.returncode == 0, done.stderr
    assert commanded(tmp_path / "out") == commands  # the run's own outputs unchanged
    calls, rows, total, channels, rate = ledger.read_text().split()
    assert int(rows) == len(commands) and channels == "ch0" and float(rate) == 10_000.0
    assert float(total) == pytest.approx(sum(commands), abs=0.5e-6 * len(commands))
    blocks = len(commands) // 50  # 5 ms blocks at 10 kHz
    # a clock that paces is asked before every block: one block per pipeline call
    assert metronome.read_text().split() == [str(blocks), str(blocks), "0.005"]
    assert int(calls) == blocks
    ledger.unlink()
    done = run([sys.executable, "-c", SINK_USE, str(ledger), str(metronome)], plugin_path,
               tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == [str(len(commands))]
    assert int(ledger.read_text().split()[1]) == len(commands)


@pytest.mark.parametrize("option, message", [
    (["--renderer", "methodless"],
     "renderer 'methodless' of frictex-test-wobble (frictex_test_wobble:Methodless) built a "
     "Methodless without initial_state() or render() for layer 'lines'; expected a "
     "LayerRenderer (frictex.rendering.renderers.LayerRenderer)"),
    (["--device", "numbered"],
     "output device 'numbered' of frictex-test-wobble (frictex_test_wobble:NUMBER) is the "
     "int 42; expected a factory(arg, request) returning an OutputDevice"),
    (["--device", "unplugged"],
     "output device 'unplugged' of frictex-test-wobble (frictex_test_wobble:open_unplugged) "
     "failed opening: RuntimeError: USB interface 3 not found"),
    (["--device", "jammed:{tmp}/jammed.txt"],
     "output device 'jammed' of frictex-test-wobble (frictex_test_wobble:open_jammed) failed "
     "in send(): ValueError: amplitude buffer overflow in driver"),
    (["--sink", "leaky:{tmp}/leaky.txt"],
     "sink 'leaky' of frictex-test-wobble (frictex_test_wobble:Leaky) failed writing: "
     "RuntimeError: the lab server's disk is full"),
    (["--clock", "stuck:{tmp}/stuck.txt"],
     "clock 'stuck' of frictex-test-wobble (frictex_test_wobble:Stuck) failed in wait(): "
     "RuntimeError: no sync pulse from the lab's clock"),
])
def test_a_plugin_that_fails_is_named_and_the_last_run_stays(plugin_path, tmp_path, option,
                                                            message):
    """A renderer, output device, sink or clock of a package that raises (or is not what
    its group holds) fails the run with one line naming the package (exit 1), never
    frictex's internal error (exit 70); the previous run's outputs in the folder stay as
    they were (all or nothing)."""
    out = tmp_path / "out"
    args = [str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out),
            "--quiet"]
    assert run(args, None, tmp_path).returncode == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    done = run(args + [o.format(tmp=tmp_path) for o in option], plugin_path, tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip().splitlines() == [f"frictex: error: {message}"]
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


API_FAILURES = """
import json, sys
import frictex
got = []
for options in [{"renderer": "methodless"}, {"device": "numbered"}, {"device": "unplugged"},
                {"sinks": ["leaky:" + sys.argv[1]]}, {"clock": "stuck:" + sys.argv[1]},
                {"sinks": ["nosuch"]}, {"clock": "nosuch"}]:
    try:
        frictex.replay("grating-5mm", "swipe-40mms-50hz", **options)
        got.append("no error")
    except frictex.FrictexError as exc:
        got.append(type(exc).__name__ + ": " + str(exc))
print(json.dumps(got))
"""


def test_the_python_api_raises_a_plugins_failure_as_a_plugin_error(plugin_path, tmp_path):
    done = run([sys.executable, "-c", API_FAILURES, str(tmp_path / "x.txt")], plugin_path,
               tmp_path)
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout.splitlines()[-1])
    assert [g.split(":")[0] for g in got] == ["PluginError"] * 5 + ["UnknownName"] * 2
    for text, name in zip(got, ("methodless", "numbered", "unplugged", "leaky", "stuck")):
        assert f"{name!r} of frictex-test-wobble" in text
    known = {"sink": {"tables", "link", "frames", "memory", "progress", "threaded", "ledger",
                      "leaky"}, "clock": {"virtual", "wall", "device", "metronome", "stuck"}}
    for text, kind in zip(got[5:], known):
        said, listed = text.split("; expected one of ")
        assert said == f"UnknownName: unknown {kind} 'nosuch'"
        assert set(listed.split(", ")) == known[kind]


@pytest.mark.parametrize("option, message", [
    (["--sink", "tables"], "sink 'tables': the run builds its own 'tables' sink (its tables); "
                           "a sink is attached once"),
    (["--sink", "threaded:link"], "sink 'link' streams to an output device, and the run has "
                                  "none: choose one (--device, device=)"),
    (["--sink", "nosuch:3"], "unknown sink 'nosuch'; expected one of tables, link, frames, "
                             "memory, progress, threaded"),
    (["--clock", "device"], "clock 'device' is paced by an output device, and the run has "
                            "none: choose one (--device, device=)"),
])
def test_a_sink_or_clock_that_cannot_be_is_an_input_error(tmp_path, option, message):
    out = tmp_path / "out"
    done = run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out),
                "--quiet", *option], None, tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [f"frictex: error: {message}"]
    assert not out.exists()


def test_a_wall_clock_replay_takes_the_traces_time(tmp_path):
    """--clock wall paces the replay in real time: 2 s of output take 2 s or more (a
    lower bound only: a busy machine is slower, never faster), as many rows."""
    outs = {}
    for clock in ("virtual", "wall"):
        outs[clock] = tmp_path / clock
        done = run([str(FRICTEX), "replay", "grating-5mm", "swipe-40mms-50hz", "--out",
                    str(outs[clock]), "--quiet", "--clock", clock], None, tmp_path)
        assert done.returncode == 0, done.stderr
    paced = json.loads((outs["wall"] / "summary.json").read_text(encoding="utf-8"))
    assert paced["timings"]["wall_s"] >= paced["output"]["duration_s"] - 0.006
    assert len(commanded(outs["wall"])) == len(commanded(outs["virtual"])) > 20_000


def test_a_profile_entry_of_the_wrong_type_is_left_out_with_one_warning(tmp_path):
    """A frictex.profiles entry that is a dict, not a ProfileSpec, broke every scene
    command (an ImportError of frictex's own tables, exit 70): it is left out, one warning
    naming it; a scene that names it is an error naming it."""
    site = fake_distribution(tmp_path / "site", "frictex-test-dictplate", """
        [frictex.profiles]
        dict-plate = frictex_test_dictplate:PLATE
        """)
    (site / "frictex_test_dictplate.py").write_text('PLATE = {"channels": 1}\n',
                                                    encoding="utf-8")
    warning = ("frictex: warning: device profile 'dict-plate' of frictex-test-dictplate "
               "(frictex_test_dictplate:PLATE) is a dict; expected a "
               "frictex.device.profile.ProfileSpec; left out")
    scene = resolve_scene("grating-5mm")
    for args in (["validate", str(scene)],
                 ["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(tmp_path / "o"),
                  "--quiet"]):
        done = run([str(FRICTEX), *args], site, tmp_path)
        assert done.returncode == 0, done.stderr
        assert done.stderr.strip().splitlines() == [warning]
    text = scene.read_text(encoding="utf-8")
    named = tmp_path / "named.toml"
    named.write_text(text.replace('profile = "plate-seed003"', 'profile = "dict-plate"'),
                     encoding="utf-8")
    done = run([str(FRICTEX), "validate", str(named)], site, tmp_path)
    assert done.returncode in (1, 2) and "Traceback" not in done.stderr
    assert "'dict-plate' of frictex-test-dictplate" in done.stderr


LATE_INSTALL = """
import sys
import frictex
try:
    frictex.replay("grating-5mm", "swipe-40mms-50hz", renderer="wobble")
except frictex.InputError as exc:
    print("before:", exc)
sys.path.append(sys.argv[1])  # as %pip install in a running notebook would
run = frictex.replay("grating-5mm", "swipe-40mms-50hz", renderer="wobble")
print("after:", sorted(set(run.friction.column("mu_target").to_pylist())))
"""


def test_a_renderer_installed_mid_session_is_found(plugin_path, tmp_path):
    """The API's renderer choice reads the registry's names, which are read again once
    the installed packages have changed, as a name looked up is."""
    done = run([sys.executable, "-c", LATE_INSTALL, str(plugin_path)], None, tmp_path)
    assert done.returncode == 0, done.stderr
    before, after = done.stdout.strip().splitlines()[-2:]
    assert before.startswith("before: renderer='wobble': expected one of sho,")
    assert after == f"after: [{WOBBLE_MU!r}]"


def test_a_registry_sees_a_package_installed_into_a_folder_on_its_path(tmp_path):
    """A package installed since the metadata was read, into a folder already on
    sys.path, is listed by names() (no lookup of a missing name needed)."""
    sys.path.insert(0, str(tmp_path))
    try:
        registry: Registry = Registry("gadget", "frictex.test-late")
        assert registry.names() == ()
        fake_distribution(tmp_path, "frictex-test-late", "[frictex.test-late]\nlate = m:X\n")
        os.utime(tmp_path, ns=(0, os.stat(tmp_path).st_mtime_ns + 1))  # a coarse clock
        assert registry.names() == ("late",)
    finally:
        sys.path.remove(str(tmp_path))


def test_a_registry_refuses_an_entry_that_is_not_what_it_holds(tmp_path):
    site = fake_distribution(tmp_path, "frictex-test-typed", """
        [frictex.test-typed]
        text = frictex_test_typed:TEXT
        number = frictex_test_typed:NUMBER
        """)
    (site / "frictex_test_typed.py").write_text("TEXT = 'x'\nNUMBER = 3\n", encoding="utf-8")
    sys.path.insert(0, str(site))
    try:
        registry: Registry = Registry("gadget", "frictex.test-typed",
                                      expect=Expect.instance_of(int))
        assert registry.get("number") == 3
        with pytest.raises(PluginError, match=r"gadget 'text' of frictex-test-typed "
                                              r"\(frictex_test_typed:TEXT\) is the str 'x'; "
                                              r"expected a builtins.int"):
            registry.get("text")
        assert registry.loaded() == {"number": 3}
    finally:
        sys.path.remove(str(site))
        sys.modules.pop("frictex_test_typed", None)


def test_validating_a_scene_imports_no_plugin_it_does_not_name(tmp_path):
    """A layer's render was checked against every loadable renderer, importing each
    installed plugin (one whose import takes a second made validate 1.34 s, not 0.30 s;
    one that fails warned on every scene read); only the one named is imported now."""
    site = tmp_path / "site"
    fake_distribution(site, "frictex-test-slow", """
        [frictex.renderers]
        slow = frictex_test_slow_renderer:Slow
        """)
    (site / "frictex_test_slow_renderer.py").write_text(
        "raise RuntimeError('imported frictex_test_slow_renderer')\n", encoding="utf-8")
    done = run([str(FRICTEX), "validate", "grating-5mm"], site, tmp_path)
    assert done.returncode == 0, done.stderr
    assert "frictex_test_slow_renderer" not in done.stderr, done.stderr
    scene = tmp_path / "slow.toml"
    scene.write_text(resolve_scene("grating-5mm").read_text(encoding="utf-8").replace(
        'render = "', 'render = "slow"  # was "', 1), encoding="utf-8")
    named = run([str(FRICTEX), "validate", str(scene)], site, tmp_path)
    assert named.returncode == 2 and "frictex_test_slow_renderer" in named.stderr


@pytest.mark.parametrize("name, entry, says", [
    ("gone-plate", "frictex_no_such_module_z:PLATE", r"cannot be loaded: ModuleNotFoundError"),
    ("dict-plate", "frictex_test_not_a_profile:PLATE", r"is a dict; expected"),
])
def test_a_file_naming_a_broken_plugin_profile_is_told_the_plugin_s_error(tmp_path, name, entry,
                                                                          says):
    """A texture file naming another package's profile that is installed but cannot be
    loaded, or is no profile, gets that package's PluginError (load_scene's docstring),
    not "is not one of" with the reason only in a warning printed once a process."""
    site = fake_distribution(tmp_path / "site", "frictex-test-profile",
                             f"[frictex.profiles]\n{name} = {entry}\n")
    (site / "frictex_test_not_a_profile.py").write_text("PLATE = {'plate': 1}\n", encoding="utf-8")
    scene = tmp_path / "bad.toml"
    text = resolve_scene("grating-5mm").read_text(encoding="utf-8")
    assert 'profile = "plate-seed003"' in text
    scene.write_text(text.replace('profile = "plate-seed003"', f'profile = "{name}"'),
                     encoding="utf-8")
    sys.path.insert(0, str(site))
    try:
        with pytest.raises(PluginError, match=rf"^device profile '{name}' of "
                                              rf"frictex-test-profile \({re.escape(entry)}\) {says}"):
            load_scene(scene)
    finally:
        sys.path.remove(str(site))
