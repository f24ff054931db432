"""The wire protocol: COBS, CRC, every message round trip, any byte string, resync."""

import re
import zlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from frictex.device.link import protocol as p
from frictex.device.link.faults import Faults, inject

SETTINGS = settings(derandomize=True, max_examples=150, deadline=None)
U16 = st.integers(0, 65535)
U32 = st.integers(0, 2**32 - 1)


def _limits(n):
    # values that are whole wire counts, so the round trip is exact
    return st.lists(st.integers(1, 65535).map(lambda c: c * p.AMPLITUDE_STEP_UM),
                    min_size=n, max_size=n).map(tuple)


@st.composite
def blocks(draw):
    ch = draw(st.integers(1, 4))
    n = draw(st.integers(0, 60))
    amps = np.array(draw(st.lists(U16, min_size=n * ch, max_size=n * ch)),
                    dtype=np.uint16).reshape(n, ch)
    phases = None
    if draw(st.booleans()):
        phases = np.array(draw(st.lists(U16, min_size=n * ch, max_size=n * ch)),
                          dtype=np.uint16).reshape(n, ch)
    return p.Block(draw(st.integers(0, 2**64 - 1)), amps, phases)


@st.composite
def infos(draw):
    ch = draw(st.integers(1, 8))
    return p.Info(ch, draw(st.integers(1, 4_000_000_000)) / 1000.0, draw(_limits(ch)),
                  draw(U32), draw(U16), draw(U16), draw(st.booleans()), draw(st.booleans()),
                  draw(st.booleans()), draw(st.text(max_size=20)))


U64 = st.integers(0, 2**64 - 1)


@st.composite
def statuses(draw):
    """A Status; with the version 2 accounting fields or (a version 1 Status) without."""
    counters = draw(st.lists(U32, min_size=9, max_size=9))
    measured = draw(st.none() | st.integers(1, 4).flatmap(_limits))
    force = draw(st.none() | st.integers(0, 65535).map(lambda mn: mn / 1000.0))
    accounting = draw(st.none() | st.tuples(U64, U32, U32, U32)) or (None,) * 4
    return p.Status(draw(U32), draw(st.integers(0, 4)), draw(U64), draw(U32), *counters,
                    measured_um=measured, force_n=force, buffer_end=accounting[0],
                    played_samples=accounting[1], flushed_samples=accounting[2],
                    flushes=accounting[3])


I16 = st.integers(-32768, 32767)


@st.composite
def force_reports(draw):
    """A ForceReport whose values are whole wire counts (an exact round trip)."""
    count = draw(st.integers(1, p.FORCE_PAIRS_MAX))
    values = st.lists(I16.map(lambda c: c * p.FORCE_STEP_N), min_size=count, max_size=count)
    return p.ForceReport(draw(U64), draw(st.integers(1, 65535)), tuple(draw(values)),
                         tuple(draw(values)))


@st.composite
def resends(draw):
    block = draw(blocks())
    return p.Resend(block.start_index, block.amplitudes, block.phases, draw(U16))


MISSINGS = st.lists(U16, min_size=1, max_size=p.MISSING_MAX).map(lambda q: p.Missing(tuple(q)))

MESSAGES = st.one_of(
    st.builds(p.Hello, U32), infos(), blocks(), st.builds(p.Heartbeat, U32),
    st.builds(p.Stop, st.booleans()), statuses(),
    st.builds(p.ErrorReport, st.integers(0, 255), U16, U32, st.text(max_size=40)),
    st.builds(p.Flushed, st.integers(0, 255), U64, U32, U32), force_reports(), resends(),
    MISSINGS)


def _version(msg, draw_one: bool) -> int:
    """A version the message exists in: Flushed and accounted Statuses from 2 (drawn 2 or
    4), ForceReport from 3 (3 or 4), Resend and Missing only in 4, a Status without
    accounting only in 1, the rest 1 or 4."""
    if isinstance(msg, (p.Resend, p.Missing)):
        return 4
    if isinstance(msg, p.ForceReport):
        return 4 if draw_one else 3
    if isinstance(msg, p.Flushed) or (isinstance(msg, p.Status) and msg.accounted):
        return 4 if draw_one else 2
    if isinstance(msg, p.Status):
        return 1
    return 4 if draw_one else 1


