"""modes ring --phase-shift: --amplitude-um is bounded as texture amplitudes are (100 um),
the forces print in 4 significant digits, and within the bound the force on a still
finger is 0 at 0 and +-180 degrees on seed 004's ring (the envelope's least amplitude,
0.0040 W there, stays under the 1 um threshold up to 251 um)."""

import json

import pytest

from frictex.app.commands.cli import main


def phase_rows(capsys, *extra):
    assert main(["modes", "ring", "--phase-shift", "--json", "--phase-step-deg", "45",
                 *extra]) == 0
    return json.loads(capsys.readouterr().out)["phase_shift"]["rows"]


@pytest.mark.parametrize("amplitude", ["1e300", "100.5"])
def test_an_amplitude_past_100_um_is_one_line_exit_2(capsys, amplitude):
    with pytest.raises(SystemExit) as exc:
        main(["modes", "ring", "--phase-shift", "--amplitude-um", amplitude])
    assert exc.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert f"argument --amplitude-um: '{amplitude}' um: expected 0.01 to 100" in captured.err


def test_no_force_at_0_and_180_degrees_up_to_the_bound(capsys):
    rows = phase_rows(capsys, "--amplitude-um", "100")
    at = {row["phase_deg"]: row for row in rows}
    for phase in (-180.0, 0.0, 180.0):
        assert at[phase]["force_n"] == [0.0, 0.0]
    assert at[-90.0]["force_n"][0] == pytest.approx(0.13 * 1.0 * (100 * 0.9985 - 1), rel=1e-3)


def test_forces_print_in_four_significant_digits(capsys):
    rows = phase_rows(capsys, "--amplitude-um", "100")
    assert main(["modes", "ring", "--phase-shift", "--phase-step-deg", "45",
                 "--amplitude-um", "100"]) == 0
    out = capsys.readouterr().out.splitlines()
    header = out.index("phase_deg   ratio     force_n@1N   force_n@0.5N")
    printed = [line.split()[2:] for line in out[header + 1:]]
    assert printed == [[f"{f:.4g}" for f in row["force_n"]] for row in rows]
    assert printed[2] == ["12.86", "6.43"]  # -90 degrees
