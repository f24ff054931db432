"""Write ``frames.json``: byte streams and what a receiver of protocol versions 1 to 4
makes of them.

Run once from the repository root (``python device/firmware/vectors/make_vectors.py``);
the file is committed. Every stream is encoded by ``device/link/protocol.py`` (or damaged
on purpose) and its expected decode is what that module's :class:`Decoder` returns, in
the canonical text of :func:`render_stream`. ``tests/test_firmware_vectors.py`` checks
that the Python decoder still agrees and the C checker (``test/check_vectors.c``) checks
the C receiver and, for frames marked ``reencode``, the C encoder, so the two sides
cannot drift apart.

One line per vector (the C checker reads the file line by line)::

    {"name": ..., "hex": ..., "expect": "event | event | ... | counts ok=N lost=N discarded=N", "reencode": bool},
"""

from __future__ import annotations

import json
import sys
import zlib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from frictex.device.link import protocol as p  # noqa: E402

NEWEST = 4  # the newest version the firmware speaks
OUT = Path(__file__).with_name("frames.json")
_DROPS = {"cobs_errors": "cobs", "short_frames": "short", "crc_errors": "crc",
          "bad_version": "version", "unknown_type": "type", "bad_payload": "payload",
          "oversize": "oversize"}


def decoder() -> p.Decoder:
    """The firmware's receiver: the versions it speaks, on the device's side."""
    return p.Decoder(max_version=NEWEST, on_device=True)


def _u16s(values) -> str:
    return ",".join(str(int(v)) for v in np.asarray(values).ravel())


def render(msg) -> str:
    """The canonical text of one decoded message (wire units: counts, mHz, mN)."""
    if isinstance(msg, p.Hello):
        return f"hello prefill={msg.prefill}"
    if isinstance(msg, p.Heartbeat):
        return f"heartbeat token={msg.token}"
    if isinstance(msg, p.Stop):
        return f"stop drain={int(msg.drain)}"
    if isinstance(msg, p.Missing):
        return f"missing seqs={_u16s(msg.seqs)}"
    if isinstance(msg, p.Resend):
        return f"resend orig={msg.orig_seq} " + render(p.Block(msg.start_index, msg.amplitudes,
                                                                msg.phases))
    if isinstance(msg, p.Block):
        n, ch = msg.amplitudes.shape
        phases = "-" if msg.phases is None else _u16s(msg.phases)
        return (f"block start={msg.start_index} n={n} ch={ch} amps={_u16s(msg.amplitudes)} "
                f"phases={phases}")
    if isinstance(msg, p.Info):
        limits = _u16s([round(x * 4096) for x in msg.limits_um])
        return (f"info version={msg.protocol_version} channels={msg.channels} "
                f"phases={int(msg.has_phases)} sensor={int(msg.has_sensor)} "
                f"force={int(msg.has_force)} rate_mhz={round(msg.sample_rate_hz * 1000)} "
                f"buffer={msg.buffer_samples} watchdog_ms={msg.watchdog_ms} "
                f"ramp_ms={msg.ramp_ms} force_reports={int(msg.has_force_reports)} "
                f"limits={limits} name={msg.name.encode().hex()}")
    if isinstance(msg, p.Status):
        counters = _u16s([msg.underruns, msg.crc_errors, msg.frames_ok, msg.lost_frames,
                          msg.gap_samples, msg.late_samples, msg.overflow_samples,
                          msg.watchdog_trips, msg.clamped])
        measured = "-" if msg.measured_um is None else _u16s(
            [round(x * 4096) for x in msg.measured_um])
        force = "-" if msg.force_n is None else str(round(msg.force_n * 1000))
        accounting = "-" if not msg.accounted else (
            f"{msg.buffer_end},{msg.played_samples},{msg.flushed_samples},{msg.flushes}")
        return (f"status echo={msg.echo} state={msg.state} play={msg.play_index} "
                f"level={msg.level} counters={counters} measured={measured} force_mn={force} "
                f"accounting={accounting}")
    if isinstance(msg, p.Flushed):
        return (f"flushed cause={msg.cause} play={msg.play_index} flushed={msg.flushed} "
                f"flushes={msg.flushes}")
    if isinstance(msg, p.ForceReport):
        return (f"force start={msg.start_index} decimation={msg.decimation} "
                f"lateral={','.join(str(round(x * 4096)) for x in msg.lateral_n)} "
                f"normal={','.join(str(round(x * 4096)) for x in msg.normal_n)}")
    if isinstance(msg, p.ErrorReport):
        return (f"error code={msg.code} ref={msg.ref_seq} detail={msg.detail} "
                f"text={msg.text.encode().hex()}")
    raise TypeError(f"no canonical text for {type(msg).__name__}")


