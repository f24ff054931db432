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
