"""A refused ``frictex calibrate --device audio:wav:PATH`` (no force reports) replaced an
earlier 1.5 MB file at PATH with a 2 ms stub: the link was closed, committing the WAV, on
every exit. A failed calibration aborts the link, so audio:wav stays all or nothing."""

from __future__ import annotations

from frictex.app.commands.cli import main


def test_a_refused_calibration_leaves_an_earlier_wav_as_it_was(tmp_path, capsys):
    path = tmp_path / "keep.wav"
    path.write_bytes(b"earlier")
    status = main(["calibrate", "--device", f"audio:wav:{path}",
                   "--out", str(tmp_path / "c.toml")])
    assert status != 0 and "sends no force reports" in capsys.readouterr().err
    assert path.read_bytes() == b"earlier"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.wav"]
