"""``frictex calibrate``: fit seed 003's friction model to a finger on a plate.

The user slides a finger while the plate steps through amplitudes
(``device.calibration_run``); frictex fits (b, k) of seed 003's eq 2
(``device.calibration_fit``), prints the fit and its residual, writes the ``[device]``
section a texture file can use and plots the measured points against the fitted curve.

``--device sim`` runs the protocol on the simulated finger of ``device.finger``
(``--finger N``: person N of the simulated population; 0: seed 003's own constants). A
serial port needs the lateral force on the wire, which the protocol does not carry yet.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from device.calibration_fit import device_toml, fit_points
from device.calibration_run import Sweep, run_sweep
from device.finger import FingerParams, FingerPlant, draw_finger

RATE_HZ = 5000.0
LIMIT_UM = 2.5


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--device", required=True, metavar="sim|PORT",
                        help="the plate: 'sim' (simulated finger) or a serial port")
    parser.add_argument("--finger", type=int, default=1, metavar="N",
                        help="simulated person N (0: seed 003's constants; default 1)")
    parser.add_argument("--out", type=Path, default=Path("calibration.toml"),
                        help="where to write the [device] section (default calibration.toml)")
    parser.add_argument("--plot", type=Path, default=None,
                        help="PNG of the measured points against the fitted curve")


def _progress(done: int, total: int) -> None:
    print(f"\rcalibrating: step {done}/{total}", end="" if done < total else "\n",
          file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    if args.device != "sim":
        raise ValueError(f"calibrate: device {args.device!r}: only 'sim' can be calibrated; a "
                         f"serial device must report the lateral force, which device/PROTOCOL.md "
                         f"does not carry yet")
    if args.finger < 0:
        raise ValueError(f"calibrate: --finger {args.finger}: expected 0 or a positive person number")
    finger = FingerParams() if args.finger == 0 else draw_finger(args.finger)
    sweep = Sweep()
    plant = FingerPlant(finger, RATE_HZ, LIMIT_UM, seed=args.finger)
    w, normal, mu = run_sweep(plant, sweep, on_step=_progress)
    fit = fit_points(w, normal, mu)
    print(f"{fit.n_points} points in {sweep.duration_s:g} s of sliding; seed 003 eq 2 fit: "
          f"b = {fit.params.b_per_um:.4f} /um, k = {fit.params.asymptote_per_n:.4f} /N, "
          f"residual RMS {fit.residual_rms:.5f} (mu')"
          + ("" if fit.fits else "; the model does not fit: calibration table written"))
    args.out.write_text(device_toml(fit, LIMIT_UM, sweep.force_n))
    print(f"wrote {args.out}")
    if args.plot is not None:
        _plot(args.plot, w, normal, mu, fit)
        print(f"wrote {args.plot}")
    return 0


def _plot(path: Path, w, normal, mu, fit) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from device.friction import forward_mu
    grid = np.linspace(0.0, max(float(w.max()), 1e-3), 200)
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot(w, mu, "o", label="measured")
    ax.plot(grid, forward_mu(grid, float(np.mean(normal)), fit.params), "-", label="seed 003 eq 2 fit")
    ax.set_xlabel("amplitude (um)")
    ax.set_ylabel("relative friction mu'")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