def render_stream(data: bytes, dec: p.Decoder | None = None) -> list[str]:
    """Feed ``data`` byte by byte: one entry per accepted or dropped frame, then counts."""
    dec = dec or decoder()
    events = []
    before = {k: getattr(dec.counts, k) for k in _DROPS}
    for i in range(len(data)):
        for frame in dec.feed(data[i:i + 1]):
            events.append(f"v{frame.version} seq={frame.seq} {render(frame.message)}")
        for key, name in _DROPS.items():
            now = getattr(dec.counts, key)
            events += [f"drop {name}"] * (now - before[key])
            before[key] = now
    c = dec.counts
    events.append(f"counts ok={c.frames_ok} lost={c.lost_frames} discarded={c.discarded}")
    return events


# ---------------------------------------------------------------------------- streams

def enc(msg, seq=0, version=1) -> bytes:
    return p.encode(msg, seq, version)


def raw_frame(body: bytes, crc_ok: bool = True) -> bytes:
    """A frame around an arbitrary body (version, type, seq, payload), CRC appended."""
    crc = zlib.crc32(body) ^ (0 if crc_ok else 1)
    return p.cobs_encode(body + crc.to_bytes(4, "little")) + b"\x00"


def _block(start, amps, phases=None):
    a = np.asarray(amps, dtype=np.uint16)
    a = a.reshape(len(a), -1) if a.ndim == 1 else a
    ph = None if phases is None else np.asarray(phases, dtype=np.uint16).reshape(a.shape)
    return p.Block(start, a, ph)


def _force(start, decimation, lateral_counts, normal_counts):
    """A ForceReport from wire counts."""
    return p.ForceReport(start, decimation,
                         tuple(float(c) * p.FORCE_STEP_N for c in lateral_counts),
                         tuple(float(c) * p.FORCE_STEP_N for c in normal_counts))


def _info(ch=1, **kw):
    args = dict(channels=ch, sample_rate_hz=10_000.0, limits_um=(4.0,) * ch,
                buffer_samples=4096, watchdog_ms=25, ramp_ms=20, name="frictex sim-device")
    args.update(kw)
    return p.Info(**args)


