"""Output tables written from column arrays, in bounded memory, all or nothing.

A :class:`TableWriter` takes chunks of rows (one 1-D array per column), gathers them
into batches of about :data:`BATCH_ROWS` rows and writes each batch on a thread of its
own, so that formatting and writing overlap the pipeline's compute (the writers release
the GIL); at most one batch is being written while the next is gathered. The file is written under ``<name>.partial`` and renamed only by
:meth:`TableWriter.commit`, so an interrupted run never leaves a file that looks
complete; :meth:`TableWriter.abort` removes what was written.

Formats:

- ``csv``: a header line, then one line per row; each float column has a fixed number
  of decimals (its ``%.Nf`` format), byte for byte Python's ``"%.Nf" % value``
  (``app.engine.csv_text``).
- ``npz``: numpy's zip of ``.npy`` arrays, one per column. Columns are streamed to raw
  files beside the output, their CRC-32 taken as they are written (on the writer
  thread), and at commit the kernel copies them into the zip (``os.copy_file_range``)
  behind headers written here, byte for byte what ``zipfile`` writes. A zip member's
  bytes must be contiguous and the ``.npy`` header holds the row count, known only at
  the end, so a member cannot be written in place while the columns grow together;
  holding the columns in memory instead would not be bounded.
- ``parquet``: Apache Parquet, one row group per batch, snappy-compressed (the codec
  every Parquet reader has); float columns in the BYTE_STREAM_SPLIT encoding (Parquet
  format 2.8: the bytes of each value in separate streams, which the compressor then
  finds alike: the 10-min replay's friction table 135 -> 83 MB and 0.38 -> 0.30 s of
  writer CPU against plain encoding), the finger column dictionary-encoded (dictionary
  encoding the float columns tripled the write time for 10 % in size). Every column is
  declared required (not nullable), as no value is ever missing: the writer then encodes
  no definition levels (the every-layer scene's 10-min friction table, 6 million rows:
  0.32 -> 0.23 s of writer CPU). pandas, polars, pyarrow and DuckDB open it directly.
- ``memory`` (:data:`MEMORY`, ``frictex.replay`` without a folder): no file; a
  :class:`MemoryTable` keeps the rows and its ``table`` is a pyarrow Table once committed.

:func:`open_table` opens the writer of a format; :func:`read_table` reads a written table
back as a pyarrow Table, typed as the writer's (equal to a :class:`MemoryTable`'s for
parquet and npz; CSV to its printed precision).
"""

from __future__ import annotations

import contextlib
import errno
import functools
import io
import os
import shutil
import struct
import zipfile
import zlib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from frictex.app.engine.csv_text import rows_text
from frictex.app.engine.staging import shown_path
from frictex.device.errors import InputError, OutputSpaceError, disk_full

FORMATS = ("csv", "npz", "parquet")
#: the format of tables kept in memory (a pyarrow Table each; no file)
MEMORY = "memory"
#: rows gathered before a batch is written (memory: ~13 MB a batch for six columns)
BATCH_ROWS = 1 << 18
#: free space a batch must leave on the output's file system (bytes)
RESERVE_BYTES = 64 << 20
#: bytes a value takes at most in a Parquet table, for the room check: measured as the
#: file's size over its values (rows x columns) in replays of the bundled scenes and
#: traces (grating-5mm, composed-fine-grating-in-disc and raster-map on
#: human-strokes-120hz, keyclick-beam on keyclick-press-beam-100hz): 0.6 to 3.5 bytes,
#: the most raster-map's friction table; half as much again kept as a margin
PARQUET_VALUE_BYTES = 4
#: what to do where the outputs do not fit, besides freeing some space
WRITE_ELSEWHERE = "or write elsewhere"
SMALLER_FORMAT = "write elsewhere, or use --format parquet (format=\"parquet\" from Python)"


def load_writer(fmt: str) -> None:
    """Import the library that writes ``fmt`` now (pyarrow for Parquet, 0.1-0.2 s),
    before the run's first block, where a replay counts it as writing time."""
    if fmt == "parquet":
        import pyarrow.parquet  # noqa: F401