@SETTINGS
@given(st.binary(max_size=1200))
def test_cobs_round_trip_has_no_zero_bytes(data):
    stuffed = p.cobs_encode(data)
    assert b"\x00" not in stuffed
    assert len(stuffed) <= len(data) + 1 + len(data) // 254
    assert p.cobs_decode(stuffed) == data


def test_cobs_matches_the_published_examples():
    # Cheshire & Baker (1999), and the Wikipedia table of COBS examples
    assert p.cobs_encode(b"\x00") == b"\x01\x01"
    assert p.cobs_encode(b"\x00\x00") == b"\x01\x01\x01"
    assert p.cobs_encode(b"\x11\x22\x00\x33") == b"\x03\x11\x22\x02\x33"
    assert p.cobs_encode(b"\x11\x00\x00\x00") == b"\x02\x11\x01\x01\x01"
    assert p.cobs_decode(bytes(range(1, 255)).join([b"\xff", b""])) == bytes(range(1, 255))


def test_crc_is_crc32_iso_hdlc():
    assert zlib.crc32(b"123456789") == 0xCBF43926  # the check value PROTOCOL.md quotes


@SETTINGS
@given(MESSAGES, U16, st.lists(st.integers(1, 40), max_size=30), st.booleans())
def test_every_message_round_trips_through_any_chunking(msg, seq, cuts, newest):
    version = _version(msg, newest)
    data = p.encode(msg, seq, version)
    assert data.endswith(b"\x00") and data.count(0) == 1
    decoder = p.Decoder()
    frames, pos = [], 0
    for cut in cuts:
        frames += decoder.feed(data[pos:pos + cut])
        pos += cut
    frames += decoder.feed(data[pos:])
    assert frames == [p.Frame(seq, msg, version)]
    assert decoder.counts.discarded == 0


def test_version_2_status_carries_the_accounting_after_the_version_1_fields():
    st_ = p.Status(7, 2, 2**64 - 1, 100, *range(1, 10), buffer_end=2**63, played_samples=5,
                   flushed_samples=6, flushes=2)
    v1 = p.cobs_decode(p.encode(st_, 0, 1)[:-1])
    v2 = p.cobs_decode(p.encode(st_, 0, 2)[:-1])
    # the version 2 payload is the version 1 one (n_measured 0, no sensors) plus
    # buffer_end:u64 played:u32 flushed:u32 flushes:u32, then the CRC
    assert v1[0] == 1 and v2[0] == 2
    assert v2[4:-4] == v1[4:-4] + (2**63).to_bytes(8, "little") + bytes(
        [5, 0, 0, 0, 6, 0, 0, 0, 2, 0, 0, 0])
    (frame,) = p.Decoder().feed(p.encode(st_, 0, 1))
    assert frame.version == 1 and frame.message.buffer_end is None
    assert not frame.message.accounted


def test_a_version_1_receiver_drops_version_2_frames_and_flushed_needs_version_2():
    old = p.Decoder(max_version=1)
    assert old.feed(p.encode(p.Heartbeat(1), 0, 2)) == []
    assert old.counts.bad_version == 1 and old.counts.last_bad_version == 2
    assert old.feed(p.encode(p.Heartbeat(1), 1, 1)) == [p.Frame(1, p.Heartbeat(1), 1)]
    with pytest.raises(p.ProtocolError, match="Flushed does not exist in protocol version 1"):
        p.encode(p.Flushed(1, 0, 0, 1), 0, 1)
    with pytest.raises(p.ProtocolError, match="version 2 needs buffer_end"):
        p.encode(p.Status(0, 0, 0, 0), 0, 2)
    # a Flushed type byte in a version 1 frame is an unknown type there
    body = bytes([1, p.Flushed.TYPE, 0, 0]) + bytes(17)
    frame = p.cobs_encode(body + zlib.crc32(body).to_bytes(4, "little")) + b"\x00"
    decoder = p.Decoder()
    assert decoder.feed(frame) == [] and decoder.counts.unknown_type == 1


