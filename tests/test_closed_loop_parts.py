"""Parts of the friction loop: RLS adaptation, the sensor chain, the report section's tables."""

import json
import math

import numpy as np
import pytest

from app.measure.report_closed_loop import markdown, summarise, write
from device.profile import DeviceProfile, FrictionParams
from rendering.control.adapt import Rls
from rendering.control.chain import Chain
from device.finger import SensorParams
from rendering.control.loop import ClosedLoop


def test_rls_converges_to_the_constants_of_exact_points():
    rls = Rls(memory_s=5.0, block_s=0.005)
    state = rls.initial_state(FrictionParams())
    rng = np.random.default_rng(0)
    b, k = 1.25, 0.95
    for _ in range(400):
        w = rng.uniform(0.1, 2.5, 5)
        f = rng.uniform(0.4, 0.6, 5)
        mu = (1 - k * f) * np.exp(-b * w) + k * f
        bh, kh = state.theta
        e = np.exp(-bh * w)
        model = (1 - kh * f) * e + kh * f
        jac = np.stack([-(1 - kh * f) * w * e, f * (1 - e)], axis=1)  # d mu' / d(b, k)
        state = rls.update(state, jac, mu - model)
    assert math.isclose(state.theta[0], b, rel_tol=1e-3)
    assert math.isclose(state.theta[1], k, rel_tol=1e-3)


def test_rls_without_points_keeps_its_estimate():
    rls = Rls()
    state = rls.initial_state(FrictionParams(b_per_um=1.4, asymptote_per_n=0.9))
    after = rls.update(state, np.zeros((0, 2)), np.zeros(0))
    assert after.theta == (1.4, 0.9)


def test_chain_is_three_poles_and_a_delay_and_splits_exactly():
    rate = 10_000.0
    chain = Chain(SensorParams(), rate)
    x = np.zeros((2, 200))
    x[0, 0] = 1.0
    x[1] = 2.0  # a row at rest at its level stays there
    start = chain.initial_state([0.0, 2.0])
    rows, _ = chain.run(x, start)
    np.testing.assert_allclose(rows[1], 2.0, rtol=1e-12)
    a, s = chain.run(x[:, :77], start)
    b, _ = chain.run(x[:, 77:], s)
    np.testing.assert_allclose(np.concatenate([a, b], axis=1), rows, rtol=1e-12, atol=1e-18)
    whole = rows[0]
    # independent: convolve the three one-pole impulse responses, then delay
    n = np.arange(200)
    h = np.array([1.0])
    for bw in (400.0, 90.0, 1000.0):
        p = math.exp(-2 * math.pi * bw / rate)
        h = np.convolve(h, (1 - p) * p ** n)[:200]
    d = int(round(0.0005 * rate))
    np.testing.assert_allclose(whole, np.concatenate([np.zeros(d), h[:200 - d]]), atol=1e-15)
    assert 0 < whole.sum() <= 1.0


def test_the_loop_needs_seed_003s_plate():
    with pytest.raises(ValueError, match="plate-seed003"):
        ClosedLoop(DeviceProfile(profile="beam-seed000"), 10_000.0, 50)
    with pytest.raises(ValueError, match="control mode .open.: expected one of open, closed"):
        ClosedLoop(DeviceProfile(), 10_000.0, 50, mode="open")


def _fake(rms):
    return {"rms": rms * 1.5, "rms_reachable": rms, "rms_settled": rms / 2, "fallbacks": 0,
            "noise_fraction": 0.01,
            "adapted_gap": 0.03, "max_command_um": 2.0, "growth": 0.5}


def test_section_tables_and_gains(tmp_path):
    values = {"grating-15mm": {"open": [_fake(0.04), _fake(0.03)],
                               "closed": [_fake(0.01), _fake(0.002)],
                               "adaptive": [_fake(0.004), _fake(0.004)]}}
    section = summarise(values, fingers=2, duration_s=1.0)
    row = section["scenes"]["grating-15mm"]
    open_pop = math.sqrt((0.04 ** 2 + 0.03 ** 2) / 2)
    closed_pop = math.sqrt((0.01 ** 2 + 0.002 ** 2) / 2)
    assert math.isclose(row["closed"]["gain_vs_open"], open_pop / closed_pop, rel_tol=1e-12)
    assert math.isclose(row["adaptive"]["gain_vs_open"], open_pop / 0.004, rel_tol=1e-12)
    assert row["closed"]["worst"] == 0.01 and row["closed"]["worst_improves"]
    text = markdown(section)
    assert "| grating-15mm | closed |" in text and "gain margin" in text
    write(section, tmp_path)
    assert json.loads((tmp_path / "closed_loop.json").read_text())["fingers"] == 2


def test_oscillation_growth_sees_a_growing_alternation():
    from app.measure.report_closed_loop import oscillation_growth
    k = np.arange(200)
    growing = 0.01 * (-1.0) ** k * 1.02 ** k
    settling = 0.01 * (-1.0) ** k * 0.98 ** k
    assert oscillation_growth(growing) > 1.0 > oscillation_growth(settling)
    assert oscillation_growth(np.zeros(10)) == 0.0
