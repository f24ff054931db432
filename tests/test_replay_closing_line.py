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
