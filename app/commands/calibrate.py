"""``frictex calibrate``: fit seed 003's friction model to a finger on a plate.

The user slides a finger while the plate steps through amplitudes
(``device.calibration_run``, streamed over the device's link and read back from its
force reports); frictex fits (b, k) of seed 003's eq 2 (``device.calibration_fit``),
prints the fit with its standard errors (of the points' scatter only), its residual and
the sliding speed b applies at (warning when b or k stopped on a bound of the fit or is
not determined, and when points were left out as not finite), writes the ``[device]``
section a texture file can use and the measured points, a CSV to re-fit or audit the
calibration from (``--points``; by default beside ``--out``, see :data:`POINTS_COLUMNS`),
and plots them against the fitted curve (a PNG: ``--plot`` names a ``.png`` file).
Where the model is not accepted the section carries a measured table instead, which
``replay --control closed`` refuses (the loop inverts eq 2): said when it is written.

``--device`` takes what ``replay --device`` takes: ``sim`` starts ``frictex sim-device``
with a simulated finger (``--finger N``: person N of ``device.finger``'s population,
sliding and pressing as the protocol asks; ``sim:finger=N`` names it too, once); a
serial port or pyserial URL is a plate, which must announce force reports (PROTOCOL.md
4.9).

Everything the person's sweep does not decide is checked before the device is opened, so
a mistake never throws a sweep away: ``--finger`` (only with a simulated device), each
output path (``--out``, ``--points``, ``--plot``: what it names, its folder, the room for
it, as ``app.engine.outfile`` writes it) and the plot's library. The outputs are written whole
or not at all (``app.engine.outfile.write_file``).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from frictex.app.commands.argtypes import sim_finger_args, sim_options
from frictex.app.engine.outfile import check_writable, write_file
from frictex.device.calibration_fit import device_toml, fit_points, usable_points
from frictex.device.calibration_identity import simulated_finger
from frictex.device.calibration_run import StepCut, Sweep, check_calibratable, run_sweep
from frictex.device.errors import InputError, require_extra
from frictex.device.profile import FittedOn

#: the plate's sample rate (Hz, seed 003) and the simulated plate's amplitude limit (um)
RATE_HZ = 10_000.0
SIM_LIMIT_UM = 2.5
#: sweeps run at most: one whose step lost its reports to a starved host is run again
SWEEPS = 3
#: the simulated finger when none is named (person number)
DEFAULT_FINGER = 1
#: bounds of the outputs' sizes (bytes): the [device] section with a measured table, and
#: the plot's 500 x 350 px at 4 bytes a pixel
TOML_BYTES = 64 << 10
PLOT_BYTES = 500 * 350 * 4
#: the points file's header, one line per point under it: the amplitude (um), the normal
#: force (N) and the relative friction mu' each to the last bit (Python's repr: ``nan``,
#: ``inf`` as they came), and 1 where the fit used the point, 0 where it left it out (not
#: finite, a negative amplitude or no normal force: ``device.calibration_fit.usable_points``)
POINTS_COLUMNS = ("amplitude_um", "normal_force_n", "mu", "used_in_fit")
#: bytes a point's line takes at most: three floats' reprs (24 characters each) and commas,
#: its flag and the line's end
POINTS_ROW_BYTES = 3 * 25 + 2


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--device", required=True, metavar="sim|PORT",
                        help="the plate: 'sim' (a simulated device with a simulated finger), "
                             "or a serial port or pyserial URL, as for replay --device")
    parser.add_argument("--finger", type=int, default=None, metavar="N",
                        help="with --device sim: the simulated finger, person N (>= 0) of "
                             f"device/finger.py's population (default {DEFAULT_FINGER}); "
                             "refused with any other device")
    parser.add_argument("--out", type=Path, default=Path("calibration.toml"),
                        help="where to write the [device] section (default calibration.toml)")
    parser.add_argument("--points", type=Path, default=None, metavar="CSV",
                        help="where to write the measured points, to re-fit or audit the "
                             f"calibration from (columns {', '.join(POINTS_COLUMNS)}; default: "
                             "beside --out, named after it: calibration-points.csv for "
                             "calibration.toml; none when --out is a stream, /dev/stdout)")
    parser.add_argument("--plot", type=Path, default=None,
                        help="PNG of the measured points against the fitted curve (a name ending "
                             "in .png)")


def _progress(done: int, total: int) -> None:
    """One line per step where stderr is a file or a pipe, one line redrawn on a terminal."""
    text = f"calibrating: step {done}/{total}"
    if sys.stderr.isatty():
        print("\r" + text, end="" if done < total else "\n", file=sys.stderr, flush=True)
    else:
        print(text, file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    from frictex.device.link.host import open_sink  # with the command: its imports stay out of --help
    sweep = Sweep()
    sim_args = _sim_args(args.device, args.finger, sweep)
    check_writable("--out", args.out, TOML_BYTES)
    points = args.points if args.points is not None else _beside(args.out)
    if points is not None:
        _check_own("--points", points, ("--out", args.out))
        # a point per step at most (the rest steps give none)
        check_writable("--points", points, len(",".join(POINTS_COLUMNS)) + 1
                       + POINTS_ROW_BYTES * len(sweep.amplitudes()))
    if args.plot is not None:
        check_writable("--plot", args.plot, PLOT_BYTES)
        _check_own("--plot", args.plot, ("--out", args.out), ("--points", points))
        if args.plot.suffix.lower() != ".png":
            raise InputError(f"--plot {args.plot}: the plot is a PNG; give a name ending in .png")
        require_extra("report", "matplotlib", "--plot")
    link = open_sink(args.device, channels=1, rate_hz=RATE_HZ, paced=True, sim_args=sim_args)
    try:
        check_calibratable(link, sweep)  # before asking for a finger
        print(f"{link.label}: slide a finger at about {sweep.speed_mm_s:g} mm/s, pressing "
              f"about {sweep.force_n:g} N, for {sweep.duration_s:g} s (the sweep starts at "
              f"the touch)", file=sys.stderr)
        w, normal, mu = _sweeps(link, sweep)
        limit_um = link.info.limits_um[0]
        fitted = FittedOn(link.info.name, simulated_finger(args.device, sim_args),
                          sweep.speed_mm_s)
    except BaseException:  # stop the plate now and keep no output (a WAV's earlier file)
        getattr(link, "abort", link.close)()
        raise
    link.close()
    fit = fit_points(w, normal, mu)
    print(f"{_points_from_steps(fit.n_points, sweep)}; seed 003 eq 2 fit at "
          f"{sweep.speed_mm_s:g} mm/s sliding (b falls as the finger speeds up): "
          f"b = {fit.params.b_per_um:.4f} ± {fit.b_se:.2g} /um, "
          f"k = {fit.params.asymptote_per_n:.4f} ± {fit.k_se:.2g} /N (standard errors of the "
          f"points' scatter only: the sweep's systematic errors come on top, 0.5 to 16 of "
          f"them on b, 0.04 to 4.2 %, in sixteen simulated sweeps), "
          f"residual RMS {fit.residual_rms:.5f} (mu')"
          + ("" if fit.calibration is None else f"; the model does not fit ({fit.misfit_reason}): "
             f"its measured table ({len(fit.calibration.amplitudes_um)} amplitudes) written"))
    for note in _warnings(fit):
        print(f"frictex: warning: {note}", file=sys.stderr)
    text = device_toml(fit, limit_um, sweep.force_n, fitted=fitted,
                       speed_mm_s=sweep.speed_mm_s).encode("utf-8")
    write_file(args.out, lambda to: to.write_bytes(text), len(text))
    print(f"wrote {args.out} (the [device] section a texture file can use; --out)")
    if points is not None:
        _write_points(points, w, normal, mu)
        print(f"wrote {points} (the {np.size(w)} measured points, {fit.n_points} of them "
              f"used in the fit: {', '.join(POINTS_COLUMNS)}; --points)")
    if args.plot is not None:
        _plot(args.plot, w, normal, mu, fit, sweep)
        print(f"wrote {args.plot} (the measured points against the fitted curve; --plot)")
    return 0


def _beside(out: Path) -> Path | None:
    """The points file's default: ``<out stem>-points.csv`` in ``out``'s folder; None
    where ``out`` is a stream (a character device or a FIFO, which has no folder of its
    own: ``check_writable`` has refused anything else that is not a file)."""
    real = Path(os.path.realpath(out))
    if real.exists() and not real.is_file():
        return None
    return out.with_name(f"{out.stem}-points.csv")


def _check_own(option: str, path: Path, *others: tuple[str, Path | None]) -> None:
    """Refuse an output ``path`` that is the file another option writes."""
    for other, taken in others:
        if taken is not None and os.path.realpath(path) == os.path.realpath(taken):
            raise InputError(f"{option} {path}: the same file as {other} {taken}; give it "
                             "a name of its own")


def _write_points(path: Path, w, normal, mu) -> None:
    """The sweep's points as :data:`POINTS_COLUMNS`, written whole
    (``app.engine.outfile.write_file``)."""
    w, normal, mu = (np.asarray(a, dtype=np.float64).ravel() for a in (w, normal, mu))
    used = usable_points(w, normal, mu)
    lines = [",".join(POINTS_COLUMNS)] + [f"{a!r},{f!r},{m!r},{int(u)}" for a, f, m, u in
                                          zip(w.tolist(), normal.tolist(), mu.tolist(), used)]
    text = "\n".join(lines + [""]).encode("utf-8")
    write_file(path, lambda to: to.write_bytes(text), len(text))


def _warnings(fit) -> list[str]:
    """What the user should know of ``fit`` beyond its figures: points left out, constants
    not determined, and a measured table that closed-loop replays refuse."""
    said = []
    if fit.n_dropped:
        said.append(f"{fit.n_dropped} points left out of the fit: not finite, a negative "
                    "amplitude or no normal force")
    said += fit.notes
    if fit.calibration is not None:
        said.append("the written [device.calibration] table replaces seed 003's eq 2: "
                    "'replay --control closed' refuses it (the loop inverts eq 2); a scene "
                    "with it plays open loop")
    return said


def _points_from_steps(n_points: int, sweep: Sweep) -> str:
    """How the sweep's steps became the fit's points: each amplitude step is one point,
    its friction over the mean of the rest steps either side of it (the friction at rest
    mu0, ``device.calibration_run``)."""
    n_steps = len(sweep.amplitudes())
    n_rest = n_steps - len(sweep.levels)
    return (f"{n_points} points from {n_steps} steps in {sweep.duration_s:g} s of sliding "
            f"(one per amplitude step, its friction over that of the rest steps either side "
            f"of it: {n_rest} rest steps, which give the friction at rest)")


def _sim_args(device: str, finger: int | None, sweep: Sweep) -> tuple[str, ...]:
    """The simulated device's flags for ``sweep`` (its finger slides and presses as the
    sweep asks; amplitude limit :data:`SIM_LIMIT_UM`), each unless ``device``'s spec names
    it (``sim:limit=3``); () for another device. ``--finger`` is refused as replay refuses
    ``--sim-finger`` (``app.commands.argtypes.sim_finger_args``)."""
    flags = sim_finger_args("--finger", finger, device)
    named = sim_options(device)
    if named is None:
        return ()
    given = {name for name, _ in named}
    own = {"finger": DEFAULT_FINGER, "finger-speed": sweep.speed_mm_s, "force": sweep.force_n,
           "limit": SIM_LIMIT_UM}
    for name, value in own.items():
        if name not in given and not (name == "finger" and flags):
            flags += (f"--{name}", f"{value:g}")
    return flags


def _sweeps(link, sweep: Sweep):
    """``run_sweep``, again from where the last one stopped when a step's reports were
    cut (said on stderr), at most :data:`SWEEPS` times."""
    first = 0
    for attempt in range(1, SWEEPS + 1):
        try:
            return run_sweep(link, sweep, on_step=_progress, first_index=first)
        except StepCut as cut:
            if attempt == SWEEPS:
                raise StepCut(f"{cut}; in each of {SWEEPS} sweeps: calibrate again with the "
                              "host less busy", cut.next_index) from None
            print(f"frictex: warning: {cut}; sweeping again ({attempt + 1} of {SWEEPS})",
                  file=sys.stderr)
            first = cut.next_index


def _plot(path: Path, w, normal, mu, fit, sweep: Sweep) -> None:
    """The measured points against the fitted curve, titled with the fit (b, k, residual
    RMS) and the sweep's force and speed; a PNG written whole
    (``app.engine.outfile.write_file``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from frictex.device.friction import forward_mu
    grid = np.linspace(0.0, max(float(w.max()), 1e-3), 200)
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot(w, mu, "o", label="measured")
    ax.plot(grid, forward_mu(grid, float(np.mean(normal)), fit.params), "-", label="seed 003 eq 2 fit")
    ax.set_xlabel("amplitude (um)")
    ax.set_ylabel("relative friction mu'")
    ax.set_title(f"b {fit.params.b_per_um:.3f}±{fit.b_se:.2g} /um, k {fit.params.asymptote_per_n:.3f}"
                 f"±{fit.k_se:.2g} /N, RMS {fit.residual_rms:.4f}\n"
                 f"at {sweep.force_n:g} N, {sweep.speed_mm_s:g} mm/s sliding", fontsize=9)
    ax.legend()
    fig.tight_layout()
    try:
        write_file(path, lambda to: fig.savefig(to, format="png", dpi=100), PLOT_BYTES)
    finally:
        plt.close(fig)
