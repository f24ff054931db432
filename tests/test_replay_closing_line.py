"""frictex replay's closing line names everything it wrote in its folder."""

from frictex.app.commands.cli import main


def test_the_closing_line_names_the_frames_folder_and_its_count(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out),
                 "--frames", "5"]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    pngs = len(list((out / "frames").glob("*.png")))
    assert pngs > 0
    assert f"commands.csv, friction.csv, summary.json, frames/ ({pngs} PNGs)" in line, line


def test_without_frames_no_folder_is_named(tmp_path, capsys):
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(tmp_path / "r")]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "commands.csv, friction.csv, summary.json;" in line and "frames/" not in line


def test_quiet_drops_the_closing_line_but_never_a_warning(tmp_path, capsys):
    """--quiet hid the warnings with the summary line: a replay whose samples went back
    in time, jumped and left the display (or, with a device, was clamped to its limit
    for half its samples) said nothing on stderr and exited 0."""
    trace = tmp_path / "t.csv"
    trace.write_text("t_s,finger,x_mm,y_mm\n0,0,10,10\n0.02,0,11,10\n0.01,0,12,10\n"
                     "0.03,0,13,10\n0.2,0,200,10\n0.22,0,14,10\n")
    assert main(["replay", "grating-5mm", str(trace), "--out", str(tmp_path / "r"),
                 "--quiet"]) == 0
    got = capsys.readouterr()
    assert got.out == ""
    warnings = got.err.strip().splitlines()
    assert len(warnings) == 3 and all(w.startswith("frictex: warning: ") for w in warnings)
    assert "went back in time" in got.err and "off the 108 x 64.8 mm display" in got.err
