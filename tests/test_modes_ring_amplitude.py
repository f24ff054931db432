"""modes ring --phase-shift: --amplitude-um stops where the driving-force line would push
a still finger harder than its friction at rest (mu0 F_n; 4.846 um with seed 004's 0.13
N/um per N above 1 um and mu0 0.5), --normal-force-n at 100 N as texture files' forces;
the forces print in 4 significant digits, and the force on a still finger is 0 at 0 and
+-180 degrees on seed 004's ring (the envelope's least amplitude, 0.0040 W there, stays
under the 1 um threshold)."""

import json

import pytest

from frictex.app.commands.cli import main
from frictex.app.commands.modes_ring import FRICTION_BOUND_UM
from frictex.device.profile import DrivingForceParams

MU0, SLOPE, THRESHOLD = 0.5, 0.13, 1.0


def phase_rows(capsys, *extra):
    assert main(["modes", "ring", "--phase-shift", "--json", "--phase-step-deg", "45",
                 *extra]) == 0
    return json.loads(capsys.readouterr().out)["phase_shift"]["rows"]


def test_the_bound_is_where_the_line_meets_the_friction():
    assert (DrivingForceParams().mu0, DrivingForceParams().slope_per_um,
            DrivingForceParams().threshold_um) == (MU0, SLOPE, THRESHOLD)
    assert FRICTION_BOUND_UM == pytest.approx(THRESHOLD + MU0 / SLOPE)  # 4.846 um


def test_an_amplitude_past_what_argparse_takes_is_one_line_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["modes", "ring", "--phase-shift", "--amplitude-um", "1e300"])
    assert exc.value.code == 2
    assert "argument --amplitude-um: '1e300' um: expected 0.01 to 100" in capsys.readouterr().err


@pytest.mark.parametrize("amplitude, said", [
    ("4.9", "--amplitude-um 4.9: above 4.846 um the driving-force line (seed 004, Fig. 3c: "
            "0.13 N/um per N above 1 um) would push a still finger harder than its friction "
            "at rest (0.5 F_n)"),
    ("100", "--amplitude-um 100: above 4.846 um"),
    ("4.85", "--amplitude-um 4.85: above 4.846 um")])  # it said 'above 4.85 um' of 4.85
def test_an_amplitude_past_the_friction_bound_is_one_line_exit_2(capsys, amplitude, said):
    # 100 um printed 12.86 N on a finger pressing with 1 N
    assert main(["modes", "ring", "--phase-shift", "--amplitude-um", amplitude]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1 and said in captured.err


def test_a_normal_force_past_100_n_is_refused(capsys):
    with pytest.raises(SystemExit) as exc:  # 1e9 N printed -1.266e+07 N
        main(["modes", "ring", "--phase-shift", "--normal-force-n", "1e9"])
    assert exc.value.code == 2
    assert "argument --normal-force-n: '1e9' N: expected 0.01 to 100" in capsys.readouterr().err


def test_no_force_at_0_and_180_degrees_and_at_most_the_friction_at_the_bound(capsys):
    w = float(f"{FRICTION_BOUND_UM:.6f}") - 1e-6
    rows = phase_rows(capsys, "--amplitude-um", f"{w:.6f}")
    at = {row["phase_deg"]: row for row in rows}
    for phase in (-180.0, 0.0, 180.0):
        assert at[phase]["force_n"] == [0.0, 0.0]
    # at -90 degrees the envelope's least amplitude lies between ratio x W and W
    ratio, force = at[-90.0]["ratio"], at[-90.0]["force_n"]
    for f_n, pushed in zip((1.0, 0.5), force):
        assert SLOPE * f_n * (ratio * w - THRESHOLD) <= pushed <= SLOPE * f_n * (w - THRESHOLD)
        assert pushed <= MU0 * f_n


def test_forces_print_in_four_significant_digits(capsys):
    rows = phase_rows(capsys, "--amplitude-um", "4.5")
    assert main(["modes", "ring", "--phase-shift", "--phase-step-deg", "45",
                 "--amplitude-um", "4.5"]) == 0
    out = capsys.readouterr().out.splitlines()
    header = out.index("phase_deg   ratio     force_n@1N   force_n@0.5N")
    printed = [line.split()[2:] for line in out[header + 1:]]
    assert printed == [[f"{f:.4g}" for f in row["force_n"]] for row in rows]
