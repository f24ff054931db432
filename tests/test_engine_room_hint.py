"""A replay refused for disk room suggests Parquet only where Parquet's own estimate
fits the room free (it was suggested with 87 MB free where Parquet needed ~192 MB)."""

import shutil

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine import tables


def _refusal(tmp_path, monkeypatch, capsys, free_bytes, fmt="csv"):
    monkeypatch.setattr(shutil, "disk_usage", lambda path: shutil._ntuple_diskusage(
        1 << 40, (1 << 40) - free_bytes, free_bytes))
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(tmp_path / fmt),
                 "--format", fmt, "--quiet"]) == 1
    return capsys.readouterr().err


def _need(err) -> float:
    """The bytes a refusal says the outputs need (its 'need about N MB')."""
    said = err.split("need about ")[1].split(" and ")[0]
    number, unit = said.split()
    return float(number) * {"kB": 1e3, "MB": 1e6, "GB": 1e9, "B": 1}[unit]


@pytest.mark.parametrize("fmt", ["csv", "npz"])
def test_parquet_is_suggested_only_where_its_estimate_fits(tmp_path, monkeypatch, capsys, fmt):
    err = _refusal(tmp_path, monkeypatch, capsys, 1 << 20, fmt)
    assert "need about" in err and "--format parquet" not in err, err
    parquet = _need(_refusal(tmp_path, monkeypatch, capsys, 1 << 20, "parquet"))
    # room for Parquet's outputs and the margin, not for this format's
    room = int(parquet * 1.2) + tables.RESERVE_BYTES
    err = _refusal(tmp_path, monkeypatch, capsys, room, fmt)
    assert _need(err) + tables.RESERVE_BYTES > room
    assert "--format parquet" in err, err
    assert not (tmp_path / fmt).exists()