def valid_messages():
    """(name, message, seq, version): every type in every version, edge values, the
    PROTOCOL.md 7 examples (version 1)."""
    yield "doc heartbeat", p.Heartbeat(1), 5
    yield "doc hello", p.Hello(100), 0
    yield "doc stop", p.Stop(True), 2
    yield "doc block", _block(0, [4096, 8192]), 1
    yield "hello zero", p.Hello(0), 65535
    yield "hello max", p.Hello(2**32 - 1), 7
    yield "heartbeat max", p.Heartbeat(2**32 - 1), 300
    yield "stop no drain", p.Stop(False), 9
    yield "block empty", _block(12, np.zeros((0, 1))), 3
    yield "block 2ch phases", _block(2**40 + 3, [[1, 2], [0, 65535], [256, 0]],
                                     [[0, 65535], [32768, 1], [2, 3]]), 4
    yield "block top index", _block(2**64 - 1, [7]), 5
    yield "block all zero", _block(0, np.zeros((300, 1))), 6
    yield "block 254 run", _block(0x0101010101010101, np.full((121, 1), 0x0101)), 8
    yield "block largest 1ch", _block(99, np.arange(2038) * 32 + 1), 10
    yield "block largest 2ch phases", _block(5, (np.arange(509 * 2) + 1).reshape(509, 2),
                                             np.arange(509 * 2)[::-1].reshape(509, 2)), 11
    yield "info default", _info(), 0
    yield "info 3ch sensors", _info(3, limits_um=(1.0, 2.5, 15.0), has_phases=True,
                                    has_sensor=True, has_force=True, name="plaque µ 三"), 1
    yield "info 8ch no name", _info(8, sample_rate_hz=4_000_000.0, name=""), 2
    yield "info force reports", _info(has_force=True, has_force_reports=True), 3
    yield "status plain", p.Status(0, 1, 0, 0), 0
    yield "status full", p.Status(42, 2, 2**63 + 5, 150, *range(1, 10),
                                  measured_um=(2.0, 0.5), force_n=0.75), 1
    yield "status force only", p.Status(1, 4, 9, 0, 2**32 - 1, force_n=65.535), 2
    yield "status v2 plain", p.Status(0, 1, 0, 0, buffer_end=0, played_samples=0,
                                      flushed_samples=0, flushes=0), 3
    yield "status v2 full", p.Status(7, 2, 2**64 - 1, 100, *range(1, 10),
                                     measured_um=(1.0, 2.0, 3.0), force_n=1.5,
                                     buffer_end=99, played_samples=2**32 - 1,
                                     flushed_samples=5, flushes=2), 4
    yield "flushed", p.Flushed(1, 2**63 + 1, 150, 3), 5
    yield "flushed other cause", p.Flushed(200, 0, 0, 2**32 - 1), 6
    yield "force report", _force(1000, 4, [-32768, -1, 0, 1, 32767], [2048, 0, -5, 7, 1]), 7
    yield "force report one value", _force(2**64 - 1, 65535, [3], [-4]), 8
    yield "force report largest", _force(2**63, 1, np.arange(255) * 257 - 32768,
                                         np.arange(255)[::-1] * 3), 9
    yield "error late", p.ErrorReport(5, 77, 10, "10 samples arrived after their time"), 3
    yield "error empty text", p.ErrorReport(2, 0, 0, ""), 4
    yield "error 200 bytes", p.ErrorReport(3, 1, 2, "x" * 200), 5
    yield "resend", p.Resend(2**63 + 9, np.array([[1, 2], [3, 65535]], dtype=np.uint16),
                             None, 65535), 12
    yield "resend phases", p.Resend(0, np.array([[7]], dtype=np.uint16),
                                    np.array([[65535]], dtype=np.uint16), 0), 13
    yield "missing one", p.Missing((0,)), 14
    yield "missing largest", p.Missing(tuple(range(65535 - 15, 65536))), 15


def _body(mtype, payload, version=1, seq=0):
    return bytes([version, mtype]) + seq.to_bytes(2, "little") + payload


def _largest_frame() -> bytes:
    """A 4096-byte body without a zero byte: 4113 stuffed bytes, the most a receiver takes."""
    block = _block(0x0102030405060708, np.full(1019, 0x0101), np.full(1019, 0x0202))
    for seq in range(1, 65536):
        frame = enc(block, seq)
        if len(frame) == p.MAX_BODY + p.MAX_BODY // 254 + 2:
            return frame
    raise RuntimeError("no sequence number gives a CRC without a zero byte")