def test_a_message_of_every_version_is_refused_in_version_0_by_name():
    """Heartbeat exists since version 1: version 0 was a KeyError, not a ProtocolError."""
    with pytest.raises(p.ProtocolError, match="^Heartbeat does not exist in protocol version 0; "
                                              "it needs version 1$"):
        p.encode(p.Heartbeat(1), 0, 0)


@SETTINGS
@given(st.binary(max_size=3000), st.lists(st.integers(1, 500), max_size=10))
def test_any_bytes_give_valid_frames_or_counted_errors(data, cuts):
    decoder = p.Decoder()
    frames, pos = [], 0
    for cut in [*cuts, len(data)]:
        frames += decoder.feed(data[pos:pos + cut])
        pos += cut
    assert all(isinstance(f.message, p.MESSAGES) for f in frames)
    for f in frames:  # anything accepted is exactly what its bytes encode
        assert p.Decoder().feed(p.encode(f.message, f.seq, f.version)) == [f]
    terminated = [piece for piece in data.split(b"\x00")[:-1] if piece]
    assert decoder.counts.frames_ok + decoder.counts.discarded == len(terminated)
    assert decoder.counts.frames_ok == len(frames)


def _stream(n):
    rng = np.random.default_rng(7)
    msgs = [p.Block(50 * k, rng.integers(0, 9000, (50, 1)).astype(np.uint16)) if k % 3
            else p.Heartbeat(k) for k in range(n)]
    return msgs, [p.encode(m, k) for k, m in enumerate(msgs)]


@SETTINGS
@given(st.integers(0, 2**32 - 1), st.sampled_from(["flip", "drop", "garbage"]))
def test_decoder_resyncs_after_the_damaged_frame(seed, kind):
    msgs, frames = _stream(40)
    faults = Faults(**{kind: 0.004})
    rng = np.random.default_rng(seed)
    damaged = [inject(f, faults, rng) for f in frames]
    # a frame survives if its own bytes are intact and the frame before ended cleanly
    expect = [k for k, (f, d) in enumerate(zip(frames, damaged))
              if f == d and (k == 0 or damaged[k - 1].endswith(b"\x00"))]
    decoder = p.Decoder()
    got = decoder.feed(b"".join(damaged))
    assert [f.seq for f in got] == expect
    assert all(f.message == msgs[f.seq] for f in got)
    if len(expect) < len(frames):
        assert decoder.counts.discarded >= 1
    # lost frames are the holes in the sequence numbers between decoded frames
    assert decoder.counts.lost_frames == (expect[-1] - expect[0] + 1 - len(expect) if expect else 0)


def test_a_flipped_bit_is_a_crc_error_and_costs_one_frame():
    msgs, frames = _stream(5)
    bad = bytearray(frames[2])
    bad[10] ^= 0x10 if bad[10] != 0x10 else 0x20  # never creates a zero byte
    decoder = p.Decoder()
    got = decoder.feed(b"".join([frames[0], frames[1], bytes(bad), frames[3], frames[4]]))
    assert [f.seq for f in got] == [0, 1, 3, 4]
    assert decoder.counts.crc_errors + decoder.counts.cobs_errors == 1
    assert decoder.counts.lost_frames == 1


def test_an_endless_frame_is_dropped_as_oversize_and_the_next_one_decodes():
    decoder = p.Decoder()
    assert decoder.feed(b"\x07" * (2 * p.MAX_BODY)) == []
    got = decoder.feed(b"\x00" + p.encode(p.Heartbeat(3), 9))
    assert got == [p.Frame(9, p.Heartbeat(3))]
    assert decoder.counts.oversize == 1


def test_a_frame_of_another_version_is_counted_and_remembered():
    decoder = p.Decoder()
    newer = p.PROTOCOL_VERSION + 1
    assert decoder.feed(p.encode(p.Heartbeat(1), 0, version=newer)) == []
    assert decoder.counts.bad_version == 1 and decoder.counts.last_bad_version == newer


