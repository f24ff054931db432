"""What another package's renderer or output device hands back is checked where frictex
wraps it: one that breaks its contract is a PluginError naming the package, never a value
written into the friction target or a traceback (exit 70)."""

import json
import os
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from frictex.device.registry import PluginError
from frictex.rendering.renderers import PluginRenderer
from frictex.rendering.tracking.tracks import BLOCK_FIELDS, FingerBlock

WHO = "renderer 'flat' of frictex-flat (frictex_flat:Flat)"


def flat_renderer(mu_value, touch=None):
    """A plugin renderer's factory whose every mu' is ``mu_value`` (any value numpy takes)
    over the whole block, after calling ``touch(block)`` where given."""
    class Flat:
        def __init__(self, layer, rate_hz):
            pass

        def initial_state(self):
            return None

        def render(self, block, state):
            if touch is not None:
                touch(block)
            shape = (len(block.ids), block.n)
            return np.full(shape, mu_value), np.ones(shape, dtype=bool), state
    return Flat


def finger_block() -> FingerBlock:
    """One finger touching for 4 samples at (10, 20) mm."""
    arrays = {name: np.zeros((1, 4)) for name in BLOCK_FIELDS}
    arrays.update(contact=np.ones((1, 4), dtype=bool), touch_id=np.zeros((1, 4), np.int64),
                  x_held=np.full((1, 4), 10.0), y_held=np.full((1, 4), 20.0))
    return FingerBlock(0, np.arange(4) * 1e-4, (0,), **arrays)


def rendered(mu_value, touch=None, block=None):
    renderer = PluginRenderer(flat_renderer(mu_value, touch), WHO,
                              SimpleNamespace(name="lines"), 1e4)
    return renderer.render(finger_block() if block is None else block,
                           renderer.initial_state())


@pytest.mark.parametrize("mu_value", [-1.0, 0.0, 5.0, 1.0 + 1e-9])
def test_a_plugin_renderers_mu_outside_0_1_is_refused_naming_it_and_the_layer(mu_value):
    with pytest.raises(PluginError, match=rf"^{WHO.replace('(', '.').replace(')', '.')} "
                                          rf"returned 4 mu' values outside \(0, 1\] "
                                          rf"\(the first {mu_value:g}\) on layer 'lines', "
                                          "where it covers$"):
        rendered(mu_value)


def test_a_plugin_renderers_nan_is_still_said_as_not_finite():
    with pytest.raises(PluginError, match="4 mu' values that are not finite"):
        rendered(np.nan)


@pytest.mark.parametrize("mu_value", [1.0, 0.05])
def test_a_plugin_renderers_mu_in_0_1_passes(mu_value):
    mu, covers, _ = rendered(mu_value)
    assert mu.tolist() == [[mu_value] * 4] and covers.all()


@pytest.mark.parametrize("mu_value, dtype", [("x", "<U1"), (0.5 + 2j, "complex128"),
                                             (None, "object")])
def test_a_plugin_renderers_mu_that_is_not_real_numbers_is_refused(mu_value, dtype):
    # once a traceback and exit 70 ("could not convert string to float"), or, complex,
    # the imaginary part dropped with numpy's ComplexWarning and the run going on
    with pytest.raises(PluginError, match=rf"returned mu' of dtype {dtype} on layer 'lines'; "
                                          "expected real numbers$"):
        rendered(mu_value)


def test_a_plugin_renderer_cannot_write_into_the_block_every_layer_reads():
    # a renderer that wrote contact = False once emptied the run's contact for every
    # later layer, the composition and the outputs, silently
    def lift(block):
        block.contact[...] = False
    block = finger_block()
    with pytest.raises(PluginError, match=r"failed rendering layer 'lines': ValueError: "
                                          "assignment destination is read-only$"):
        rendered(0.5, lift, block)
    assert block.contact.all() and block.contact.flags.writeable


#: another package's output device whose status() is what STATUS (a Python expression of
#: n, the samples sent) says, read at each call
DEVICE_MODULE = '''
import os
from types import SimpleNamespace


class Dev:
    def __init__(self, arg, request):
        self.label, self.channels = "counted", request.channels
        self.rate_hz, self.paced, self.n = request.rate_hz, request.paced, 0
        self.info = SimpleNamespace(has_force_reports=False, limits_um=None)

    def send(self, start_index, amplitudes_um, phases_rad=None):
        self.n += len(amplitudes_um)

    def wait_for_room(self, timeout_s):
        return True

    def status(self):
        return eval(os.environ["STATUS"], {"n": self.n})

    def unplayed_share(self):
        return 0.0

    def device_force_n(self):
        return None

    def force_report(self, index0=None, n=None):
        return None

    def forces_covered(self, index0, n):
        return (), ()

    def close(self):
        pass
'''