def damaged_streams(rng):
    """(name, bytes): each rule of PROTOCOL.md 2 that drops a frame, and resync."""
    hb = enc(p.Heartbeat(9), 1)
    yield "crc flipped", raw_frame(_body(p.Heartbeat.TYPE, b"\1\0\0\0"), crc_ok=False)
    yield "cobs truncated", bytes([5, 1, 3]) + b"\x00"
    yield "cobs code past end", bytes([0x20, 1, 3, 0, 0]) + b"\x00"
    yield "short body", p.cobs_encode(bytes([1, 3, 0, 0, 1, 2, 3])) + b"\x00"
    yield "empty frames ignored", b"\x00\x00" + hb + b"\x00"
    yield "version 5", raw_frame(_body(p.Heartbeat.TYPE, b"\1\0\0\0", version=5))
    yield "heartbeat in version 4", raw_frame(_body(p.Heartbeat.TYPE, b"\1\0\0\0", version=4))
    yield "type 0x05 in version 3", raw_frame(_body(0x05, bytes(14), version=3))
    yield "missing 0 seqs", raw_frame(_body(0x86, b"\0", version=4))
    yield "missing 17 seqs", raw_frame(_body(0x86, b"\x11" + bytes(34), version=4))
    yield "missing count 2, one seq", raw_frame(_body(0x86, b"\2\0\0", version=4))
    yield "missing empty", raw_frame(_body(0x86, b"", version=4))
    yield "resend 1 byte", raw_frame(_body(0x05, b"\0", version=4))
    yield "resend block cut", raw_frame(_body(0x05, bytes(2 + 12) + b"\1", version=4))
    yield "heartbeat in version 3", raw_frame(_body(p.Heartbeat.TYPE, b"\1\0\0\0", version=3))
    yield "heartbeat in version 2", raw_frame(_body(p.Heartbeat.TYPE, b"\1\0\0\0", version=2))
    yield "version 0", raw_frame(_body(p.Heartbeat.TYPE, b"\1\0\0\0", version=0))
    yield "type 0x05", raw_frame(_body(0x05, b"\1\0\0\0"))
    yield "type 0x84 in version 1", raw_frame(_body(0x84, bytes(17)))
    yield "type 0x85 in version 2", raw_frame(_body(0x85, bytes(15), version=2))
    yield "type 0x86 in version 3", raw_frame(_body(0x86, bytes(15), version=3))
    yield "force 0 values", raw_frame(_body(0x85, bytes(10) + b"\0", version=3))
    yield "force decimation 0", raw_frame(_body(0x85, bytes(10) + b"\1" + bytes(4), version=3))
    yield "force one byte short", raw_frame(_body(0x85, b"\0" * 8 + b"\1\0\2" + bytes(7),
                                                  version=3))
    yield "force one byte long", raw_frame(_body(0x85, b"\0" * 8 + b"\1\0\1" + bytes(5),
                                                 version=3))
    yield "flushed 16 bytes", raw_frame(_body(0x84, bytes(16), version=2))
    yield "flushed 18 bytes", raw_frame(_body(0x84, bytes(18), version=2))
    yield "status v2 without accounting", raw_frame(_body(p.Status.TYPE, bytes(58), version=2))
    yield "status v2 accounting cut", raw_frame(_body(p.Status.TYPE, bytes(70), version=2))
    yield "status v1 with accounting", raw_frame(_body(p.Status.TYPE, bytes(78)))
    yield "hello 3 bytes", raw_frame(_body(p.Hello.TYPE, b"\1\0\0"))
    yield "hello 5 bytes", raw_frame(_body(p.Hello.TYPE, b"\1\0\0\0\0"))
    yield "stop 2 bytes", raw_frame(_body(p.Stop.TYPE, b"\1\1"))
    yield "stop drain 7", raw_frame(_body(p.Stop.TYPE, b"\7"))
    yield "block 0 channels", raw_frame(_body(p.Block.TYPE, bytes(8) + b"\0\0\0\0"))
    yield "block short head", raw_frame(_body(p.Block.TYPE, bytes(11)))
    yield "block one byte long", raw_frame(_body(p.Block.TYPE, bytes(8) + b"\1\0\1\0" + b"\1\0\2"))
    yield "block phases missing", raw_frame(_body(p.Block.TYPE, bytes(8) + b"\1\0\1\1" + b"\1\0"))
    yield "block other flag bits", raw_frame(_body(p.Block.TYPE, bytes(8) + b"\1\0\1\xfe" + b"\1\0"))
    yield "info 0 channels", raw_frame(_body(p.Info.TYPE, bytes([1, 0, 0]) + bytes(13)))
    yield "info name too long", raw_frame(_body(p.Info.TYPE, bytes([1, 1, 0]) + bytes(12) +
                                                bytes([2]) + b"\0\x10" + b"a"))
    yield "info name bad utf8", raw_frame(_body(p.Info.TYPE, bytes([1, 1, 0]) + bytes(12) +
                                                bytes([2]) + b"\0\x10" + b"\xc3\x28"))
    yield "info name surrogate", raw_frame(_body(p.Info.TYPE, bytes([1, 1, 0]) + bytes(12) +
                                                 bytes([3]) + b"\0\x10" + b"\xed\xa0\x80"))
    yield "status sensor flag without values", raw_frame(_body(p.Status.TYPE, bytes(5) + b"\2" +
                                                               bytes(52)))
    yield "status values without flag", raw_frame(_body(p.Status.TYPE, bytes(54) +
                                                        b"\1\0\0\0" + b"\0\1"))
    yield "status huge n_measured", raw_frame(_body(p.Status.TYPE, bytes(5) + b"\2" + bytes(48)
                                                    + b"\xff\xff\xff\xff" + b"\0\1"))
    yield "status force flag no value", raw_frame(_body(p.Status.TYPE, bytes(5) + b"\4" +
                                                        bytes(52)))
    yield "error short", raw_frame(_body(p.ErrorReport.TYPE, bytes(6)))
    yield "error bad utf8", raw_frame(_body(p.ErrorReport.TYPE, bytes(7) + b"ok\xff"))
    yield "error overlong utf8", raw_frame(_body(p.ErrorReport.TYPE, bytes(7) + b"\xc0\xaf"))
    yield "error 4-byte utf8", raw_frame(_body(p.ErrorReport.TYPE, bytes(7) + "🙂".encode()))
    yield "error above U+10FFFF", raw_frame(_body(p.ErrorReport.TYPE, bytes(7) + b"\xf4\x90\x80\x80"))
    yield "largest frame, 4113 stuffed bytes, then resync", _largest_frame() + hb
    yield "stuffed 4113 bytes cut short", _largest_frame()[:-2] + b"\x00" + hb
    yield "oversize 4114 then resync", bytes([0xFF]) * 4114 + b"\x00" + hb
    yield "oversize long then resync", bytes([7]) * 10000 + b"\x00" + hb
    # zeros make stuffing cheap: a 4108-byte body fits in 4113 stuffed bytes, yet a body
    # is at most 4096 bytes (PROTOCOL.md 2): oversize
    yield "body above 4096 is oversize", raw_frame(_body(p.Block.TYPE, (1).to_bytes(8, "little") +
                                                      (2044).to_bytes(2, "little") + b"\1\0" +
                                                      b"\0\1" * 2044, seq=3))
    yield "garbage then frame", bytes(rng.integers(1, 256, 40, dtype=np.uint8)) + b"\x00" + hb
    yield "seq gap counts lost", enc(p.Heartbeat(0), 0) + enc(p.Heartbeat(0), 1) + enc(
        p.Heartbeat(0), 5)
    yield "seq backwards not lost", enc(p.Heartbeat(0), 10) + enc(p.Heartbeat(0), 2) + enc(
        p.Heartbeat(0), 3)
    yield "seq wraps", enc(p.Heartbeat(0), 65534) + enc(p.Heartbeat(0), 65535) + enc(
        p.Heartbeat(0), 1)
    # PROTOCOL.md 5.3: the device's own frames echoed back are not numbered by the host
    echo = p.Status(0, 2, 0, 0, buffer_end=0, played_samples=0, flushed_samples=0, flushes=0)
    yield "echoed device frame keeps seq", enc(_block(0, [1]), 1, 4) + enc(echo, 40, 4) + enc(
        _block(1, [1]), 3, 4)
    yield "dropped frame keeps seq", enc(p.Heartbeat(0), 0) + raw_frame(
        _body(p.Heartbeat.TYPE, b"\1\0\0\0", seq=7), crc_ok=False) + enc(p.Heartbeat(0), 1)


