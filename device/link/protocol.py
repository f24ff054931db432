"""The host <-> microcontroller wire protocol (normative text: ``device/PROTOCOL.md``).

Pure: messages are frozen dataclasses, :func:`encode` turns one into the bytes of a
frame, :class:`Decoder` turns any byte stream back into frames and counts what it had
to throw away. No I/O here; the link and the simulated device own their ports.

Grammar of the byte stream (PROTOCOL.md section 2)::

    stream  = { frame }
    frame   = COBS(body) 0x00
    body    = version:u8 type:u8 seq:u16 payload crc:u32      (little-endian)
    crc     = CRC-32/ISO-HDLC (zlib.crc32) of version..payload

Amplitudes travel as unsigned 16-bit fixed point, :data:`AMPLITUDE_STEP_UM` (1/4096 um)
per count; phases as unsigned 16-bit fractions of a turn (2 pi / 65536 rad per count).

Forces travel as signed 16-bit fixed point, :data:`FORCE_STEP_N` (1/4096 N) per count.

Versions: a frame's ``version`` byte selects the payload layouts. Version 2 adds the
buffer-accounting fields to :class:`Status` and the :class:`Flushed` message; version 3
adds the :class:`ForceReport` message (lateral and normal force); version 4 adds repair:
:class:`Missing` (the device names the host frames it found missing) and
:class:`Resend` (the host sends a missing Block again). Every other payload is the same
in all four. :func:`encode` writes the version asked for; a :class:`Decoder`
accepts versions 1 to its ``max_version``.
"""

from __future__ import annotations

import reprlib
import struct
import zlib
from dataclasses import dataclass, field, fields

import numpy as np

from frictex.device.errors import DeviceError

#: the newest version this module speaks (it speaks every version from 1)
PROTOCOL_VERSION = 4
#: the longest a device may take to be still after the host falls silent (ms):
#: its ``watchdog_ms + ramp_ms`` (section 5.3); an audio output's block and ramp too
MAX_STOP_MS = 50
#: sample numbers are u64 and wrap modulo this (PROTOCOL.md 4.3)
INDEX_MODULUS = 2 ** 64
#: one count of a wire amplitude (um, zero-to-peak)
AMPLITUDE_STEP_UM = 1.0 / 4096.0
#: largest wire amplitude (um)
AMPLITUDE_MAX_UM = 65535 * AMPLITUDE_STEP_UM
#: one count of a wire phase (rad)
PHASE_STEP_RAD = 2.0 * np.pi / 65536.0
#: one count of a wire force in a ForceReport (N)
FORCE_STEP_N = 1.0 / 4096.0
#: ForceReport values per message, at most
FORCE_PAIRS_MAX = 255
#: sequence numbers in one Missing message, at most
MISSING_MAX = 16
#: message types from here up travel device -> host; below, host -> device (section 4)
DEVICE_TYPES = 0x80
#: largest body (version..crc) a receiver must accept, bytes
MAX_BODY = 4096
#: largest COBS-stuffed frame before its 0x00 delimiter, bytes (4113; 4114 with it)
MAX_STUFFED = MAX_BODY + MAX_BODY // 254 + 1
_HEADER = struct.Struct("<BBH")
_CRC = struct.Struct("<I")
_MIN_BODY = _HEADER.size + _CRC.size


class LinkError(DeviceError):
    """Root of the device link's errors: port, handshake, protocol."""


class ProtocolError(LinkError):
    """A message that cannot be put on the wire (value out of range, wrong shape)."""


# ---------------------------------------------------------------------------- COBS

def cobs_encode(data: bytes) -> bytes:
    """Consistent Overhead Byte Stuffing: ``data`` without any zero byte (adds <= 1 + n/254)."""
    out = bytearray()
    for piece in data.split(b"\x00"):
        while len(piece) >= 254:
            out.append(255)
            out += piece[:254]
            piece = piece[254:]
        out.append(len(piece) + 1)
        out += piece
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    """Inverse of :func:`cobs_encode`; raises ValueError on a malformed block."""
    out = bytearray()
    i, n = 0, len(data)
    while i < n:
        code = data[i]
        end = i + code
        if code == 0 or end > n:
            raise ValueError(f"COBS block code {code} at byte {i} of {n}")
        out += data[i + 1:end]
        if code < 255 and end < n:
            out.append(0)
        i = end
    return bytes(out)


