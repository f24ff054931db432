"""Ring resonator (seed 004): degenerate symmetric/asymmetric pairs and where they coincide.

The oblong ring of seed 004 (two straights of length L, two semicircles of radius R)
has, for each order n (wavelengths around the ring), a symmetric and an asymmetric
mode; driven 90 degrees apart they make a travelling wave, best where their
frequencies coincide. Defaults are seed 004's design (aluminium 5052, L 140 mm,
R 50 mm, h 2.75 mm, w 30 mm). For each order the table gives both frequencies, their
split, and the L/R ratios (R fixed) at which the pair is exactly degenerate
(seed 004, Fig. 2c). --band lists every mode between two frequencies instead.
--phase-shift adds, for the first --orders pair, the travelling-wave ratio and the force
on a still finger against the phase shift between the two modes (seed 004, Fig. 4).
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from frictex.app.commands.argtypes import bounded, positive_float
from frictex.app.commands.modes_output import (add_plot_argument, check_below, check_finite,
                                               check_orders, check_plot, check_wavelength,
                                               density_kg_m3, dimension_mm, format_hz,
                                               refuse_without, save_figure, warn, youngs_gpa)
from frictex.device.structures.beam import VALID_WAVELENGTH_IN_THICKNESSES, ModesError
from frictex.device.actuation.travelling import phase_shift_response, ring_wave
from frictex.device.profile import DrivingForceParams
from frictex.device.structures.ring import THIN_RING_H_OVER_R, RingResonator
from frictex.textures.keys import MAX_FORCE_N, MAX_MODE_ORDER, MAX_UM

#: crossings listed: L/R within this factor of the ring's own
_RATIO_WINDOW = 2.0
#: what the model (Rayleigh straights, thin curved beam) misses at short wavelengths
_BEYOND = "shear makes the true frequency lower"
#: --phase-shift's defaults, seed 004's Fig. 4 conditions: its largest amplitude (+-3 um,
#: section IV.B) and the two normal forces of Fig. 4c; the step of the phase shift (deg)
_PHASE_DEFAULTS = {"phase_step_deg": 15.0, "amplitude_um": 3.0, "normal_force_n": [1.0, 0.5]}
#: the amplitude (um) above which the driving-force line (seed 004, Fig. 3c: k_p F_n
#: (w - w_th)) would push a still finger harder than its friction at rest, mu0 F_n, can:
#: the plate drives the finger through that friction, and seed 004 expects a plateau
_DRIVE = DrivingForceParams()
FRICTION_BOUND_UM = _DRIVE.threshold_um + _DRIVE.mu0 / _DRIVE.slope_per_um
#: the plot's rows at most (3 inches each, the phase shift's included): 7 x 9 inches at
#: 110 dpi stays within modes_output.PLOT_BYTES, the room --plot is checked for
PLOT_ROWS = 3


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--length-mm", type=dimension_mm, default=140.0,
                        help="length L of each straight part (default 140)")
    parser.add_argument("--radius-mm", type=dimension_mm, default=50.0,
                        help="radius R of the semicircles, to the neutral line (default 50)")
    parser.add_argument("--thickness-mm", type=dimension_mm, default=2.75,
                        help="thickness h (default 2.75)")
    parser.add_argument("--width-mm", type=dimension_mm, default=30.0, help="width w (default 30)")
    parser.add_argument("--youngs-gpa", type=youngs_gpa, default=69.0,
                        help="Young's modulus E in GPa (default 69)")
    parser.add_argument("--density", type=density_kg_m3, default=2680.0,
                        help="density in kg/m^3 (default 2680)")
    parser.add_argument("--orders", type=int, nargs="+", default=[24], metavar="N",
                        help="mode orders, wavelengths around the ring, 2 to "
                             f"{MAX_MODE_ORDER} (default 24)")
    parser.add_argument("--band", type=positive_float, nargs=2, metavar=("MIN_HZ", "MAX_HZ"),
                        help="list every mode between two frequencies instead of --orders")
    parser.add_argument("--json", action="store_true",
                        help='print {"modes": [{"order", "kind", "frequency_hz"}, ...], '
                             '"pairs": [...]} instead of a table')
    parser.add_argument("--phase-shift", action="store_true",
                        help="also give, for the first --orders pair, the travelling-wave ratio "
                             "and the force (N) on a still finger against the phase shift (deg) "
                             "between its two modes (seed 004, Fig. 4)")
    parser.add_argument("--phase-step-deg", type=bounded(float, 0.5, 90.0, "degrees"),
                        metavar="DEG", help="with --phase-shift: step of the phase shift from "
                                            "-180 to 180 deg, dividing 180 (default 15)")
    parser.add_argument("--amplitude-um", type=bounded(float, 0.01, MAX_UM, "um"), metavar="W",
                        help="with --phase-shift: amplitude of each mode, um zero-to-peak, "
                             f"0.01 to {FRICTION_BOUND_UM:.4g} (default 3, seed 004's largest; "
                             "above, the force's line would pass the finger's friction)")
    parser.add_argument("--normal-force-n", type=bounded(float, 0.01, MAX_FORCE_N, "N"),
                        nargs="+", metavar="N",
                        help="with --phase-shift: normal force(s) of the finger in N, 0.01 to "
                             f"{MAX_FORCE_N:g} (default 1 0.5, seed 004 Fig. 4c)")
    add_plot_argument(parser, "also write each pair's frequency split against L/R (seed 004, "
                              f"Fig. 2c; the first {PLOT_ROWS} orders), and with --phase-shift "
                              "the ratio and force against the phase shift (Fig. 4; then the "
                              f"first {PLOT_ROWS - 1} orders)")


def run(args: argparse.Namespace) -> int:
    check_plot(args.plot)
    _check_phase_options(args)
    check_below("--thickness-mm", args.thickness_mm, "--radius-mm", args.radius_mm,
                "the thin curved beam of seed 004, eq 3 needs h well below R")
    if args.thickness_mm > THIN_RING_H_OVER_R * args.radius_mm:
        warn(f"--thickness-mm {args.thickness_mm:g}: above {THIN_RING_H_OVER_R:g} R = "
             f"{THIN_RING_H_OVER_R * args.radius_mm:g} mm, outside the thin-ring model's "
             "validity (seed 004, eq 3 takes h much below R)")
    ring = RingResonator(args.length_mm, args.radius_mm, args.thickness_mm, args.width_mm,
                         args.youngs_gpa, args.density)
    if args.band:
        _check_band(ring, *args.band)
        modes = ring.modes_in_band(*args.band)
        pairs = []
    else:
        check_orders(args.orders, 2, "wavelengths around the ring; order 1 would move it "
                                     "rigidly")
        perimeter_mm = 2 * ring.length_mm + 2 * np.pi * ring.radius_mm
        for n in args.orders:  # the perimeter over n first: a cheap bound on the wavelength
            check_wavelength(f"--orders {n}", perimeter_mm / n, ring.thickness_mm,
                             VALID_WAVELENGTH_IN_THICKNESSES["euler-bernoulli"], _BEYOND)
        found = [_pair(ring, n) for n in args.orders]
        modes = [m for pair in found for m in pair]
        pairs = [_pair_summary(ring, sym, asym) for sym, asym in found]
    check_finite([{"order": m.order, "frequency_hz": m.frequency_hz} for m in modes])
    phase = _phase_shift(ring, args) if args.phase_shift else None
    if args.json:
        out = {"modes": [{"order": m.order, "kind": m.kind, "frequency_hz": m.frequency_hz}
                         for m in modes], "pairs": pairs}
        if phase is not None:
            out["phase_shift"] = phase
        print(json.dumps(out, indent=2))
    else:
        _print_table(ring, modes, pairs, args.band)
        if phase is not None:
            _print_phase(phase)
    if args.plot:
        orders = [p["order"] for p in pairs] or sorted({m.order for m in modes})
        save_figure(_plot(ring, _plotted(orders, phase is not None), phase), args.plot)
    return 0


def _plotted(orders: list[int], with_phase: bool) -> list[int]:
    """The first of ``orders`` whose panels fit the plot beside the phase shift's row, if
    any; a warning names them when some are left out."""
    rows = PLOT_ROWS - with_phase
    if len(orders) <= rows:
        return orders
    warn(f"--plot: {len(orders)} orders; the plot shows the first {rows} "
         f"({' '.join(map(str, orders[:rows]))}), as many as fit its "
         f"{PLOT_ROWS * 3} inches of height (the table lists every order)")
    return orders[:rows]


def _pair(ring: RingResonator, order: int):
    """``ring.pair(order)``, its refusal naming --orders."""
    try:
        return ring.pair(order)
    except ModesError as exc:
        raise ModesError(f"--orders {order}: {exc}") from None


def _check_phase_options(args: argparse.Namespace) -> None:
    """Refuse --phase-shift's options without it, --phase-shift with --band, and a step
    that does not divide 180 degrees; fill in the defaults; warn of an amplitude beyond
    seed 004's measurements."""
    for name, default in _PHASE_DEFAULTS.items():
        option = "--" + name.replace("_", "-")
        given = getattr(args, name)
        if given is not None and not args.phase_shift:
            refuse_without(option, given, "--phase-shift")
        if given is None:
            setattr(args, name, default)
    if not args.phase_shift:
        return
    if args.band:
        raise ModesError("--phase-shift: needs --orders (its first pair), not --band")
    steps = 180.0 / args.phase_step_deg
    if abs(steps - round(steps)) > 1e-9:
        raise ModesError(f"--phase-step-deg {args.phase_step_deg:g}: must divide 180 (e.g. 5, "
                         "10, 15, 30, 45)")
    if args.amplitude_um > FRICTION_BOUND_UM:
        raise ModesError(f"--amplitude-um {args.amplitude_um:g}: above {FRICTION_BOUND_UM:.4g} "
                         f"um the driving-force line (seed 004, Fig. 3c: {_DRIVE.slope_per_um:g} "
                         f"N/um per N above {_DRIVE.threshold_um:g} um) would push a still "
                         f"finger harder than its friction at rest ({_DRIVE.mu0:g} F_n), "
                         "through which the plate drives it")
    limit_um = _PHASE_DEFAULTS["amplitude_um"]
    if args.amplitude_um > limit_um:
        warn(f"--amplitude-um {args.amplitude_um:g}: above {limit_um:g} um, beyond seed 004's "
             "measurements (Fig. 3c): the force's line is extrapolated")


