"""Ring resonator (seed 004): degenerate symmetric/asymmetric pairs and where they coincide.

The oblong ring of seed 004 (two straights of length L, two semicircles of radius R)
has, for each order n (wavelengths around the ring), a symmetric and an asymmetric
mode; driven 90 degrees apart they make a travelling wave, best where their
frequencies coincide. Defaults are seed 004's design (aluminium 5052, L 140 mm,
R 50 mm, h 2.75 mm, w 30 mm). For each order the table gives both frequencies, their
split, and the L/R ratios (R fixed) at which the pair is exactly degenerate
(seed 004, Fig. 2c). --band lists every mode between two frequencies instead.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from frictex.app.commands.argtypes import positive_float
from frictex.app.commands.modes_output import (add_plot_argument, check_below, check_orders,
                                               check_plot, check_wavelength, save_figure, warn)
from frictex.device.structures.beam import VALID_WAVELENGTH_IN_THICKNESSES, ModesError
from frictex.device.structures.ring import THIN_RING_H_OVER_R, RingResonator
from frictex.textures.keys import MAX_MODE_ORDER

#: crossings listed: L/R within this factor of the ring's own
_RATIO_WINDOW = 2.0
#: what the model (Rayleigh straights, thin curved beam) misses at short wavelengths
_BEYOND = "shear makes the true frequency lower"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--length-mm", type=positive_float, default=140.0,
                        help="length L of each straight part (default 140)")
    parser.add_argument("--radius-mm", type=positive_float, default=50.0,
                        help="radius R of the semicircles, to the neutral line (default 50)")
    parser.add_argument("--thickness-mm", type=positive_float, default=2.75,
                        help="thickness h (default 2.75)")
    parser.add_argument("--width-mm", type=positive_float, default=30.0, help="width w (default 30)")
    parser.add_argument("--youngs-gpa", type=positive_float, default=69.0,
                        help="Young's modulus E in GPa (default 69)")
    parser.add_argument("--density", type=positive_float, default=2680.0,
                        help="density in kg/m^3 (default 2680)")
    parser.add_argument("--orders", type=int, nargs="+", default=[24], metavar="N",
                        help="mode orders, wavelengths around the ring, 2 to "
                             f"{MAX_MODE_ORDER} (default 24)")
    parser.add_argument("--band", type=positive_float, nargs=2, metavar=("MIN_HZ", "MAX_HZ"),
                        help="list every mode between two frequencies instead of --orders")
    parser.add_argument("--json", action="store_true",
                        help='print {"modes": [{"order", "kind", "frequency_hz"}, ...], '
                             '"pairs": [...]} instead of a table')
    add_plot_argument(parser, "also write each pair's frequency split against L/R (seed 004, "
                              "Fig. 2c)")


def run(args: argparse.Namespace) -> int:
    check_plot(args.plot)
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
        found = [ring.pair(n) for n in args.orders]
        modes = [m for pair in found for m in pair]
        pairs = [_pair_summary(ring, sym, asym) for sym, asym in found]
    if args.json:
        print(json.dumps({"modes": [{"order": m.order, "kind": m.kind, "frequency_hz": m.frequency_hz}
                                    for m in modes], "pairs": pairs}, indent=2))
    else:
        _print_table(ring, modes, pairs, args.band)
    if args.plot:
        save_figure(_plot(ring, [p["order"] for p in pairs] or sorted({m.order for m in modes})),
                    args.plot)
    return 0


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
            print(f"{m.order:5d}  {m.kind:10s}  {m.frequency_hz:12.2f}  {m.wavelength_mm:13.3f}")
        return
    print("order  symmetric_hz  asymmetric_hz  split_hz  wavelength_mm  degenerate at L/R "
          f"(R fixed; within x{_RATIO_WINDOW:g} of {ratio:.4g})")
    for p in pairs:
        lr = " ".join(f"{c:.4f}" for c in p["degenerate_l_over_r"]) or "none"
        print(f"{p['order']:5d}  {p['symmetric_hz']:12.2f}  {p['asymmetric_hz']:13.2f}  "
              f"{round(p['split_hz'], 2) + 0.0:8.2f}  {p['wavelength_mm']:13.3f}  {lr}")


def _plot(ring: RingResonator, orders: list[int]):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ratio = ring.length_mm / ring.radius_mm
    ratios = np.linspace(ratio / 1.25, ratio * 1.25, 61)
    fig, axes = plt.subplots(len(orders), 1, figsize=(7, 3 * len(orders)), squeeze=False)
    for ax, n in zip(axes[:, 0], orders):
        freqs = np.array([[m.frequency_hz for m in ring.with_length(r * ring.radius_mm).pair(n)]
                          for r in ratios])
        ax.plot(ratios, freqs[:, 1] - freqs[:, 0], label="asymmetric - symmetric")
        ax.axhline(0.0, color="k", lw=0.5)
        for c in ring.crossings(n):
            if ratios[0] <= c <= ratios[-1]:
                ax.axvline(c, color="k", lw=0.5)
        ax.axvline(ratio, color="r", lw=0.8, label=f"this ring, L/R {ratio:.3g}")
        ax.set(xlabel="L/R (R fixed)", ylabel="split (Hz)",
               title=f"order {n}: {ring.pair(n)[0].frequency_hz:.0f} Hz at L/R {ratio:.3g}")
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
