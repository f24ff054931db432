"""``frictex trace synth``'s output files: refused in one line naming the option, exit 2,
before anything is written."""

import os

from frictex.app.commands.cli import main


def test_a_truth_that_is_the_trace_itself_is_refused(tmp_path, capsys):
    os.symlink("me.csv", tmp_path / "link.csv")
    for truth in ("me.csv", "./me.csv", "link.csv"):
        assert main(["trace", "synth", "human", "--rate", "120", "--duration", "1", "-o",
                     str(tmp_path / "me.csv"), "--truth", str(tmp_path / truth)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "the same file as -o" in err[0]
    assert sorted(os.listdir(tmp_path)) == ["link.csv"]


def test_an_output_in_a_missing_folder_is_named_with_its_option(tmp_path, capsys):
    missing = tmp_path / "nonexist" / "dir"
    assert main(["trace", "synth", "swipe", "--duration", "1", "-o", str(missing / "x.csv")]) == 2
    assert capsys.readouterr().err.strip() == (
        f"frictex: error: -o {missing / 'x.csv'}: the folder {missing} does not exist; give a "
        "file in an existing folder")
    assert main(["trace", "synth", "swipe", "--duration", "1", "-o", str(tmp_path / "x.csv"),
                 "--truth", str(missing / "t.csv")]) == 2
    assert capsys.readouterr().err.startswith(f"frictex: error: --truth {missing / 't.csv'}: ")
    assert not (tmp_path / "x.csv").exists()
