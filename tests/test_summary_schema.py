"""app/engine/SUMMARY.md documents every key a replay's summary.json holds, and no other."""

import json
import re
from pathlib import Path

import pytest

from frictex.app.commands.cli import main

DOC = Path(__file__).resolve().parents[1] / "app" / "engine" / "SUMMARY.md"
#: objects whose keys are data (finger ids, layer names) or documented elsewhere
OPEN = ("fingers", "fingers_others", "forces", "device", "control", "layer_clipped",
        "timings.layers_s",
        "timings.loop_s", "timings.stages_s", "trace.time_order", "trace.gaps")


def documented() -> set[str]:
    return set(re.findall(r"^\| `([a-z0-9_.]+)` \|", DOC.read_text(encoding="utf-8"), re.M))


def keys(doc: dict, prefix: str = "") -> set[str]:
    found = set()
    for key, value in doc.items():
        path = f"{prefix}{key}"
        found.add(path)
        if isinstance(value, dict) and path not in OPEN:
            found |= keys(value, path + ".")
    return found


@pytest.fixture(scope="module")
def summaries(tmp_path_factory):
    runs = [("grating-5mm", "swipe-40mms-50hz"), ("keyclick-ring", "keyclick-press-100hz")]
    docs = []
    for scene, trace in runs:
        out = tmp_path_factory.mktemp("s")
        assert main(["replay", scene, trace, "--out", str(out), "--quiet"]) == 0
        text = (out / "summary.json").read_text()
        docs.append(json.loads(text))
    return docs


def test_every_key_written_is_documented(summaries):
    written = set().union(*(keys(doc) for doc in summaries))
    assert written - documented() == set()


def test_every_documented_key_is_written(summaries):
    # --device only; more than 100 finger ids only (tests/test_summary_fingers.py); --control
    # closed or adaptive only (tests/test_control_summary.py)
    written = set().union(*(keys(doc) for doc in summaries)) | {"device", "fingers_others",
                                                                "control"}
    assert documented() - written == set()


@pytest.mark.parametrize("scene", ["slider-clips", "height-bump", "objects-bump-edge-disc",
                                   "raster-map", "guidance-beam"])
def test_each_layers_type_is_the_one_its_texture_file_gives(scene):
    """summary.json named layers by their classes: heightlayer, artexturelayer,
    cliplayer, rastermap, and shape for both a rectangle and a disc."""
    import tomllib

    import frictex
    from frictex.textures.library import resolve_scene
    path = resolve_scene(scene)
    written = [layer["type"] for layer in tomllib.loads(path.read_text())["layer"]]
    run = frictex.replay(path, frictex.synth_trace("swipe", duration_s=0.2))
    assert [layer["type"] for layer in run.summary.to_dict()["scene"]["layers"]] == written
