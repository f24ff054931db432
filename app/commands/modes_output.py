"""What ``frictex modes`` prints for every structure: a table or JSON of the modes, and plots."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from frictex.app.commands.argtypes import bounded
from frictex.app.engine.outfile import check_writable, write_file
from frictex.device.errors import require_extra
from frictex.device.structures.beam import MIN_WAVELENGTH_IN_THICKNESSES, ModesError
from frictex.textures.keys import MAX_MODE_ORDER

#: physically generous ranges of a structure's dimensions (mm: 1 um to 100 m), Young's
#: modulus (GPa: 1 MPa, a soft rubber, to 2000 GPa, above diamond's 1220) and density
#: (kg/m^3: 1, about air's, to 30000, above osmium's 22590)
DIMENSION_MM = (1e-3, 1e5)
YOUNGS_GPA = (1e-3, 2000.0)
DENSITY_KG_M3 = (1.0, 30_000.0)
dimension_mm = bounded(float, *DIMENSION_MM, "mm")
youngs_gpa = bounded(float, *YOUNGS_GPA, "GPa")
density_kg_m3 = bounded(float, *DENSITY_KG_M3, "kg/m^3")

#: a plot's PNG at most (bytes): 8 x 9 inches at 110 dpi, 4 bytes a pixel
PLOT_BYTES = 880 * 990 * 4


def add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """--json and --plot, shared by every structure."""
    parser.add_argument("--json", action="store_true",
                        help='print {"modes": [{"order", "frequency_hz", "wavelength_mm", '
                             '"nodes_mm"}, ...]} instead of a table')
    add_plot_argument(parser, "also write a plot of the modes and of det Phi over finger "
                              "positions")


def add_plot_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """--plot FILE.png, whose ``what`` is the help."""
    parser.add_argument("--plot", metavar="PNG", type=_png_name, help=f"{what} (a .png file)")


def _png_name(text: str) -> Path:
    if Path(text).suffix.lower() != ".png":
        raise argparse.ArgumentTypeError(f"{text!r}: the plot is a PNG image; give a file "
                                          "name ending in .png")
    return Path(text)


def check_plot(path: Path | None) -> None:
    """Refuse, before any work, a ``--plot`` that cannot be written (a folder, a folder
    that does not exist, no room), or matplotlib missing."""
    if path is not None:
        check_writable("--plot", path, PLOT_BYTES)
        require_extra("report", "matplotlib", "--plot")


def check_orders(orders: list[int], lowest: int, what: str) -> None:
    """Refuse ``--orders`` below ``lowest`` (``what`` says why that is the lowest), above
    :data:`~frictex.textures.keys.MAX_MODE_ORDER` or given twice, in one line."""
    for order in orders:
        if order < lowest:
            raise ModesError(f"--orders {order}: a mode order is at least {lowest} ({what})")
        if order > MAX_MODE_ORDER:
            raise ModesError(f"--orders {order}: at most {MAX_MODE_ORDER}, the highest mode "
                             f"order frictex computes (as in a scene's [device.structure])")
    twice = next((o for i, o in enumerate(orders) if o in orders[:i]), None)
    if twice is not None:
        raise ModesError(f"--orders {' '.join(map(str, orders))}: {twice} is given twice; "
                         "give each order once")


def check_wavelength(which: str, wavelength_mm: float, thickness_mm: float,
                     valid_in_thicknesses: float, beyond: str) -> None:
    """Refuse a mode (``which``, e.g. "--orders 120") whose wavelength is under
    ``MIN_WAVELENGTH_IN_THICKNESSES`` thicknesses, where no bending theory holds; under
    ``valid_in_thicknesses`` warn on stderr, ``beyond`` saying what the model misses."""
    if wavelength_mm < MIN_WAVELENGTH_IN_THICKNESSES * thickness_mm:
        raise ModesError(f"{which}: wavelength {wavelength_mm:.3g} mm is shorter than the "
                         f"thickness {thickness_mm:g} mm (--thickness-mm): no bending theory "
                         "holds there (the wave runs along the surfaces)")
    if wavelength_mm < valid_in_thicknesses * thickness_mm:
        warn(f"{which}: wavelength {wavelength_mm:.3g} mm is under {valid_in_thicknesses:g} "
             f"thicknesses ({valid_in_thicknesses * thickness_mm:g} mm): outside the "
             f"model's validity, {beyond}")


def check_below(option: str, value: float, limit_option: str, limit: float, why: str) -> None:
    """Refuse ``option`` ``value`` (mm) unless it is below ``limit_option`` ``limit``."""
    if not value < limit:
        raise ModesError(f"{option} {value:g}: must be below {limit_option} {limit:g} ({why})")


def refuse_without(option: str, given, needed: str) -> None:
    """Refuse ``option`` (given as ``given``, a number or a list of them) used without
    the option ``needed`` that it only modifies."""
    shown = " ".join(f"{v:g}" for v in given) if isinstance(given, list) else f"{given:g}"
    raise ModesError(f"{option} {shown}: needs {needed}")


def warn(message: str) -> None:
    """One line ``frictex: warning: message`` on stderr."""
    print(f"frictex: warning: {message}", file=sys.stderr)


def check_finite(modes: list[dict]) -> None:
    """Refuse, in one line, modes whose frequency (Hz) or wavelength (mm) is not a finite
    number above 0 (what a structure far outside the ranges above can give): printed,
    they would be Infinity (invalid JSON) or 0.0 Hz."""
    for m in modes:
        for key in ("frequency_hz", "wavelength_mm") & m.keys():
            if not (math.isfinite(m[key]) and m[key] > 0):
                raise ModesError(f"order {m['order']}: {key} came out {m[key]:g}, not a finite "
                                 "number above 0; check the dimensions and material")


def format_hz(value_hz: float, width: int = 12, decimals: int = 1,
              scale_hz: float | None = None) -> str:
    """A frequency or a difference of frequencies (Hz) in a table's ``width`` columns: to
    ``decimals`` places, or in 3 significant digits where ``scale_hz`` (default the value
    itself; for a split, the frequencies it separates) would show as 0 to those places.
    Never -0."""
    scale_hz = abs(value_hz) if scale_hz is None else scale_hz
    if scale_hz >= 0.5 * 10.0 ** -decimals:
        return f"{round(value_hz, decimals) + 0.0:{width}.{decimals}f}"
    return f"{value_hz:{width}.3g}"


def print_modes(title: str, modes: list[dict], as_json: bool) -> None:
    """Print ``modes`` (dicts with order, frequency_hz, wavelength_mm, nodes_mm) as JSON or a
    table, after :func:`check_finite`."""
    check_finite(modes)
    if as_json:
        print(json.dumps({"modes": modes}, indent=2))
        return
    print(title)
    extra = [k for k in modes[0] if k not in ("order", "frequency_hz", "wavelength_mm", "nodes_mm")]
    print("".join(f"{k:>6s} " for k in extra) + "order  frequency_hz  wavelength_mm  nodes  nodes_mm")
    for m in modes:
        nodes = " ".join(f"{x:.2f}" for x in m["nodes_mm"])
        print("".join(f"{str(m[k]):>6s} " for k in extra)
              + f"{m['order']:5d}  {format_hz(m['frequency_hz'])}  {m['wavelength_mm']:13.3f}  "
                f"{len(m['nodes_mm']):5d}  {nodes}")


def save_figure(fig, path: Path) -> None:
    """Write ``fig`` to ``path`` as a PNG, all or nothing (``app.engine.outfile``), and
    say where on stderr (stdout holds the table or the JSON)."""
    import matplotlib.pyplot as plt
    try:
        write_file(path, lambda to: fig.savefig(to, format="png", dpi=110), PLOT_BYTES)
    finally:
        plt.close(fig)
    print(f"plot written to {path}", file=sys.stderr)