def _random_message_block(rng):
    ch, n = int(rng.integers(1, 5)), int(rng.integers(0, 60))
    ph = rng.integers(0, 65536, (n, ch)) if rng.integers(0, 2) else None
    return _block(int(rng.integers(0, 2**63)), rng.integers(0, 65536, (n, ch)), ph)


def _random_message(rng):
    kind = rng.integers(0, 11)
    u32 = lambda: int(rng.integers(0, 2**32))  # noqa: E731
    if kind == 0:
        return p.Hello(u32())
    if kind == 1:
        return p.Heartbeat(u32())
    if kind == 2:
        return p.Stop(bool(rng.integers(0, 2)))
    if kind == 3:
        return _random_message_block(rng)
    if kind == 4:
        ch = int(rng.integers(1, 9))
        return _info(ch, limits_um=tuple(int(c) / 4096 for c in rng.integers(1, 65536, ch)),
                     has_phases=bool(rng.integers(0, 2)), buffer_samples=u32())
    if kind == 5:
        meas = tuple(int(c) / 4096 for c in rng.integers(0, 65536, int(rng.integers(1, 5))))
        accounting = (int(rng.integers(0, 2**63)), u32(), u32(), u32()) \
            if rng.integers(0, 2) else (None,) * 4
        return p.Status(u32(), int(rng.integers(0, 5)), int(rng.integers(0, 2**63)), u32(),
                        *[u32() for _ in range(9)],
                        measured_um=meas if rng.integers(0, 2) else None,
                        force_n=int(rng.integers(0, 65536)) / 1000 if rng.integers(0, 2) else None,
                        buffer_end=accounting[0], played_samples=accounting[1],
                        flushed_samples=accounting[2], flushes=accounting[3])
    if kind == 6:
        return p.Flushed(int(rng.integers(0, 256)), int(rng.integers(0, 2**63)), u32(), u32())
    if kind == 9:
        block = _random_message_block(rng)
        return p.Resend(block.start_index, block.amplitudes, block.phases,
                        int(rng.integers(0, 65536)))
    if kind == 10:
        return p.Missing(tuple(int(q) for q in rng.integers(0, 65536,
                                                             int(rng.integers(1, 17)))))
    if kind == 7:
        count = int(rng.integers(1, 30))
        return _force(int(rng.integers(0, 2**63)), int(rng.integers(1, 65536)),
                      rng.integers(-32768, 32768, count), rng.integers(-32768, 32768, count))
    return p.ErrorReport(int(rng.integers(1, 6)), int(rng.integers(0, 65536)), u32(),
                         "".join(chr(int(c)) for c in rng.integers(32, 0x3000, 12)))


