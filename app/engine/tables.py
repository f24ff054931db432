"""Streaming writers for replay outputs: CSV or NPZ tables written chunk by chunk.

Memory stays bounded whatever the length of the replay: each chunk of rows is written
as it comes. Files are written under a temporary name and renamed only by
:meth:`TableWriter.commit`, so an interrupted replay never leaves a file that looks
complete; :meth:`TableWriter.abort` removes the partial file.

NPZ: numpy's ``.npz`` is a zip of ``.npy`` files. Columns are streamed to raw temporary
files and, at commit, each is copied into the zip behind its ``.npy`` header (known only
then, with the final row count), so ``np.load(path)[column]`` reads them back.
"""

from __future__ import annotations

import os
import shutil
import zipfile
from pathlib import Path

import numpy as np


class TableWriter:
    """Rows of named columns, appended in chunks, to ``<stem>.csv`` or ``<stem>.npz``.

    ``columns``: (name, numpy dtype, CSV %-format) triples.
    """

    def __init__(self, out_dir: Path, stem: str, columns, fmt: str):
        if fmt not in ("csv", "npz"):
            raise ValueError(f"output format {fmt!r}: expected csv or npz")
        self.fmt = fmt
        self.columns = list(columns)
        self.path = Path(out_dir) / f"{stem}.{fmt}"
        self.partial = self.path.with_name(self.path.name + ".partial")
        self.rows = 0
        if fmt == "csv":
            self._fh = open(self.partial, "w", encoding="ascii", newline="\n")
            self._fh.write(",".join(name for name, _, _ in self.columns) + "\n")
            self._row_format = ",".join(f for _, _, f in self.columns) + "\n"
        else:
            self._raw = {name: open(self._raw_path(name), "wb") for name, _, _ in self.columns}

    def _raw_path(self, name: str) -> Path:
        return self.path.with_name(f"{self.path.name}.{name}.raw")

    def write(self, chunk: dict[str, np.ndarray]) -> None:
        """Append rows: one equal-length 1-D array per column."""
        n = len(next(iter(chunk.values())))
        if n == 0:
            return
        if self.fmt == "csv":
            # one % per row is what np.savetxt does too; zip keeps it to a single pass
            cols = [chunk[name].tolist() for name, _, _ in self.columns]
            self._fh.write("".join(self._row_format % row for row in zip(*cols)))
        else:
            for name, dtype, _ in self.columns:
                self._raw[name].write(np.ascontiguousarray(chunk[name], dtype=dtype).tobytes())
        self.rows += n

    def commit(self) -> Path:
        """Finish the file and move it into place; returns its path."""
        if self.fmt == "csv":
            self._fh.close()
        else:
            for fh in self._raw.values():
                fh.close()
            with zipfile.ZipFile(self.partial, "w", compression=zipfile.ZIP_STORED,
                                 allowZip64=True) as zf:
                for name, dtype, _ in self.columns:
                    header = {"descr": np.lib.format.dtype_to_descr(np.dtype(dtype)),
                              "fortran_order": False, "shape": (self.rows,)}
                    with zf.open(f"{name}.npy", "w", force_zip64=True) as member:
                        np.lib.format.write_array_header_2_0(member, header)
                        with open(self._raw_path(name), "rb") as raw:
                            shutil.copyfileobj(raw, member, 1 << 20)
                    os.remove(self._raw_path(name))
        os.replace(self.partial, self.path)
        return self.path

    def abort(self) -> None:
        """Close and delete everything written so far."""
        if self.fmt == "csv":
            self._fh.close()
        else:
            for name, fh in self._raw.items():
                fh.close()
                self._raw_path(name).unlink(missing_ok=True)
        self.partial.unlink(missing_ok=True)