# ---------------------------------------------------------------------------- fixed point

def amplitude_to_wire(amplitudes_um: np.ndarray, limits_um: np.ndarray | None = None
                      ) -> tuple[np.ndarray, int]:
    """Amplitudes (um) to wire counts, clamped to [0, limit] per channel.

    Parameters
    ----------
    amplitudes_um : (n, channels) float64, um zero-to-peak.
    limits_um : (channels,) float64 or None
        Upper limit per channel (um); None means the wire's own maximum.

    Returns
    -------
    counts : (n, channels) uint16, round to nearest count (error <= step / 2).
    clamped : number of values outside [0, limit] (non-finite values count and become 0).
    """
    a = np.asarray(amplitudes_um, dtype=np.float64)
    top = np.full(a.shape[-1], AMPLITUDE_MAX_UM) if limits_um is None else \
        np.minimum(np.asarray(limits_um, dtype=np.float64), AMPLITUDE_MAX_UM)
    finite = np.isfinite(a)
    safe = np.where(finite, a, 0.0)
    clamped = int((~finite).sum() + (safe < 0.0).sum() + (safe > top).sum())
    # floor the limit to a whole count so a clamped value never rounds above it
    top_counts = np.floor(top / AMPLITUDE_STEP_UM + 1e-9)
    counts = np.minimum(np.rint(np.clip(safe, 0.0, None) / AMPLITUDE_STEP_UM), top_counts)
    return counts.astype(np.uint16), clamped


def amplitude_from_wire(counts: np.ndarray) -> np.ndarray:
    """Wire counts to amplitudes (um), float64, same shape."""
    return np.asarray(counts, dtype=np.float64) * AMPLITUDE_STEP_UM


def force_to_wire(force_n) -> np.ndarray:
    """Forces (N) to int16 wire counts of :data:`FORCE_STEP_N`, round to nearest, clipped
    to [-32768, 32767] counts (-8 N to 8 N minus one count); non-finite values become 0."""
    f = np.asarray(force_n, dtype=np.float64)
    f = np.where(np.isfinite(f), f, 0.0)
    return np.clip(np.rint(f / FORCE_STEP_N), -32768, 32767).astype(np.int16)


def force_from_wire(counts) -> np.ndarray:
    """Wire force counts to N, float64, same shape."""
    return np.asarray(counts, dtype=np.float64) * FORCE_STEP_N


def phase_to_wire(phases_rad: np.ndarray) -> np.ndarray:
    """Phases (rad, any finite value) to uint16 fractions of a turn; non-finite become 0."""
    p = np.asarray(phases_rad, dtype=np.float64)
    p = np.where(np.isfinite(p), p, 0.0)
    return (np.rint(np.mod(p, 2.0 * np.pi) / PHASE_STEP_RAD).astype(np.int64) % 65536
            ).astype(np.uint16)


def phase_from_wire(counts: np.ndarray) -> np.ndarray:
    """Wire phases to rad in [0, 2 pi), float64."""
    return np.asarray(counts, dtype=np.float64) * PHASE_STEP_RAD


# ---------------------------------------------------------------------------- messages

class DeviceState:
    """Values of :attr:`Status.state` (PROTOCOL.md section 5)."""

    IDLE, BUFFERING, PLAYING, DRAINING, SILENT = range(5)
    NAMES = ("idle", "buffering", "playing", "draining", "silent")


class FlushCause:
    """Values of :attr:`Flushed.cause` (PROTOCOL.md section 4.8)."""

    WATCHDOG = 1


class ErrorCode:
    """Values of :attr:`ErrorReport.code` (PROTOCOL.md section 4.7)."""

    BAD_VERSION, NOT_READY, BAD_BLOCK, OVERFLOW, LATE = range(1, 6)
    NAMES = {1: "bad_version", 2: "not_ready", 3: "bad_block", 4: "overflow", 5: "late"}


@dataclass(frozen=True)
class Hello:
    """Host -> device: who are you? ``prefill``: samples to buffer before playing."""

    TYPE = 0x01
    prefill: int


