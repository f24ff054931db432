"""A travelling-wave replay's finger with no contact sample (a trace of lone up events) has
no force error to report: null, not 0 N (as its amplitude errors are)."""

import json

from frictex.app.commands.cli import main


def test_a_finger_without_contact_has_null_force_errors(tmp_path):
    trace = tmp_path / "ups.csv"
    trace.write_text("t_s,finger,x_mm,y_mm,event\n0,0,70,15,up\n0.01,1,70,15,up\n")
    out = tmp_path / "out"
    assert main(["replay", "guidance-ring", str(trace), "--out", str(out), "--quiet"]) == 0
    forces = json.loads((out / "summary.json").read_text())["forces"]
    assert forces, "the ring's force stage reports its fingers"
    for entry in forces.values():
        assert entry["contact_samples"] == 0
        assert entry["force_error_rms_n"] is None and entry["force_error_max_n"] is None
        assert entry["wanted_max_n"] is None
