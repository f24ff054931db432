"""Free-free beam: flexural frequencies, wavelengths and nodes (seed 000, eq 2, Table I).

Orders count flexural modes from the first bending mode; mode n has n + 1 nodes.
Defaults are seed 000's aluminium beam (Table I). With two orders, --plot also maps
det Phi over the two finger positions (seed 000, Fig. 8): its zero lines are where two
fingers cannot be given independent amplitudes.
"""

from __future__ import annotations

import argparse

import numpy as np

from frictex.app.commands.modes_output import (add_output_arguments, check_below, check_orders,
                                               check_plot, check_wavelength, print_modes,
                                               save_figure)
from frictex.app.commands.argtypes import positive_float
from frictex.device.structures.beam import (THEORIES, VALID_WAVELENGTH_IN_THICKNESSES,
                                            FreeFreeBeam, ModesError)

#: what each theory misses where the wavelength is too short for it
_BEYOND = {"euler-bernoulli": "shear and rotary inertia make the true frequency lower "
                              "(try --theory timoshenko)",
           "timoshenko": "the section no longer stays plane"}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--length-mm", type=positive_float, default=350.0, help="length L (default 350)")
    parser.add_argument("--width-mm", type=positive_float, default=6.0, help="width b (default 6)")
    parser.add_argument("--thickness-mm", type=positive_float, default=6.0,
                        help="thickness h, bending across it (default 6)")
    parser.add_argument("--youngs-gpa", type=positive_float, default=57.0,
                        help="Young's modulus E in GPa (default 57)")
    parser.add_argument("--density", type=positive_float, default=2561.0,
                        help="density in kg/m^3 (default 2561)")
    parser.add_argument("--poisson", type=float, default=0.33,
                        help="Poisson's ratio, used by Timoshenko (default 0.33)")
    parser.add_argument("--theory", choices=THEORIES, default="euler-bernoulli",
                        help="beam theory (default euler-bernoulli; timoshenko adds shear "
                             "and rotary inertia)")
    parser.add_argument("--orders", type=int, nargs="+", default=[16, 17], metavar="N",
                        help="flexural mode orders, 1 = first bending mode (default 16 17)")
    add_output_arguments(parser)


def run(args: argparse.Namespace) -> int:
    check_plot(args.plot)
    check_orders(args.orders, 1, "1 = the first bending mode")
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
    print_modes(title, modes, args.json)
    if args.plot:
        save_figure(_plot(beam, args.orders, title), args.plot)
    return 0


def _plot(beam: FreeFreeBeam, orders: list[int], title: str):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.linspace(0, beam.length_mm, 1401)
    two = len(orders) == 2
    fig, axes = plt.subplots(2 if two else 1, 1, figsize=(8, 9 if two else 4), squeeze=False)
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