@dataclass(frozen=True)
class Info:
    """Device -> host: the answer to :class:`Hello`."""

    TYPE = 0x81
    channels: int
    sample_rate_hz: float
    limits_um: tuple[float, ...]
    buffer_samples: int
    watchdog_ms: int
    ramp_ms: int
    has_phases: bool = False
    has_sensor: bool = False
    has_force: bool = False
    name: str = ""
    protocol_version: int = PROTOCOL_VERSION
    has_force_reports: bool = False


@dataclass(frozen=True, eq=False)
class Block:
    """Host -> device: ``n`` samples for every channel, starting at sample ``start_index``.

    ``amplitudes``: (n, channels) uint16 wire counts; ``phases``: same shape or None.
    """

    TYPE = 0x02
    start_index: int
    amplitudes: np.ndarray
    phases: np.ndarray | None = None

    def __eq__(self, other):
        if not isinstance(other, Block):
            return NotImplemented
        same_phases = (self.phases is None and other.phases is None) or (
            self.phases is not None and other.phases is not None
            and np.array_equal(self.phases, other.phases))
        return (self.start_index == other.start_index
                and np.array_equal(self.amplitudes, other.amplitudes) and same_phases)


@dataclass(frozen=True)
class Heartbeat:
    """Host -> device: I am alive; answer with a :class:`Status` echoing ``token``."""

    TYPE = 0x03
    token: int


@dataclass(frozen=True)
class Stop:
    """Host -> device: stop. ``drain``: play what is buffered first, else ramp down now."""

    TYPE = 0x04
    drain: bool = False


@dataclass(frozen=True)
class Status:
    """Device -> host: counters and state (answer to :class:`Heartbeat`).

    The last four fields are in version 2 frames only (None when decoded from version 1):
    ``buffer_end`` is one past the highest sample number held (``play_index`` when the
    buffer is empty); ``played_samples``, ``flushed_samples`` and ``flushes`` count since
    the last Hello.
    """

    TYPE = 0x82
    echo: int
    state: int
    play_index: int
    level: int
    underruns: int = 0
    crc_errors: int = 0
    frames_ok: int = 0
    lost_frames: int = 0
    gap_samples: int = 0
    late_samples: int = 0
    overflow_samples: int = 0
    watchdog_trips: int = 0
    clamped: int = 0
    measured_um: tuple[float, ...] | None = None
    force_n: float | None = None
    buffer_end: int | None = None
    played_samples: int | None = None
    flushed_samples: int | None = None
    flushes: int | None = None

    @property
    def accounted(self) -> bool:
        """Whether this Status carries the version 2 buffer accounting."""
        return self.buffer_end is not None


@dataclass(frozen=True)
class Flushed:
    """Device -> host (version 2): the device discarded its buffer (``cause``, see
    :class:`FlushCause`) and will play ``play_index`` next; ``flushed``: samples discarded
    by this flush; ``flushes``: flushes since the last Hello, this one included."""

    TYPE = 0x84
    cause: int
    play_index: int
    flushed: int
    flushes: int


@dataclass(frozen=True)
class ForceReport:
    """Device -> host (version 3): lateral and normal force (N) measured while samples
    ``start_index .. start_index + decimation * len(lateral_n) - 1`` played; value ``k`` is
    the mean over samples ``start_index + k * decimation`` onwards (``decimation`` of them).
    Values are whole multiples of :data:`FORCE_STEP_N` after a round trip."""

    TYPE = 0x85
    start_index: int
    decimation: int
    lateral_n: tuple[float, ...]
    normal_n: tuple[float, ...]


@dataclass(frozen=True, eq=False)
class Resend(Block):
    """Host -> device (version 4): the Block first sent in the frame of sequence number
    ``orig_seq``, sent again because the device reported it missing (:class:`Missing`).
    A device plays it only if ``orig_seq`` is still missing; else it is a duplicate and
    has no effect (PROTOCOL.md 4.10)."""

    TYPE = 0x05
    orig_seq: int = 0

    def __eq__(self, other):
        if not isinstance(other, Resend):
            return NotImplemented
        return self.orig_seq == other.orig_seq and Block.__eq__(self, other)


