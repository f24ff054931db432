"""``audio:wav:PATH`` where PATH is a folder: the whole replay ran before the rename failed
with '[Errno 21] Is a directory', leaving PATH.partial beside it. A folder is refused at
open, and a rename that fails removes the stream and names the file."""

from __future__ import annotations

import numpy as np
import pytest

from frictex.device.errors import DeviceError, InputError
from frictex.device.link.host import open_sink

RATE = 10_000.0


def test_a_folder_is_refused_at_open(tmp_path):
    folder = tmp_path / "wd"
    folder.mkdir()
    with pytest.raises(InputError) as refused:
        open_sink(f"audio:wav:{folder}", 1, RATE, paced=True)
    assert str(refused.value) == (f"audio:wav:{folder}: is a folder; give the path of a "
                                  ".wav file to write")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["wd"]


def test_a_failed_rename_discards_the_stream_and_names_the_file(tmp_path):
    path = tmp_path / "s.wav"
    sink = open_sink(f"audio:wav:{path}", 1, RATE, paced=True)
    sink.send(0, np.full((500, 1), 1.0))
    path.mkdir()  # made while the stream ran: the rename onto it fails
    with pytest.raises(DeviceError) as refused:
        sink.close()
    assert str(refused.value) == f"audio:wav:{path}: cannot write it: Is a directory"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.wav"] and path.is_dir()