def _phase_shift(ring: RingResonator, args: argparse.Namespace) -> dict:
    """Seed 004, Fig. 4 for the first --orders pair: travelling-wave ratio (min over max
    of the envelope on the straight) and force (N, + towards +x) on a still finger at
    each phase shift phi of the symmetric mode over the asymmetric (W_sym = e^{j phi} W_asym)."""
    order = args.orders[0]
    steps = int(round(180.0 / args.phase_step_deg))
    phase_deg = np.linspace(-180.0, 180.0, 2 * steps + 1)
    params = DrivingForceParams()
    wave = ring_wave(ring, order)
    responses = [phase_shift_response(wave, np.radians(phase_deg), args.amplitude_um, f, params)
                 for f in args.normal_force_n]
    ratio = responses[0][0]
    forces = np.array([force for _, force in responses]) + 0.0  # + 0.0: no -0.0
    return {"order": order, "amplitude_um": args.amplitude_um,
            "normal_force_n": list(args.normal_force_n),
            "slope_per_um": params.slope_per_um, "threshold_um": params.threshold_um,
            "rows": [{"phase_deg": float(p), "ratio": float(r), "force_n": forces[:, i].tolist()}
                     for i, (p, r) in enumerate(zip(phase_deg, ratio))]}


def _print_phase(phase: dict) -> None:
    print(f"phase shift phi of order {phase['order']}'s pair, W_sym = e^(j phi) W_asym, "
          f"{phase['amplitude_um']:g} um each (seed 004, Fig. 4)")
    print("ratio: min over max of the envelope along the straight; force on a still finger "
          "(+ towards +x):")
    print(f"{phase['slope_per_um']:g} N/um per N of normal force above "
          f"{phase['threshold_um']:g} um (Fig. 3c)")
    print("phase_deg   ratio" + "".join(f"  {f'force_n@{f:g}N':>13s}"
                                          for f in phase["normal_force_n"]))
    for row in phase["rows"]:
        print(f"{row['phase_deg']:9.1f}  {row['ratio']:6.4f}"
              + "".join(f"  {f:13.4g}" for f in row["force_n"]))


