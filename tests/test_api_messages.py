"""What the Python API refuses it says in both its forms, the command's flag and the
function's argument, and it refuses what the command refuses: max_unplayed without a
device, as ``--max-unplayed`` without ``--device``."""

import pytest

import frictex


@pytest.fixture(scope="module")
def trace():
    return frictex.synth_trace("swipe", duration_s=0.2)


def test_closed_control_without_a_device_names_the_argument_and_the_flag(trace):
    with pytest.raises(frictex.InputError) as caught:
        frictex.replay("grating-5mm", trace, control="closed")
    said = str(caught.value)
    assert "--device sim:finger=SEED, device=\"sim:finger=SEED\", simulates a finger" in said
    assert said.endswith("or use --control open, control=\"open\"")


def test_closed_control_on_a_device_without_force_reports_names_both_forms(trace):
    with pytest.raises(frictex.DeviceError) as caught:
        frictex.replay("grating-5mm", trace, control="closed", device="sim")
    assert str(caught.value).endswith("use a device with one (--device sim:finger=SEED, "
                                      "device=\"sim:finger=SEED\", simulates a finger), or "
                                      "--control open, control=\"open\"")


def test_the_frames_sink_says_the_api_makes_no_frames(trace):
    with pytest.raises(frictex.InputError, match=r"ask for them with --frames FPS \(frictex "
                                                 r"replay only: frictex\.replay makes no "
                                                 r"frames\)$"):
        frictex.replay("grating-5mm", trace, sinks=["frames"])


def test_max_unplayed_without_a_device_is_refused_as_the_command_refuses_it(trace):
    with pytest.raises(frictex.InputError, match=r"^max_unplayed 0\.5: needs device \(the "
                                                 r"share of samples a device never played\); "
                                                 r"no device was given$"):
        frictex.replay("grating-5mm", trace, max_unplayed=0.5)
    assert frictex.replay("grating-5mm", trace).summary.device is None
    run = frictex.replay("grating-5mm", trace, device="sim", max_unplayed=0.5)
    device = run.summary.device  # paced in real time: a busy machine may leave some unplayed
    assert device["unplayed_known"] and device["commanded_samples"] > 0
    assert device["unplayed_samples"] <= 0.5 * device["commanded_samples"]


def test_outputs_that_do_not_fit_name_the_format_argument_too(trace, tmp_path, monkeypatch):
    from collections import namedtuple

    from frictex.app.engine import tables
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(tables.shutil, "disk_usage", lambda path: usage(10**12, 0,
                                                                     tables.RESERVE_BYTES + 100_000))
    with pytest.raises(frictex.OutputSpaceError, match=r"free some space, write elsewhere, or "
                                                       r"use --format parquet "
                                                       r'\(format="parquet" from Python\)$'):
        frictex.replay("grating-5mm", trace, out=tmp_path / "out")
