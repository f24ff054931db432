"""A bundled scene edited again after a copy of it was saved: Ctrl+S names the copy
already in the user's folder and says that saving again replaces its earlier edits,
not that an edit of the file reloads (the panel holds the bundled file)."""

import pytest

from frictex.app.live.layer_edit import LayerEdit, SaveConflict
from frictex.textures.library import resolve_scene


def edited_bundled() -> LayerEdit:
    ed = LayerEdit(resolve_scene("slider-clips"))
    ed.select(0)
    ed.set("mu", 0.8)  # the track
    return ed


def test_a_second_copy_names_the_first_and_says_it_replaces_its_edits(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    first = edited_bundled().save()
    earlier = first.read_text()
    ed = edited_bundled()
    ed.set("mu", 0.75)
    with pytest.raises(SaveConflict) as refused:
        ed.save()
    said = str(refused.value)
    assert said == (f"{first} is there already (a copy saved before): not saved. Ctrl+S again "
                    "replaces its earlier edits with these")
    # the window's banner says the same, not that the file changed on disk
    assert refused.value.banner == ("not saved: a copy saved before is there; Ctrl+S again "
                                    "replaces it")
    assert first.read_text() == earlier
    assert ed.save() == first and "mu = 0.75" in first.read_text()
