"""Job names may not differ in case only: each is a folder, and macOS and Windows fold
case."""

import pytest

from frictex.app.engine.batch import ManifestError, read_manifest
from frictex.rendering.pipeline import RENDERERS


@pytest.mark.parametrize("second", ["DUP", "Dup", "dup"])
def test_names_differing_in_case_only_are_one_name(tmp_path, second):
    manifest = tmp_path / "m.csv"
    manifest.write_text(f"scene,trace,name\ngrating-5mm,swipe-40mms-50hz,dup\n"
                        f"grating-5mm,swipe-40mms-50hz,{second}\n")
    with pytest.raises(ManifestError) as error:
        read_manifest(manifest, ("sho", *RENDERERS))
    assert error.value.error_lines == (
        f'{manifest}:3: name "{second}" is used by an earlier job'
        + ("" if second == "dup" else ' as "dup" (names must differ in more than case)'),)


def test_a_clash_is_said_with_the_rows_other_problems_in_one_run(tmp_path):
    """A row with a bad rate still holds its name: its clash with a later row was said only
    once the rate was mended, where every problem of a manifest is said at once."""
    manifest = tmp_path / "m.csv"
    manifest.write_text("scene,trace,rate_hz,name\ngrating-5mm,swipe-40mms-50hz,50,dup\n"
                        "grating-5mm,swipe-40mms-50hz,,DUP\n")
    with pytest.raises(ManifestError) as error:
        read_manifest(manifest, ("sho", *RENDERERS))
    assert error.value.error_lines == (
        f'{manifest}:2: rate_hz "50": expected 100 to 1e+06 Hz (as the command line\'s option)',
        f'{manifest}:3: name "DUP" is used by an earlier job as "dup" (names must differ in '
        "more than case)")
