"""``frictex report``'s closed-loop section: open loop, closed loop and closed loop with
adaptation over a simulated population of fingers.

Each finger (``device.finger.draw_finger``, seeds 1..N; its moisture drifts during the
run) slides with a human-like motion (``rendering.input.trace_synth``, kind ``human``,
60 mm/s, touch trace at 50 Hz with 0.05 mm noise) over the seed 003 gratings and the
object scene, rendered at 5 kHz in 5 ms blocks by the hybrid renderer; its normal force
is ``force_n`` (0.35-0.65 N, drawn per finger) with a 0.5 Hz, 15 % swell. All three
modes read the normal force from the device; the loop modes also read the lateral force.

Measured, over the samples where the finger touches and slides (>= 5 mm/s):

- ``rms``: RMS of delivered mu' (what the simulated finger gets) minus the target mu'
  (the pipeline's composed target at that sample);
- ``rms_reachable``: the same against the best the plate can deliver: what a controller
  knowing this finger exactly delivers (its own inverse of the target, clipped to the
  amplitude limit, through the plate's 400 Hz amplitude loop of seed 003, Fig. 3b) --
  the part no controller of the amplitude command can fix removed; the ratios of the
  targets are judged on this one;
- ``noise``: the lateral force noise the loop adds (N RMS): the delivered friction force
  of the run against the same run with a noiseless sensor, adaptive mode on
  ``NOISE_SCENES`` only, as a
  fraction of the mean friction force, against the Weber fraction 0.11 for detecting a
  change of friction (Gueorguiev et al., J. R. Soc. Interface 14 (2017) 20170641);
- ``growth``: the loop's log-gain steps late in the run against early (a growing
  oscillation shows as > 1); ``max_command_um``: the largest amplitude commanded;
- ``adapted_gap``: after the adaptive run, seed 003's eq 2 with the adapted (b, k)
  against the true finger at the run's end, over the amplitudes 0..limit (relative RMS);
  the adaptation study runs each finger ``ADAPT_S`` on ``ADAPT_SCENE`` (whose bump asks
  for every amplitude, where a grating asks for one) and reports this gap.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from app.engine.clocks import VirtualClock
from app.engine.driver import drive
from app.engine.sources import TraceSource
from app.measure.closed_loop_sim import FingerSink, LoopStage
from app.measure.report_matrix import load
from device.finger import FingerPlant, SensorParams, draw_finger, true_mu
from device.friction import forward_mu
from rendering.control.margins import margins
from rendering.input.trace_synth import make_motion, sample, truth
from rendering.pipeline import build_pipeline

SCENES = ("grating-15mm", "grating-5mm", "grating-0.6mm", "objects-bump-edge-disc")
MODES = ("open", "closed", "adaptive")
RATE_HZ = 5000.0
BLOCK = 25
FINGERS = 20
DURATION_S = 10.0
QUICK_DURATION_S = 4.0
#: the adaptation study: each finger slides this long (s) over this scene, loop adapting
ADAPT_S = 60.0
QUICK_ADAPT_S = 20.0
ADAPT_SCENE = "objects-bump-edge-disc"
#: Gueorguiev et al. 2017: Weber fraction for a change of friction
WEBER_FRACTION = 0.11
SLIDING_MM_S = 5.0
#: the second RMS leaves out the run's first second (the loop finding mu0 and its gain)
SETTLE_S = 1.0
#: scenes whose adaptive runs are run again with a noiseless sensor (added noise)
NOISE_SCENES = ("grating-15mm", "grating-0.6mm")


@dataclass(frozen=True)
class Run:
    """One run's inputs."""

    scene: str
    finger: int
    mode: str
    duration_s: float
    noiseless: bool = False
    noise: bool = False
    sensor_dead_after_s: float | None = None


def finger_force(seed: int):
    """The finger's normal force (N) as a function of time (s): drawn mean, 0.5 Hz swell."""
    rng = np.random.default_rng([seed, 17])
    f0, phase = rng.uniform(0.35, 0.65), rng.uniform(0, 2 * np.pi)
    return lambda t: f0 * (1.0 + 0.15 * np.sin(2 * np.pi * 0.5 * np.asarray(t) + phase))


def finger_speed(motion):
    """The motion's true speed (mm/s) as a function of time (s)."""
    path = truth(motion, 2000.0)
    speed = np.hypot(np.gradient(path.x_mm, path.t_s), np.gradient(path.y_mm, path.t_s))
    return lambda t: np.interp(t, path.t_s, speed)