@dataclass(frozen=True)
class Missing:
    """Device -> host (version 4): sequence numbers of host frames the device found
    missing (a gap in the numbers) and still wants, oldest first, at most
    :data:`MISSING_MAX` (PROTOCOL.md 4.10)."""

    TYPE = 0x86
    seqs: tuple[int, ...]


@dataclass(frozen=True)
class ErrorReport:
    """Device -> host: something the host sent was refused."""

    TYPE = 0x83
    code: int
    ref_seq: int
    detail: int = 0
    text: str = ""


MESSAGES = (Hello, Info, Block, Heartbeat, Stop, Status, ErrorReport, Flushed, ForceReport,
            Resend, Missing)
#: message types by the first version that has them
_SINCE = {Flushed: 2, ForceReport: 3, Resend: 4, Missing: 4}
_BY_TYPE = {m.TYPE: m for m in MESSAGES}


@dataclass(frozen=True)
class Frame:
    """One decoded frame: its sequence number, message and the version it was sent in."""

    seq: int
    message: object
    version: int = PROTOCOL_VERSION
    #: frames missing just before this one (its sequence number skipped ahead by this)
    lost: int = 0


# ---------------------------------------------------------------------------- payloads

_HELLO = struct.Struct("<I")
_INFO = struct.Struct("<BBBIIHHB")  # version, channels, flags, rate_mHz, buffer, wd, ramp, namelen
_BLOCK = struct.Struct("<QHBB")     # start_index, n, channels, flags
_HEARTBEAT = struct.Struct("<I")
_STOP = struct.Struct("<B")
_STATUS = struct.Struct("<IBBQI10I")  # echo, state, flags, play_index, level, 9 counters, n_meas
_STATUS_V2 = struct.Struct("<QIII")   # buffer_end, played, flushed, flushes
_FLUSHED = struct.Struct("<BQII")
_ERROR = struct.Struct("<BHI")
_FORCES = struct.Struct("<QHB")     # start_index, decimation, count; then count x (i16, i16)
_U16S = struct.Struct("<H")
_U16 = np.dtype("<u2")
_I16 = np.dtype("<i2")
_FLAG_PHASES, _FLAG_SENSOR, _FLAG_FORCE, _FLAG_FORCE_REPORTS = 1, 2, 4, 8
#: payload bytes left for samples in one Block frame
BLOCK_SAMPLE_BYTES = MAX_BODY - _MIN_BODY - _BLOCK.size


def max_block_samples(channels: int, phases: bool) -> int:
    """Largest ``n`` one Block frame can carry for ``channels`` channels."""
    return BLOCK_SAMPLE_BYTES // (2 * channels * (2 if phases else 1))


def _u16_limit(values_um) -> list[int]:
    return [int(c) for c in amplitude_to_wire(np.array([values_um], dtype=np.float64))[0][0]]


def _encode_hello(msg: Hello, version: int) -> bytes:
    return _HELLO.pack(msg.prefill)


def _encode_info(msg: Info, version: int) -> bytes:
    if len(msg.limits_um) != msg.channels:
        raise ProtocolError(f"Info: {len(msg.limits_um)} limits for {msg.channels} channels")
    name = msg.name.encode("utf-8")[:255]
    flags = (_FLAG_PHASES * msg.has_phases | _FLAG_SENSOR * msg.has_sensor
             | _FLAG_FORCE * msg.has_force | _FLAG_FORCE_REPORTS * msg.has_force_reports)
    head = _INFO.pack(msg.protocol_version, msg.channels, flags,
                      int(round(msg.sample_rate_hz * 1000.0)), msg.buffer_samples,
                      msg.watchdog_ms, msg.ramp_ms, len(name))
    return head + np.array(_u16_limit(msg.limits_um), dtype=_U16).tobytes() + name


