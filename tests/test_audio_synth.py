"""The audio output's synthesis and ring, without PortAudio (device/audio/)."""

from __future__ import annotations

from decimal import Decimal, getcontext

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.device.audio.options import AudioArgs, make_plan, parse_arg
from frictex.device.audio.ring import FrameRing, Player
from frictex.device.audio.synth import AudioSynth, carrier_cycles
from frictex.device.errors import InputError
from frictex.device.profile import DEFAULT_PROFILE, PROFILES

RATE = 10_000.0
FS = 192_000
TEN_HOURS = 10 * 3600 * FS


def plan(channels=1, **options):
    return make_plan(AudioArgs(**options), channels, RATE)


def exact_phase(n: int, f: float, fs: int) -> float:
    """2 pi ((n f / fs) mod 1), the fraction in 60-digit decimal arithmetic (f's binary
    value is exact in Decimal)."""
    getcontext().prec = 60
    cycles = (Decimal(n) * Decimal(f) / Decimal(fs)) % 1
    return 2 * np.pi * float(cycles)


# ---------------------------------------------------------------------- ARG
def test_arg_grammar():
    assert parse_arg("") == AudioArgs()
    assert parse_arg("hw:1") == AudioArgs(target="hw:1")
    assert parse_arg("envelope") == AudioArgs(envelope=True)
    a = parse_arg("wav:/tmp/x.wav,envelope,rate=96000,carrier=31000.5,profile=beam-seed000")
    assert (a.wav_path, a.envelope, a.rate, a.carrier, a.profile) == (
        "/tmp/x.wav", True, 96000.0, 31000.5, "beam-seed000")
    assert parse_arg("Scarlett 2i2,blocksize=128,ramp_ms=1").blocksize == 128


def test_a_path_or_name_may_hold_an_equals_sign():
    """Only an option's name before '=' makes the first part an option."""
    assert parse_arg("wav:/tmp/a=b.wav") == AudioArgs(wav_path="/tmp/a=b.wav")
    assert parse_arg("wav:/tmp/a=b.wav,rate=96000").rate == 96000.0
    assert parse_arg("card=2,envelope") == AudioArgs(target="card=2", envelope=True)
    assert parse_arg("rate").target == "rate"  # a name with no '='
    assert parse_arg("rate=96000,envelope") == AudioArgs(rate=96000.0, envelope=True)
    assert parse_arg(" profile = beam-seed000").profile == "beam-seed000"


@pytest.mark.parametrize("arg, match", [
    ("x,loud", "option 'loud'"), ("rate=fast", "rate='fast'"), ("blocksize=1.5", "whole"),
    ("ramp_ms=-1", "> 0"), ("carrier=nan", "> 0"), ("wav:", "wav:PATH"),
    # a misspelt first option was taken for a device NAME holding '='
    ("rat=1000", r"no option 'rat' \(did you mean rate=\?\)"),
    ("bufer_ms=3,envelope", "did you mean buffer_ms="),
])
def test_arg_errors(arg, match):
    with pytest.raises(InputError, match=match):
        parse_arg(arg)


@settings(max_examples=200, derandomize=True, deadline=None)
@given(st.text(alphabet=st.sampled_from(list("ab=,.:/-_ 019e")), max_size=30))
def test_arg_parser_takes_any_text_or_says_why(text):
    try:
        parse_arg(text)
    except InputError as exc:
        assert "audio device" in str(exc)


def test_rate_must_fit_the_carrier():
    assert make_plan(parse_arg("rate=96000,profile=beam-seed000"), 2, RATE).audio_rate == 96000
    with pytest.raises(InputError, match="below 0.4 of the rate"):
        make_plan(parse_arg("rate=96000,profile=ring-seed004"), 2, RATE)  # 39.5 kHz
    assert make_plan(parse_arg("rate=48000,envelope"), 1, RATE).envelope  # no carrier
    with pytest.raises(InputError, match="whole number"):
        make_plan(parse_arg("rate=96000.5"), 1, RATE)


def test_profile_figures():
    p = make_plan(AudioArgs(), 2, RATE, requested_profile="ring-seed004")
    assert (p.carrier_hz, p.limit_v, p.profile) == (39_500.0, 80.0, "ring-seed004")
    p = make_plan(AudioArgs(full_scale=10.0, carrier=31_000.0), 1, RATE)
    assert (p.carrier_hz, p.limit_v, p.full_scale_v) == (31_000.0, 10.0, 10.0)


# ---------------------------------------------------------------------- carrier phase
@pytest.mark.parametrize("f", [30_000.0, 28_300.0, 39_500.0, 33_000.123456789])
def test_carrier_phase_after_ten_hours_is_exact(f):
    cycles = carrier_cycles(TEN_HOURS, 1000, f, FS)
    for j in (0, 1, 999):
        got = 2 * np.pi * cycles[j]
        want = exact_phase(TEN_HOURS + j, f, FS)
        err = (got - want + np.pi) % (2 * np.pi) - np.pi
        assert abs(err) < 1e-9, (f, j, err)


