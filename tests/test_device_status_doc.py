"""device/PROTOCOL.md 6.4 documents every key of summary.json's ``device`` section.

Twelve keys a replay writes there (``port``, ``paced``, ``queued_blocks``,
``lost_frames_from_device``, ``device_lost_frames``, ``device_clamped``,
``device_errors``, ``last_error`` and the Info's ``has_phases``, ``has_sensor``,
``has_force``, ``has_force_reports``) were documented nowhere, and nothing said that
``clamped_samples`` / ``device_clamped`` and ``lost_frames_from_device`` /
``device_lost_frames`` are the host's and the device's counts. 6.4 is now a table with
one row per key; a key added to ``CommandSink.status()`` without its row fails here.
"""

import json
import re
from pathlib import Path

import pytest

from frictex.app.commands.cli import main
from frictex.device.link import protocol as p

PROTOCOL_MD = Path(p.__file__).parents[1] / "PROTOCOL.md"
#: keys whose value is an object of named fields, each documented as ``key.field``
NESTED = ("device",)
#: keys whose value maps names (causes, error codes) to counts: each name in the key's row
NAMED = ("unplayed_by_cause", "device_errors")


def section_6_4() -> str:
    """The text of PROTOCOL.md section 6.4, up to the next heading."""
    text = PROTOCOL_MD.read_text(encoding="utf-8")
    start = re.search(r"^### 6\.4\b.*$", text, re.M).end()
    return text[start:re.search(r"^#+ ", text[start:], re.M).start() + start]


def rows() -> dict[str, str]:
    """Section 6.4's table: key -> its row's meaning."""
    return {key: meaning for key, meaning in
            re.findall(r"^\| `([a-z0-9_.]+)` \| [^|]+ \| (.+) \|$", section_6_4(), re.M)}


def written_keys(device: dict) -> set[str]:
    """The keys of a ``device`` section, those of :data:`NESTED` objects as ``key.field``."""
    keys = set(device)
    for key in NESTED:
        keys |= {f"{key}.{field}" for field in device.get(key) or {}}
    return keys


@pytest.fixture(scope="module")
def device_sections(tmp_path_factory):
    """The ``device`` sections of a replay on the simulated device, without and with a
    simulated finger (which turns force reports on)."""
    sections = []
    for extra in ([], ["--sim-finger", "3"]):
        out = tmp_path_factory.mktemp("device")
        # --max-unplayed 1: the keys are the point; a starved host's watchdog flushes
        # (1.3 % of the samples in a CI run beside heavy load) would fail the run
        assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out),
                     "--quiet", "--device", "sim", "--max-unplayed", "1", *extra]) == 0
        sections.append(json.loads((out / "summary.json").read_text())["device"])
    return sections


def test_every_device_key_written_has_a_row_in_6_4(device_sections):
    written = set().union(*(written_keys(device) for device in device_sections))
    assert {"port", "device_clamped", "device.has_force_reports"} <= written
    assert written - set(rows()) == set()


def test_every_row_of_6_4_names_a_key_the_host_writes(device_sections):
    """No stale rows: the keys absent from these runs are the device's, present once a
    Status arrived (both runs got one), so every row is written here."""
    written = set().union(*(written_keys(device) for device in device_sections))
    assert set(rows()) - written == set()


def test_the_names_inside_named_objects_are_in_their_row():
    """Every cause and every error code the host can write is named in its row."""
    from frictex.device.link.ledger import Ledger
    documented = rows()
    for cause in Ledger().breakdown():
        assert f"`{cause}`" in documented["unplayed_by_cause"], cause
    for code in [*p.ErrorCode.NAMES.values(), "other"]:
        assert f"`{code}`" in documented["device_errors"], code


@pytest.mark.parametrize("host, device", [("clamped_samples", "device_clamped"),
                                          ("lost_frames_from_device", "device_lost_frames"),
                                          ("crc_errors", "device_crc_errors")])
def test_each_pair_says_who_counts_and_points_at_the_other(host, device):
    documented = rows()
    assert documented[host].startswith("host:") and f"Not `{device}`" in documented[host]
    assert (documented[device].startswith("device, since power-up:")
            and f"Not `{host}`" in documented[device])
