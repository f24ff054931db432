"""The bundled two-finger replay: seed 000's beam, two fingers crossing each other and the
singular loci of det Phi, end to end through `frictex replay`."""

import csv
import json

import numpy as np
import pytest
from trace_text import assert_same_trace_text
from numpy.testing import assert_allclose

from frictex.app.commands.cli import main
from frictex.device.structures.beam import FreeFreeBeam
from frictex.rendering.input.trace_file import format_trace, read_trace
from frictex.rendering.input.two_finger_trace import description, two_finger_trace
from frictex.textures.library import resolve_trace

SCENE, TRACE = "two-finger-beam-seed000", "two-fingers-crossing-50hz"
BEAM = FreeFreeBeam(350, 6, 6, 57, 2561)
LIMIT_UM = 0.75  # the scene's channel_limit_um


@pytest.fixture(scope="module")
def replayed(tmp_path_factory):
    out = tmp_path_factory.mktemp("two-finger")
    assert main(["replay", SCENE, TRACE, "--out", str(out)]) == 0
    return out


def read_columns(path):
    with path.open() as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def test_commands_have_amplitude_and_phase_per_channel(replayed):
    cmd = read_columns(replayed / "commands.csv")
    assert list(cmd) == ["t_s", "xA_um", "xB_um", "xA_phase_rad", "xB_phase_rad"]
    amps = np.stack([cmd["xA_um"], cmd["xB_um"]])
    assert np.isfinite(amps).all() and amps.min() >= 0 and amps.max() <= LIMIT_UM + 1e-6
    phases = np.stack([cmd["xA_phase_rad"], cmd["xB_phase_rad"]])
    assert np.abs(phases).max() <= np.pi + 1e-6


def test_summary_reports_each_fingers_amplitude_error(replayed):
    summary = json.loads((replayed / "summary.json").read_text())
    assert summary["scene"]["device"] == "beam-seed000"
    assert summary["output"]["channels"] == ["xA", "xB"]
    fingers = summary["fingers"]
    assert set(fingers) == {"0", "1"}
    # finger 0 touches 4.4 s, finger 1 4.0 s (10 kHz output)
    assert fingers["0"]["contact_samples"] == 44000 and fingers["1"]["contact_samples"] == 40000
    for f in fingers.values():
        assert 0.01 < f["amplitude_error_rms_um"] < f["amplitude_error_max_um"] < 0.4


def test_error_is_nil_where_phi_is_well_conditioned_and_large_near_the_loci(replayed):
    """From friction.csv alone: recompute the wanted amplitude (seed 003 eq 3) and the
    conditioning of Phi at the two fingers (seed 000's modes 16 and 17)."""
    fr = read_columns(replayed / "friction.csv")
    cmd = read_columns(replayed / "commands.csv")
    t, finger = fr["t_s"], fr["finger"].astype(int)
    a = 1.13 * 0.5
    wanted = -np.log1p(-(1 - fr["mu_target"]) / (1 - a)) / 1.67
    err = np.abs(fr["amplitude_um"] - wanted)
    both_t = np.intersect1d(t[finger == 0], t[finger == 1])
    rows0 = np.flatnonzero((finger == 0) & np.isin(t, both_t))
    rows1 = np.flatnonzero((finger == 1) & np.isin(t, both_t))
    phi = np.stack([BEAM.phi((16, 17), fr["x_mm"][rows0]), BEAM.phi((16, 17), fr["x_mm"][rows1])], -2)
    s = np.linalg.svd(phi, compute_uv=False)
    ratio = s[:, 1] / s[:, 0]
    limited_t = cmd["t_s"][np.maximum(cmd["xA_um"], cmd["xB_um"]) > LIMIT_UM - 1e-6]
    free = ~np.isin(both_t, limited_t)  # both files write t_s with the same format
    pair_err = np.maximum(err[rows0], err[rows1])
    assert (~free).any() and free.sum() > 10000
    good = (ratio >= 0.1) & free       # exact region of the regularised inverse, within limits
    assert pair_err[good].max() < 1e-5  # friction.csv keeps 6 decimals
    near = ratio < 0.02                # the loci: fingers crossing, and seed 000's Fig. 8 lines
    assert near.sum() > 500 and pair_err[near].mean() > 0.1
    # single-finger samples (before finger 1 lands, after it lifts) are exact too
    alone = ~np.isin(t, both_t)
    assert alone.sum() == 4000 and err[alone].max() < 1e-5


def test_the_last_line_counts_the_samples_at_an_actuator_limit(tmp_path, capsys):
    assert main(["replay", SCENE, TRACE, "--out", str(tmp_path)]) == 0
    limited = json.loads((tmp_path / "summary.json").read_text())["counts"]["actuator_limited"]
    assert limited > 0  # the crossing passes the singular loci
    assert f"; 0 clamped by the friction inversion, {limited} samples at an actuator limit; " in capsys.readouterr().out


def test_replay_is_deterministic(replayed, tmp_path):
    assert main(["replay", SCENE, TRACE, "--out", str(tmp_path)]) == 0
    for name in ("commands.csv", "friction.csv"):
        assert (tmp_path / name).read_bytes() == (replayed / name).read_bytes()


def test_bundled_trace_is_what_its_script_makes():
    path = resolve_trace(TRACE)
    assert_same_trace_text(format_trace(two_finger_trace(), description()), path.read_text())
    trace = read_trace(path)
    x = {f: trace.x_mm[trace.finger == f] for f in (0, 1)}
    assert x[0][0] < x[1][0] and x[0][-1] > x[1][-1]  # the fingers swap sides: they cross
    assert_allclose(trace.t_s[trace.finger == 1][0], 0.2)


def test_the_trace_script_takes_help_and_an_output(tmp_path, capsys):
    """Before, any argument (--help included) rewrote the bundled trace inside the
    installed package."""
    from frictex.rendering.input.two_finger_trace import main as write_main
    from frictex.textures.library import LIBRARY_DIR
    bundled = (LIBRARY_DIR / "traces" / "two-fingers-crossing-50hz.csv").stat().st_mtime_ns
    with pytest.raises(SystemExit) as done:
        write_main(["--help"])
    assert done.value.code == 0 and "--out" in capsys.readouterr().out
    write_main(["-o", str(tmp_path / "t.csv")])
    assert_same_trace_text(format_trace(two_finger_trace(), description()),
                           (tmp_path / "t.csv").read_text())
    assert (LIBRARY_DIR / "traces" / "two-fingers-crossing-50hz.csv").stat().st_mtime_ns == bundled