def _versions(msg) -> tuple[int, ...]:
    """The versions a message can be sent in: a Status's layout says which; Flushed is 2
    to 4, ForceReport 3 and 4, Resend and Missing 4."""
    if isinstance(msg, p.Status):
        return (2, 3, 4) if msg.accounted else (1,)
    if isinstance(msg, p.ForceReport):
        return (3, 4)
    if isinstance(msg, (p.Resend, p.Missing)):
        return (4,)
    return (2, 3, 4) if isinstance(msg, p.Flushed) else (1, 2, 3, 4)


def _version(msg, rng) -> int:
    versions = _versions(msg)
    return versions[int(rng.integers(0, len(versions)))]


def _mutate(frame: bytes, rng) -> bytes:
    data = bytearray(frame)
    for _ in range(int(rng.integers(1, 4))):
        op, at = int(rng.integers(0, 4)), int(rng.integers(0, len(data)))
        if op == 0:
            data[at] ^= 1 << int(rng.integers(0, 8))
        elif op == 1 and len(data) > 2:
            del data[at]
        elif op == 2:
            data.insert(at, int(rng.integers(0, 256)))
        else:
            data[at:at] = bytes(rng.integers(0, 256, int(rng.integers(1, 9)), dtype=np.uint8))
    return bytes(data)


def _payload_mutant(rng) -> bytes:
    """A valid-CRC frame whose body was damaged before the CRC: exercises the payload checks."""
    msg = _random_message(rng)
    frame = enc(msg, int(rng.integers(0, 65536)), _version(msg, rng))
    body = bytearray(p.cobs_decode(frame[:-1])[:-4])
    op = int(rng.integers(0, 3))
    if op == 0 and len(body) > 5:
        del body[int(rng.integers(4, len(body))):]
    elif op == 1:
        body += bytes(rng.integers(0, 256, int(rng.integers(1, 4)), dtype=np.uint8))
    else:
        at = int(rng.integers(4, len(body))) if len(body) > 4 else 3
        body[at] = int(rng.integers(0, 256))
    return raw_frame(bytes(body))


def vectors():
    rng = np.random.default_rng(20240517)
    out = []

    def add(name, data, reencode=False):
        out.append({"name": name, "hex": data.hex(), "expect": " | ".join(render_stream(data)),
                    "reencode": reencode})

    for name, msg, seq in valid_messages():
        for version in _versions(msg):
            add(f"{name} v{version}", enc(msg, seq, version), reencode=True)
    for name, data in damaged_streams(rng):
        add(name, data)
    for i in range(120):
        msg = _random_message(rng)
        add(f"random {i}", enc(msg, int(rng.integers(0, 65536)), _version(msg, rng)),
            reencode=True)
    for i in range(200):
        msg = _random_message(rng)
        frame = enc(msg, int(rng.integers(0, 65536)), _version(msg, rng))
        add(f"mutated {i}", _mutate(frame, rng) + enc(p.Heartbeat(i), 100))
    for i in range(150):
        add(f"payload mutant {i}", _payload_mutant(rng))
    return out


def main() -> None:
    rows = [json.dumps(v, ensure_ascii=True) for v in vectors()]
    OUT.write_text("[\n" + ",\n".join(rows) + "\n]\n", encoding="ascii")
    print(f"wrote {len(rows)} vectors to {OUT}")


if __name__ == "__main__":
    main()
