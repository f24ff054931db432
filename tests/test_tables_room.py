"""The room check before tables are written: Parquet estimated on its own (compressed,
smaller than npz), and a refusal never suggests the format already chosen."""

import shutil
from collections import namedtuple

import numpy as np
import pytest

from frictex.app.engine import tables
from frictex.app.engine.sinks import command_columns, friction_columns
from frictex.app.engine.tables import TableWriter, row_bytes
from frictex.device.errors import OutputSpaceError

usage = namedtuple("usage", "total used free")


@pytest.mark.parametrize("columns", [friction_columns(False), friction_columns(True),
                                     command_columns(("amplitude",), False)])
def test_parquet_is_estimated_below_npz(columns):
    assert row_bytes(columns, "parquet") == tables.PARQUET_VALUE_BYTES * len(columns)
    assert row_bytes(columns, "parquet") < row_bytes(columns, "npz")


@pytest.mark.parametrize("fmt, suggested", [("csv", True), ("npz", True), ("parquet", False)])
def test_a_refusal_suggests_parquet_only_when_it_is_not_chosen(tmp_path, monkeypatch, fmt,
                                                                suggested):
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(1 << 30, 0, 1 << 20))
    columns = friction_columns(False)
    table = TableWriter(tmp_path, "friction", columns, fmt)
    table.write({name: np.zeros(10, dtype=dtype) for name, dtype, _ in columns})
    with pytest.raises(OutputSpaceError) as raised:
        table.commit()
    table.abort()
    assert str(raised.value).startswith(f"{tmp_path}: the next 10 rows of friction.{fmt} need")
    assert ("--format parquet" in str(raised.value)) == suggested