def _encode_block(msg: Block, version: int) -> bytes:
    amps = np.asarray(msg.amplitudes)
    if amps.ndim != 2 or amps.dtype != np.uint16 or amps.shape[1] < 1:
        raise ProtocolError(f"Block amplitudes: got {amps.dtype} {amps.shape}, expected "
                            "uint16 (n, channels)")
    n, ch = amps.shape
    flags = 0
    body = amps.astype(_U16).tobytes()
    if msg.phases is not None:
        ph = np.asarray(msg.phases)
        if ph.shape != amps.shape or ph.dtype != np.uint16:
            raise ProtocolError(f"Block phases: got {ph.dtype} {ph.shape}, expected uint16 "
                                f"{amps.shape}")
        flags = _FLAG_PHASES
        body += ph.astype(_U16).tobytes()
    if len(body) > BLOCK_SAMPLE_BYTES:
        raise ProtocolError(f"Block of {n} samples x {ch} channels is {len(body)} bytes; at "
                            f"most {BLOCK_SAMPLE_BYTES} fit in one frame")
    return _BLOCK.pack(msg.start_index, n, ch, flags) + body


def _encode_resend(msg: Resend, version: int) -> bytes:
    return _U16S.pack(msg.orig_seq) + _encode_block(msg, version)


def _encode_missing(msg: Missing, version: int) -> bytes:
    if not 1 <= len(msg.seqs) <= MISSING_MAX:
        raise ProtocolError(f"Missing: {len(msg.seqs)} sequence numbers; expected 1 to "
                            f"{MISSING_MAX}")
    return bytes([len(msg.seqs)]) + b"".join(_U16S.pack(q) for q in msg.seqs)


def _encode_heartbeat(msg: Heartbeat, version: int) -> bytes:
    return _HEARTBEAT.pack(msg.token)


def _encode_stop(msg: Stop, version: int) -> bytes:
    return _STOP.pack(int(msg.drain))


def _status_accounting(msg: Status) -> bytes:
    """The version 2 buffer-accounting fields of a Status (counters wrap at 2**32)."""
    extra = (msg.buffer_end, msg.played_samples, msg.flushed_samples, msg.flushes)
    if None in extra:
        raise ProtocolError("Status in version 2 needs buffer_end, played_samples, "
                            "flushed_samples and flushes; got None")
    return _STATUS_V2.pack(extra[0], *(c & 0xFFFFFFFF for c in extra[1:]))


def _encode_status(msg: Status, version: int) -> bytes:
    flags = (_FLAG_SENSOR * (msg.measured_um is not None)
             | _FLAG_FORCE * (msg.force_n is not None))
    if msg.measured_um is not None and len(msg.measured_um) == 0:
        raise ProtocolError("Status measured_um: empty; expected one value per channel or None")
    counters = (msg.underruns, msg.crc_errors, msg.frames_ok, msg.lost_frames,
                msg.gap_samples, msg.late_samples, msg.overflow_samples,
                msg.watchdog_trips, msg.clamped)
    # counters wrap at 2**32 on the wire (PROTOCOL.md 4.6)
    out = _STATUS.pack(msg.echo, msg.state, flags, msg.play_index, msg.level,
                       *(c & 0xFFFFFFFF for c in counters), len(msg.measured_um or ()))
    if version >= 2:
        out += _status_accounting(msg)
    if msg.measured_um is not None:
        out += np.array(_u16_limit(msg.measured_um), dtype=_U16).tobytes()
    if msg.force_n is not None:
        out += struct.pack("<H", int(min(max(round(msg.force_n * 1000.0), 0), 65535)))
    return out


def _encode_flushed(msg: Flushed, version: int) -> bytes:
    return _FLUSHED.pack(msg.cause, msg.play_index, msg.flushed & 0xFFFFFFFF,
                         msg.flushes & 0xFFFFFFFF)


def _encode_force_report(msg: ForceReport, version: int) -> bytes:
    count = len(msg.lateral_n)
    if not 1 <= count <= FORCE_PAIRS_MAX or len(msg.normal_n) != count:
        raise ProtocolError(f"ForceReport: {count} lateral and {len(msg.normal_n)} normal "
                            f"values; expected the same number, 1 to {FORCE_PAIRS_MAX}")
    if not 1 <= msg.decimation <= 65535:
        raise ProtocolError(f"ForceReport decimation {msg.decimation}: expected 1 to 65535")
    pairs = np.column_stack([force_to_wire(msg.lateral_n), force_to_wire(msg.normal_n)])
    return _FORCES.pack(msg.start_index, msg.decimation, count) + pairs.astype(_I16).tobytes()


def _encode_error_report(msg: ErrorReport, version: int) -> bytes:
    return _ERROR.pack(msg.code, msg.ref_seq, msg.detail) + msg.text.encode("utf-8")[:200]


