"""Output tables: CSV text exactly Python's %-formatting, npz and Parquet exact, all or nothing."""

import numpy as np
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings, strategies as st

from frictex.app.engine import tables
from frictex.app.engine.csv_text import rows_text
from frictex.app.engine.tables import TableWriter

COLUMNS = [("t_s", np.float64, "%.7f"), ("finger", np.int64, "%d"),
           ("x_mm", np.float64, "%.4f"), ("amplitude_um", np.float64, "%.6f")]

#: values where a float64 product could round the other way, and other edges
HARD = [0.00390625, -0.0, 0.0, -1e-9, 0.5e-6, 2.5e-7, -2.5e-7, 1.00000005, 0.12345675,
        0.12345665, 5e-5, 123456.78901235, 9.9999999995, 1e15, 1e300, -1e300, 2.0 ** 53,
        float("nan"), float("inf"), -float("inf")]


def python_rows(cols, formats) -> bytes:
    """The definition: one %-formatted line per row."""
    fmt = ",".join(formats) + "\n"
    return "".join(fmt % row for row in zip(*(c.tolist() for c in cols))).encode("ascii")


def test_hard_values_format_as_python_does():
    x = np.array(HARD)
    ids = np.arange(x.size, dtype=np.int64) * 7919
    for decimals in (0, 1, 4, 6, 7, 9):
        fmt = f"%.{decimals}f"
        assert bytes(rows_text([x, ids], [fmt, "%d"])) == python_rows([x, ids], [fmt, "%d"])


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=1,
                max_size=50),
       st.integers(min_value=0, max_value=12))
def test_any_float_formats_as_python_does(values, decimals):
    x = np.array(values, dtype=np.float64)
    fmt = f"%.{decimals}f"
    with np.errstate(over="ignore"):
        assert bytes(rows_text([x, x * 3.0], [fmt, "%.4f"])) == python_rows([x, x * 3.0], [fmt, "%.4f"])


@settings(max_examples=100, deadline=None, derandomize=True)
@given(st.lists(st.floats(min_value=-1e6, max_value=1e6), min_size=1, max_size=40).map(
    lambda v: [round(a, 6) + k * 5e-8 for a in v for k in (0, 1)]))
def test_near_half_units_format_as_python_does(values):
    """Values on and next to the half of the last decimal: the float product's own
    rounding must not decide them."""
    x = np.array(values)
    assert bytes(rows_text([x], ["%.7f"])) == python_rows([x], ["%.7f"])


def chunks(n, seed=0):
    rng = np.random.default_rng(seed)
    t = 12.3 + np.arange(n) / 1e4
    cols = {"t_s": t, "finger": rng.integers(0, 3, n).astype(np.int64),
            "x_mm": rng.uniform(-10, 300, n), "amplitude_um": np.abs(rng.normal(0.5, 0.3, n))}
    for lo in range(0, n, 997):
        yield {k: v[lo:lo + 997] for k, v in cols.items()}, lo


@pytest.mark.parametrize("fmt", ["csv", "npz", "parquet"])
def test_tables_hold_every_row_across_batches(tmp_path, monkeypatch, fmt):
    """Several batches (BATCH_ROWS made small), written on the writer's thread: the file
    holds every row once, in order, exactly (CSV: as %-formatted)."""
    monkeypatch.setattr(tables, "BATCH_ROWS", 3000)
    writer = TableWriter(tmp_path, "friction", COLUMNS, fmt)
    parts = []
    for chunk, _ in chunks(10_000):
        writer.write(chunk)
        parts.append(chunk)
    path = writer.commit()
    want = {name: np.concatenate([p[name] for p in parts]) for name, _, _ in COLUMNS}
    if fmt == "csv":
        header = b"t_s,finger,x_mm,amplitude_um\n"
        assert path.read_bytes() == header + python_rows(
            [want[n] for n, _, _ in COLUMNS], [f for _, _, f in COLUMNS])
        return
    if fmt == "parquet":  # required columns: no value is ever missing
        assert [f.nullable for f in pq.read_schema(path)] == [False] * len(COLUMNS)
    got = np.load(path) if fmt == "npz" else pq.read_table(path).to_pydict()
    for name, dtype, _ in COLUMNS:
        assert np.asarray(got[name]).dtype == dtype
        np.testing.assert_array_equal(np.asarray(got[name]), want[name])
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]


@pytest.mark.parametrize("fmt", ["csv", "npz", "parquet"])
def test_abort_leaves_nothing(tmp_path, monkeypatch, fmt):
    monkeypatch.setattr(tables, "BATCH_ROWS", 3000)
    writer = TableWriter(tmp_path, "commands", COLUMNS, fmt)
    for chunk, _ in chunks(7000):
        writer.write(chunk)
    writer.abort()
    assert list(tmp_path.iterdir()) == []


def test_a_failing_write_raises_and_leaves_nothing(tmp_path, monkeypatch):
    """An error on the writer's thread (a full disk) reaches the caller; abort cleans up."""
    monkeypatch.setattr(tables, "BATCH_ROWS", 1000)
    writer = TableWriter(tmp_path, "friction", COLUMNS, "csv")

    def full(batch):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(writer._out, "write", full)
    with pytest.raises(OSError, match="No space left"):
        for chunk, _ in chunks(5000):
            writer.write(chunk)
        writer.commit()
    writer.abort()
    assert list(tmp_path.iterdir()) == []


