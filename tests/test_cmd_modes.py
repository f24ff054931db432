"""``frictex modes beam|plate|ring`` as a user runs it."""

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.app.commands import modes as cmd_modes
from frictex.app.commands.cli import main
from frictex.app.commands.modes_output import PLOT_BYTES
from frictex.device.structures.beam import FreeFreeBeam

SEED000 = ["--length-mm", "350", "--width-mm", "6", "--thickness-mm", "6",
           "--youngs-gpa", "57", "--density", "2561"]


def run_json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)["modes"]


def test_beam_json_example_from_the_issue(capsys):
    modes = run_json(capsys, ["modes", "beam", *SEED000, "--orders", "16", "17", "--json"])
    beam = FreeFreeBeam(350, 6, 6, 57, 2561)
    assert [m["order"] for m in modes] == [16, 17]
    assert set(modes[0]) == {"order", "frequency_hz", "wavelength_mm", "nodes_mm"}
    for m in modes:
        assert_allclose(m["frequency_hz"], beam.frequency_hz(m["order"]), rtol=1e-15)
        assert_allclose(m["wavelength_mm"], beam.wavelength_mm(m["order"]), rtol=1e-15)
        assert len(m["nodes_mm"]) == m["order"] + 1


def test_beam_order_100_lists_101_nodes(capsys):
    (mode,) = run_json(capsys, ["modes", "beam", "--orders", "100", "--json"])
    assert len(mode["nodes_mm"]) == 101


def test_timoshenko_is_lower_than_euler_bernoulli(capsys):
    eb = run_json(capsys, ["modes", "beam", "--json"])
    timo = run_json(capsys, ["modes", "beam", "--theory", "timoshenko", "--json"])
    assert all(t["frequency_hz"] < e["frequency_hz"] for t, e in zip(timo, eb))


def test_beam_table_and_plot(capsys, tmp_path):
    png = tmp_path / "beam.png"
    assert main(["modes", "beam", "--plot", str(png)]) == 0
    out, err = capsys.readouterr()
    assert "euler-bernoulli" in out and "28526.3" in out and err == f"plot written to {png}\n"
    assert png.stat().st_size > 10_000