def simulate(run: Run):
    """Run one (scene, finger, mode); returns (FingerSink, LoopStage after the run)."""
    scene = load(run.scene)
    motion = make_motion("human", speed_mm_s=60.0, duration_s=run.duration_s, seed=run.finger)
    trace = sample(motion, 50.0, noise_mm=0.05, seed=100 + run.finger)
    pipeline = build_pipeline(scene, rate_hz=RATE_HZ, block_size=BLOCK, render_override="hybrid",
                              control=run.mode)
    sensor = SensorParams(lateral_noise_n=0.0, normal_noise_n=0.0) if run.noiseless else SensorParams()
    plant = FingerPlant(draw_finger(run.finger), RATE_HZ, scene.device.amplitude_limit_um,
                        sensor=sensor, seed=run.finger)
    sink = FingerSink(plant, finger_speed(motion), finger_force(run.finger),
                      sensor_dead_after_s=run.sensor_dead_after_s)
    stage = LoopStage(pipeline, sink)
    source = TraceSource(iter([trace]), until_s=run.duration_s)
    source.start(pipeline.tracker_config)
    drive(stage, source, [sink], VirtualClock(), chunk_blocks=1)
    return sink, stage


def score(run: Run) -> dict:
    """The measurements of one run (module docstring)."""
    sink, stage = simulate(run)
    a = sink.arrays()
    slide = a["speed"] >= SLIDING_MM_S
    err = a["delivered"][slide] - a["target"][slide]
    reach = a["delivered"][slide] - a["best"][slide]
    settled = a["t"][slide] >= SETTLE_S
    out = {"rms": _rms(err), "rms_reachable": _rms(reach),
           "rms_settled": _rms(reach[settled]), "max_command_um": sink.max_command_um}
    control = stage.state.control
    if control is not None:
        out.update(fallbacks=control.fallbacks, log_c=control.log_c, mu0_estimate=control.mu0,
                   b_per_um=control.rls.theta[0], k_per_n=control.rls.theta[1],
                   growth=oscillation_growth(np.array(stage.log_c)))
        if run.mode == "adaptive":
            out["adapted_gap"] = adapted_gap(run, control.rls.params, float(a["t"][-1]))
            if run.noise:
                quiet, _ = simulate(Run(run.scene, run.finger, run.mode, run.duration_s,
                                        noiseless=True))
                q = quiet.arrays()
                m = min(q["delivered"].size, a["delivered"].size)
                friction = a["mu0"][:m] * a["force"][:m]
                diff = friction * (a["delivered"][:m] - q["delivered"][:m])
                noise = _rms(diff[slide[:m]])
                mean = float(np.mean(friction[slide[:m]] * a["delivered"][:m][slide[:m]]))
                out.update(noise_n=noise, noise_fraction=noise / mean if mean > 0 else 0.0)
    return out


def adapted_gap(run: Run, params, t_s: float) -> float:
    """Relative RMS of the adapted model against the true finger at ``t_s`` over 0..limit um
    (at the finger's mean force and the motion's 60 mm/s)."""
    w = np.linspace(0.0, load(run.scene).device.amplitude_limit_um, 51)
    force = float(np.mean(finger_force(run.finger)(np.linspace(0, 2, 9))))
    truth_mu = true_mu(w, force, 60.0, t_s, draw_finger(run.finger))
    model = forward_mu(w, force, params)
    return _rms((model - truth_mu) / truth_mu)


def adaptation(run: Run) -> float:
    """The adapted model's gap to the true finger (:func:`adapted_gap`) after ``run``."""
    sink, stage = simulate(run)
    return adapted_gap(run, stage.state.control.rls.params, float(sink.arrays()["t"][-1]))


def oscillation_growth(log_c: np.ndarray) -> float:
    """RMS block-to-block step of the loop's log gain over the run's second half against
    its first half: above 1 with alternating steps would be a growing oscillation (0 when
    the loop never moved)."""
    steps = np.diff(log_c)
    half = steps.size // 2
    early, late = _rms(steps[:half]), _rms(steps[half:])
    return late / early if early > 0 else 0.0


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if np.size(x) else 0.0


def measure(fingers: int = FINGERS, duration_s: float = DURATION_S, workers: int = 1,
            scenes=SCENES, adapt_s: float = ADAPT_S, adapt_fingers: int | None = None,
            noise_scenes=NOISE_SCENES) -> dict:
    """Every scene x mode x finger (the added noise measured on ``noise_scenes``), and
    fingers 1..``adapt_fingers`` (default all) adapting for ``adapt_s`` on the object
    scene; returns the section's JSON (see :func:`summarise`)."""
    from app.engine.fanout import fan_out
    runs = [Run(s, f, m, duration_s, noise=s in noise_scenes and m == "adaptive")
            for s in scenes for m in MODES for f in range(1, fingers + 1)]
    results = fan_out(score, runs, workers=workers)
    values: dict = {}
    for run, res in zip(runs, results):
        values.setdefault(run.scene, {}).setdefault(run.mode, []).append(res)
    section = summarise(values, fingers, duration_s)
    if adapt_s > 0:
        gaps = fan_out(adaptation, [Run(ADAPT_SCENE, f, "adaptive", adapt_s)
                                    for f in range(1, (adapt_fingers or fingers) + 1)],
                       workers=workers)
        section["adaptation"] = {"scene": ADAPT_SCENE, "duration_s": adapt_s,
                                 "fingers": len(gaps),
                                 "gap_max": max(gaps), "gap_median": float(np.median(gaps)),
                                 "gaps": gaps}
    return section