#: payload encoder of each message class: ``encoder(msg, version) -> bytes``
_ENCODERS = {Hello: _encode_hello, Info: _encode_info, Block: _encode_block,
             Resend: _encode_resend, Missing: _encode_missing, Heartbeat: _encode_heartbeat,
             Stop: _encode_stop, Status: _encode_status, Flushed: _encode_flushed,
             ForceReport: _encode_force_report, ErrorReport: _encode_error_report}


def _payload(msg, version: int) -> bytes:
    """The payload of ``msg`` in a ``version`` frame (a subclass of a message is encoded
    as its nearest message class)."""
    encoder = _ENCODERS.get(type(msg))
    if encoder is None:
        encoder = next(_ENCODERS[c] for c in type(msg).__mro__ if c in _ENCODERS)
    return encoder(msg, version)


class _BriefRepr(reprlib.Repr):
    """reprlib's cut repr, arrays as their shape and dtype."""

    def __init__(self):
        super().__init__()
        self.maxtuple, self.maxstring, self.maxother = 4, 40, 40

    def repr_ndarray(self, obj, level):
        return f"<{obj.dtype} array {obj.shape}>"


_BRIEF = _BriefRepr()


def _brief(msg) -> str:
    """``msg`` as ``Type(field=value, ...)`` with long values cut (a message line, not
    kilobytes of limits or samples)."""
    values = ", ".join(f"{f.name}={_BRIEF.repr(getattr(msg, f.name))}" for f in fields(msg))
    return f"{type(msg).__name__}({values})"


def encode(msg, seq: int = 0, version: int = PROTOCOL_VERSION) -> bytes:
    """The bytes of one frame carrying ``msg`` (COBS-stuffed, 0x00-terminated).

    ``seq`` is taken modulo 2**16; ``version`` selects the payload layouts (1, or the
    newest for anything else, so tests can write frames of versions nobody speaks).
    Raises :class:`ProtocolError` for a value that does not fit its field or a message
    that ``version`` does not have.
    """
    if not isinstance(msg, MESSAGES):
        raise ProtocolError(f"cannot encode {type(msg).__name__}; expected one of "
                            f"{', '.join(m.__name__ for m in MESSAGES)}")
    since = _SINCE.get(type(msg), 1)
    if version < since:
        raise ProtocolError(f"{type(msg).__name__} does not exist in protocol version "
                            f"{version}; it needs version {since}")
    try:
        body = _HEADER.pack(version, msg.TYPE, seq & 0xFFFF) + _payload(msg, version)
    except struct.error as exc:
        raise ProtocolError(f"cannot encode {_brief(msg)}: {exc}") from None
    body += _CRC.pack(zlib.crc32(body))
    if len(body) > MAX_BODY:
        raise ProtocolError(f"{type(msg).__name__} frame is {len(body)} bytes; at most "
                            f"{MAX_BODY}")
    return cobs_encode(body) + b"\x00"


def _decode_hello(p: bytes, version: int) -> Hello:
    return Hello(*_HELLO.unpack(p))


def _decode_info(p: bytes, version: int) -> Info:
    version, ch, flags, rate, buf, wd, ramp, namelen = _INFO.unpack_from(p)
    rest = p[_INFO.size:]
    if ch < 1 or len(rest) != 2 * ch + namelen:
        raise ValueError("Info length")
    limits = amplitude_from_wire(np.frombuffer(rest[:2 * ch], dtype=_U16))
    return Info(ch, rate / 1000.0, tuple(float(x) for x in limits), buf, wd, ramp,
                bool(flags & _FLAG_PHASES), bool(flags & _FLAG_SENSOR),
                bool(flags & _FLAG_FORCE), rest[2 * ch:].decode("utf-8"), version,
                bool(flags & _FLAG_FORCE_REPORTS))


def _decode_block(p: bytes, version: int) -> Block:
    start, n, ch, flags = _BLOCK.unpack_from(p)
    k = 2 if flags & _FLAG_PHASES else 1
    data = p[_BLOCK.size:]
    if ch < 1 or len(data) != 2 * n * ch * k:
        raise ValueError("Block length")
    words = np.frombuffer(data, dtype=_U16).astype(np.uint16)
    amps = words[:n * ch].reshape(n, ch)
    phases = words[n * ch:].reshape(n, ch) if k == 2 else None
    return Block(start, amps, phases)