def test_plate_json_and_plot(capsys, tmp_path):
    png = tmp_path / "plate.png"
    modes = run_json(capsys, ["modes", "plate", "--youngs-gpa", "69", "--density", "2700",
                              "--json", "--plot", str(png)][:-2])
    assert [m["axis"] for m in modes] == ["x", "y"]
    assert_allclose(modes[0]["nodes_mm"], 2 * np.arange(9) * 140 / 17)
    assert main(["modes", "plate", "--youngs-gpa", "69", "--density", "2700", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize("argv, message", [
    (["modes", "beam", "--orders", "0"], "--orders 0: a mode order is at least 1 (1 = the first "
                                         "bending mode)"),
    (["modes", "beam", "--poisson", "0.6"], "poisson must be in (-1, 0.5), got 0.6"),
    (["modes", "beam", "--theory", "timoshenko", "--orders", "95"],
     "--orders 95: mode order 95 is above the Timoshenko cutoff 245187 Hz of this beam"),
    (["modes", "plate", "--youngs-gpa", "69", "--density", "2700", "--finger", "10", "10"],
     "--finger 10 10: needs --plot"),
    (["modes", "beam", "--plot", "/nonexistent-dir/x.png"],
     "--plot /nonexistent-dir/x.png: the folder /nonexistent-dir does not exist"),
    (["modes", "ring", "--plot", "/nonexistent-dir/x.png"], "the folder /nonexistent-dir"),
])
def test_bad_input_is_one_line_exit_2(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: ") and message in err and err.count("\n") == 1


def test_plate_finger_off_the_plate_is_refused_before_the_plot(capsys, tmp_path):
    png = tmp_path / "p.png"
    assert main(["modes", "plate", "--youngs-gpa", "69", "--density", "2700", "--finger", "200",
                 "5", "--plot", str(png)]) == 2
    err = capsys.readouterr().err
    assert err == "frictex: error: --finger 200 5 is outside the 140 x 140 mm plate\n"
    assert not png.exists()


@pytest.mark.parametrize("argv, message", [
    (["beam", "--orders", "100000"], "--orders 100000: at most 100, the highest mode order"),
    (["beam", "--orders", "16", "16"], "--orders 16 16: 16 is given twice; give each order once"),
    (["beam", "--thickness-mm", "1000"], "--thickness-mm 1000: must be below --length-mm 350 (a "
                                        "beam is longer than its cross-section)"),
    (["beam", "--width-mm", "350"], "--width-mm 350: must be below --length-mm 350"),
    # order 100: wavelength 6.97 mm on an 8 mm thick beam
    (["beam", "--thickness-mm", "8", "--orders", "100"],
     "--orders 100: wavelength 6.97 mm is shorter than the thickness 8 mm (--thickness-mm): no "
     "bending theory holds there"),
    (["ring", "--thickness-mm", "200"], "--thickness-mm 200: must be below --radius-mm 50 (the "
                                        "thin curved beam of seed 004, eq 3 needs h well below R)"),
    (["ring", "--orders", "5000"], "--orders 5000: at most 100"),
    (["ring", "--orders", "24", "24"], "--orders 24 24: 24 is given twice"),
    (["ring", "--band", "1", "1e9"], "--band 1 1e+09: reaches order 117097; at most 100"),
    (["ring", "--band", "5", "4"], "--band 5 4: MIN_HZ must be below MAX_HZ"),
    (["ring", "--thickness-mm", "8", "--orders", "90"], "--orders 90: wavelength 6.6 mm is shorter "
                                                        "than the thickness 8 mm"),
    (["plate", "--order", "1000"], "--order 1000: expected 1 to 100"),
    (["plate", "--order", "0"], "--order 0: expected 1 to 100"),
    (["plate", "--thickness-mm", "1000"], "--thickness-mm 1000: must be below --width-mm 140"),
])
def test_inputs_outside_the_models_are_refused_in_one_line(capsys, argv, message):
    material = ["--youngs-gpa", "69", "--density", "2700"] if argv[0] == "plate" else []
    assert main(["modes", *argv, *material]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    *warnings, error = captured.err.splitlines()  # a warning may come first
    assert error.startswith(f"frictex: error: {message}")
    assert all(w.startswith("frictex: warning: ") for w in warnings)


@pytest.mark.parametrize("orders", [["0"], ["1"], ["-3"]])
def test_ring_orders_below_2_get_one_message_with_the_real_bound(capsys, orders):
    assert main(["modes", "ring", "--orders", *orders]) == 2
    assert capsys.readouterr().err == (f"frictex: error: --orders {orders[0]}: a mode order is at "
                                       "least 2 (wavelengths around the ring; order 1 would move "
                                       "it rigidly)\n")


@pytest.mark.parametrize("argv, warning", [
    # Euler-Bernoulli reads 18 % above Timoshenko at mode 20 (5.7 thicknesses)
    (["beam", "--orders", "20"], "--orders 20: wavelength 34.1 mm is under 6 thicknesses (36 mm): "
                                 "outside the model's validity, shear and rotary inertia"),
    (["beam", "--theory", "timoshenko", "--orders", "60"],
     "--orders 60: wavelength 11.6 mm is under 2 thicknesses (12 mm)"),
    (["ring", "--thickness-mm", "6"], "--thickness-mm 6: above 0.1 R = 5 mm, outside the "
                                      "thin-ring model's validity"),
    (["ring", "--orders", "90"], "--orders 90: wavelength 6.6 mm is under 6 thicknesses"),
    (["plate", "--order", "20"], "--order 20 (x): wavelength 13.7 mm is under 6 thicknesses"),
])
def test_inputs_the_models_compute_outside_their_validity_warn(capsys, argv, warning):
    material = ["--youngs-gpa", "69", "--density", "2700"] if argv[0] == "plate" else []
    assert main(["modes", *argv, *material]) == 0
    captured = capsys.readouterr()
    assert f"frictex: warning: {warning}" in captured.err
    assert "order" in captured.out  # the table still comes


@pytest.mark.parametrize("argv", [["beam"], ["ring"], ["plate", "--youngs-gpa", "69", "--density",
                                                        "2700"]])
def test_defaults_warn_nothing(capsys, argv):
    assert main(["modes", *argv]) == 0
    assert capsys.readouterr().err == ""


def test_ring_split_never_prints_minus_zero(capsys, monkeypatch):
    from frictex.app.commands import modes_ring
    summary = modes_ring._pair_summary
    monkeypatch.setattr(modes_ring, "_pair_summary",
                        lambda *a: {**summary(*a), "split_hz": -0.001})
    assert main(["modes", "ring"]) == 0
    row = capsys.readouterr().out.splitlines()[-1].split()
    assert row[0] == "24" and row[3] == "0.00"


def test_ring_plot_is_seed_004_fig_2c(capsys, tmp_path):
    png = tmp_path / "ring.png"
    assert main(["modes", "ring", "--orders", "24", "--plot", str(png), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["modes"] and err == f"plot written to {png}\n"  # stdout all JSON
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


@pytest.mark.parametrize("argv, plotted", [
    (["--band", "1", "3000"], "5 orders; the plot shows the first 3 (2 3 4)"),
    (["--orders", "22", "24", "26", "--phase-shift"], "3 orders; the plot shows the first 2 (22 24)"),
])
def test_ring_plot_of_many_orders_stays_within_the_room_checked_for_it(capsys, tmp_path, argv,
                                                                        plotted):
    # before: --band 1 548000 stacked 99 panels, a 770 x 32670 px PNG of 4.5 MB, above the
    # 3.48 MB (8 x 9 inches at 110 dpi, 4 bytes a pixel) check_plot had checked room for
    png = tmp_path / "ring.png"
    assert main(["modes", "ring", *argv, "--plot", str(png)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert f"frictex: warning: --plot: {plotted}, as many as fit its 9 inches of height " \
           "(the table lists every order)" in err
    width, height = (int.from_bytes(png.read_bytes()[i:i + 4], "big") for i in (16, 20))
    assert width * height * 4 <= PLOT_BYTES and png.stat().st_size <= PLOT_BYTES


@pytest.mark.parametrize("structure", [["beam"], ["ring"],
                                       ["plate", "--youngs-gpa", "69", "--density", "2700"]])
def test_a_plot_that_cannot_be_written_is_refused_before_any_work(capsys, tmp_path, structure):
    folder = tmp_path / "taken.png"
    folder.mkdir()
    assert main(["modes", *structure, "--plot", str(folder)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # no table printed: refused first
    assert captured.err == f"frictex: error: --plot {folder}: is a folder; give a file to write\n"


@pytest.mark.parametrize("name", ["plot.txt", "plot", "plot.pdf"])
def test_a_plot_name_that_is_no_png_is_refused(capsys, name):
    with pytest.raises(SystemExit) as exc:
        main(["modes", "beam", "--plot", name])
    assert exc.value.code == 2
    assert "give a file name ending in .png" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [["modes", "beam", "--length-mm", "-3"],
                                  ["modes", "beam", "--orders", "x"],
                                  ["modes", "plate"], ["modes"], ["modes", "disc"]])
def test_argparse_rejections_exit_2(capsys, argv):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert "error:" in capsys.readouterr().err


def test_missing_structure_module_says_not_available(capsys, monkeypatch):
    monkeypatch.setitem(cmd_modes.STRUCTURES, "ring", "app.modes_ring_not_installed")
    assert main(["modes", "ring", "--anything"]) == 1  # an install problem, not bad input
    assert "modes ring: not available" in capsys.readouterr().err


def test_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["modes", "beam", "--help"])
    assert exc.value.code == 0
    assert "--theory" in capsys.readouterr().out


# --- seed 004, Fig. 4: ratio and force against the phase shift (modes ring --phase-shift)

def phase_json(capsys, *extra):
    assert main(["modes", "ring", "--phase-shift", "--json", *extra]) == 0
    return json.loads(capsys.readouterr().out)["phase_shift"]


def test_ring_phase_shift_follows_two_degenerate_modes_in_closed_form(capsys):
    """Two degenerate modes cos and sin at one k with W_A = e^{j phi} W_B: |W|^2 =
    W^2 (1 + cos phi sin 2kx), so min |W| = W sqrt(1 - |cos phi|), ratio =
    tan(min(|phi|, 180 - |phi|) / 2), and the force k_p F_n max(0, min |W| - w_th)
    reverses with the sign of phi. The ring's pair is split by 7 Hz: 1 % tolerance."""
    got = phase_json(capsys, "--amplitude-um", "2.5", "--normal-force-n", "1", "0.4")
    assert (got["order"], got["amplitude_um"], got["normal_force_n"]) == (24, 2.5, [1.0, 0.4])
    phase = np.array([row["phase_deg"] for row in got["rows"]])
    assert_allclose(phase, np.arange(-180, 181, 15))  # the default step
    ratio = np.array([row["ratio"] for row in got["rows"]])
    force = np.array([row["force_n"] for row in got["rows"]])  # (phases, normal forces)
    phi = np.radians(phase)
    folded = np.minimum(np.abs(phi), np.pi - np.abs(phi))
    assert_allclose(ratio, np.tan(folded / 2), atol=0.01)
    w_min = 2.5 * np.sqrt(1 - np.abs(np.cos(phi)))
    expected = 0.13 * np.array([1.0, 0.4]) * np.maximum(w_min - 1.0, 0.0)[:, None]
    assert_allclose(np.abs(force), expected, rtol=0.01, atol=1e-4)
    assert_allclose(force, -force[::-1], atol=1e-12)  # reverses with the sign of phi
    at = {p: i for i, p in enumerate(phase)}
    for p in (-90, 90):  # a pure travelling wave: ratio 1, k_p F_n (W - w_th)
        assert abs(ratio[at[p]] - 1) < 0.01
        assert_allclose(np.abs(force[at[p]]), 0.13 * np.array([1.0, 0.4]) * 1.5, rtol=0.01)
    assert np.sign(force[at[-90], 0]) == -np.sign(force[at[90], 0]) != 0
    for p in (-180, 0, 180):  # a standing wave: ratio near 0, no force
        assert ratio[at[p]] < 0.01 and np.all(force[at[p]] == 0)


def test_ring_phase_shift_table_prints_the_json_values(capsys):
    got = phase_json(capsys, "--phase-step-deg", "45")
    assert main(["modes", "ring", "--phase-shift", "--phase-step-deg", "45"]) == 0
    out = capsys.readouterr().out.splitlines()
    header = out.index("phase_deg   ratio     force_n@1N   force_n@0.5N")
    rows = [line.split() for line in out[header + 1:]]
    assert len(rows) == len(got["rows"]) == 9
    for printed, row in zip(rows, got["rows"]):
        assert float(printed[0]) == row["phase_deg"]
        assert_allclose([float(v) for v in printed[1:]], [row["ratio"], *row["force_n"]],
                        atol=5e-5)
        assert not any(v.startswith("-0.0000") for v in printed)


def test_ring_phase_shift_plot_and_default_output_unchanged_without_it(capsys, tmp_path):
    png = tmp_path / "phase.png"
    assert main(["modes", "ring", "--phase-shift", "--plot", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    capsys.readouterr()
    assert main(["modes", "ring", "--json"]) == 0
    assert set(json.loads(capsys.readouterr().out)) == {"modes", "pairs"}


def test_ring_phase_shift_amplitude_beyond_seed_004_warns(capsys):
    assert main(["modes", "ring", "--phase-shift", "--amplitude-um", "4"]) == 0
    assert capsys.readouterr().err == ("frictex: warning: --amplitude-um 4: above 3 um, beyond "
                                       "seed 004's measurements (Fig. 3c): the force's line is "
                                       "extrapolated\n")


# --- the local travelling-wave ratio along a beam (modes beam --travelling)

SEED002 = ["--length-mm", "600", "--width-mm", "6", "--thickness-mm", "6", "--youngs-gpa", "69",
           "--density", "2700", "--orders", "28", "29"]


def test_beam_travelling_ratio_on_seed_002_beam(capsys):
    """Two adjacent modes drift out of quadrature by delta = (k_B - k_A)(x - L/2):
    tau = (1 - |sin delta|) / |cos delta| away from the ends' evanescent terms."""
    assert main(["modes", "beam", *SEED002, "--travelling", "--points", "49", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert [m["order"] for m in got["modes"]] == [28, 29]
    travelling = got["travelling"]
    x, ratio = np.array(travelling["positions_mm"]), np.array(travelling["ratio"])
    assert_allclose(x, np.linspace(0, 600, 49))
    beam = FreeFreeBeam(600, 6, 6, 69, 2700)
    k_a, k_b = (2 * np.pi / beam.wavelength_mm(n) for n in (28, 29))
    delta = (k_b - k_a) * (x - 300)
    tau = (1 - np.abs(np.sin(delta))) / np.abs(np.cos(delta))
    inner = (x > 50) & (x < 550)
    assert_allclose(ratio[inner], tau[inner], atol=1e-3)
    assert ratio[0] < 0.01 and ratio[-1] < 0.01
    spans = {s["threshold"]: s["spans_mm"] for s in travelling["spans"]}
    # the bundled directional-beam and guidance-beam keep to 230-370 mm, inside the 0.68 span
    [(start, end)] = spans[0.68]
    assert 227 < start < 230 and 370 < end < 373 and abs(start + end - 600) < 0.1
    crossing = 300 - np.arcsin((1 - 0.68 ** 2) / (1 + 0.68 ** 2)) / (k_b - k_a)  # tau = 0.68
    assert abs(start - crossing) < 0.1
    assert np.all(ratio[(x < start) | (x > end)] < 0.68)
    assert np.all(ratio[(x > start) & (x < end)] >= 0.68)
    [(start9, end9)] = spans[0.9]
    assert start < start9 < 300 < end9 < end


def test_beam_travelling_table_prints_the_json_spans(capsys, tmp_path):
    png = tmp_path / "travelling.png"
    argv = ["modes", "beam", *SEED002, "--travelling", "--threshold", "0.5", "0.9"]
    assert main([*argv, "--json"]) == 0
    spans = json.loads(capsys.readouterr().out)["travelling"]["spans"]
    assert main([*argv, "--plot", str(png)]) == 0
    out = capsys.readouterr().out.splitlines()
    for item in spans:
        (s, e), = item["spans_mm"]
        assert f"ratio >= {item['threshold']:g}: {s:.1f}-{e:.1f} mm" in out
    assert len([line for line in out if line.startswith(" ") and len(line.split()) == 2]) >= 25
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize("argv, message", [
    (["ring", "--amplitude-um", "2"], "--amplitude-um 2: needs --phase-shift"),
    (["ring", "--normal-force-n", "1", "0.5"], "--normal-force-n 1 0.5: needs --phase-shift"),
    (["ring", "--phase-step-deg", "30"], "--phase-step-deg 30: needs --phase-shift"),
    (["ring", "--phase-shift", "--phase-step-deg", "7"], "--phase-step-deg 7: must divide 180"),
    (["ring", "--phase-shift", "--band", "39000", "41000"],
     "--phase-shift: needs --orders (its first pair), not --band"),
    (["beam", "--travelling", "--orders", "16", "18"], "--travelling: needs two adjacent --orders "
                                                       "N N+1 (got 16 18)"),
    (["beam", "--travelling", "--orders", "17", "16"], "(got 17 16)"),
    (["beam", "--points", "10"], "--points 10: needs --travelling"),
    (["beam", "--threshold", "0.7"], "--threshold 0.7: needs --travelling"),
])
def test_bad_travelling_options_are_one_line_exit_2(capsys, argv, message):
    assert main(["modes", *argv]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert captured.err.startswith("frictex: error: ") and message in captured.err


@pytest.mark.parametrize("argv, message", [
    (["ring", "--phase-shift", "--phase-step-deg", "0.1"], "argument --phase-step-deg: '0.1' "
                                                           "degrees: expected 0.5 to 90"),
    (["ring", "--phase-shift", "--amplitude-um", "-1"], "argument --amplitude-um: '-1' must be"),
    (["ring", "--phase-shift", "--normal-force-n", "inf"], "argument --normal-force-n: 'inf'"),
    (["beam", "--travelling", "--points", "1"], "argument --points: '1' positions: expected 2"),
    (["beam", "--travelling", "--threshold", "1.5"], "argument --threshold: '1.5' must be between"),
])
def test_bad_travelling_values_are_refused_by_the_parser_in_one_line(capsys, argv, message):
    with pytest.raises(SystemExit) as exc:
        main(["modes", *argv])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: ") and message in err and err.count("\n") == 1


def test_ring_phase_shift_on_a_straight_shorter_than_a_quarter_wavelength(capsys):
    assert main(["modes", "ring", "--length-mm", "1", "--phase-shift", "--json"]) == 0
    rows = {r["phase_deg"]: r for r in json.loads(capsys.readouterr().out)["phase_shift"]["rows"]}
    assert rows[90.0]["ratio"] == pytest.approx(1.0, abs=1e-3)
    assert rows[90.0]["force_n"][0] == pytest.approx(-rows[-90.0]["force_n"][0], abs=1e-15)