def row_bytes(columns, fmt: str) -> int:
    """Bytes one row of ``columns`` takes at most in ``fmt``: for values of up to four
    integer digits (CSV), exactly (npz), or :data:`PARQUET_VALUE_BYTES` a value (Parquet,
    compressed: a measured bound, not a guarantee)."""
    if fmt == "csv":
        return sum(3 if f == "%d" else 7 + int(f[2:-1]) for _, _, f in columns)
    if fmt == "parquet":
        return PARQUET_VALUE_BYTES * len(columns)
    return sum(np.dtype(dtype).itemsize for _, dtype, _ in columns)


def room_hint(fmt: str) -> str:
    """What to do where tables in ``fmt`` do not fit: write elsewhere, or (but for Parquet,
    the smallest) write Parquet."""
    return WRITE_ELSEWHERE if fmt == "parquet" else SMALLER_FORMAT


def has_room(out_dir: Path, need_bytes: float) -> bool:
    """Whether ``out_dir``'s file system has room for ``need_bytes`` more and
    :data:`RESERVE_BYTES` to spare (what :func:`check_room` demands)."""
    return need_bytes + RESERVE_BYTES <= shutil.disk_usage(out_dir).free


def check_room(out_dir: Path, need_bytes: float, what: str,
               hint: str = SMALLER_FORMAT) -> None:
    """Raise a one-line :class:`OutputSpaceError` (errno ENOSPC) unless ``out_dir``'s file
    system has room for ``need_bytes`` more and :data:`RESERVE_BYTES` to spare; the
    message names the folder (where it will be: ``staging.shown_path``) and ``what``, and
    ends with ``hint``. A file system of no size (proc, sysfs:
    nothing can be written there) is bad input, said as such."""
    usage = shutil.disk_usage(out_dir)
    shown = shown_path(out_dir)  # not a staging folder's name
    if usage.total == 0:
        raise InputError(f"{shown}: a file system that holds no files (such as /proc or "
                         "/sys); write the outputs elsewhere")
    if not has_room(out_dir, need_bytes):
        free = shutil.disk_usage(out_dir).free
        full = OutputSpaceError(f"{shown}: {what} need about {_size(need_bytes)} and "
                                f"{_size(free)} is free (a margin of {_size(RESERVE_BYTES)} "
                                f"kept); free some space, {hint}")
        full.errno = errno.ENOSPC
        raise full


#: the share of the memory available (:func:`available_memory`) that a run's arrays may
#: be planned to take: the rest is left to the process's other needs and to the system
MEMORY_SHARE = 0.5