def _decode_resend(p: bytes, version: int) -> Resend:
    (orig,) = _U16S.unpack_from(p)
    block = _decode_block(p[_U16S.size:], version)
    return Resend(block.start_index, block.amplitudes, block.phases, orig)


def _decode_missing(p: bytes, version: int) -> Missing:
    if len(p) < 1 or not 1 <= p[0] <= MISSING_MAX or len(p) != 1 + 2 * p[0]:
        raise ValueError("Missing length")
    return Missing(tuple(int(q) for q in np.frombuffer(p[1:], dtype=_U16)))


def _decode_heartbeat(p: bytes, version: int) -> Heartbeat:
    return Heartbeat(*_HEARTBEAT.unpack(p))


def _decode_stop(p: bytes, version: int) -> Stop:
    (drain,) = _STOP.unpack(p)
    if drain > 1:
        raise ValueError("Stop drain is neither 0 nor 1")
    return Stop(bool(drain))


def _decode_status(p: bytes, version: int) -> Status:
    echo, state, flags, play, level, *counters, n_meas = _STATUS.unpack_from(p)
    rest = p[_STATUS.size:]
    extra = {}
    if version >= 2:
        values = _STATUS_V2.unpack_from(rest)
        extra = dict(zip(("buffer_end", "played_samples", "flushed_samples", "flushes"),
                         values))
        rest = rest[_STATUS_V2.size:]
    n_force = 2 if flags & _FLAG_FORCE else 0
    if len(rest) != 2 * n_meas + n_force or bool(flags & _FLAG_SENSOR) != (n_meas > 0):
        raise ValueError("Status length")
    measured = None
    if flags & _FLAG_SENSOR:
        measured = tuple(float(x) for x in amplitude_from_wire(
            np.frombuffer(rest[:2 * n_meas], dtype=_U16)))
    force = struct.unpack("<H", rest[2 * n_meas:])[0] / 1000.0 if n_force else None
    return Status(echo, state, play, level, *counters, measured_um=measured, force_n=force,
                  **extra)


def _decode_flushed(p: bytes, version: int) -> Flushed:
    return Flushed(*_FLUSHED.unpack(p))


def _decode_force_report(p: bytes, version: int) -> ForceReport:
    start, decimation, count = _FORCES.unpack_from(p)
    if count < 1 or decimation < 1 or len(p) != _FORCES.size + 4 * count:
        raise ValueError("ForceReport length")
    pairs = force_from_wire(np.frombuffer(p[_FORCES.size:], dtype=_I16).reshape(count, 2))
    return ForceReport(start, decimation, tuple(float(x) for x in pairs[:, 0]),
                       tuple(float(x) for x in pairs[:, 1]))


def _decode_error_report(p: bytes, version: int) -> ErrorReport:
    code, ref, detail = _ERROR.unpack_from(p)
    return ErrorReport(code, ref, detail, p[_ERROR.size:].decode("utf-8"))


#: payload decoder of each message type byte: ``decoder(payload, version) -> message``
_DECODERS = {Hello.TYPE: _decode_hello, Info.TYPE: _decode_info, Block.TYPE: _decode_block,
             Resend.TYPE: _decode_resend, Missing.TYPE: _decode_missing,
             Heartbeat.TYPE: _decode_heartbeat, Stop.TYPE: _decode_stop,
             Status.TYPE: _decode_status, Flushed.TYPE: _decode_flushed,
             ForceReport.TYPE: _decode_force_report, ErrorReport.TYPE: _decode_error_report}


def _parse(mtype: int, p: bytes, version: int):
    """The message of type ``mtype`` in payload ``p`` of a ``version`` frame; ValueError or
    struct.error if malformed, KeyError for an unknown type."""
    return _DECODERS[mtype](p, version)


# ---------------------------------------------------------------------------- decoder

