"""``frictex.replay``'s ``format``: a name that is none of csv, npz or parquet is said to be
so, with ``out`` or without it (without, the message was that the tables are kept in
memory, as for a good name)."""

import pytest

import frictex


@pytest.mark.parametrize("out", [None, "run"])
def test_an_unknown_format_is_named_as_such_with_or_without_out(tmp_path, out):
    folder = None if out is None else tmp_path / out
    with pytest.raises(frictex.InputError) as caught:
        frictex.replay("grating-5mm", "swipe-40mms-50hz", out=folder, format="xls")
    assert str(caught.value) == "format 'xls': expected one of csv, npz, parquet"
    assert folder is None or not folder.exists()


def test_a_known_format_without_out_says_the_tables_are_kept_in_memory():
    with pytest.raises(frictex.InputError, match="kept in memory unless out names a folder"):
        frictex.replay("grating-5mm", "swipe-40mms-50hz", format="parquet")
