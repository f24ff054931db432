"""Free-free beam: flexural frequencies, wavelengths and nodes (seed 000, eq 2, Table I).

Orders count flexural modes from the first bending mode; mode n has n + 1 nodes.
Defaults are seed 000's aluminium beam (Table I). With two orders, --plot also maps
det Phi over the two finger positions (seed 000, Fig. 8): its zero lines are where two
fingers cannot be given independent amplitudes. With two adjacent orders, --travelling
adds the local travelling-wave ratio along the beam when the two are driven in
quadrature (seed 002, eq 4; ratio as seed 004, Fig. 4 defines it): where the wave can push.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from frictex.app.commands.modes_output import (add_output_arguments, check_below, check_orders,
                                               check_plot, check_wavelength, density_kg_m3,
                                               dimension_mm, print_modes, refuse_without,
                                               save_figure, youngs_gpa)
from frictex.app.commands.argtypes import bounded, share
from frictex.device.actuation.travelling import TwoModeWave, beam_wave
from frictex.device.structures.beam import (THEORIES, VALID_WAVELENGTH_IN_THICKNESSES,
                                            FreeFreeBeam, ModesError)

#: what each theory misses where the wavelength is too short for it
_BEYOND = {"euler-bernoulli": "shear and rotary inertia make the true frequency lower "
                              "(try --theory timoshenko)",
           "timoshenko": "the section no longer stays plane"}
#: --travelling's defaults: positions listed, and the ratios whose spans are given (the
#: bundled travelling-wave beam scenes keep to where the ratio is 0.68 or more)
_TRAVELLING_DEFAULTS = {"points": 25, "threshold": [0.68, 0.9]}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--length-mm", type=dimension_mm, default=350.0, help="length L (default 350)")
    parser.add_argument("--width-mm", type=dimension_mm, default=6.0, help="width b (default 6)")
    parser.add_argument("--thickness-mm", type=dimension_mm, default=6.0,
                        help="thickness h, bending across it (default 6)")
    parser.add_argument("--youngs-gpa", type=youngs_gpa, default=57.0,
                        help="Young's modulus E in GPa (default 57)")
    parser.add_argument("--density", type=density_kg_m3, default=2561.0,
                        help="density in kg/m^3 (default 2561)")
    parser.add_argument("--poisson", type=float, default=0.33,
                        help="Poisson's ratio, used by Timoshenko (default 0.33)")
    parser.add_argument("--theory", choices=THEORIES, default="euler-bernoulli",
                        help="beam theory (default euler-bernoulli; timoshenko adds shear "
                             "and rotary inertia)")
    parser.add_argument("--orders", type=int, nargs="+", default=[16, 17], metavar="N",
                        help="flexural mode orders, 1 = first bending mode (default 16 17)")
    parser.add_argument("--travelling", action="store_true",
                        help="also give the local travelling-wave ratio (min over max of the "
                             "local envelope) along the beam of two adjacent --orders N N+1 "
                             "driven in quadrature (seed 002, eq 4)")
    parser.add_argument("--points", type=bounded(int, 2, 1001, "positions"), metavar="K",
                        help="with --travelling: positions listed, evenly spaced from end to end "
                             "(default 25)")
    parser.add_argument("--threshold", type=share, nargs="+", metavar="RATIO",
                        help="with --travelling: give the spans (mm) where the ratio is at least "
                             "each RATIO, 0 to 1 (default 0.68 0.9)")
    add_output_arguments(parser)


def run(args: argparse.Namespace) -> int:
    check_plot(args.plot)
    check_orders(args.orders, 1, "1 = the first bending mode")
    _check_travelling_options(args)
    for option, value in (("--thickness-mm", args.thickness_mm), ("--width-mm", args.width_mm)):
        check_below(option, value, "--length-mm", args.length_mm, "a beam is longer than its "
                                                                  "cross-section")
    beam = FreeFreeBeam(args.length_mm, args.width_mm, args.thickness_mm, args.youngs_gpa,
                        args.density, theory=args.theory, poisson=args.poisson)
    for n in args.orders:
        try:
            wavelength_mm = beam.wavelength_mm(n)
        except ModesError as exc:  # above the Timoshenko cutoff
            raise ModesError(f"--orders {n}: {exc}") from None
        check_wavelength(f"--orders {n}", wavelength_mm, beam.thickness_mm,
                         VALID_WAVELENGTH_IN_THICKNESSES[beam.theory], _BEYOND[beam.theory])
    modes = [{"order": n, "frequency_hz": beam.frequency_hz(n),
              "wavelength_mm": beam.wavelength_mm(n), "nodes_mm": beam.nodes_mm(n).tolist()}
             for n in args.orders]
    title = (f"free-free beam {beam.length_mm:g} x {beam.width_mm:g} x {beam.thickness_mm:g} mm, "
             f"E {beam.youngs_gpa:g} GPa, rho {beam.density_kg_m3:g} kg/m^3, {beam.theory}")
    travelling = _travelling(beam, args) if args.travelling else None
    if travelling is None:
        print_modes(title, modes, args.json)
    elif args.json:
        shown = {k: v for k, v in travelling.items() if k != "grid"}  # the plot's
        print(json.dumps({"modes": modes, "travelling": shown}, indent=2))
    else:
        print_modes(title, modes, False)
        _print_travelling(travelling)
    if args.plot:
        save_figure(_plot(beam, args.orders, title, travelling), args.plot)
    return 0


def _check_travelling_options(args: argparse.Namespace) -> None:
    """Refuse --travelling without two adjacent orders, and its options without it; fill
    in the defaults."""
    for name, default in _TRAVELLING_DEFAULTS.items():
        given = getattr(args, name)
        if given is not None and not args.travelling:
            refuse_without(f"--{name}", given, "--travelling")
        if given is None:
            setattr(args, name, default)
    if args.travelling and not (len(args.orders) == 2 and args.orders[1] == args.orders[0] + 1):
        raise ModesError(f"--travelling: needs two adjacent --orders N N+1 (got "
                         f"{' '.join(map(str, args.orders))}), the pair that makes the wave")


def _travelling(beam: FreeFreeBeam, args: argparse.Namespace) -> dict:
    """The local travelling-wave ratio of --orders N N+1 in quadrature: at --points
    positions, on the whole grid (for the plot), and its spans at each --threshold."""
    wave = beam_wave(beam, args.orders[0])
    ratio = wave.local_ratio(wave.modal(1.0, 1))
    positions = np.linspace(0.0, beam.length_mm, args.points)
    return {"orders": list(args.orders), "positions_mm": positions.tolist(),
            "ratio": np.interp(positions, wave.x_mm, ratio).tolist(),
            "spans": [{"threshold": t, "spans_mm": _spans(wave, ratio, t)} for t in args.threshold],
            "grid": (wave.x_mm, ratio)}


def _spans(wave: TwoModeWave, ratio: np.ndarray, threshold: float) -> list[list[float]]:
    """[start, end] (mm) of each run of the grid where ``ratio`` >= ``threshold``, its
    ends interpolated linearly to where the ratio crosses it."""
    x = wave.x_mm
    above = np.concatenate([[False], ratio >= threshold, [False]])
    starts = np.flatnonzero(~above[:-1] & above[1:])   # first index of each run
    ends = np.flatnonzero(above[:-1] & ~above[1:]) - 1  # last index of each run

    def crossing(i: int, j: int) -> float:  # between grid points i (below) and j (above)
        return float(x[i] + (threshold - ratio[i]) / (ratio[j] - ratio[i]) * (x[j] - x[i]))

    return [[float(x[s]) if s == 0 else crossing(s - 1, s),
             float(x[e]) if e == x.size - 1 else crossing(e + 1, e)] for s, e in zip(starts, ends)]


def _print_travelling(travelling: dict) -> None:
    a, b = travelling["orders"]
    print(f"travelling wave of modes {a} and {b} in quadrature (seed 002, eq 4)")
    print("local travelling-wave ratio: min over max of the envelope (seed 004, Fig. 4)")
    print("     x_mm   ratio")
    for x, r in zip(travelling["positions_mm"], travelling["ratio"]):
        print(f"{x:9.2f}  {r:6.3f}")
    for item in travelling["spans"]:
        spans = ", ".join(f"{s:.1f}-{e:.1f} mm" for s, e in item["spans_mm"]) or "nowhere"
        print(f"ratio >= {item['threshold']:g}: {spans}")


def _plot(beam: FreeFreeBeam, orders: list[int], title: str, travelling: dict | None = None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.linspace(0, beam.length_mm, 1401)
    two = len(orders) == 2
    if travelling is None:
        fig, axes = plt.subplots(2 if two else 1, 1, figsize=(8, 9 if two else 4), squeeze=False)
    else:  # shapes, ratio, det map; within the same 8 x 9 inches
        fig, axes = plt.subplots(3, 1, figsize=(8, 9), squeeze=False,
                                 gridspec_kw={"height_ratios": [1, 1, 2]})
        _plot_travelling(axes[1, 0], travelling)
        axes = axes[[0, 2]]
    ax = axes[0, 0]
    for n in orders:
        ax.plot(x, beam.shape(n, x), label=f"mode {n}, {beam.frequency_hz(n):.0f} Hz")
    ax.set(xlabel="x (mm)", ylabel="shape (unit RMS)", title=title)
    ax.legend(loc="upper right", fontsize=8)
    if two:
        g = np.linspace(0, beam.length_mm, 351)
        pa, pb = beam.phi(orders, g[:, None]), beam.phi(orders, g[None, :])
        det = pa[..., 0] * pb[..., 1] - pa[..., 1] * pb[..., 0]  # rows: finger a, cols: finger b
        ax = axes[1, 0]
        lim = np.max(np.abs(det))
        im = ax.imshow(det, origin="lower", extent=(0, beam.length_mm, 0, beam.length_mm),
                       cmap="RdBu", vmin=-lim, vmax=lim)
        ax.contour(g, g, det, levels=[0.0], colors="k", linewidths=0.5)
        ax.set(xlabel="finger b x (mm)", ylabel="finger a x (mm)",
               title=f"det Phi of modes {orders[0]}, {orders[1]} (black: det = 0)")
        fig.colorbar(im, ax=ax)
    fig.tight_layout()
    return fig


def _plot_travelling(ax, travelling: dict) -> None:
    """The local travelling-wave ratio along the beam, with each threshold's spans."""
    x, ratio = travelling["grid"]
    ax.plot(x, ratio, label="travelling-wave ratio")
    for item in travelling["spans"]:
        threshold = item["threshold"]
        ax.axhline(threshold, color="k", lw=0.5, ls="--", label=f"threshold {threshold:g}")
        for i, (start, end) in enumerate(item["spans_mm"]):
            ax.axvspan(start, end, alpha=0.1, color="g",
                       label=f"ratio >= {threshold:g} (shaded)" if i == 0 else None)
    ax.legend(fontsize=7, loc="lower right")
    ax.set(xlabel="x (mm)", ylabel="ratio", ylim=(0, 1.05),
           title="modes {} and {} in quadrature: local min / max of the envelope".format(
               *travelling["orders"]))
