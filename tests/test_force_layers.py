"""Force layers through the pipeline (seed 002 eqs 7-8, seed 004 Fig. 3-5): the forces
recomputed from the channel commands alone are the forces each layer wanted."""

import numpy as np
from numpy.testing import assert_allclose, assert_array_equal

from frictex.rendering.input.trace_synth import make_motion, sample
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.input.trace_file import make_trace
from frictex.rendering.tracking.tracks import apply_index
from frictex.device.profile import DeviceProfile
from frictex.textures.model import Directional, Display, Guidance, Scene, VisualHints

RATE = 10_000.0
KP, TH, MU0, K_A, B = 0.13, 1.0, 0.5, 1.13, 1.67   # seed 004 Fig. 3c; seed 003 eq 2
RING_DISPLAY = Display(140.0, 30.0, 700, 150)
BEAM_DISPLAY = Display(600.0, 6.0, 3000, 30)


def layer(cls, **kw):
    return cls(name=cls.__name__.lower(), render="sho", region=None, blend="multiply",
               visual=VisualHints(), **kw)


def scene(profile, display, *layers, limit=3.0):
    return Scene(1, "t", "", display, DeviceProfile(profile=profile, amplitude_limit_um=limit),
                 tuple(layers))


def run(sc, trace, blocks_per_call=None):
    """The pipeline over the trace, ``blocks_per_call`` blocks per call (as replay feeds it)."""
    p = build_pipeline(sc, rate_hz=RATE, block_size=50, t0_s=float(trace.t_s[0]))
    applied = apply_index(trace.t_s, p.tracker_config)
    total = int(applied[-1] // 50) + 1
    step = blocks_per_call or total
    state, outs = p.initial_state(), []
    for b in range(0, total, step):
        nb = min(step, total - b)
        lo, hi = np.searchsorted(applied, [b * 50, (b + nb) * 50])
        chunk = trace.slice(lo, hi) if hi > lo else None
        out, state = p.process(b, chunk, state, n_blocks=nb)
        outs.append(out)
    return p, outs


def ring_forces_from_commands(p, out, fn, motion):
    """F_t (N, resisting a finger moving ``motion``) from the ring's commands alone:
    W_A = e^{j phi} W_B, d = sign * sign(sin phi) (seed 004, eq 1), then seed 002 eqs 7-8."""
    w = out.commands_um[:, 1]
    phi = out.phases_rad[:, 0] - out.phases_rad[:, 1]
    d = p.actuation.wave.sign * np.sign(np.sin(phi))
    tau = p.actuation.ratio_at(out.x_mm[0])
    w = w * p.actuation.gain_at(out.x_mm[0])   # envelope under the finger (1.000x on the ring)
    a = K_A * fn
    friction = MU0 * fn * ((1 - a) * np.exp(-B * w) + a)
    drive = KP * fn * np.maximum(tau * w - TH, 0.0)
    return friction + motion * d * drive, d, drive


def test_directional_net_force_differs_by_direction_as_asked():
    sc = scene("ring-seed004", RING_DISPLAY,
               layer(Directional, target="force", forward=0.03, backward=0.2))
    trace = sample(make_motion("back-and-forth", speed_mm_s=40, duration_s=3.0, x0_mm=20,
                               y0_mm=15, length_mm=100), 60.0)
    p, (out,) = run(sc, trace)
    motion = np.sign(np.gradient(out.x_mm[0]))
    # away from the reversals and the touch-down (no velocity yet: a still finger)
    steady = (np.abs(np.gradient(out.x_mm[0]) * RATE) > 30.0) & (out.t_s > 0.1)
    for turn in np.flatnonzero(np.diff(motion)):   # the velocity fit lags a reversal
        steady[max(turn - 200, 0):turn + 200] = False
    f_t, _, drive = ring_forces_from_commands(p, out, 0.5, motion)
    forward, backward = steady & (motion > 0), steady & (motion < 0)
    assert forward.sum() > 4000 and backward.sum() > 4000
    assert_allclose(f_t[forward], 0.03, atol=1e-9)
    assert_allclose(f_t[backward], 0.2, atol=1e-9)
    assert np.all(drive[forward] > 0.1)        # zero-ish net force needs the drive
    assert_allclose(out.forces.achieved_n[0, steady, 0], -motion[steady] * f_t[steady], atol=1e-9)


def test_guidance_pushes_a_still_finger_towards_the_target_with_the_drive_alone():
    sc = scene("ring-seed004", RING_DISPLAY,
               layer(Guidance, x_mm=70.0, y_mm=15.0, gain_n_per_mm=0.002, max_force_n=0.05))
    n = 101
    t = np.linspace(0.0, 1.0, n)
    for x0, fn, sign in ((40.0, 0.5, 1.0), (120.0, 0.8, -1.0), (65.0, 0.5, 1.0)):
        trace = make_trace(t, np.zeros(n), np.full(n, x0), np.full(n, 15.0), np.full(n, fn))
        p, (out,) = run(sc, trace)
        inside = out.contact[0]
        want = min(0.002 * abs(70.0 - x0), 0.05)
        _, d, drive = ring_forces_from_commands(p, out, fn, 1.0)
        assert_allclose(drive[inside], want, rtol=1e-9)          # |P| = k_p F_n (tau W - w_th)
        assert np.all(-d[inside] == sign)                          # wave runs against the push
        assert out.forces.unreachable.sum() == 0
        assert_allclose(out.forces.wanted_n[0, inside, 0], sign * want, rtol=1e-12)


def test_finger_near_a_beam_end_is_not_promised_what_the_wave_cannot_give():
    sc = scene("travelling-beam-seed002", BEAM_DISPLAY,
               layer(Directional, target="mu", forward=0.5, backward=0.5))
    trace = sample(make_motion("swipe", speed_mm_s=75, duration_s=4.0, x0_mm=2.0, y0_mm=3.0), 60.0)
    p, (out,) = run(sc, trace)
    f = out.forces
    x = out.x_mm[0]
    moving = out.contact[0] & (x > 3.0)
    ratio = p.actuation.ratio_at(x)
    end, mid = moving & (x < 40.0), moving & (x > 220.0)
    assert f.unreachable[0, end].all() and not f.unreachable[0, mid].any()
    assert out.clamps.unreachable == f.unreachable.sum() > 0
    assert_allclose(f.achieved_n[0, mid, 0], -0.5 * MU0 * 0.5, atol=1e-9)
    # near the end the wave stands (ratio < 0.3): the amplitude limit gives what it can,
    # and what it gives is reported, not the target
    assert ratio[end].max() < 0.3
    assert np.all(-f.achieved_n[0, end, 0] > 0.125 + 1e-3)
    assert_allclose(out.amplitude_um[0, end], 3.0, rtol=1e-9)


def test_any_split_into_calls_gives_the_same_commands_and_forces():
    sc = scene("ring-seed004", RING_DISPLAY,
               layer(Directional, target="mu", forward=0.4, backward=0.9),
               layer(Guidance, x_mm=70.0, y_mm=15.0, gain_n_per_mm=0.002, max_force_n=0.05))
    trace = sample(make_motion("human", speed_mm_s=60, duration_s=2.0, area_mm=(140.0, 30.0),
                               seed=4), 120.0, noise_mm=0.05)
    _, whole = run(sc, trace)
    _, parts = run(sc, trace, blocks_per_call=7)
    for name in ("commands_um", "phases_rad"):
        assert_array_equal(np.concatenate([getattr(o, name) for o in parts]), getattr(whole[0], name))
    assert_array_equal(np.concatenate([o.forces.achieved_n for o in parts], axis=1),
                       whole[0].forces.achieved_n)


def test_a_push_beyond_what_the_beam_actuators_give_is_counted_unreachable():
    # seed 002's actuator references peak at 1.164 W: at x = 300 mm (g = 1) the channels
    # give at most 3 / 1.164 = 2.58 um of envelope, a push of k_p F_n (2.58 - w_th) =
    # 0.10 N at 0.5 N; 0.12 N was planned at 2.85 um, capped, and not counted
    sc = scene("travelling-beam-seed002", BEAM_DISPLAY,
               layer(Guidance, x_mm=590.0, y_mm=3.0, gain_n_per_mm=1.0, max_force_n=0.12))
    n = 101
    trace = make_trace(np.linspace(0.0, 1.0, n), np.zeros(n), np.full(n, 300.0),
                       np.full(n, 3.0), np.full(n, 0.5))
    p, (out,) = run(sc, trace)
    f, inside = out.forces, out.contact[0]
    assert inside.sum() > 5000
    reachable = KP * 0.5 * (p.actuation.ratio_at(300.0) * 3.0 / 1.16405249 - TH)
    assert_allclose(f.achieved_n[0, inside, 0], reachable, rtol=1e-6)
    assert f.unreachable[0, inside].all() and out.clamps.unreachable == inside.sum()
    assert out.limited == 0
    assert_allclose(out.commands_um[inside].max(), 3.0, rtol=1e-9)


def test_every_force_missed_by_more_than_a_millinewton_is_counted_unreachable():
    # 0.025 N at 0.5 N needs 2.8 um of envelope mid-span: more than the channels give
    sc = scene("travelling-beam-seed002", BEAM_DISPLAY,
               layer(Directional, target="force", forward=0.025, backward=0.3))
    trace = sample(make_motion("back-and-forth", speed_mm_s=60, duration_s=3.0, x0_mm=150,
                               y0_mm=3.0, length_mm=300), 60.0)
    _, (out,) = run(sc, trace)
    f = out.forces
    missed = np.abs(f.achieved_n[..., 0] - f.wanted_n[..., 0]) > 1e-3
    assert missed.sum() > 1000
    assert not (missed & ~f.unreachable).any()


def test_a_press_beyond_the_friction_model_is_counted_as_the_friction_inversion_counts_it():
    # 1.0 N: seed 003's asymptote 1.13 F_n passes 1; grating scenes count such samples as
    # force_beyond_model (not also unreachable), a travelling-wave scene counted none
    sc = scene("travelling-beam-seed002", BEAM_DISPLAY,
               layer(Directional, target="mu", forward=0.5, backward=0.9))
    trace = sample(make_motion("back-and-forth", speed_mm_s=60, duration_s=2.0, x0_mm=220,
                               y0_mm=3.0, length_mm=160), 60.0, force_n=1.0)
    _, (out,) = run(sc, trace)
    given = out.contact[0] & (out.amplitude_um[0] > 0)
    assert given.sum() > 5000
    assert out.clamps.force_beyond_model > 0.9 * given.sum()
    assert out.clamps.unreachable == out.forces.unreachable.sum() == 0
