"""Shared test vectors (device/firmware/vectors/frames.json): the Python codec and the C
firmware decode the same byte streams the same way, so the two sides cannot drift."""

import json
import re
import subprocess

import pytest

from frictex.device.firmware.build import BUILD, FIRMWARE, FirmwareBuildError, make
from frictex.device.firmware.vectors import make_vectors

VECTORS = FIRMWARE / "vectors" / "frames.json"


def _rows():
    return json.loads(VECTORS.read_text())


def test_the_vectors_cover_every_message_and_every_reason_to_drop_a_frame():
    text = " | ".join(r["expect"] for r in _rows())
    for word in ("hello", "block", "heartbeat", "stop", "info", "status", "error", "flushed",
                 "force"):
        assert f" {word} " in text
    for reason in ("cobs", "short", "crc", "version", "type", "payload", "oversize"):
        assert f"drop {reason} |" in text


def test_the_python_decoder_agrees_with_the_vectors():
    for row in _rows():
        got = make_vectors.render_stream(bytes.fromhex(row["hex"]))
        assert " | ".join(got) == row["expect"], row["name"]


def test_the_file_is_what_the_generator_writes_from_the_python_encoder():
    """Re-running the generator changes nothing: the committed frames are still exactly
    what device/link/protocol.py encodes (regenerate the file if the protocol changed)."""
    assert make_vectors.vectors() == _rows()


def _checker():
    try:
        make("check")
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)
    return BUILD / "test" / "check_vectors"


def test_the_c_decoder_and_encoder_agree_with_the_vectors():
    out = subprocess.run([str(_checker()), str(VECTORS)], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-3000:]
    m = re.match(r"(\d+) vectors, (\d+) failed; (\d+) frames re-encoded", out.stdout)
    total, failed, reencoded = (int(g) for g in m.groups())
    assert total == len(_rows()) and failed == 0 and reencoded >= 60


def test_the_c_checker_fails_on_a_vector_it_disagrees_with(tmp_path):
    rows = _rows()
    rows[0]["expect"] = rows[0]["expect"].replace("token=1 ", "token=2 ")
    bad = tmp_path / "frames.json"
    bad.write_text("[\n" + ",\n".join(json.dumps(r) for r in rows) + "\n]\n")
    out = subprocess.run([str(_checker()), str(bad)], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 1 and f"{rows[0]['name']}: decodes differ" in out.stderr