def section(quick: bool, workers: int = 1) -> dict:
    """The section for ``frictex report`` (``--quick``: shorter runs, same population)."""
    if quick:
        return measure(FINGERS, QUICK_DURATION_S, workers, adapt_s=QUICK_ADAPT_S)
    return measure(FINGERS, DURATION_S, workers)


def summarise(values: dict, fingers: int, duration_s: float) -> dict:
    """Population statistics and the issue's targets from per-finger results."""
    scenes = {}
    for scene, modes in values.items():
        row = {}
        for mode, results in modes.items():
            rms = np.array([r["rms_reachable"] for r in results])
            row[mode] = {"rms_reachable_pop": _rms(rms), "worst": float(rms.max()),
                         "rms_pop": _rms(np.array([r["rms"] for r in results])),
                         "fallbacks": int(sum(r.get("fallbacks", 0) for r in results)),
                         "max_command_um": max(r["max_command_um"] for r in results)}
            if mode != "open":
                row[mode]["growth_max"] = max(r["growth"] for r in results)
            row[mode]["rms_settled_pop"] = _rms(np.array([r["rms_settled"] for r in results]))
            if mode == "adaptive":
                noise = [r["noise_fraction"] for r in results if "noise_fraction" in r]
                if noise:
                    row[mode]["noise_fraction_max"] = max(noise)
                row[mode]["adapted_gap_max"] = max(r["adapted_gap"] for r in results)
        for mode in ("closed", "adaptive"):
            if mode in row and "open" in row:
                row[mode]["gain_vs_open"] = row["open"]["rms_reachable_pop"] / max(
                    row[mode]["rms_reachable_pop"], 1e-12)
                row[mode]["gain_settled"] = row["open"]["rms_settled_pop"] / max(
                    row[mode]["rms_settled_pop"], 1e-12)
                row[mode]["worst_improves"] = row[mode]["worst"] < row["open"]["worst"]
        scenes[scene] = row
    return {"fingers": fingers, "duration_s": duration_s, "rate_hz": RATE_HZ,
            "block": BLOCK, "weber_fraction": WEBER_FRACTION, "margins": margins(),
            "scenes": scenes}


def markdown(section: dict) -> str:
    """The section as markdown."""
    m = section["margins"]
    lines = ["## Closed-loop friction", "",
             f"{section['fingers']} simulated fingers (device/finger.py), {section['duration_s']:g} s "
             f"of human-like sliding each, {section['rate_hz']:g} Hz in blocks of {section['block']}. "
             "RMS error of delivered mu' against the reachable target, over the population "
             "(RMS of per-finger RMS); worst finger; gain against open loop.", "",
             f"'after {SETTLE_S:g} s': the same from the run's second second on (the loop has "
             "found mu0 and its gain).", "",
             "| scene | mode | RMS | worst | gain | RMS after 1 s | gain after 1 s | raw RMS | max um "
             "| step growth (max) | fallbacks | noise / friction (max) | adapted model gap (max) |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for scene, row in section["scenes"].items():
        for mode, r in row.items():
            gain = f"{r['gain_vs_open']:.1f}x" if "gain_vs_open" in r else ""
            noise = f"{r['noise_fraction_max']:.3f}" if "noise_fraction_max" in r else ""
            gap = f"{r['adapted_gap_max']:.3f}" if "adapted_gap_max" in r else ""
            growth = f"{r['growth_max']:.2f}" if "growth_max" in r else ""
            settled = f"{r['gain_settled']:.1f}x" if "gain_settled" in r else ""
            lines.append(f"| {scene} | {mode} | {r['rms_reachable_pop']:.4f} | {r['worst']:.4f} | "
                         f"{gain} | {r['rms_settled_pop']:.4f} | {settled} | {r['rms_pop']:.4f} | "
                         f"{r['max_command_um']:.3f} | {growth} | "
                         f"{r['fallbacks']} | {noise} | {gap} |")
    if "adaptation" in section:
        ad = section["adaptation"]
        lines += ["", f"Adaptation ({ad['fingers']} fingers): after {ad['duration_s']:g} s on "
                      f"{ad['scene']}, seed 003's "
                      f"eq 2 with the adapted (b, k) against each true finger over 0-2.5 um: "
                      f"relative RMS gap median {ad['gap_median']:.3f}, worst {ad['gap_max']:.3f}."]
    lines += ["", f"Loop margins (integrator on log gain, ki = {m['ki']:g} per block, "
                  f"{m['delay_blocks']} block(s) of delay): gain margin {m['gain_margin']:.2f}, "
                  f"phase margin {m['phase_margin_deg']:.0f} deg; noise threshold: Weber "
                  f"fraction {section['weber_fraction']:g} (Gueorguiev et al. 2017).", ""]
    return "\n".join(lines)


def write(section: dict, out_dir) -> None:
    """``closed_loop.md`` and ``closed_loop.json`` in ``out_dir``."""
    from pathlib import Path
    out = Path(out_dir)
    (out / "closed_loop.json").write_text(json.dumps(section, indent=1))
    (out / "closed_loop.md").write_text(markdown(section))