def test_unknown_format_is_refused(tmp_path):
    with pytest.raises(ValueError, match="output format 'xlsx'"):
        TableWriter(tmp_path, "friction", COLUMNS, "xlsx")


@pytest.mark.parametrize("fmt", ["csv", "npz", "parquet"])
def test_a_table_in_memory_is_what_the_file_reads_back_as(tmp_path, monkeypatch, fmt):
    """MemoryTable (frictex.replay without a folder) holds the rows a writer's file reads
    back as (read_table): the same columns, types and values (CSV: to its decimals)."""
    monkeypatch.setattr(tables, "BATCH_ROWS", 3000)
    writer = TableWriter(tmp_path, "friction", COLUMNS, fmt)
    memory = tables.open_table(None, "friction", COLUMNS, tables.MEMORY)
    for chunk, _ in chunks(10_000):
        writer.write(chunk)
        memory.write(chunk)
    memory.commit()
    got, want = tables.read_table(writer.commit()), memory.table
    assert memory.path is None and want.num_rows == 10_000
    assert got.column_names == want.column_names == [name for name, _, _ in COLUMNS]
    assert [f.nullable for f in want.schema] == [False] * len(COLUMNS)
    for (name, dtype, form), a, b in zip(COLUMNS, got.columns, want.columns):
        a, b = a.to_numpy(), b.to_numpy()
        assert a.dtype == b.dtype == dtype
        if fmt == "csv" and form != "%d":
            np.testing.assert_allclose(a, b, rtol=0, atol=0.51 * 10.0 ** -int(form[2:-1]))
        else:
            np.testing.assert_array_equal(a, b)


def test_an_empty_table_in_memory_has_its_columns():
    memory = tables.MemoryTable(COLUMNS)
    memory.commit()
    assert memory.table.num_rows == 0
    assert [f.type.to_pandas_dtype() for f in memory.table.schema] == [d for _, d, _ in COLUMNS]


@pytest.mark.parametrize("fmt", ["csv", "npz", "parquet"])
@pytest.mark.parametrize("rows", [0, 1000])
def test_a_table_file_reads_back_typed_as_written(tmp_path, fmt, rows):
    """read_table gives the writer's schema (not nullable; a CSV without rows typed as one
    with rows); npz and parquet equal the table in memory exactly."""
    writer = TableWriter(tmp_path, "friction", COLUMNS, fmt)
    memory = tables.open_table(None, "friction", COLUMNS, tables.MEMORY)
    for chunk, _ in chunks(rows):
        writer.write(chunk)
        memory.write(chunk)
    memory.commit()
    path = writer.commit()
    for got in (tables.read_table(path), tables.read_table(path, COLUMNS)):
        assert got.schema.equals(memory.table.schema)
        if fmt != "csv" or rows == 0:
            assert got.equals(memory.table)


@settings(max_examples=25, deadline=None)
@given(sizes=st.lists(st.integers(0, 3000), min_size=1, max_size=4))
def test_npz_bytes_are_zipfiles_own(tmp_path_factory, sizes):
    """The npz written from raw column files (CRCs taken as written, data copied by the
    kernel) is byte for byte the archive zipfile writes for the same members."""
    check_npz_against_zipfile(tmp_path_factory.mktemp("npz"), sizes)


def test_npz_beyond_zip64_limits_is_zipfiles_own(tmp_path, monkeypatch):
    """Members and a directory past the 4 GiB limits take zip64 records as zipfile
    writes them (the limit lowered to 20 kB for both, so that a test can cross it)."""
    import zipfile
    monkeypatch.setattr(zipfile, "ZIP64_LIMIT", 20_000)
    check_npz_against_zipfile(tmp_path, [1500, 2000])


def check_npz_against_zipfile(out, sizes):
    writer = TableWriter(out, "t", COLUMNS, "npz")
    rng = np.random.default_rng(len(sizes))
    chunks = [{name: (rng.integers(0, 9, n) if dtype is np.int64 else rng.normal(size=n))
               for name, dtype, _ in COLUMNS} for n in sizes]
    for chunk in chunks:
        writer.write(chunk)
    path = writer.commit()
    import io
    import zipfile
    with zipfile.ZipFile(path) as archive:
        infos = archive.infolist()
    expected = io.BytesIO()
    with zipfile.ZipFile(expected, "w", zipfile.ZIP_STORED, allowZip64=True) as archive:
        for info, (name, dtype, _) in zip(infos, COLUMNS):
            column = np.concatenate([np.asarray(c[name], dtype=dtype) for c in chunks])
            with archive.open(zipfile.ZipInfo(f"{name}.npy", info.date_time), "w",
                              force_zip64=True) as member:
                np.lib.format.write_array(member, column, version=(2, 0))
    assert path.read_bytes() == expected.getvalue()
    with np.load(path) as got:
        for name, dtype, _ in COLUMNS:
            assert np.array_equal(got[name], np.concatenate([c[name] for c in chunks]))


def test_crc32_combine_is_zlibs():
    import zlib
    rng = np.random.default_rng(3)
    for n1, n2 in [(0, 0), (0, 7), (9, 0), (128, 1), (1000, 65537), (3, 1 << 20)]:
        a, b = rng.bytes(n1), rng.bytes(n2)
        assert tables._crc32_combine(zlib.crc32(a), zlib.crc32(b), n2) == zlib.crc32(a + b)
