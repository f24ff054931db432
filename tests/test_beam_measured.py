"""Measured mode tables (seed 000 Fig. 10 style scans), interpolated smoothly."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.device.structures.beam import MAX_MODES, FreeFreeBeam, ModesError
from frictex.device.structures.measured_modes import MeasuredModes

BEAM = FreeFreeBeam(350, 6, 6, 57, 2561)
SCAN_X = np.arange(0.0, 350.0 + 1e-9, 2.0)  # a 2 mm vibrometer grid
#: the model's largest |deflection| on the scan (2 at the free ends): a table is scaled to 1 there
PEAK = float(np.abs(BEAM.phi((16, 17), SCAN_X)).max())


def scan():
    return MeasuredModes(SCAN_X, BEAM.phi((16, 17), SCAN_X), ("A", "B"))


def test_scan_of_the_model_reproduces_it_and_its_nodes():
    modes = scan()
    x = np.linspace(0, 350, 3001)
    # spline error ~ h^4 beta^4 max|W| / 384 = 1e-4 (h = 2 mm, beta = 0.157 /mm), a few times
    # that in the end intervals, where not-a-knot has no slope information
    assert_allclose(modes.phi(x) * PEAK, BEAM.phi((16, 17), x), atol=5e-4)
    assert_allclose(modes.nodes_mm(0), BEAM.nodes_mm(16), atol=2e-3)
    assert modes.nodes_mm(1).size == 18


def test_exact_on_cubics_and_held_outside():
    x = np.linspace(10, 30, 7)
    cubic = lambda t: 0.01 * t ** 3 - 0.2 * t + 1  # noqa: E731
    modes = MeasuredModes(x, cubic(x)[:, None], ("m",))
    peak = np.abs(cubic(x)).max()
    assert_allclose(modes.phi(np.array([12.3, 27.9]))[:, 0] * peak, cubic(np.array([12.3, 27.9])),
                    rtol=1e-12)
    assert_allclose(modes.phi(np.array([0.0, 50.0]))[:, 0] * peak, cubic(np.array([10.0, 30.0])),
                    rtol=1e-12)
    assert modes.outside(np.array([0.0, 20.0, 50.0])).tolist() == [True, False, True]


def test_csv_round_trip(tmp_path):
    path = tmp_path / "scan.csv"
    rows = "\n".join(f"{x:.17g},{a:.17g},{b:.17g}" for x, (a, b) in
                     zip(SCAN_X, BEAM.phi((16, 17), SCAN_X)))
    path.write_text("# vibrometer scan, seed 000 beam\nx_mm,A,B\n" + rows + "\n")
    modes = MeasuredModes.from_csv(path)
    assert modes.names == ("A", "B")
    assert_allclose(modes.phi(SCAN_X) * PEAK, BEAM.phi((16, 17), SCAN_X), rtol=1e-15)


@pytest.mark.parametrize("text, match", [
    ("x,A\n0,1\n", "line 1: header must be 'x_mm"),
    ("x_mm,A\n0,1\n1,2\n2\n", "line 4: expected 2 values, got 1"),
    ("x_mm,A\n0,1\n1,abc\n", "line 3: .* not a number"),
    ("x_mm,A\n0,1\n1,inf\n", "line 3: values must be finite"),
    ("x_mm,A\n0,1\n2,2\n1,3\n3,4\n", "x = 1 mm follows 2 mm"),
    ("x_mm,A\n0,1\n1,2\n", "at least 4 positions, got 2"),
    ("x_mm,A,B\n0,0,0\n1,0,-0\n2,0,0\n3,0,0\n", "every deflection is 0: no mode moves"),
    ("x_mm,m1,m1\n0,1,1\n1,2,2\n2,3,1\n3,4,0\n", 'line 1: mode name "m1" appears twice'),
])
def test_bad_tables(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ModesError, match=match):
        MeasuredModes.from_csv(path)


def test_mode_columns_are_bounded_before_rows_are_read(tmp_path):
    """A header of 20,000 mode columns is refused at the header: the rows (here not
    even numbers) are never parsed, and no (p, p) matrix is built later."""
    names = ",".join(f"m{i}" for i in range(20_000))
    path = tmp_path / "wide.csv"
    path.write_text(f"x_mm,{names}\n" + "0,x\n" * 4)
    with pytest.raises(ModesError, match=r"line 1: 20000 mode columns; expected at most 26"):
        MeasuredModes.from_csv(path)
    at_bound = ",".join(f"m{i}" for i in range(MAX_MODES))
    path.write_text(f"x_mm,{at_bound}\n" + "".join(f"{x}" + ",1" * MAX_MODES + "\n" for x in range(4)))
    assert len(MeasuredModes.from_csv(path).names) == MAX_MODES


@pytest.mark.parametrize("unit", [1e-100, 1e-9, 1e100])
def test_a_table_in_any_unit_is_the_same_table(unit):
    """Scaled to 1 at its largest deflection: a scan in metres, or of 1e-100 (whose modal
    solve overflowed to NaN commands, 80,000 of 80,050 rows of a replay), is the scan."""
    shapes = BEAM.phi((16, 17), SCAN_X)
    modes = MeasuredModes(SCAN_X, shapes * unit, ("A", "B"))
    assert_allclose(modes.shapes, shapes / PEAK, rtol=1e-15)
    assert_allclose(modes.phi(SCAN_X[:50] + 0.7), scan().phi(SCAN_X[:50] + 0.7), rtol=1e-13)