def _check_band(ring: RingResonator, f_min_hz: float, f_max_hz: float) -> None:
    """Refuse a --band reaching above order MAX_MODE_ORDER or a wavelength under the
    thickness; warn where its top is outside the model's validity."""
    if not f_min_hz < f_max_hz:
        raise ModesError(f"--band {f_min_hz:g} {f_max_hz:g}: MIN_HZ must be below MAX_HZ")
    order = ring.order_at(f_max_hz)
    if order > MAX_MODE_ORDER + 0.5:
        raise ModesError(f"--band {f_min_hz:g} {f_max_hz:g}: reaches order {order:.0f}; at "
                         f"most {MAX_MODE_ORDER}, the highest mode order frictex computes")
    wavelength_mm = 2e3 * np.pi / float(ring.k_s(2 * np.pi * f_max_hz))
    check_wavelength(f"--band {f_min_hz:g} {f_max_hz:g}", wavelength_mm, ring.thickness_mm,
                     VALID_WAVELENGTH_IN_THICKNESSES["euler-bernoulli"], _BEYOND)


def _pair_summary(ring: RingResonator, sym, asym) -> dict:
    ratio = ring.length_mm / ring.radius_mm
    crossings = [c for c in ring.crossings(sym.order)
                 if ratio / _RATIO_WINDOW <= c <= ratio * _RATIO_WINDOW]
    return {"order": sym.order, "symmetric_hz": sym.frequency_hz,
            "asymmetric_hz": asym.frequency_hz,
            "split_hz": asym.frequency_hz - sym.frequency_hz,
            "wavelength_mm": sym.wavelength_mm, "degenerate_l_over_r": crossings}