def test_synth_carrier_after_ten_hours():
    """The synthesis state carried to 10 h of output: each frame is amp * cos of the
    exact phase (|cos a - cos b| <= |a - b|, so 1e-9 of amplitude bounds the phase)."""
    p = plan(carrier=28_300.0)
    s = AudioSynth(p)
    s.commands = 10 * 3600 * int(RATE)
    s.frames = s.frames_until(s.commands)
    block = np.full((50, 1), 1.2)
    s.render(block)  # from the zero before it up to 1.2 um
    n0 = s.frames
    out = s.render(block)[:, 0]
    level = 1.2 / p.um_per_volt / p.full_scale_v
    want = level * np.cos([exact_phase(n0 + j, 28_300.0, FS) for j in range(out.size)])
    np.testing.assert_allclose(out, want, rtol=0, atol=1e-9 * level)


# ---------------------------------------------------------------------- synthesis
def commands(n, channels, seed=0):
    rng = np.random.default_rng(seed)
    a = np.cumsum(rng.normal(0, 0.05, (n, channels)), axis=0) % 2.0
    ph = rng.choice([0.0, np.pi, 0.5], size=(n, channels))
    return a, ph


@settings(max_examples=40, derandomize=True, deadline=None)
@given(st.lists(st.integers(1, 400), min_size=1, max_size=8))
def test_split_blocks_equal_one_call(sizes):
    """Any split of the commands into blocks gives the frames of one call (state carried)."""
    n = sum(sizes)
    a, ph = commands(n, 2)
    whole = AudioSynth(plan(2, carrier=28_300.0)).render(a, ph)
    s = AudioSynth(plan(2, carrier=28_300.0))
    parts, lo = [], 0
    for size in sizes:
        parts.append(s.render(a[lo:lo + size], ph[lo:lo + size]))
        lo += size
    np.testing.assert_allclose(np.concatenate(parts), whole, rtol=0, atol=1e-12)
    assert s.frames == whole.shape[0] == -(-n * FS // int(RATE))


def test_envelope_is_the_commands_interpolated_one_sample_late():
    p = plan(2, envelope=True)
    a, _ = commands(3000, 2, seed=3)
    s = AudioSynth(p)
    out = np.concatenate([s.render(a[lo:lo + 37]) for lo in range(0, 3000, 37)])
    n = np.arange(out.shape[0])
    q = n * RATE / FS - 1.0  # command position each frame carries
    k = np.arange(-1, 3000)
    for ch in range(2):
        want = np.interp(q, k, np.concatenate([[0.0], a[:, ch]])) / p.um_per_volt / p.full_scale_v
        want[:p.ramp_frames] *= np.minimum(1.0, (n[:p.ramp_frames] + 1.0) / p.ramp_frames)
        np.testing.assert_allclose(out[:, ch], want, rtol=0, atol=1e-12)


def test_no_step_at_block_boundaries():
    """Constant commands in blocks of 7: sample-to-sample change never exceeds what the
    carrier itself makes (2 pi f / fs of the level)."""
    p = plan()
    s = AudioSynth(p)
    out = np.concatenate([s.render(np.full((7, 1), 1.0)) for _ in range(100)])[:, 0]
    level = 1.0 / p.um_per_volt / p.full_scale_v
    assert np.max(np.abs(np.diff(out))) <= level * 2 * np.pi * p.carrier_hz / FS * 1.0001


def test_clamp_at_the_voltage_limit_is_counted():
    p = plan(full_scale=100.0)  # limit 100 V = 2 um at 0.02 um/V
    s = AudioSynth(p)
    a = np.concatenate([np.full((100, 1), 1.0), np.full((100, 1), 2.5), np.full((100, 1), 3.0)])
    out = s.render(a, np.zeros_like(a))
    assert s.clamped == 200
    assert np.max(np.abs(out)) <= 1.0 + 1e-12
    assert np.max(np.abs(out)) > 0.9


@pytest.mark.parametrize("phases", [False, True])
def test_a_negative_amplitude_plays_zero_and_is_counted_as_the_link_plays_it(phases):
    """-3 um is no amplitude: played as its magnitude it drove the plate at the full
    voltage limit, carrier inverted, uncounted."""
    s = AudioSynth(plan())
    a = np.concatenate([np.zeros((50, 1)), np.full((100, 1), -3.0), np.zeros((50, 1))])
    out = s.render(a, np.full_like(a, 0.7) if phases else None)
    assert s.clamped == 100
    assert np.max(np.abs(out)) == 0.0


def test_finish_ramps_to_zero():
    p = plan()
    s = AudioSynth(p)
    s.render(np.full((100, 1), 2.0))
    tail = s.finish()[:, 0]
    assert tail.shape[0] == p.ramp_frames
    assert abs(tail[-1]) < 1e-12
    with pytest.raises(InputError, match="after its end"):
        s.render(np.ones((1, 1)))


def test_bad_blocks():
    s = AudioSynth(plan(2))
    with pytest.raises(InputError, match=r"expected \(n, 2\)"):
        s.render(np.ones((5, 3)))
    with pytest.raises(InputError, match="finite"):
        s.render(np.full((5, 2), np.nan))
    with pytest.raises(InputError, match="phases shape"):
        s.render(np.ones((5, 2)), np.ones((4, 2)))


# ---------------------------------------------------------------------- ring and callback
R = 384


def carrier_step(level: float) -> float:
    """The largest change between two samples of the default profile's carrier at
    ``level`` (full scale): ``2 level sin(pi f / fs)``."""
    return 2 * level * np.sin(np.pi * PROFILES.get(DEFAULT_PROFILE).carrier_hz / FS)


def ring_with(frames: int, level: float = 0.5):
    """A ring holding ``frames`` of the default profile's carrier at ``level``, with its
    fade."""
    p = plan(ramp_ms=R / FS * 1e3)
    s = AudioSynth(p)
    ring = FrameRing(8192, 1, p.ramp_frames)
    while s.frames < frames:
        out = s.render(np.full((10, 1), level * p.um_per_volt * p.full_scale_v))
        ring.write(out.astype(np.float32), s.fade_tail().astype(np.float32))
    return ring, s


def play(player, frames, block=256):
    out = np.zeros((frames, 1), dtype=np.float32)
    for lo in range(0, frames, block):
        player.fill(out[lo:lo + block])
    return out[:, 0]


def test_starving_callback_ramps_to_zero_and_counts():
    ring, s = ring_with(3000)
    player = Player(ring, R, tap_frames=8000)
    out = play(player, 6000)
    tail = ring.tail
    assert player.played == tail and player.underruns == 1
    assert player.underrun_frames == 6000 - tail
    assert np.max(np.abs(out[tail + R:])) < 0.01  # below 1 % of full scale after the ramp
    assert np.max(np.abs(out[tail - 200:tail])) > 0.45  # it was playing at 0.5
    # the fade continues the carrier: no step bigger than the carrier's own slope
    assert np.max(np.abs(np.diff(out[:tail + R]))) <= carrier_step(0.5) * 1.01
    np.testing.assert_array_equal(player.tap[:6000, 0], out)
    assert player.marks[0] == tail


def test_late_frames_are_dropped_counted_and_the_stream_ramps_back_in():
    ring, s = ring_with(2000)
    player = Player(ring, R)
    play(player, 2560)  # 560 slots starved
    starved = player.slot - ring.tail
    before = ring.tail
    for _ in range(30):  # 30 x 192 frames arrive, the first `starved` of them late
        ring.write(s.render(np.full((10, 1), 0.5 * 3.0)).astype(np.float32),
                   s.fade_tail().astype(np.float32))
    out = play(player, 8192)
    assert player.late == starved
    assert player.played + player.late == ring.tail  # every frame accounted for
    resumed = ring.tail - before - starved
    assert resumed > 0
    assert np.max(np.abs(np.diff(out[:resumed]))) <= carrier_step(0.5) * 1.01


def test_emergency_stop_ramps_and_drops_the_rest():
    ring, _ = ring_with(6000)
    player = Player(ring, R)
    first = play(player, 1024)
    player.estop = True
    out = play(player, 2048)
    assert np.max(np.abs(out[R:])) == 0.0
    steps = np.abs(np.diff(np.concatenate([first, out])))
    assert np.max(steps) <= carrier_step(0.5) * 1.01
    assert player.played + player.stopped == ring.tail


def test_ended_stream_is_silence_not_underrun():
    ring, _ = ring_with(1000)
    player = Player(ring, R)
    player.ended = True
    play(player, 4096)
    assert player.underruns == 0 and player.underrun_frames == 0
    assert player.played == ring.tail


def test_idle_before_the_first_frame_does_not_count():
    ring = FrameRing(4096, 1, R)
    player = Player(ring, R)
    out = play(player, 1024)
    assert not out.any() and player.slot == 0 and player.underruns == 0


def test_play_log_gives_each_played_frame_its_dac_time():
    ring, s = ring_with(1000)
    player = Player(ring, R)
    out = np.zeros((256, 1), dtype=np.float32)
    for i in range(6):  # 1536 slots: frames 0..tail-1 play, then starvation
        player.fill(out, dac_time=10.0 + i * 256 / FS)
    assert player.dac_time(0, FS) == pytest.approx(10.0)
    assert player.dac_time(300, FS) == pytest.approx(10.0 + 300 / FS)
    assert player.dac_time(ring.tail - 1, FS) == pytest.approx(10.0 + (ring.tail - 1) / FS)
    assert player.dac_time(ring.tail, FS) is None  # not played (yet)
    late = ring.tail
    ring.write(s.render(np.full((10, 1), 1.5)).astype(np.float32), None)
    player.fill(out, dac_time=20.0)
    assert player.late > 0 and player.dac_time(late, FS) is None  # dropped, never played