#: each status, then what the run says: its PluginError's message after the device's name
STATUSES = [
    ("{'commanded_samples': n}", "returned a dict without 'unplayed_samples' from status()"),
    ("None", "returned a NoneType, not a dict, from status()"),
    ("{'commanded_samples': n, 'unplayed_samples': 0, 'x': object()}",
     "returned a value JSON cannot hold (Object of type object is not JSON serializable) "
     "from status()"),
    ("{'commanded_samples': n, 'unplayed_samples': float('nan')}",
     "returned unplayed_samples nan, not a count (an int, 0 or more), from status()"),
    ("{'commanded_samples': n, 'unplayed_samples': -1}",
     "returned unplayed_samples -1, not a count (an int, 0 or more), from status()"),
    ("{'commanded_samples': n, 'unplayed_samples': n + 1}",
     "returned unplayed_samples 3051 over commanded_samples 3050 from status()"),
    ("{'commanded_samples': n, 'unplayed_samples': 0, 'unplayed_by_cause': {'late': 0.5}}",
     "returned unplayed_by_cause {'late': 0.5}, not a dict of cause -> count, from status()"),
    ("{'commanded_samples': n, 'unplayed_samples': 0, 'underruns': True}",
     "returned underruns True, not a count (an int, 0 or more), from status()"),
]

RUN = '''
import json, os, sys
import frictex
trace = frictex.synth_trace("swipe", duration_s=0.3)
for status in json.loads(sys.argv[1]):
    os.environ["STATUS"] = status
    try:
        run = frictex.replay("grating-5mm", trace, device="counted")
        print("ok", json.dumps(run.summary.device))
    except frictex.PluginError as exc:
        print(exc)
'''


def install_counted_device(folder):
    """The package frictex-counted (DEVICE_MODULE, output device 'counted') in ``folder``,
    found through PYTHONPATH=folder."""
    dist = folder / "frictex_counted-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: frictex-counted\n"
                                   "Version: 1.0\n", encoding="utf-8")
    (dist / "entry_points.txt").write_text("[frictex.devices]\ncounted = frictex_counted:Dev\n",
                                           encoding="utf-8")
    (folder / "frictex_counted.py").write_text(DEVICE_MODULE, encoding="utf-8")


def test_a_plugin_devices_status_that_breaks_the_contract_is_named_not_a_traceback(tmp_path):
    """Missing counts, None, an object JSON cannot hold, NaN (once '-nan% never played'):
    a PluginError naming the package, where the summary reads the status."""
    install_counted_device(tmp_path)
    good = "{'commanded_samples': n, 'unplayed_samples': 0, 'unplayed_by_cause': {}}"
    statuses = [good] + [status for status, _ in STATUSES]
    done = subprocess.run([sys.executable, "-c", RUN, json.dumps(statuses)], cwd=tmp_path,
                          env={**os.environ, "PYTHONPATH": str(tmp_path)},
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    who = "output device 'counted' of frictex-counted (frictex_counted:Dev)"
    expected = ("dict of counts (commanded_samples, unplayed_samples, unplayed_by_cause) "
                "that JSON can hold")
    assert done.stdout.splitlines() == [
        'ok {"commanded_samples": 3050, "unplayed_samples": 0, "unplayed_by_cause": {}}',
        *(f"{who} {said}; expected a {expected}" for _, said in STATUSES)]


def test_faults_for_a_plugin_device_are_refused_not_ignored(tmp_path):
    """frictex injects faults into its own serial links; another package's device got
    them in its request and could drop them silently (a run 'with faults' and none)."""
    install_counted_device(tmp_path)
    (tmp_path / "trace.csv").write_text("t_s,finger,x_mm,y_mm,contact\n0,0,10,10,1\n"
                                        "0.2,0,40,10,1\n", encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "frictex", "replay", "grating-5mm",
                           "trace.csv", "--device", "counted", "--faults", "corrupt=0.01",
                           "--out", "out"], cwd=tmp_path,
                          env={**os.environ, "PYTHONPATH": str(tmp_path), "STATUS": "{}"},
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines()[-1] == (
        "frictex: error: device 'counted': faults are injected into frictex's serial links (sim or a "
        "port), not into output device 'counted' of frictex-counted "
        "(frictex_counted:Dev), another package's")
    assert not (tmp_path / "out").exists()
