"""device/RING.md states the --amplitude-um bound that ``modes ring --phase-shift`` applies."""

import re
from pathlib import Path

from frictex.app.commands.modes_ring import FRICTION_BOUND_UM

RING_MD = Path(__file__).resolve().parents[1] / "device" / "RING.md"


def test_ring_md_gives_the_amplitude_bound_the_command_refuses_above():
    # it said 'stops at 100 um' while 50 um was refused above 4.85 um
    text = " ".join(RING_MD.read_text(encoding="utf-8").split())
    stated = re.findall(r"`--amplitude-um` stops at ([0-9.]+) um", text)
    assert stated == [f"{FRICTION_BOUND_UM:.4g}"]
