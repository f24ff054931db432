"""The perception check of a design of levels compares the reference with its level
farthest by the relative difference the threshold bounds, on either side of it: a
same-different or magnitude design's levels may lie below the reference."""

import pytest

from frictex.app.commands.cli import main
from frictex.app.experiment.perception_check import protocol_findings
from frictex.app.experiment.protocol import load_protocol

PROTOCOL = ('format = 1\nname = "sd"\nmethod = "{method}"\nrepetitions = 10\n\n[stimuli]\n'
            'scene = "grating-5mm"\nvary = "{vary}"\nreference = {reference}\n'
            'levels = {levels}\n')


def _findings(tmp_path, method, vary, reference, levels):
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL.format(method=method, vary=vary, reference=reference,
                                    levels=levels))
    return path, protocol_findings(load_protocol(path))


@pytest.mark.parametrize("levels", ["[2.5, 5.2]", "[5.2, 2.5]"])
@pytest.mark.parametrize("method", ["same-different", "magnitude"])
def test_a_level_below_the_reference_beyond_the_threshold_is_no_warning(tmp_path, capsys,
                                                                        method, levels):
    """Periods 5 against 2.5 (dp/p 100 %) and 5.2 (4 %): the largest, 5.2, was taken as
    the farthest and warned of though 2.5 is far beyond the 14 % threshold."""
    path, found = _findings(tmp_path, method, "period_mm", 5.0, levels)
    assert found == []
    capsys.readouterr()
    assert main(["validate", "--perception", str(path)]) == 0
    assert "5.2" not in capsys.readouterr().out


@pytest.mark.parametrize("levels", ["[4.8, 3.0]", "[3.0, 4.8]"])
def test_the_level_farthest_below_is_the_one_compared(tmp_path, levels):
    """Periods 5 against 4.8 (dp/p 4.2 %) and 3 (67 %): the largest, 4.8, was warned
    of; 3 is beyond the threshold, so nothing is."""
    assert _findings(tmp_path, "same-different", "period_mm", 5.0, levels)[1] == []


@pytest.mark.parametrize("levels", ["[0.31, 0.26]", "[0.26, 0.31]"])
def test_levels_all_under_the_threshold_name_the_farthest_by_friction(tmp_path, levels):
    """Depths 0.3 against 0.31 and 0.26 on grating-5mm (mu_high 1): mu' 0.7 against 0.69
    (dmu'/mu' 1.4 %) and 0.74 (5.4 %); 0.26 is the farthest, whichever order (the
    largest, 0.31, was named)."""
    [found] = _findings(tmp_path, "same-different", "depth", 0.3, levels)[1]
    assert found.kind == "weber" and "stimuli 0.3 and 0.26" in found.message
    assert found.value == pytest.approx((0.74 - 0.7) / 0.74, rel=1e-9)
