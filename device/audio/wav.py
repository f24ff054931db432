"""``audio:wav:PATH``: the stream the audio output would play, written to a WAV file.

The file is RIFF/WAVE, IEEE float (format tag 3), 32-bit float samples, one channel per
actuator, at the plan's audio rate: the very float32 frames PortAudio would be given,
start and end ramps included (a file has no starvation: it is written as fast as the
pipeline runs, unpaced). Full scale 1.0 is ``full_scale_v`` volts of drive. RIFF's 32-bit
sizes bound a file to 4 GiB (about 93 min of one channel at 192 kHz): a stream past that
is a DeviceError. The header's sizes are written when the file is closed.

All or nothing, as a replay's tables: the stream is written under ``PATH.partial`` and
renamed to PATH when it ends (:meth:`WavOutput.close`); a run that fails or is stopped
(:meth:`WavOutput.abort`, a refused closed loop included) removes it and leaves an earlier
PATH as it was, as does a rename the file system refuses. A PATH that is a folder is
refused when the output opens, before anything runs. A PATH that is a character device or
a FIFO (``/dev/null``, a pipe) is written directly; one that cannot be rewound (a pipe)
keeps a header declaring the most a WAV file holds, as streamed WAV does. A write the file
system refuses (a full disk, ``/dev/full``) is a DeviceError naming the file:
``audio:wav:PATH: cannot write it: ...``.
"""

from __future__ import annotations

import os
import stat
import struct
import sys
from pathlib import Path

import numpy as np

from frictex.device.audio.options import AudioPlan
from frictex.device.audio.output import CAUSES, AudioOutput
from frictex.device.errors import DeviceError, InputError

_FLOAT = 3  # WAVE_FORMAT_IEEE_FLOAT
_HEADER = 12 + 26 + 12 + 8  # RIFF, fmt (18-byte body), fact, data chunk header
_MAX_DATA = 2**32 - 1 - _HEADER


def wav_header(channels: int, rate: int, frames: int) -> bytes:
    """The 58-byte header of a float32 WAV file of ``frames`` frames."""
    data = frames * channels * 4
    return (b"RIFF" + struct.pack("<I", _HEADER - 8 + data) + b"WAVE"
            + b"fmt " + struct.pack("<IHHIIHHH", 18, _FLOAT, channels, rate,
                                    rate * channels * 4, channels * 4, 32, 0)
            + b"fact" + struct.pack("<II", 4, frames)
            + b"data" + struct.pack("<I", data))


class WavOutput(AudioOutput):
    """Writes the audio stream to ``path`` (module docstring)."""

    def __init__(self, plan: AudioPlan, path: str, *, phases: bool, stderr=sys.stderr):
        super().__init__(plan, f"audio:wav:{path}", phases=phases, paced=False, stderr=stderr)
        self.path = Path(path)
        if self.path.is_dir():
            raise InputError(f"{self.label}: is a folder; give the path of a .wav file to write")
        self._partial = None if _is_stream(self.path) else self.path.with_name(
            self.path.name + ".partial")
        try:
            self._file = open(self._partial or self.path, "wb")  # noqa: SIM115 (closed by close())
        except OSError as exc:
            raise InputError(f"{self.label}: cannot write it: {exc.strerror or exc}") from None
        # a stream cannot be rewound to its header: it declares the most a file holds
        declared = 0 if self._partial is not None else _MAX_DATA // (plan.channels * 4)
        self._write(wav_header(plan.channels, plan.audio_rate, declared))
        self._frames = 0

    def _write(self, data: bytes) -> None:
        """Write ``data``; a write the file system refuses (a full disk) is a DeviceError
        naming the file."""
        try:
            self._file.write(data)
        except OSError as exc:
            raise self._cannot_write(exc) from None

    def _cannot_write(self, exc: OSError) -> DeviceError:
        return DeviceError(f"{self.label}: cannot write it: {exc.strerror or exc}")

    def _emit(self, frames: np.ndarray) -> None:
        if (self._frames + frames.shape[0]) * self.channels * 4 > _MAX_DATA:
            raise DeviceError(f"{self.label}: the stream outgrows a WAV file's 4 GiB")
        self._write(np.ascontiguousarray(frames, dtype="<f4").tobytes())
        self._frames += frames.shape[0]
        self.commanded_frames += frames.shape[0]

    def _end(self, tail: np.ndarray) -> None:
        try:
            self._emit(tail)
            if self._file.seekable():
                self._file.seek(0)
                self._write(wav_header(self.channels, self.plan.audio_rate, self._frames))
            self._file.close()
        except OSError as exc:  # the buffered rest refused at close
            self._discard()
            raise self._cannot_write(exc) from None
        except BaseException:
            self._discard()
            raise
        if self._partial is not None:
            self._rename()

    def _rename(self) -> None:
        """Put the finished stream at its path; one the file system refuses (a folder made
        there since the open) is removed and is a DeviceError naming the file."""
        try:
            os.replace(self._partial, self.path)
        except OSError as exc:
            self._partial.unlink(missing_ok=True)
            raise self._cannot_write(exc) from None

    def abort(self) -> None:
        """A failed or stopped run: close the file and remove what was written (an earlier
        file at the path stays); idempotent."""
        if not self.closed:
            self.closed = True
            self._discard()

    def _discard(self) -> None:
        try:
            self._file.close()
        except OSError:  # its buffered rest refused (a full disk): nothing of it is kept
            pass
        if self._partial is not None:
            self._partial.unlink(missing_ok=True)

    def played_frames(self) -> int:
        """Frames written."""
        return self._frames

    def unplayed_by_cause(self) -> dict[str, int]:
        """None: every frame is written."""
        return dict.fromkeys(CAUSES, 0)


def _is_stream(path: Path) -> bool:
    """True for a character device or a FIFO (links followed): written directly."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode)
