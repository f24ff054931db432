"""Modal actuation (seed 000 eq 10, seed 001 eqs 4-5) on its own and through the whole pipeline."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
from numpy.testing import assert_allclose


from frictex.device.actuation.base import SingleModeActuation
from frictex.device.structures.beam import FreeFreeBeam
from frictex.device.actuation.modal_actuation import ModalActuation, make_modal_actuation
from frictex.device.structures.plate2d import ACTUATORS, Plate2D
from frictex.rendering.tracking.finger_select import HYSTERESIS_MM
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.input.trace_file import make_trace
from frictex.rendering.tracking.tracks import apply_index
from scenes import grating_box_mean, grating_scene
from frictex.device.profile import BeamStructure, DeviceProfile, PlateStructure
from frictex.textures.model import Display, RectRegion, Scene, Shape, VisualHints

BEAM = FreeFreeBeam(350, 6, 6, 57, 2561)          # seed 000, Table I
ORDERS = (16, 17)
ACT_BEAM = BEAM.phi(ORDERS, np.array([60.0, 290.0]))  # seed 000 eq 9, transducers 60 mm from each end
PLATE = Plate2D(140, 140, 4, 57, 2561, order=8)


def wanted_for(mu, force_n=0.5):
    """Seed 003 eq 3 with its constants (b = 1.67 /um, A = 1.13 F_n)."""
    a = 1.13 * force_n
    return -math.log((mu - a) / (1 - a)) / 1.67


def uniform_layers(width, height, mus):
    """One uniform rectangle per finger number: finger k feels mus[k - 1]."""
    return tuple(Shape(name=f"finger-{k}", render="sho", region=None, blend="multiply",
                       visual=VisualHints(), fingers=str(k), geometry=RectRegion(0, 0, width, height),
                       mu=mu) for k, mu in enumerate(mus, start=1))


def beam_scene(mus=(0.8, 0.9), **structure):
    device = DeviceProfile(profile="beam-seed000", amplitude_limit_um=0.7,
                           structure=BeamStructure(**structure))
    return Scene(1, "beam", "", Display(350, 6, 1400, 24), device, uniform_layers(350, 6, mus))


def plate_scene(mus=(0.8, 0.9)):
    device = DeviceProfile(profile="plate-seed001", amplitude_limit_um=1.0, structure=PlateStructure())
    return Scene(1, "plate", "", Display(140, 140, 560, 560), device, uniform_layers(140, 140, mus))


def trace_of(paths, rate=50.0, duration=0.4, stagger=0.01):
    """Fingers touching one after another (``stagger`` s apart), each on x(t), y(t)."""
    t = np.arange(0, duration + 1e-9, 1 / rate)
    cols = []
    for k, (fx, fy) in enumerate(paths):
        cols.append((t + k * stagger, np.full(t.size, k), fx(t), fy(t)))
    tt, ff, xx, yy = (np.concatenate(c) for c in zip(*cols))
    order = np.argsort(tt, kind="stable")
    return make_trace(tt[order], ff[order], xx[order], yy[order])


def still(x, y):
    return (lambda t: np.full(t.size, float(x))), (lambda t: np.full(t.size, float(y)))


def run(scene, trace, render_override=None):
    p = build_pipeline(scene, t0_s=float(trace.t_s[0]), render_override=render_override)
    blocks = int(apply_index(trace.t_s, p.tracker_config)[-1] // p.block_size) + 1
    out, _ = p.process(0, trace, p.initial_state(), n_blocks=blocks)
    return p, out


def complex_commands(out):
    return out.commands_um * np.exp(1j * out.phases_rad)


def test_seed000_worked_example_eqs_12_to_14():
    """Measured shapes at the transducers (eq 12) and at x_a = 120, x_b = 250 mm (eq 13);
    0.8 um peak-to-peak (0.4 um zero-to-peak) under finger a, 0 under b -> eq 14."""
    rows = {120.0: [0.9436, 0.6809], 250.0: [0.9715, -0.7388]}

    def shapes(x, y):
        return np.array([rows[float(v)] for v in np.ravel(x)]).reshape(np.shape(x) + (2,))

    act = ModalActuation(shapes, ((0, 350), (-np.inf, np.inf)), (0, 0), [[-0.9680, -0.6949], [1, -0.7447]],
                         ("xA", "xB"), 0.75, "regularised", 0.1)
    fingers = SimpleNamespace(contact=np.ones((2, 1), bool), touch_start=np.array([[0.0], [1.0]]),
                              x_pred=np.array([[120.0], [250.0]]), y_pred=np.zeros((2, 1)))
    result = act.command(np.array([[0.4], [0.0]]), fingers)
    assert_allclose(result.commands_um[0], [0.4093, 0.0045], atol=6e-5)  # the paper's 4 decimals
    assert_allclose(result.phases_rad[0], [math.pi, 0.0], atol=1e-12)     # -0.4093 and +0.0045
    assert_allclose(result.achieved_um[:, 0], [0.4, 0.0], atol=1e-12)
    assert result.limited == 0


def test_beam_pipeline_gives_each_finger_its_amplitude_exactly():
    """Through tracking, layers, composition and inversion: at seed 000's well-conditioned
    pair (120, 250 mm) each finger gets its own texture's amplitude to 1e-9 um, and the
    channel commands are eq 10 computed independently."""
    pipeline, out = run(beam_scene(), trace_of([still(120, 3), still(250, 3)]))
    both = out.contact.all(axis=0)
    assert both.sum() > 3000
    w = np.array([wanted_for(0.8), wanted_for(0.9)])
    assert_allclose(out.wanted_um[:, both], np.broadcast_to(w[:, None], (2, both.sum())), rtol=1e-12)
    assert_allclose(out.amplitude_um[:, both], out.wanted_um[:, both], atol=1e-9)
    phi_f = BEAM.phi(ORDERS, np.array([120.0, 250.0]))
    expected = ACT_BEAM @ np.linalg.solve(phi_f, w)  # seed 000, eq 10
    assert_allclose(complex_commands(out)[both], np.broadcast_to(expected, (both.sum(), 2)), atol=1e-12)
    assert pipeline.channels == ("xA", "xB") and out.limited == 0


def test_plate_pipeline_gives_each_finger_its_amplitude_exactly():
    x1, y1, x2, y2 = 30.0, 75.0, 100.0, 45.0
    phi_f = PLATE.phi(np.array([x1, x2]), np.array([y1, y2]))
    s = np.linalg.svd(phi_f, compute_uv=False)
    assert s[1] / s[0] > 0.2  # a well-conditioned pair, away from seed 001's eq 8 loci
    pipeline, out = run(plate_scene(), trace_of([still(x1, y1), still(x2, y2)]))
    both = out.contact.all(axis=0)
    assert_allclose(out.amplitude_um[:, both], out.wanted_um[:, both], atol=1e-9)
    w = np.array([wanted_for(0.8), wanted_for(0.9)])
    expected = ACTUATORS @ np.linalg.solve(phi_f, w)  # (V_AC, V_BD) = ((W_X + W_Y)/2, (W_X - W_Y)/2)
    assert_allclose(complex_commands(out)[both][0], expected, atol=1e-12)
    assert pipeline.channels == ("V_AC", "V_BD")


def test_one_finger_gets_the_minimum_norm_solution():
    _, out = run(beam_scene(), trace_of([still(120, 3)]))
    on = out.contact[0]
    assert_allclose(out.amplitude_um[0, on], wanted_for(0.8), atol=1e-9)
    phi = BEAM.phi(ORDERS, 120.0)
    modal = phi * wanted_for(0.8) / (phi @ phi)
    assert_allclose(complex_commands(out)[on][0], ACT_BEAM @ modal, atol=1e-12)


def test_more_fingers_than_modes_serves_the_longest_touching():
    """Three fingers, two modes: fingers 1 and 2 get their amplitudes, the third gets
    what the forward model gives it there (seed 001 eq 5)."""
    _, out = run(beam_scene(mus=(0.8, 0.9, 0.7)),
                 trace_of([still(120, 3), still(250, 3), still(300, 3)]))
    all3 = out.contact.all(axis=0)
    assert_allclose(out.amplitude_um[:2, all3], out.wanted_um[:2, all3], atol=1e-9)
    modal = np.linalg.solve(BEAM.phi(ORDERS, np.array([120.0, 250.0])),
                            [wanted_for(0.8), wanted_for(0.9)])
    third = abs(BEAM.phi(ORDERS, 300.0) @ modal)
    assert_allclose(out.amplitude_um[2, all3], third, atol=1e-12)
    assert abs(third - out.wanted_um[2, all3][0]) > 0.05  # it does not get what it asks


def crossing_trace():
    """Finger 1 still at 120 mm; finger 2 slides from 140 to 100 mm through it."""
    return trace_of([still(120, 3), (lambda t: 140 - 40 * t, lambda t: np.full(t.size, 3.0))],
                    duration=1.0)


def largest_step(out):
    """Largest change of a complex command between consecutive samples with both fingers
    down, where neither finger moved more than 0.01 mm (the tracker's own position steps,
    e.g. when prediction starts, are not the actuation's doing)."""
    c = complex_commands(out)
    both = out.contact.all(axis=0)
    smooth = (np.abs(np.diff(out.x_mm, axis=1)).max(axis=0) < 0.01) & both[1:] & both[:-1]
    return np.abs(np.diff(c, axis=0)).max(axis=1)[smooth].max()


def test_crossing_a_singular_locus_stays_finite_within_limits_and_continuous():
    _, out = run(beam_scene(), crossing_trace())
    both = out.contact.all(axis=0)
    gap = np.abs(out.x_mm[0] - out.x_mm[1])
    assert gap[both].min() < 0.01  # the fingers do coincide (det Phi = 0)
    for name in ("commands_um", "phases_rad", "amplitude_um"):
        assert np.isfinite(getattr(out, name)).all()
    assert out.commands_um.max() <= 0.75 + 1e-12 and out.limited > 0
    assert largest_step(out) < 0.01
    # what is reported near the locus is the forward model: |Phi_f W_M| with W_M from the commands
    k = np.flatnonzero(both)[np.argmin(gap[both])]
    modal = np.linalg.solve(ACT_BEAM, complex_commands(out)[k])
    phi = BEAM.phi(ORDERS, out.x_mm[:, k])
    assert_allclose(out.amplitude_um[:, k], np.abs(phi @ modal), atol=1e-12)


def test_the_exact_inverse_jumps_at_the_same_crossing():
    """The continuity check above can fail: seed 000's plain inverse flips sign there."""
    _, out = run(beam_scene(method="exact"), crossing_trace())
    assert largest_step(out) > 0.5


def test_positions_off_the_beam_are_held_at_its_end_and_counted():
    act = make_modal_actuation(beam_scene().device)
    fingers = SimpleNamespace(contact=np.array([[True, True, False]]), touch_start=np.zeros((1, 3)),
                              x_pred=np.array([[352.0, 350.0, 400.0]]), y_pred=np.zeros((1, 3)))
    result = act.command(np.full((1, 3), 0.3), fingers)
    assert result.off_structure == 1  # the finger not touching is not counted
    assert_allclose(result.commands_um[0], result.commands_um[1], atol=0)
    assert_allclose(result.achieved_um[0], [0.3, 0.3, 0.0], atol=1e-9)


def test_channel_limits_scale_commands_and_are_counted():
    _, out = run(beam_scene(channel_limit_um=0.2), trace_of([still(120, 3), still(250, 3)]))
    assert out.commands_um.max() == pytest.approx(0.2, abs=1e-12)
    assert out.limited == out.contact.any(axis=0).sum()  # every sample with a finger down
    on = out.contact
    assert (out.amplitude_um[on] < out.wanted_um[on]).all()


def test_a_single_mode_scene_builds_no_modal_stage():
    pipeline = build_pipeline(grating_scene(5.0))
    assert type(pipeline.actuation) is SingleModeActuation
    assert not pipeline.actuation.has_phases and not isinstance(pipeline.actuation, ModalActuation)


def test_bundled_plate_scene_gives_the_left_finger_the_grating_as_fingers_cross():
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene

    scene = load_scene(resolve_scene("two-finger-plate-seed001"))
    grating, slippery = scene.layers
    trace = trace_of([(lambda t: 30 + 80 * t, lambda t: np.full(t.size, 75.0)),
                      (lambda t: 110 - 80 * t, lambda t: np.full(t.size, 45.0))], duration=1.0)
    # the position map (SHO) makes mu' a function of where each finger is: which finger
    # gets which layer is then checkable sample by sample (auto would pick the hybrid)
    _, out = run(scene, trace, render_override="sho-predicted")
    both = out.contact.all(axis=0)
    left = np.argmin(out.x_mm, axis=0)
    assert set(left[both]) == {0, 1}  # each finger is the left one for a while
    # the left-most role changes hands once the other finger is HYSTERESIS_MM beyond
    cols = np.flatnonzero(both & (np.abs(out.x_mm[0] - out.x_mm[1]) > HYSTERESIS_MM))
    # each sample plays the grating's mean from the finger's position at the sample before
    # (rendering.layers.band_limit): the level, but for the samples straddling a line
    phase = grating.phase_at(out.x_mm, out.y_mm)
    rows = left[cols]
    expected = grating_box_mean(grating, phase[rows, cols - 1], phase[rows, cols])
    assert_allclose(out.mu_target[rows, cols], expected, rtol=1e-12)
    assert_allclose(out.mu_target[1 - left[cols], cols], slippery.mu, rtol=1e-12)
