"""Recorded-texture layers in texture files: the toolkit's XML models in their published
form (units, sample rate, 1-based triangles, the sign of A(z)), line-located errors."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.rendering.layers.ar_texture import ArTextureRenderer
from test_ar_texture import _db_error, _model, _synthesise, _xml
from test_texture_loader import write
from frictex.textures.errors import TextureError
from frictex.textures.hatt import ArTextureLayer, parse_hatt_xml
from frictex.textures.loader import load_scene

BODY = '[[layer]]\ntype = "recorded"\nmodel = "wood.xml"\ngain = 0.03\n'


def test_a_toolkit_model_file_loads(tmp_path):
    (tmp_path / "wood.xml").write_text(_xml(), encoding="utf-8")
    layer = load_scene(write(tmp_path, BODY)).layers[0]
    assert isinstance(layer, ArTextureLayer) and (layer.gain, layer.mu_mean, layer.seed) == (0.03, 0.8, 0)
    assert_allclose(layer.model.at(110.0, 1.1)[0], _model().at(110.0, 1.1)[0], atol=1e-12)


@pytest.mark.parametrize("xml, extra, message", [
    (None, "", r"scene\.toml:9: layer\[1\]\.model: \"wood\.xml\""),
    (_xml(extra="<numMACoeff>2</numMACoeff>"), "", r"scene\.toml:9: layer\[1\]\.model: .*<gain> missing"),
    (_xml(), "mu_mean = 0.5\n", r"scene\.toml:11: layer\[1\]\.mu_mean: mu_min 0\.6 < mu_mean 0\.5"),
    (_xml(), "seed = -1\n", r"scene\.toml:11: layer\[1\]\.seed"),
])
def test_problems_are_reported_at_their_line(tmp_path, xml, extra, message):
    if xml is not None:
        (tmp_path / "wood.xml").write_text(xml, encoding="utf-8")
    with pytest.raises(TextureError, match=message):
        load_scene(write(tmp_path, BODY + extra))


# -- the published file form ---------------------------------------------------------------
#
# A model written as the toolkit writes its files (units, SampleRate, 1-based <tri>, per
# model ARcoeff = [1, a_1 .. a_p] and its ARlsf), from LSFs chosen here; its A(z) and its
# spectrum are computed here from the LSFs, independently of textures.hatt.

PEAKS = [((80, 0.95), (400, 0.93)), ((150, 0.96), (600, 0.94)),  # (Hz, pole radius)
         ((60, 0.9), (250, 0.95)), ((300, 0.95), (700, 0.92))]     # two resonances per vertex
SPEEDS, FORCES = [20.0, 250.0, 20.0, 250.0], [0.2, 0.2, 3.0, 3.0]
VARS = [1e-6, 2e-6, 0.5e-6, 1.5e-6]


def _lsf(peaks, rate):
    """The LSFs of the vertex model with pole pairs at ``peaks``, rounded as the toolkit
    writes them (6 decimals): the angles in (0, pi) of the roots of A(z) +- z^-5 A(1/z)."""
    a = np.ones(1)
    for f, r in peaks:
        a = np.convolve(a, [1.0, -2 * r * np.cos(2 * np.pi * f / rate), r * r])
    ext = np.append(a, 0.0)
    w = np.angle(np.concatenate([np.roots(ext + ext[::-1]), np.roots(ext - ext[::-1])]))
    return np.round(np.sort(w[(w > 1e-9) & (w < np.pi - 1e-9)]), 6)


def _poly(lsf):
    """A(z) = [1, a_1 .. a_4] of even-order LSFs, written out: P(z) = (1 + z^-1) times the
    sections 1 - 2 cos(w) z^-1 + z^-2 of the 1st and 3rd LSFs, Q(z) = (1 - z^-1) times
    those of the 2nd and 4th, A = (P + Q) / 2 (its z^-5 term cancels)."""
    p, q = np.array([1.0, 1.0]), np.array([1.0, -1.0])
    for w in lsf[0::2]:
        p = np.convolve(p, [1.0, -2 * np.cos(w), 1.0])
    for w in lsf[1::2]:
        q = np.convolve(q, [1.0, -2 * np.cos(w), 1.0])
    a = (p + q) / 2
    assert abs(a[-1]) < 1e-12
    return a[:-1]


def _spectrum(lsf, variance, f, rate):
    """One-sided PSD (units^2/Hz) of y[n] + sum_k a_k y[n-k] = e[n], var(e) = variance."""
    a = _poly(lsf)
    response = np.exp(-2j * np.pi * np.outer(f, np.arange(a.size)) / rate) @ a
    return 2 * variance / (rate * np.abs(response) ** 2)


def published_xml(rate=10_000.0, rate_tag=True, speed_unit="mm/s", sign=1.0, extra="", ma=None):
    """The test's model as the toolkit writes a file; ``ma``: (Hz, radius) of a zero pair
    of every vertex's B(z) and ``gain`` (an ARMA model, as the toolkit's 1 kHz files)."""
    speed_scale = 1e-3 if speed_unit == "m/s" else 1.0
    values = lambda xs, fmt="{:.6f}": "".join(f"<value>{fmt.format(x)}</value>" for x in xs)  # noqa: E731
    models = ""
    for k, (peaks, var, s, f) in enumerate(zip(PEAKS, VARS, SPEEDS, FORCES), start=1):
        lsf = _lsf(peaks, rate)
        coeff = _poly(lsf) * np.r_[1.0, np.full(4, sign)]
        moving = ""
        if ma is not None:
            gain, mlsf = ma[1], _lsf([ma[0]], rate)
            moving = (f"<MAcoeff>{values(_poly(mlsf), '{:.20f}')}</MAcoeff><MAlsf>{values(mlsf)}"
                      f"</MAlsf><gain>{gain:.6f}</gain>")
        models += (f"<model><modNum>{k}</modNum><ARcoeff>{values(coeff, '{:.20f}')}</ARcoeff>"
                   f"<ARlsf>{values(lsf)}</ARlsf>{moving}<var>{var:.10f}</var>"
                   f"<speedMod>{s * speed_scale:.6f}</speedMod><forceMod>{f:.6f}</forceMod></model>")
    tris = "".join(f'<tri type="array">{values(t, "{}")}</tri>' for t in ((1, 2, 3), (2, 4, 3)))
    return (f'<?xml version="1.0" encoding="utf-8"?>\n<modelSet texture="1"><material>test</material>'
            f"<AccelUnits>m/s^2</AccelUnits><SpeedUnits>{speed_unit}</SpeedUnits><ForceUnits>N</ForceUnits>"
            + (f"<SampleRate>{rate:g}</SampleRate>" if rate_tag else "")
            + f"<mu>0.3</mu><numMod>4</numMod><numTri>2</numTri><maxSpeed>{250 * speed_scale:.6f}</maxSpeed>"
            f"<maxForce>3</maxForce><speedList type=\"array\">{values(np.array(SPEEDS) * speed_scale)}"
            f"</speedList><forceList type=\"array\">{values(FORCES)}</forceList>{tris}"
            f"<numARCoeff>4</numARCoeff><numMACoeff>{0 if ma is None else 2}</numMACoeff>{extra}"
            f"{models}</modelSet>")


@pytest.mark.parametrize("vertex", [0, 1, 3])
def test_a_published_form_model_renders_each_vertex_spectrum_within_1_db(tmp_path, vertex):
    """Through the texture file: at each vertex's speed and force the synthesised mu'
    has gain^2 times that vertex's spectrum (20-800 Hz), which fixes the sign convention
    (the other sign mirrors the peaks about fs/4) and the vertex numbering (read from 0,
    the numbers would pick another vertex's peaks)."""
    (tmp_path / "wood.xml").write_text(published_xml(), encoding="utf-8")
    layer = load_scene(write(tmp_path, BODY)).layers[0]
    mu, state = _synthesise(ArTextureRenderer(layer, 10_000.0), SPEEDS[vertex], FORCES[vertex], 60.0)
    assert state.clipped == 0 and np.isfinite(mu).all()
    err = _db_error(mu, lambda f: 0.03 ** 2 * _spectrum(_lsf(PEAKS[vertex], 1e4), VARS[vertex], f, 1e4))
    assert err.max() < 1.0, f"worst {err.max():.2f} dB"


def test_the_sample_rate_and_speed_unit_a_file_states_are_used(tmp_path):
    """A model made at 5 kHz with speeds in m/s: read at 5 kHz (rendered at 10 kHz its
    peaks stay at the same Hz) and at the speeds in mm/s; without SampleRate, 10 kHz."""
    model = parse_hatt_xml(published_xml(rate=5_000.0, speed_unit="m/s"))
    assert model.rate_hz == 5_000.0
    assert_allclose(model.speeds_mm_s, SPEEDS, atol=1e-9)
    assert parse_hatt_xml(published_xml(rate_tag=False)).rate_hz == 10_000.0
    (tmp_path / "wood.xml").write_text(published_xml(rate=5_000.0), encoding="utf-8")
    layer = load_scene(write(tmp_path, BODY)).layers[0]
    mu, _ = _synthesise(ArTextureRenderer(layer, 10_000.0), SPEEDS[1], FORCES[1], 60.0)
    err = _db_error(mu, lambda f: 0.03 ** 2 * _spectrum(_lsf(PEAKS[1], 5e3), VARS[1], f, 5e3))
    assert err.max() < 1.0, f"worst {err.max():.2f} dB"


@pytest.mark.parametrize("text, message", [
    (published_xml(sign=-1.0), r"model 1: ARcoeff is not the A\(z\) = 1 \+ sum a_k z\^-k of its ARlsf "
     r"\(its a_1 \.\. a_4 have the other sign: .*; negate them\)$"),
    (published_xml(sign=0.5),  # neither sign: no advice about one
     r"model 1: ARcoeff is not the A\(z\) = 1 \+ sum a_k z\^-k of its ARlsf \(largest "
     r"difference [0-9.]+ of the largest coefficient\)$"),
    (published_xml().replace("<ARcoeff><value>1.00000000000000000000</value>", "<ARcoeff>", 1),
     r"model 1: ARcoeff has 4 values; expected 5: \[1, a_1 \.\. a_4\]$"),
    (published_xml().replace("<SpeedUnits>mm/s", "<SpeedUnits>in/s"), r'<SpeedUnits> is "in/s", expected one of mm/s, m/s'),
    (published_xml().replace("<ForceUnits>N", "<ForceUnits>lbf"), r'<ForceUnits> is "lbf"'),
    (published_xml(rate=10.0), r"<SampleRate> is 10 Hz, expected 100 to 1e\+06"),
    (published_xml(ma=((300, 0.8), 1.5)).replace("gain>", "gaim>"), r"model 1: <gain> missing"),
    (published_xml(ma=((300, 0.8), 1.5)).replace("<numMACoeff>2", "<numMACoeff>3"),
     r"model 1: MAlsf must be 3 increasing values"),
    (published_xml().replace("<var>", "<var>0_0", 1), r"model 1: <var> missing or not a finite number \(ASCII"),
    (published_xml().replace("<forceMod>", "<forceMod>\u0660", 1), r"model 1: <forceMod> missing or not"),
    (published_xml().replace("<speedMod>", "<speedMod>\u2003", 1), r"model 1: <speedMod> missing or not"),
    (published_xml().replace("</speedList>", "<value>1_0</value></speedList>", 1), r"<speedList> value \"1_0\" is not a number"),
    (published_xml().replace("<numARCoeff>", "<numARCoeff>99</numARCoeff><numARCoeff>", 1),
     r"<numARCoeff> appears 2 times; expected one"),
    (published_xml().replace("<forceList", "<speedList><value>1</value></speedList><forceList", 1),
     r"<speedList> appears 2 times"),
])
def test_a_file_against_the_published_form_is_one_line_error(text, message):
    with pytest.raises(TextureError, match=message) as info:
        parse_hatt_xml(text, "wood.xml")
    assert "\n" not in str(info.value) and str(info.value).startswith("wood.xml: ")


def test_an_arma_model_renders_its_spectrum_within_1_db(tmp_path):
    """ARMA, as the toolkit's resampled files are: y = gain B(z) / A(z) e (its renderer
    adds gain * (e[n] + sum b_i e[n-i])). The spectrum var gain^2 |B|^2 / (fs |A|^2),
    computed here, has a notch at the zero (300 Hz) that an AR model of the same order
    could not make; frictex's AR(100) fit renders it within 1 dB over 20-800 Hz."""
    zero, gain = (300.0, 0.8), 1.5
    (tmp_path / "wood.xml").write_text(published_xml(ma=(zero, gain)), encoding="utf-8")
    layer = load_scene(write(tmp_path, BODY)).layers[0]
    mu, state = _synthesise(ArTextureRenderer(layer, 10_000.0), SPEEDS[1], FORCES[1], 60.0)
    assert state.clipped == 0

    def expected(f):
        b = _poly(_lsf([zero], 1e4))
        response = np.exp(-2j * np.pi * np.outer(f, np.arange(3)) / 1e4) @ b
        return 0.03 ** 2 * gain ** 2 * np.abs(response) ** 2 * _spectrum(_lsf(PEAKS[1], 1e4), VARS[1], f, 1e4)

    err = _db_error(mu, expected)
    assert err.max() < 1.0, f"worst {err.max():.2f} dB"
    without_b = _db_error(mu, lambda f: 0.03 ** 2 * gain ** 2 * _spectrum(_lsf(PEAKS[1], 1e4), VARS[1], f, 1e4))
    assert without_b.max() > 3.0  # the zeros shaped it


def _no_lsf(a):
    raise ValueError("found 3 line spectral frequencies of an order-4 A(z), expected 4: ...")


def test_a_failed_ar_fit_names_the_file_in_validate(tmp_path, monkeypatch, capsys):
    """poly_to_lsf's ValueError from the AR fit of an ARMA model (parse) is a TextureError
    naming the model file and the model: one line from ``frictex validate``, exit 2."""
    from frictex.app.commands.cli import main
    (tmp_path / "wood.xml").write_text(published_xml(ma=((300, 0.8), 1.5)), encoding="utf-8")
    scene = write(tmp_path, BODY)
    monkeypatch.setattr("frictex.textures.hatt.poly_to_lsf", _no_lsf)
    with pytest.raises(TextureError, match=r"scene\.toml:9: layer\[1\]\.model: .*wood\.xml: model 1: "
                                           r"its ARMA model has no AR\(100\) fit: found 3"):
        load_scene(scene)
    capsys.readouterr()
    assert main(["validate", str(scene)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("frictex: error: ") and "wood.xml: model 1" in err[0], err


def test_a_failed_resampling_names_the_file_in_replay(tmp_path, monkeypatch, capsys):
    """The same from the fit that resamples a 5 kHz model to the 10 kHz output, when the
    renderer is built: ``frictex replay`` prints one line naming the file, exit 2."""
    from frictex.app.commands.cli import main
    (tmp_path / "wood.xml").write_text(published_xml(rate=5_000.0), encoding="utf-8")
    scene = write(tmp_path, BODY)
    model = load_scene(scene).layers[0].model
    monkeypatch.setattr("frictex.textures.hatt.poly_to_lsf", _no_lsf)
    with pytest.raises(TextureError, match=r"wood\.xml: model 1: its AR\(32\) fit at 10000 Hz failed"):
        model.resampled(10_000.0)
    capsys.readouterr()
    assert main(["replay", str(scene), "swipe-40mms-50hz", "--out", str(tmp_path / "r"), "--quiet"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("frictex: error: ") and "wood.xml: model 1" in err[0], err


def _grid_xml(side: int, ma: bool) -> str:
    """A model of side x side vertices on a speed-force grid, each the same AR(4) (with an
    MA(2) part and a gain if ``ma``), triangulated cell by cell."""
    values = lambda xs, fmt="{:.6f}": "".join(f"<value>{fmt.format(x)}</value>" for x in xs)  # noqa: E731
    speeds = [10.0 + 10 * (k // side) for k in range(side * side)]
    forces = [0.1 + 0.1 * (k % side) for k in range(side * side)]
    lsf = _lsf(PEAKS[0], 1e4)
    mlsf = _lsf([(1500.0, 0.5)], 1e4)
    moving = f"<MAlsf>{values(mlsf)}</MAlsf><MAcoeff>{values(_poly(mlsf), '{:.20f}')}</MAcoeff><gain>0.5</gain>"
    models = "".join(f"<model><ARcoeff>{values(_poly(lsf), '{:.20f}')}</ARcoeff><ARlsf>{values(lsf)}</ARlsf>"
                     f"{moving if ma else ''}<var>0.01</var><speedMod>{s:.6f}</speedMod>"
                     f"<forceMod>{f:.6f}</forceMod></model>" for s, f in zip(speeds, forces))
    tris = "".join(f"<tri>{values(t, '{}')}</tri>" for i in range(side - 1) for j in range(side - 1)
                   for a in [i * side + j + 1] for t in ((a, a + 1, a + side), (a + 1, a + side + 1, a + side)))
    return (f"<modelSet><SpeedUnits>mm/s</SpeedUnits><speedList>{values(speeds)}</speedList>"
            f"<forceList>{values(forces)}</forceList>{tris}<numARCoeff>4</numARCoeff>"
            f"<numMACoeff>{2 if ma else 0}</numMACoeff>{models}</modelSet>")


def test_model_cost_is_bounded_before_any_fit(monkeypatch):
    """An ARMA file refits every vertex when read, and any file refits every vertex when
    played at another rate: more than MAX_FIT_VERTICES of them is a one-line error raised
    before the first fit (fit_ar is never called), whatever the file's size in bytes."""
    from frictex.textures import hatt
    side = math.isqrt(hatt.MAX_FIT_VERTICES) + 1
    fits = []
    monkeypatch.setattr(hatt, "fit_ar", lambda *a, **k: fits.append(a))
    with pytest.raises(TextureError, match=rf"{side * side} vertices hold ARMA models, each refitted .* "
                                           rf"at most {hatt.MAX_FIT_VERTICES} are refitted"):
        hatt.parse_hatt_xml(_grid_xml(side, ma=True), "big.xml")
    model = hatt.parse_hatt_xml(_grid_xml(side, ma=False), "big.xml")  # AR: nothing to refit
    assert model.rate_hz == 1e4 and model.resampled(1e4) is model
    with pytest.raises(TextureError, match=rf"big.xml: {side * side} vertices made at 10000 Hz to play "
                                           rf"at 48000 Hz"):
        model.resampled(48_000.0)
    assert fits == []


def test_the_model_file_of_authoring_md_reads_as_it_says(tmp_path):
    """AUTHORING.md's element table and example: four AR(2) vertices, 1-based <tri>, and
    its poly_to_lsf recipe gives the first model's LSFs."""
    import re
    from pathlib import Path

    from frictex.textures.hatt import poly_to_lsf
    page = (Path(__file__).resolve().parents[1] / "textures" / "AUTHORING.md").read_text("utf-8")
    xml = re.search(r"<!-- example: hatt-model -->\n```xml\n(.*?)```", page, re.S).group(1)
    model = parse_hatt_xml(xml)
    poly, var = model.at(0.0, 0.0)
    assert_allclose(poly, [1.0, -1.6, 0.8], atol=1e-5) and var == pytest.approx(0.5)
    poly, var = model.at(300.0, 4.0)
    assert_allclose(poly, [1.0, -1.0, 0.6], atol=1e-5) and var == pytest.approx(1.5)
    assert_allclose(poly_to_lsf(np.array([1.0, -1.6, 0.8])), [0.451027, 0.795399], atol=5e-7)
    (tmp_path / "wood.xml").write_text(xml, encoding="utf-8")
    assert isinstance(load_scene(write(tmp_path, BODY)).layers[0], ArTextureLayer)


def test_pipeline_process_plays_a_recorded_texture_as_replay_does(tmp_path):
    """A recorded texture's noise is keyed by the pipeline row its finger takes. replay
    maps a recording's fingers onto rows (slots) and Pipeline.process took the ids as
    rows, so a stroke by finger 5 sounded different (mu' off by up to 0.067); process
    maps them as replay does, and labels its rows with the recording's ids."""
    import frictex
    (tmp_path / "wood.xml").write_text(_xml(), encoding="utf-8")
    scene = write(tmp_path, BODY)
    swipe = frictex.synth_trace("swipe", rate_hz=50, duration_s=1.5, speed_mm_s=40)
    by_five = frictex.make_trace(swipe.t_s, np.full(swipe.t_s.size, 5), swipe.x_mm,
                                 swipe.y_mm, swipe.force_n, swipe.event)
    processed = frictex.build_pipeline(scene).process(by_five)
    replayed = frictex.replay(scene, by_five).friction
    assert processed.finger_ids == (5,)
    assert set(replayed.column("finger").to_pylist()) == {5}
    touching = processed.mu_target[processed.contact]
    assert_allclose(touching, replayed.column("mu_target").to_numpy(), atol=1e-12)
