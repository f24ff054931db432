"""frictex modes: dimensions and materials within physically generous ranges, refused in
one line outside them, and modes that are not finite numbers refused rather than printed."""

import pytest

from frictex.app.commands.cli import main
from frictex.app.commands.modes_output import check_finite, print_modes
from frictex.device.structures.beam import ModesError

PLATE = ["--youngs-gpa", "69", "--density", "2700"]


@pytest.mark.parametrize("argv, option", [
    (["beam", "--length-mm", "1e308"], "--length-mm"),        # ZeroDivisionError, exit 70
    (["beam", "--thickness-mm", "1e-300"], "--thickness-mm"),  # 0.0 Hz, exit 0
    (["plate", *PLATE, "--width-mm", "1e308", "--json"], "--width-mm"),  # Infinity in the JSON
    (["ring", "--length-mm", "1e308"], "--length-mm"),        # blamed a --band never given
    (["ring", "--radius-mm", "1e-9"], "--radius-mm"),
    (["beam", "--youngs-gpa", "1e9"], "--youngs-gpa"),
    (["plate", "--youngs-gpa", "69", "--density", "1e-9"], "--density"),
])
def test_a_dimension_or_material_out_of_range_is_one_line_exit_2(capsys, argv, option):
    with pytest.raises(SystemExit) as exc:
        main(["modes", *argv])
    assert exc.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert f"argument {option}: " in captured.err and ": expected " in captured.err


def test_the_range_ends_are_taken_and_give_finite_modes(capsys):
    assert main(["modes", "beam", "--length-mm", "1e5", "--width-mm", "1e-3", "--thickness-mm",
                 "1e-3", "--youngs-gpa", "1e-3", "--density", "30000", "--orders", "1"]) == 0
    row = capsys.readouterr().out.splitlines()[-1].split()
    assert row[0] == "1" and 0 < float(row[1]) < 1e-5  # shown in significant digits, not 0.0


@pytest.mark.parametrize("value", [float("inf"), float("nan"), 0.0])
def test_a_mode_that_is_not_a_finite_positive_number_is_refused(capsys, value):
    modes = [{"order": 3, "frequency_hz": value, "wavelength_mm": 10.0, "nodes_mm": []}]
    with pytest.raises(ModesError, match=r"^order 3: frequency_hz came out .*not a finite"):
        print_modes("t", modes, True)
    assert capsys.readouterr().out == ""
    check_finite([{"order": 3, "frequency_hz": 1.0}])  # a ring's modes have no wavelength


TINY_RING = ["ring", "--thickness-mm", "0.001", "--length-mm", "1e5", "--radius-mm", "1e5",
             "--youngs-gpa", "0.001", "--density", "30000"]


def test_a_ring_under_0_005_hz_prints_in_significant_digits(capsys):
    """Both frequencies of the pair (4.19e-11 and 3.11e-11 Hz) and their split printed
    0.00 0.00 0.00 though --json gave them."""
    assert main(["modes", *TINY_RING, "--orders", "2"]) == 0
    row = capsys.readouterr().out.splitlines()[-1].split()
    assert [float(x) for x in row[1:4]] == pytest.approx([4.19e-11, 3.11e-11, -1.08e-11],
                                                         rel=0.01)
    assert main(["modes", *TINY_RING, "--band", "1e-11", "1e-10"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()[-2:]]
    assert [float(r[2]) for r in rows] == pytest.approx([3.11e-11, 4.19e-11], rel=0.01)


def test_a_ring_on_its_crossing_prints_a_split_of_0_not_its_float_noise(capsys):
    """At L/R 1.91775 order 3's pair differs by about 1e-13 Hz of rounding."""
    assert main(["modes", "ring", "--orders", "3", "--length-mm", "95.88762973326832"]) == 0
    row = capsys.readouterr().out.splitlines()[-1].split()
    assert row[1] == row[2] and row[3] == "0.00"