@dataclass
class DecoderCounts:
    """Why frames were thrown away (each thrown-away frame counts once)."""

    frames_ok: int = 0
    crc_errors: int = 0
    cobs_errors: int = 0
    short_frames: int = 0
    oversize: int = 0
    bad_version: int = 0
    unknown_type: int = 0
    bad_payload: int = 0
    lost_frames: int = 0
    last_bad_version: int | None = None

    @property
    def discarded(self) -> int:
        """Frames thrown away for any reason: each one is a resynchronisation."""
        return (self.crc_errors + self.cobs_errors + self.short_frames + self.oversize
                + self.bad_version + self.unknown_type + self.bad_payload)


@dataclass
class Decoder:
    """Incremental frame decoder: ``feed`` any chunks of the stream, get whole frames back.

    A corrupted, truncated or foreign frame is counted in :attr:`counts` and dropped; the
    next 0x00 starts a fresh frame, so the decoder resynchronises within one frame.
    Sequence numbers that skip forward count as ``lost_frames`` (and as the next frame's
    :attr:`Frame.lost`). Frames of versions 1 to
    ``max_version`` are accepted. ``on_device``: True for the device's receiver (as the
    C firmware's ``rx.c`` always is), False for the host's: only frames of the other
    side's types are numbered by the peer; a frame of the receiver's own side's types is
    its own echoed back (a half-duplex adapter, a loopback fault: section 5.3), is
    delivered with ``lost`` 0 and leaves the sequence bookkeeping alone. None (the
    default: a decoder reading a recorded stream) counts every frame.
    """

    max_version: int = PROTOCOL_VERSION
    on_device: bool | None = None
    counts: DecoderCounts = field(default_factory=DecoderCounts)
    _pending: bytearray = field(default_factory=bytearray)
    _overflowed: bool = False
    _next_seq: int | None = None

    def feed(self, data: bytes) -> list[Frame]:
        frames = []
        pieces = bytes(data).split(b"\x00")
        for i, piece in enumerate(pieces):
            last = i == len(pieces) - 1
            if not self._overflowed:
                self._pending += piece
                if len(self._pending) > MAX_STUFFED:
                    self._overflowed = True
                    self._pending.clear()
            if last:
                break
            if self._overflowed:
                self.counts.oversize += 1
                self._overflowed = False
            elif self._pending:
                frame = self._frame(bytes(self._pending))
                if frame is not None:
                    frames.append(frame)
            self._pending.clear()
        return frames

    def _frame(self, stuffed: bytes) -> Frame | None:
        c = self.counts
        try:
            body = cobs_decode(stuffed)
        except ValueError:
            c.cobs_errors += 1
            return None
        if len(body) > MAX_BODY:  # zeros stuff cheaply: 4113 bytes decode to up to 4112
            c.oversize += 1
            return None
        if len(body) < _MIN_BODY:
            c.short_frames += 1
            return None
        if zlib.crc32(body[:-4]) != _CRC.unpack_from(body, len(body) - 4)[0]:
            c.crc_errors += 1
            return None
        version, mtype, seq = _HEADER.unpack_from(body)
        if not 1 <= version <= self.max_version:
            c.bad_version += 1
            c.last_bad_version = version
            return None
        if mtype not in _BY_TYPE or version < _SINCE.get(_BY_TYPE[mtype], 1):
            c.unknown_type += 1
            return None
        try:
            msg = _parse(mtype, body[_HEADER.size:-4], version)
        except (ValueError, struct.error):
            c.bad_payload += 1
            return None
        echoed = self.on_device is not None and (mtype >= DEVICE_TYPES) == self.on_device
        skipped = 0 if echoed else self._count_seq(mtype, seq)
        c.frames_ok += 1
        return Frame(seq, msg, version, skipped)

    def _count_seq(self, mtype: int, seq: int) -> int:
        """Follow the peer's sequence numbers through a frame of type ``mtype`` numbered
        ``seq``; returns how many frames were skipped just before it."""
        if mtype == Hello.TYPE:
            self._next_seq = None  # a new host numbers from anywhere (section 2)
        skipped = (seq - self._next_seq) & 0xFFFF if self._next_seq is not None else 0
        if skipped >= 0x8000:  # a jump backwards is the sender restarting, not a loss
            skipped = 0
        self.counts.lost_frames += skipped
        self._next_seq = (seq + 1) & 0xFFFF
        return skipped
