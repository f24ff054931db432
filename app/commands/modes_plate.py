"""2D plate with X and Y modes of order k (seed 001, eqs 2, 6 and 8).

Mode shapes sin(lambda_k x / a) and sin(lambda_k y / b), lambda_k = (2k + 1) pi / 2;
frequencies from the plate equation at that wavenumber (a strip estimate). Four
actuators wired as V_AC and V_BD: mode X follows V_AC + V_BD, mode Y V_AC - V_BD.
Seed 001 does not name the plate's material, so --youngs-gpa and --density are required.
--plot maps both shapes and det Phi over the second finger's position for the first
finger at --finger (seed 001, Fig. 1).
"""

from __future__ import annotations

import argparse

import numpy as np

from frictex.app.commands.modes_output import (add_output_arguments, check_below, check_plot,
                                               check_wavelength, density_kg_m3, dimension_mm,
                                               print_modes, refuse_without, save_figure, warn,
                                               youngs_gpa)
from frictex.device.structures.beam import VALID_WAVELENGTH_IN_THICKNESSES, ModesError
from frictex.textures.keys import MAX_MODE_ORDER
from frictex.device.structures.plate2d import AXES, Plate2D


#: both shapes (unit peak) under this at finger 1: det Phi is 0 over the whole plate
NODE_TOLERANCE = 1e-9


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--width-mm", type=dimension_mm, default=140.0, help="side a along x (default 140)")
    parser.add_argument("--height-mm", type=dimension_mm, default=140.0, help="side b along y (default 140)")
    parser.add_argument("--thickness-mm", type=dimension_mm, default=4.0, help="thickness h (default 4)")
    parser.add_argument("--youngs-gpa", type=youngs_gpa, required=True, help="Young's modulus E in GPa")
    parser.add_argument("--density", type=density_kg_m3, required=True, help="density in kg/m^3")
    parser.add_argument("--poisson", type=float, default=0.33, help="Poisson's ratio (default 0.33)")
    parser.add_argument("--order", type=int, default=8, metavar="K",
                        help=f"k of seed 001 eq 6, 1 to {MAX_MODE_ORDER} (default 8, the paper's "
                             "prototype)")
    parser.add_argument("--finger", type=float, nargs=2, metavar=("X_MM", "Y_MM"),
                        help="first finger for the det Phi map (default 0.25 a, 0.5 b as Fig. 1)")
    add_output_arguments(parser)


def run(args: argparse.Namespace) -> int:
    check_plot(args.plot)
    if args.finger is not None and not args.plot:
        refuse_without("--finger", args.finger, "--plot")
    if not 1 <= args.order <= MAX_MODE_ORDER:
        raise ModesError(f"--order {args.order}: expected 1 to {MAX_MODE_ORDER} (k of seed 001, "
                         "eq 6; the highest mode order frictex computes)")
    for option, value in (("--width-mm", args.width_mm), ("--height-mm", args.height_mm)):
        check_below("--thickness-mm", args.thickness_mm, option, value,
                    "a plate is thin against its sides")
    plate = Plate2D(args.width_mm, args.height_mm, args.thickness_mm, args.youngs_gpa,
                    args.density, poisson=args.poisson, order=args.order)
    finger = args.finger or (0.25 * plate.width_mm, 0.5 * plate.height_mm)
    if not (0 <= finger[0] <= plate.width_mm and 0 <= finger[1] <= plate.height_mm):
        raise ModesError(f"--finger {finger[0]:g} {finger[1]:g} is outside the "
                         f"{plate.width_mm:g} x {plate.height_mm:g} mm plate")
    for axis in AXES:
        check_wavelength(f"--order {plate.order} ({axis})", plate.wavelength_mm(axis),
                         plate.thickness_mm, VALID_WAVELENGTH_IN_THICKNESSES["euler-bernoulli"],
                         "Kirchhoff's plate leaves out shear and rotary inertia, which make "
                         "the true frequency lower")
    modes = [{"axis": axis, "order": plate.order, "frequency_hz": plate.frequency_hz(axis),
              "wavelength_mm": plate.wavelength_mm(axis), "nodes_mm": plate.nodes_mm(axis).tolist()}
             for axis in AXES]
    title = (f"plate {plate.width_mm:g} x {plate.height_mm:g} x {plate.thickness_mm:g} mm, "
             f"E {plate.youngs_gpa:g} GPa, rho {plate.density_kg_m3:g} kg/m^3, k = {plate.order}")
    print_modes(title, modes, args.json)
    if args.plot:
        on_nodes = _on_both_nodes(plate, finger)
        if on_nodes:
            warn(f"--finger {finger[0]:g} {finger[1]:g}: on a node of both modes, so det Phi "
                 "(seed 001, eq 8) is 0 wherever the second finger is; the map is blank. "
                 "Move --finger off the nodes")
        save_figure(_plot(plate, finger, title, on_nodes), args.plot)
    return 0


def _on_both_nodes(plate: Plate2D, finger) -> bool:
    """Whether (x, y) (mm) is on a node of both modes: det Phi with a finger there is
    phi_X phi_Y' - phi_Y phi_X', 0 for every second finger."""
    return bool(np.max(np.abs(plate.phi(*finger))) < NODE_TOLERANCE)


def _plot(plate: Plate2D, finger, title: str, on_nodes: bool):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.linspace(0, plate.width_mm, 281)
    y = np.linspace(0, plate.height_mm, 281)
    xx, yy = np.meshgrid(x, y)
    phi = plate.phi(xx, yy)
    # on the nodes only rounding (1e-16) is left of det Phi: shown as the 0 it is
    det = np.zeros_like(xx) if on_nodes else plate.det(finger[0], finger[1], xx, yy)
    extent = (0, plate.width_mm, plate.height_mm, 0)  # y down, as on the screen
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.6))
    panels = ((phi[..., 0], "mode X"), (phi[..., 1], "mode Y"),
              (det, f"det Phi, finger 1 at ({finger[0]:g}, {finger[1]:g}) mm"))
    for ax, (img, name) in zip(axes, panels):
        lim = np.max(np.abs(img)) or 1.0
        im = ax.imshow(img, extent=extent, cmap="RdBu", vmin=-lim, vmax=lim)
        ax.contour(xx, yy, img, levels=[0.0], colors="k", linewidths=0.5)
        ax.set(xlabel="x (mm)", ylabel="y (mm)", title=name)
        fig.colorbar(im, ax=ax, shrink=0.8)
    axes[2].plot(*finger, "o", color="gold", markeredgecolor="k")
    if on_nodes:
        axes[2].text(0.5, 0.5, "det Phi = 0 everywhere:\nfinger 1 is on a node\nof both modes",
                     transform=axes[2].transAxes, ha="center", va="center",
                     bbox={"facecolor": "white", "edgecolor": "k"})
    fig.suptitle(title + " (black: zero lines)")
    fig.tight_layout()
    return fig