def available_memory() -> int | None:
    """Bytes of memory a process can take now without swapping: Linux's ``MemAvailable``
    (``/proc/meminfo``), elsewhere the free physical pages (``os.sysconf``); None when
    the system says neither."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024  # the file says kB: KiB
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, OSError, ValueError):
        return None


def check_memory(need_bytes: float, what: str, hint: str) -> None:
    """Raise a one-line :class:`InputError` when ``need_bytes`` is more than
    :data:`MEMORY_SHARE` (half) of :func:`available_memory`, before anything is computed;
    the message names ``what`` and ends with ``hint``. Nothing is checked where the
    memory available is unknown."""
    available = available_memory()
    if available is not None and need_bytes > MEMORY_SHARE * available:
        raise InputError(f"{what} would take about {_size(need_bytes)} of memory, more than "
                         f"{MEMORY_SHARE:.0%} of the {_size(available)} available: {hint}")


def _size(n: float) -> str:
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if n < 1000 or unit == "PB":
            return f"{n:.3g} {unit}"
        n /= 1000


class TableWriter:
    """Rows of named columns, appended in chunks, to ``<stem>.<fmt>`` in ``out_dir``.

    ``columns``: (name, numpy dtype, CSV %-format) triples; the %-format is ``%d`` for
    integer columns and ``%.Nf`` for float columns.
    """

    def __init__(self, out_dir: Path, stem: str, columns, fmt: str):
        if fmt not in FORMATS:
            raise InputError(f"output format {fmt!r}: expected one of {', '.join(FORMATS)}")
        self.fmt = fmt
        self.columns = list(columns)
        self.path = Path(out_dir) / f"{stem}.{fmt}"
        self.partial = self.path.with_name(self.path.name + ".partial")
        self.rows = 0
        self._pending: list[dict[str, np.ndarray]] = []
        self._pending_rows = 0
        self._out = _OPENERS[fmt](self)
        self._thread = ThreadPoolExecutor(1, thread_name_prefix=f"frictex-{stem}")
        self._writing = None  # the batch being written (a Future)

    def write(self, chunk: dict[str, np.ndarray]) -> None:
        """Append rows: one equal-length 1-D array per column."""
        n = len(next(iter(chunk.values())))
        if n == 0:
            return
        self._pending.append({name: np.asarray(chunk[name], dtype=dtype)
                              for name, dtype, _ in self.columns})
        self._pending_rows += n
        self.rows += n
        if self._pending_rows >= BATCH_ROWS:
            self._flush()

    def _flush(self) -> None:
        self._wait_written()  # raises the writer's error, if any
        if self._pending:
            check_room(self.path.parent, self._pending_rows * row_bytes(self.columns, self.fmt),
                       f"the next {self._pending_rows} rows of {self.path.name}",
                       room_hint(self.fmt))
            self._writing = self._thread.submit(self._write_batch, self._pending)
            self._pending, self._pending_rows = [], 0

    def _write_batch(self, chunks: list[dict[str, np.ndarray]]) -> None:
        self._out.write(chunks)  # as handed over: joining them first would copy every byte

    def _wait_written(self) -> None:
        writing, self._writing = self._writing, None
        if writing is not None:
            with self._full_disk_said():
                writing.result()

    def commit(self) -> Path:
        """Finish the file and move it into place; returns its path."""
        try:
            self._flush()
            self._wait_written()
        finally:
            self._thread.shutdown()
        with self._full_disk_said():
            self._out.close()
            os.replace(self.partial, self.path)
        return self.path

    @contextlib.contextmanager
    def _full_disk_said(self):
        """A disk or quota filled while writing (ENOSPC, EDQUOT) raised as a one-line
        :class:`OutputSpaceError` naming the output folder (``staging.shown_path``) and
        the file, with what to do; other errors as they are."""
        try:
            yield
        except OSError as exc:
            full = disk_full(exc, f"{shown_path(self.path.parent)}: the disk filled while "
                                  f"{self.path.name} was written ({exc.strerror}); free some "
                                  f"space, {room_hint(self.fmt)}")
            if full is None:
                raise
            raise full from None

    def abort(self) -> None:
        """Close and delete everything written so far."""
        self._pending = []
        if self._writing is not None:
            self._writing.exception()  # wait for it; its error is moot now
        self._thread.shutdown()
        self._out.discard()
        self.partial.unlink(missing_ok=True)


class MemoryTable:
    """Rows of named columns kept in memory; :meth:`commit` makes them a pyarrow Table.

    The same interface as :class:`TableWriter` (``write``, ``commit``, ``abort``) without a
    file: ``table`` is the result once committed (columns typed as the writers' files,
    declared not nullable), ``path`` is None. Memory: 8 bytes per value.
    """

    def __init__(self, columns):
        self.columns = list(columns)
        self.path = None
        self.rows = 0
        self.table = None
        self._chunks: list[dict[str, np.ndarray]] = []

    def write(self, chunk: dict[str, np.ndarray]) -> None:
        """Append rows: one equal-length 1-D array per column."""
        n = len(next(iter(chunk.values())))
        if n:
            self._chunks.append({name: np.asarray(chunk[name], dtype=dtype)
                                 for name, dtype, _ in self.columns})
            self.rows += n

    def commit(self) -> None:
        """Join the rows into ``table``."""
        import pyarrow as pa
        schema = arrow_schema(self.columns)
        arrays = [np.concatenate([c[f.name] for c in self._chunks]) if self._chunks
                  else np.zeros(0, dtype=np.dtype(f.type.to_pandas_dtype())) for f in schema]
        self.table = pa.Table.from_arrays([pa.array(a, type=f.type) for a, f in zip(arrays, schema)],
                                          schema=schema)
        self._chunks = []

    def abort(self) -> None:
        """Drop the rows."""
        self._chunks = []


def open_table(out_dir: Path | None, stem: str, columns, fmt: str) -> TableWriter | MemoryTable:
    """The writer of table ``stem`` in ``fmt``: a :class:`MemoryTable` for :data:`MEMORY`
    (``out_dir`` unused), else a :class:`TableWriter` into ``out_dir``."""
    if fmt == MEMORY:
        return MemoryTable(columns)
    if out_dir is None:
        raise InputError(f"a {fmt} table is a file: it needs an output folder")
    return TableWriter(Path(out_dir), stem, columns, fmt)


def arrow_schema(columns):
    """The pyarrow schema of ``columns`` ((name, dtype, %-format) triples), not nullable."""
    import pyarrow as pa
    return pa.schema([pa.field(name, pa.from_numpy_dtype(np.dtype(dtype)), nullable=False)
                      for name, dtype, _ in columns])


def read_table(path: Path, columns=None):
    """A table file written here (csv, npz or parquet, by its suffix) as a pyarrow Table
    typed as the writer's: the schema of ``columns`` ((name, dtype, %-format) triples, as
    given to the writer), or where None the one every frictex table has (``finger``
    int64, every other column float64), all declared not nullable, as a
    :class:`MemoryTable`'s. Parquet and npz then read back exactly as they were written
    (``table.equals`` holds); CSV to its printed precision (each column's ``%.Nf``), and
    a CSV without rows with its columns typed all the same.
    """
    import pyarrow as pa
    path = Path(path)
    fmt = path.suffix[1:]
    if fmt == "parquet":
        import pyarrow.parquet as pq
        table = pq.read_table(path)
    elif fmt == "npz":
        with np.load(path) as arrays:
            table = pa.table({name: arrays[name] for name in arrays.files})
    elif fmt == "csv":
        import pyarrow.csv as pa_csv
        with open(path, "rb") as fh:
            names = fh.readline().decode("ascii").strip().split(",")
        schema = _schema(names, columns)
        table = pa_csv.read_csv(path, convert_options=pa_csv.ConvertOptions(
            column_types={f.name: f.type for f in schema}))
    else:
        raise InputError(f"{path}: not a table file ({', '.join(FORMATS)})")
    return table.cast(_schema(table.column_names, columns))


def _schema(names, columns):
    """The writer's schema of a table with columns ``names`` (see :func:`read_table`)."""
    if columns is None:
        columns = [(name, np.int64 if name == "finger" else np.float64, None) for name in names]
    elif [name for name, _, _ in columns] != list(names):
        raise InputError(f"a table with columns {', '.join(names)}: expected "
                         f"{', '.join(name for name, _, _ in columns)}")
    return arrow_schema(columns)


class _Csv:
    def __init__(self, table: TableWriter):
        self.columns = table.columns
        self.fh = open(table.partial, "wb")
        self.fh.write((",".join(name for name, _, _ in self.columns) + "\n").encode("ascii"))

    def write(self, chunks: list[dict[str, np.ndarray]]) -> None:
        formats = [fmt for _, _, fmt in self.columns]
        for chunk in chunks:
            self.fh.write(rows_text([chunk[name] for name, _, _ in self.columns], formats))

    def close(self) -> None:
        self.fh.close()

    discard = close


class _Npz:
    def __init__(self, table: TableWriter):
        self.table = table
        self.raw = {name: open(self._raw_path(name), "wb") for name, _, _ in table.columns}
        self.crc = dict.fromkeys(self.raw, 0)  # each raw file's CRC-32 so far

    def _raw_path(self, name: str) -> Path:
        return self.table.path.with_name(f"{self.table.path.name}.{name}.raw")

    def write(self, chunks: list[dict[str, np.ndarray]]) -> None:
        for name, fh in self.raw.items():
            for chunk in chunks:
                data = np.ascontiguousarray(chunk[name]).data
                fh.write(data)
                self.crc[name] = zlib.crc32(data, self.crc[name])  # (it releases the GIL)

    def close(self) -> None:
        for fh in self.raw.values():
            fh.close()
        members = []
        with open(self.table.partial, "wb", buffering=0) as out:
            for name, dtype, _ in self.table.columns:
                header = io.BytesIO()
                np.lib.format.write_array_header_2_0(
                    header, {"descr": np.lib.format.dtype_to_descr(np.dtype(dtype)),
                             "fortran_order": False, "shape": (self.table.rows,)})
                members.append(_stored_member(out, f"{name}.npy", header.getvalue(),
                                              self._raw_path(name), self.crc[name]))
                os.remove(self._raw_path(name))
            _zip_directory(out, members)

    def discard(self) -> None:
        for name, fh in self.raw.items():
            fh.close()
            self._raw_path(name).unlink(missing_ok=True)


class _Parquet:
    def __init__(self, table: TableWriter):
        import pyarrow as pa
        import pyarrow.parquet as pq
        self.schema = arrow_schema(table.columns)
        floats = [name for name, dtype, _ in table.columns if np.dtype(dtype).kind == "f"]
        self.writer = pq.ParquetWriter(table.partial, self.schema, compression="snappy",
                                       use_dictionary=["finger"], use_byte_stream_split=floats)
        self.pa = pa

    def write(self, chunks: list[dict[str, np.ndarray]]) -> None:
        arrays = [self.pa.chunked_array([self.pa.array(c[field.name]) for c in chunks],
                                        type=field.type) for field in self.schema]
        self.writer.write_table(self.pa.Table.from_arrays(arrays, schema=self.schema),
                                row_group_size=sum(len(c["t_s"]) for c in chunks))

    def close(self) -> None:
        self.writer.close()

    discard = close


#: the date every npz member carries: the zip format's earliest, not the time of writing,
#: so that two replays of the same inputs are byte-identical in every format (as
#: reproducible builds date their archives)
ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)