def test_amplitudes_quantise_to_half_a_step_and_clamp_with_a_count():
    um = np.array([[0.0, 1.0], [1e-9, 2.49999], [3.0, 2.6], [-0.5, np.nan], [np.inf, 17.0]])
    counts, clamped = p.amplitude_to_wire(um, np.array([2.5, 2.5]))
    back = p.amplitude_from_wire(counts)
    inside = np.array([[1, 1], [1, 1], [0, 0], [0, 0], [0, 0]], dtype=bool)
    np.testing.assert_allclose(back[inside], um[inside], atol=p.AMPLITUDE_STEP_UM / 2)
    assert clamped == 6
    assert back.max() <= 2.5
    np.testing.assert_array_equal(back[2], [2.5, 2.5])
    np.testing.assert_array_equal(back[3], [0.0, 0.0])  # negative and NaN become 0
    assert p.amplitude_to_wire(np.array([[20.0]]))[0][0, 0] == 65535


def test_phases_wrap_to_one_turn_within_half_a_step():
    rad = np.array([[-np.pi / 2, 0.0, 2 * np.pi - 1e-7, 7 * np.pi]])
    back = p.phase_from_wire(p.phase_to_wire(rad))
    err = np.angle(np.exp(1j * (back - rad)))
    assert np.abs(err).max() <= p.PHASE_STEP_RAD / 2
    assert back.min() >= 0 and back.max() < 2 * np.pi


def test_encoding_refuses_what_does_not_fit():
    with pytest.raises(p.ProtocolError, match=r"got float64 \(5, 1\), expected uint16"):
        p.encode(p.Block(0, np.zeros((5, 1))))
    too_many = p.max_block_samples(1, False) + 1
    with pytest.raises(p.ProtocolError, match=f"Block of {too_many} samples"):
        p.encode(p.Block(0, np.zeros((too_many, 1), dtype=np.uint16)))
    with pytest.raises(p.ProtocolError, match="Hello"):
        p.encode(p.Hello(-1))
    with pytest.raises(p.ProtocolError, match="cannot encode str"):
        p.encode("hello")
    assert issubclass(p.ProtocolError, OSError)


def test_the_worked_examples_in_protocol_md_are_what_encode_produces():
    text = (Path(p.__file__).parents[1] / "PROTOCOL.md").read_text(encoding="utf-8")
    examples = re.findall(r"`(encode\(.+?\))`\s*->\s*`([0-9a-f ]+)`", text)
    assert len(examples) >= 6
    names = {m.__name__: m for m in p.MESSAGES} | {"np": np, "encode": p.encode}
    for call, hexbytes in examples:
        frame = eval(call, names)  # noqa: S307 -- our own document
        assert frame.hex(" ") == hexbytes.strip(), call


# ---------------------------------------------------------------------------- force reports

def test_the_largest_frame_is_4113_stuffed_bytes_and_4114_with_its_delimiter():
    """PROTOCOL.md 2: COBS adds one byte per 254 and one more to a body without zeros."""
    body = bytes(range(1, 256)) * 16 + bytes(range(1, 17))
    assert len(body) == p.MAX_BODY
    assert len(p.cobs_encode(body)) == p.MAX_STUFFED == 4096 + 16 + 1 == 4113
    text = (Path(p.__file__).parents[1] / "PROTOCOL.md").read_text(encoding="utf-8")
    assert "at most 4113 bytes before its\n  delimiter, 4114 with it" in text


def test_force_report_layout_is_the_documented_one():
    """PROTOCOL.md 4.9: start u64, decimation u16, count u8, then (lateral, normal) i16
    pairs of 1/4096 N, little-endian."""
    msg = p.ForceReport(2**64 - 2, 4, (1.0, -8.0), (0.5, 7.0))
    body = p.cobs_decode(p.encode(msg, 3, 3)[:-1])
    assert body[:4] == bytes([3, 0x85, 3, 0])
    payload = body[4:-4]
    assert payload[:11] == (2**64 - 2).to_bytes(8, "little") + bytes([4, 0, 2])
    pairs = np.frombuffer(payload[11:], dtype="<i2").reshape(2, 2)
    np.testing.assert_array_equal(pairs, [[4096, 2048], [-32768, 28672]])


