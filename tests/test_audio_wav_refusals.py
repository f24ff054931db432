"""``audio:wav:PATH`` refuses what it cannot do in one line naming the file: faults (a
serial link's; --faults corrupt=0.1 was ignored without a word), a file system that
refuses the writes (/dev/full printed a bare '[Errno 28] No space left on device'); and
a pipe, which cannot be rewound to its header, gets the stream ('File or stream is not
seekable' before)."""

from __future__ import annotations

import os
import threading
from pathlib import Path

import numpy as np
import pytest
from scipy.io import wavfile

import frictex
from frictex.device.errors import DeviceError, InputError

SCENE, TRACE = "grating-5mm", "swipe-40mms-50hz"


def test_faults_are_refused_on_audio(tmp_path):
    path = tmp_path / "a.wav"
    with pytest.raises(InputError) as refused:
        frictex.replay(SCENE, TRACE, device=f"audio:wav:{path}", faults="corrupt=0.1")
    assert str(refused.value) == (f"audio:wav:{path}: faults are injected into a serial "
                                  "link (sim or a port); audio has none")
    assert not path.exists()


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full")
def test_a_full_disk_names_the_file():
    with pytest.raises(DeviceError) as refused:
        frictex.replay(SCENE, TRACE, device="audio:wav:/dev/full")
    assert str(refused.value) == "audio:wav:/dev/full: cannot write it: No space left on device"


def test_a_pipe_gets_the_whole_stream(tmp_path):
    fifo, copy = tmp_path / "w.fifo", tmp_path / "copy.wav"
    os.mkfifo(fifo)
    reader = threading.Thread(target=lambda: copy.write_bytes(Path(fifo).read_bytes()))
    reader.start()
    run = frictex.replay(SCENE, TRACE, device=f"audio:wav:{fifo}")
    reader.join(timeout=30)
    with pytest.warns(wavfile.WavFileWarning, match="Reached EOF prematurely"):
        rate, frames = wavfile.read(copy)  # its header declares the most a file holds
    assert rate == run.summary.device["audio"]["rate_hz"]
    assert frames.shape[0] > 0 and np.max(np.abs(frames)) > 0