def _stored_member(out, name: str, head: bytes, raw: Path, raw_crc: int) -> zipfile.ZipInfo:
    """Write a stored (uncompressed) zip member, ``head`` then the file ``raw`` whose
    CRC-32 is ``raw_crc``, at ``out``'s position (an unbuffered file); its ZipInfo.

    The same bytes as ``zipfile.ZipFile.open(name, "w", force_zip64=True)`` would write
    (tests/test_tables.py compares them), without reading the data again: the CRC was
    taken as it was written, and the kernel copies the file (``os.copy_file_range``)."""
    size = os.path.getsize(raw)
    info = zipfile.ZipInfo(name, date_time=ZIP_EPOCH)
    info.compress_type = zipfile.ZIP_STORED
    info.external_attr = 0o600 << 16  # as zipfile gives a member written by name
    info.file_size = info.compress_size = len(head) + size
    info.CRC = _crc32_combine(zlib.crc32(head), raw_crc, size)
    info.header_offset = out.tell()
    out.write(info.FileHeader(zip64=True))
    out.write(head)
    with open(raw, "rb") as src:
        _copy_file(src, out, size)
    return info


def _copy_file(src, out, size: int) -> None:
    """Copy ``size`` bytes from ``src`` to ``out`` (both at their positions) in the kernel
    where it can, else through a buffer."""
    try:
        while size > 0:
            done = os.copy_file_range(src.fileno(), out.fileno(), size)
            if done == 0:
                raise OSError(errno.EIO, "the file ended early")
            size -= done
    except (AttributeError, OSError) as exc:  # not Linux, or a file system without it
        if isinstance(exc, OSError) and exc.errno not in (errno.EXDEV, errno.ENOSYS,
                                                         errno.EINVAL, errno.EOPNOTSUPP):
            raise
        shutil.copyfileobj(src, out, _COPY_BYTES)