def test_forces_quantise_to_half_a_count_and_clip_to_the_i16_range():
    f = np.array([0.0, 1e-5, -1e-4, 2.5, 7.9998, 9.0, -8.0, -9.0, np.nan, np.inf])
    counts = p.force_to_wire(f)
    assert counts.dtype == np.int16
    np.testing.assert_array_equal(counts, [0, 0, 0, 10240, 32767, 32767, -32768, -32768, 0, 0])
    inside = np.abs(f) < 7.99
    assert np.all(np.abs(p.force_from_wire(counts)[inside] - f[inside]) <= p.FORCE_STEP_N / 2)


def test_force_reports_exist_from_version_3_and_need_one_to_255_values():
    msg = p.ForceReport(0, 4, (0.0,), (0.0,))
    for version in (1, 2):
        with pytest.raises(p.ProtocolError, match="ForceReport does not exist in protocol "
                                                  f"version {version}; it needs version 3"):
            p.encode(msg, 0, version)
    for bad, match in [(p.ForceReport(0, 4, (), ()), "0 lateral and 0 normal"),
                       (p.ForceReport(0, 4, (0.0,) * 256, (0.0,) * 256), "256 lateral"),
                       (p.ForceReport(0, 4, (0.0, 0.0), (0.0,)), "2 lateral and 1 normal"),
                       (p.ForceReport(0, 0, (0.0,), (0.0,)), "decimation 0")]:
        with pytest.raises(p.ProtocolError, match=match):
            p.encode(bad, 0, 3)
    # a version 2 receiver (a version 2 host) drops a version 3 frame, counted
    old = p.Decoder(max_version=2)
    assert old.feed(p.encode(msg, 0, 3)) == [] and old.counts.bad_version == 1
    # the type byte in a version 2 frame is an unknown type there
    body = bytes([2, p.ForceReport.TYPE, 0, 0]) + p.cobs_decode(p.encode(msg, 0, 3)[:-1])[4:-4]
    frame = p.cobs_encode(body + zlib.crc32(body).to_bytes(4, "little")) + b"\x00"
    decoder = p.Decoder()
    assert decoder.feed(frame) == [] and decoder.counts.unknown_type == 1


def test_info_flag_bit_3_announces_force_reports_and_older_hosts_ignore_it():
    info = p.Info(1, 10_000.0, (4.0,), 4096, 25, 20, has_force_reports=True, name="x")
    (frame,) = p.Decoder().feed(p.encode(info, 0, 1))
    assert frame.message.has_force_reports
    flags = p.cobs_decode(p.encode(info, 0, 1)[:-1])[4 + 2]
    assert flags == 0b1000


@SETTINGS
@given(st.lists(force_reports(), min_size=1, max_size=6), st.lists(st.integers(1, 300),
                                                                    max_size=40),
       st.integers(0, 2**32 - 1))
def test_force_reports_survive_any_rechunking_and_damage_costs_only_the_damaged(msgs, cuts,
                                                                                seed):
    """Re-chunked at random, every report decodes; with bits flipped on the wire, every
    report whose bytes (and the delimiter before) survived decodes exactly, the rest are
    counted drops, never a wrong report."""
    frames = [p.encode(m, k, 3) for k, m in enumerate(msgs)]
    data = b"".join(frames)
    decoder, got, pos = p.Decoder(), [], 0
    for cut in [*cuts, len(data)]:
        got += decoder.feed(data[pos:pos + cut])
        pos += cut
    assert [f.message for f in got] == msgs and decoder.counts.discarded == 0
    rng = np.random.default_rng(seed)
    damaged = [inject(f, Faults(flip=0.002), rng) for f in frames]
    expect = [k for k, (f, d) in enumerate(zip(frames, damaged))
              if f == d and (k == 0 or damaged[k - 1].endswith(b"\x00"))]
    decoder = p.Decoder()
    got = decoder.feed(b"".join(damaged))
    assert [f.seq for f in got] == expect
    assert all(f.message == msgs[f.seq] for f in got)
    # a stream whose last delimiter was damaged holds its last frame, neither decoded
    # nor discarded: it waits for a delimiter that has not come
    incomplete = not b"".join(damaged).endswith(b"\x00")
    assert (decoder.counts.discarded >= 1 or incomplete) == (len(expect) < len(frames))
