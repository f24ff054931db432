"""frictex.Summary reads the summary.json of an earlier version (app/engine/SUMMARY.md): a
key added since is None, and left out again, so that the document round-trips."""

import copy
import json

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine.summary_types import Summary


@pytest.fixture(scope="module")
def current(tmp_path_factory) -> dict:
    out = tmp_path_factory.mktemp("replay")
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out), "--quiet"]) == 0
    return json.loads((out / "summary.json").read_text())


def as_version(doc: dict, version: int) -> dict:
    """``doc`` as a replay of summary_version ``version`` wrote it: without the keys added
    after it."""
    older = copy.deepcopy(doc)
    older["summary_version"] = version
    if version < 7:
        del older["counts"]["modal_unserved"]
    if version < 6:
        del older["counts"]["modal_capped"]
    if version < 5:
        del older["trace"]["touch_samples_off_display"]
    if version < 4:
        del older["layer_clipped"]
    return older


@pytest.mark.parametrize("version", [4, 5, 6])
def test_a_summary_from_before_modal_capped_reads_it_as_not_counted(current, version):
    """A version 5 summary.json raised a bare KeyError 'modal_capped'."""
    older = as_version(current, version)
    summary = Summary.from_dict(older)
    assert summary.counts.modal_capped is (None if version < 6 else older["counts"]["modal_capped"])
    assert summary.counts.modal_unserved is None
    assert summary.counts.off_structure == older["counts"]["off_structure"]
    assert summary.to_dict() == older


def test_the_current_summary_round_trips_with_its_modal_capped(current):
    summary = Summary.from_dict(current)
    assert summary.counts.modal_capped == current["counts"]["modal_capped"] == 0
    assert summary.counts.modal_unserved == current["counts"]["modal_unserved"] == 0
    assert summary.to_dict() == current


def test_a_summary_before_version_4_lacks_a_required_key(current):
    with pytest.raises(KeyError, match="layer_clipped"):
        Summary.from_dict(as_version(current, 3))