def _zip_directory(out, members: list[zipfile.ZipInfo]) -> None:
    """The zip's central directory and end records after its ``members`` (written by
    :func:`_stored_member`), as ``zipfile`` writes them when it closes an archive."""
    start = out.tell()
    for info in members:
        dt = info.date_time
        dosdate = (dt[0] - 1980) << 9 | dt[1] << 5 | dt[2]
        dostime = dt[3] << 11 | dt[4] << 5 | (dt[5] // 2)
        extra, size, offset = [], info.file_size, info.header_offset
        if size > zipfile.ZIP64_LIMIT:
            extra += [size, size]
            size = 0xFFFFFFFF
        if offset > zipfile.ZIP64_LIMIT:
            extra.append(offset)
            offset = 0xFFFFFFFF
        extra_data = struct.pack("<HH" + "Q" * len(extra), 1, 8 * len(extra), *extra) if extra else b""
        name = info.filename.encode("ascii")
        out.write(struct.pack(zipfile.structCentralDir, zipfile.stringCentralDir,
                              info.create_version, info.create_system, info.extract_version,
                              info.reserved, info.flag_bits, info.compress_type, dostime,
                              dosdate, info.CRC, size, size, len(name), len(extra_data), 0, 0,
                              info.internal_attr, info.external_attr, offset))
        out.write(name + extra_data)
    end = out.tell()
    count, dir_size = len(members), end - start
    if start > zipfile.ZIP64_LIMIT or dir_size > zipfile.ZIP64_LIMIT:
        out.write(struct.pack(zipfile.structEndArchive64, zipfile.stringEndArchive64, 44, 45,
                              45, 0, 0, count, count, dir_size, start))
        out.write(struct.pack(zipfile.structEndArchive64Locator,
                              zipfile.stringEndArchive64Locator, 0, end, 1))
    out.write(struct.pack(zipfile.structEndArchive, zipfile.stringEndArchive, 0, 0, count,
                          count, min(dir_size, 0xFFFFFFFF), min(start, 0xFFFFFFFF), 0))


def _crc32_combine(crc1: int, crc2: int, len2: int) -> int:
    """The CRC-32 of A + B from ``crc1`` = CRC-32(A), ``crc2`` = CRC-32(B) and ``len2`` =
    len(B) (zlib's crc32_combine, which Python's zlib does not offer): crc1 carried
    through len2 zero bytes, by the CRC's operator for 2**k zero bytes for each bit k
    of len2 (:func:`_zero_bytes`), then crc2 added (over GF(2))."""
    k = 0
    while len2 >> k:
        if len2 >> k & 1:
            crc1 = _gf2_times(_zero_bytes(k), crc1)
        k += 1
    return crc1 ^ crc2


@functools.lru_cache(maxsize=None)
def _zero_bytes(k: int) -> list[int]:
    """The CRC-32 register's operator (32 columns over GF(2)) for 2**k zero bytes."""
    if k == 0:
        bit = [0xEDB88320] + [1 << j for j in range(31)]  # one zero bit
        for _ in range(3):  # 2, 4, 8 bits
            bit = _gf2_square(bit)
        return bit
    return _gf2_square(_zero_bytes(k - 1))


def _gf2_times(matrix: list[int], vector: int) -> int:
    total, row = 0, 0
    while vector:
        if vector & 1:
            total ^= matrix[row]
        vector >>= 1
        row += 1
    return total


def _gf2_square(matrix: list[int]) -> list[int]:
    return [_gf2_times(matrix, column) for column in matrix]


#: bytes copied at a time where the kernel cannot copy a file
_COPY_BYTES = 1 << 24

_OPENERS = {"csv": _Csv, "npz": _Npz, "parquet": _Parquet}