def _print_table(ring: RingResonator, modes, pairs: list[dict], band) -> None:
    ratio = ring.length_mm / ring.radius_mm
    print(f"ring L {ring.length_mm:g} mm, R {ring.radius_mm:g} mm (L/R {ratio:.4g}), "
          f"h {ring.thickness_mm:g} mm, w {ring.width_mm:g} mm, E {ring.youngs_gpa:g} GPa, "
          f"rho {ring.density_kg_m3:g} kg/m^3 (seed 004, eqs 6-11)")
    if band:
        print(f"every mode between {band[0]:g} and {band[1]:g} Hz:")
        print("order  kind        frequency_hz  wavelength_mm")
        for m in modes:
            print(f"{m.order:5d}  {m.kind:10s}  {format_hz(m.frequency_hz, 12, 2)}  "
                  f"{m.wavelength_mm:13.3f}")
        return
    print("order  symmetric_hz  asymmetric_hz  split_hz  wavelength_mm  degenerate at L/R "
          f"(R fixed; within x{_RATIO_WINDOW:g} of {ratio:.4g})")
    for p in pairs:
        lr = " ".join(f"{c:.4f}" for c in p["degenerate_l_over_r"]) or "none"
        # the split to the frequencies' precision: 0.00 at a crossing, not its float noise
        split = format_hz(p["split_hz"], 8, 2, scale_hz=min(p["symmetric_hz"], p["asymmetric_hz"]))
        print(f"{p['order']:5d}  {format_hz(p['symmetric_hz'], 12, 2)}  "
              f"{format_hz(p['asymmetric_hz'], 13, 2)}  {split}  {p['wavelength_mm']:13.3f}  {lr}")


def _plot(ring: RingResonator, orders: list[int], phase: dict | None = None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ratio = ring.length_mm / ring.radius_mm
    # the table's window, so that every crossing it lists is on the plot
    ratios = np.linspace(ratio / _RATIO_WINDOW, ratio * _RATIO_WINDOW, 61)
    if phase is None:
        fig, axes = plt.subplots(len(orders), 1, figsize=(7, 3 * len(orders)), squeeze=False)
        split_axes = axes[:, 0]
    else:  # a last row: ratio and force against the phase shift
        fig = plt.figure(figsize=(7, 3 * (len(orders) + 1)))
        grid = fig.add_gridspec(len(orders) + 1, 2)
        split_axes = [fig.add_subplot(grid[i, :]) for i in range(len(orders))]
        _plot_phase(fig.add_subplot(grid[-1, 0]), fig.add_subplot(grid[-1, 1]), phase)
    for ax, n in zip(split_axes, orders):
        freqs = np.array([[m.frequency_hz for m in ring.with_length(r * ring.radius_mm).pair(n)]
                          for r in ratios])
        ax.plot(ratios, freqs[:, 1] - freqs[:, 0], label="asymmetric - symmetric")
        ax.axhline(0.0, color="k", lw=0.5)
        shown = [c for c in ring.crossings(n) if ratios[0] <= c <= ratios[-1]]
        for i, c in enumerate(shown):
            ax.axvline(c, color="k", lw=0.5, label="degenerate (split 0)" if i == 0 else None)
        ax.axvline(ratio, color="r", lw=0.8, label=f"this ring, L/R {ratio:.3g}")
        ax.set(xlabel="L/R (R fixed)", ylabel="split (Hz)",
               title=f"order {n}: {ring.pair(n)[0].frequency_hz:.0f} Hz at L/R {ratio:.3g}")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _plot_phase(ratio_ax, force_ax, phase: dict) -> None:
    """Seed 004, Fig. 4b and 4c: ratio and force against the phase shift."""
    phase_deg = [row["phase_deg"] for row in phase["rows"]]
    ratio_ax.plot(phase_deg, [row["ratio"] for row in phase["rows"]], "o-", ms=3)
    ratio_ax.set(xlabel="phase shift (deg)", ylabel="travelling-wave ratio", ylim=(0, 1.05),
                 title=f"order {phase['order']}, {phase['amplitude_um']:g} um (Fig. 4b)")
    for i, normal_n in enumerate(phase["normal_force_n"]):
        force_ax.plot(phase_deg, [row["force_n"][i] for row in phase["rows"]], "o-", ms=3,
                      label=f"F_n {normal_n:g} N")
    force_ax.axhline(0.0, color="k", lw=0.5)
    force_ax.set(xlabel="phase shift (deg)", ylabel="force on a still finger (N, +x)",
                 title="Fig. 4c")
    force_ax.legend(fontsize=8)
