"""Hot reload in the demo: the texture file and every file it names (a 16-bit height map,
a recorded-texture model, an AHAP clip) are watched; a good edit of any of them reloads
the scene, a bad one keeps the last good scene and shows why.

The watcher is driven by the test: the loop's clock is the ``now`` passed to
``check_reload`` and every file's modification time is set with ``os.utime``, so
nothing depends on how fast the machine is or on the file system's time resolution."""

import json
import os
import shutil

import numpy as np
import pytest
from numpy.testing import assert_allclose
from PIL import Image

from frictex.app.live.demo_loop import GONE_S, RELOAD_POLL_S, DemoLoop
from frictex.app.live.haptic_thread import HapticThread
from frictex.app.live.watch import FileWatch
from test_ar_texture import VARIANCES, _xml
from test_live_demo_loop import ScriptedWindow
from test_texture_loader import HEAD
from frictex.textures.clips import ClipLayer
from frictex.textures.errors import TextureError
from frictex.textures.hatt import ArTextureLayer
from frictex.textures.heights import HeightLayer
from frictex.textures.library import list_scenes
from frictex.textures.loader import check_scene, load_scene
from frictex.textures.references import referenced_files

LAYERS = """
[[layer]]
type = "height"
name = "relief"
shape = "map"
image = "maps/relief.png"
rise_mm = 1.0
x_mm = 10
width_mm = 40
height_mm = 20

[[layer]]
type = "recorded"
name = "wood"
model = "wood.xml"

[[layer]]
type = "clip"
name = "tap"
trigger = "down"
clip = "ahap"
file = "tap.ahap"
"""


def _ahap(intensity):
    return json.dumps({"Version": 1.0, "Pattern": [{"Event": {
        "Time": 0.0, "EventType": "HapticTransient",
        "EventParameters": [{"ParameterID": "HapticIntensity", "ParameterValue": intensity}]}}]})


def _ramp(step):
    """A 16-bit height map rising ``step`` levels per pixel along x."""
    return (np.arange(40) * step).astype(np.uint16)[None, :].repeat(20, axis=0)


class Files:
    """The scene's files in ``folder``, each written with a modification time the test
    sets (1 s apart, from 1000 s): a change is a change whatever the clock does."""

    def __init__(self, folder):
        self.folder = folder
        self.t_ns = 1000 * 10 ** 9
        (folder / "maps").mkdir(exist_ok=True)

    def write(self, name, content):
        path = self.folder / name
        if isinstance(content, np.ndarray):
            Image.fromarray(content).save(path, format="PNG")
        else:
            path.write_text(content, encoding="utf-8")
        self.t_ns += 10 ** 9
        os.utime(path, ns=(self.t_ns, self.t_ns))
        return path

    def scene(self, layers=LAYERS):
        self.write("maps/relief.png", _ramp(1000))
        self.write("wood.xml", _xml())
        self.write("tap.ahap", _ahap(0.5))
        return self.write("scene.toml", HEAD + layers)


def _layer(scene, kind):
    return next(layer for layer in scene.layers if isinstance(layer, kind))


# -- which files a texture file names ------------------------------------------------------


def test_the_files_a_scene_names_are_listed_as_the_loader_resolves_them(tmp_path):
    path = Files(tmp_path).scene()
    assert referenced_files(path) == tuple(
        (tmp_path / name).resolve() for name in ("maps/relief.png", "wood.xml", "tap.ahap"))
    structure = ('[device]\nprofile = "beam-seed000"\n[device.structure]\nmodes_file = "m.csv"\n'
                 '[[layer]]\ntype = "raster"\nimage = "a.png"\n[[layer]]\ntype = "raster"\n'
                 'image = "a.png"\n[[layer]]\ntype = "grating"\n')
    (tmp_path / "beam.toml").write_text(structure)
    assert referenced_files(tmp_path / "beam.toml") == ((tmp_path / "m.csv").resolve(),
                                                        (tmp_path / "a.png").resolve())


@pytest.mark.parametrize("text, message", [
    ("[[layer]\n", "not TOML"), ("x = " + "[" * 40 + "]" * 40 + "\n", "nested too deep"),
    (b"\xff\xfe", "UTF-16")])
def test_a_texture_file_that_is_not_toml_is_one_line_error(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(TextureError, match=message) as info:
        referenced_files(path)
    assert "\n" not in str(info.value) and "bad.toml" in str(info.value)


@pytest.mark.parametrize("own", [True, False], ids=["test-scene", "bundled-scenes"])
def test_the_list_is_complete_and_each_file_on_it_is_needed(tmp_path, own):
    """Copied with only the files listed, each scene loads; without any one of them, it
    does not, and the problem names that file (the list and the loader agree)."""
    if own:
        (tmp_path / "own").mkdir()
        scenes = [(Files(tmp_path / "own").scene(), tmp_path / "own")]
    else:
        scenes = [(entry.path, entry.path.parent) for entry in list_scenes()]
    named_somewhere = 0
    for k, (scene_path, folder) in enumerate(scenes):
        copy = tmp_path / f"copy{k}"
        copy.mkdir()
        shutil.copy(scene_path, copy / scene_path.name)
        listed = referenced_files(scene_path)
        relative = [p.relative_to(folder.resolve()) for p in listed]
        for rel in relative:
            (copy / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(folder / rel, copy / rel)
        scene, problems, _ = check_scene(copy / scene_path.name)
        assert scene is not None, (scene_path.name, problems)
        for rel in relative:
            named_somewhere += 1
            (copy / rel).rename(copy / "aside")
            _, problems, _ = check_scene(copy / scene_path.name)
            (copy / "aside").rename(copy / rel)
            assert problems and any(rel.name in str(p) for p in problems), (scene_path.name, rel)
    assert named_somewhere >= (3 if own else 2)  # the bundled raster image and AHAP clip


# -- the watcher ---------------------------------------------------------------------------


def test_a_file_watch_sees_edits_renames_over_appearing_and_vanishing(tmp_path):
    """Each change is reported at the second look that finds it, once and in watch order."""
    a, b = tmp_path / "a", tmp_path / "b"
    a.write_text("one")
    os.utime(a, ns=(5, 5))
    watch = FileWatch([a, b])
    assert watch.changed() == []

    def settled():
        first = watch.changed()
        return first, watch.changed(), watch.changed()

    os.utime(a, ns=(6, 6))
    assert settled() == ([], [a], [])
    b.write_text("new")
    assert settled() == ([], [b], [])
    (tmp_path / "c").write_text("two")  # renamed over it: same size and time, a new inode
    os.utime(tmp_path / "c", ns=(6, 6))
    os.replace(tmp_path / "c", a)
    assert settled() == ([], [a], [])
    a.unlink()
    assert settled() == ([], [a], []) and watch.stamps[a] is None
    watch.watch([b])
    assert watch.paths == (b,) and watch.changed() == []


def test_a_file_watch_waits_for_a_file_being_written_to_hold_still(tmp_path):
    """Truncated, then written: the empty file seen in between is never reported; a file
    changed back to what was last reported before it settled is not reported at all."""
    a = tmp_path / "a"
    a.write_text("first")
    os.utime(a, ns=(5, 5))
    watch = FileWatch([a])
    a.write_text("")  # the editor has truncated it
    os.utime(a, ns=(6, 6))
    assert watch.changed() == []
    a.write_text("second")  # and written it
    os.utime(a, ns=(7, 7))
    assert watch.changed() == []
    assert watch.changed() == [a] and watch.stamps[a][1] == len("second")
    a.write_text("third")
    os.utime(a, ns=(8, 8))
    assert watch.changed() == []
    a.write_text("second")
    os.utime(a, ns=(7, 7))  # back to the stamp last reported
    assert watch.changed() == [] and watch.changed() == []


def test_a_file_watch_keeps_an_unreported_change_across_watch(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.write_text("one")
    watch = FileWatch([a])
    a.write_text("three")
    assert watch.changed() == []
    watch.watch([a, b])  # what the demo does after each reload
    assert watch.changed() == [a]


# -- the demo loop ----------------------------------------------------------------------------


@pytest.fixture
def demo(gl, tmp_path):
    files = Files(tmp_path)
    path = files.scene()
    scene = load_scene(path)
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene)  # not started: switch() builds the pipeline here
    loop = DemoLoop(window, haptic, [path], 0, scene, load_scene, tmp_path,
                    events_path=tmp_path / "events.csv")
    clock = [0.0]

    def poll(step=RELOAD_POLL_S, looks=2):
        """Move the loop's clock on by ``step`` (s) ``looks`` times, letting it look at its
        files each time: by default a change is seen, then found to have held still."""
        for _ in range(looks):
            clock[0] += step
            loop.check_reload(clock[0])

    loop.check_reload(0.0)
    yield loop, files, poll
    loop.close()
    window.close()


def _events(tmp_path, kind):
    lines = (tmp_path / "events.csv").read_text().splitlines()[1:]
    return [line.split(",", 2)[2] for line in lines if line.split(",")[1] == kind]


def test_each_named_file_reloads_the_scene_and_a_bad_edit_keeps_the_last_good_one(demo, tmp_path):
    loop, files, poll = demo
    assert loop.files.paths == (tmp_path / "scene.toml", *(
        (tmp_path / n).resolve() for n in ("maps/relief.png", "wood.xml", "tap.ahap")))
    first = loop.scene

    # the height map: a steeper ramp, seen at the next poll, loaded at the one after
    files.write("maps/relief.png", _ramp(3000))
    poll(RELOAD_POLL_S / 2, looks=1)
    poll(RELOAD_POLL_S / 2, looks=1)
    assert loop.scene is first
    poll(looks=1)
    heights = _layer(loop.scene, HeightLayer).shape.heights_mm
    assert_allclose(heights[0, :3], np.array([0, 3000, 6000]) / 65535)
    assert loop.error is None and "relief.png changed" in _events(tmp_path, "reload")[-1]

    # a bad edit of each file: the error names it, the last good scene stays; mending reloads
    bad = {"maps/relief.png": (np.zeros((4, 4), np.uint8), "16-bit"),
           "wood.xml": (_xml()[:-30], "not well-formed XML"),
           "tap.ahap": (_ahap(1.5), "HapticIntensity is 1.5")}
    good = {"maps/relief.png": _ramp(500), "wood.xml": _xml().replace(
        f"<var>{VARIANCES[0]!r}</var>", "<var>4e-06</var>"), "tap.ahap": _ahap(0.9)}
    for failures, (name, (content, message)) in enumerate(bad.items(), start=1):
        kept = loop.scene
        files.write(name, content)
        poll()
        assert loop.scene is kept
        assert loop.error.startswith(f"reload failed ({name.split('/')[-1]} changed), keeping the "
                                     "last good scene") and message in loop.error
        poll()  # nothing changed since: no second attempt
        assert len(_events(tmp_path, "reload-failed")) == failures
        files.write(name, good[name])
        poll()
        assert loop.scene is not kept and loop.error is None
    assert_allclose(_layer(loop.scene, HeightLayer).shape.heights_mm[0, 1], 500 / 65535)
    assert _layer(loop.scene, ArTextureLayer).model.variances[0] == 4e-6
    assert _layer(loop.scene, ClipLayer).clip.events[0].intensity == 0.9
    assert len(_events(tmp_path, "reload")) == 4


def test_an_edit_that_names_another_file_moves_the_watch_to_it(demo, tmp_path):
    loop, files, poll = demo
    files.write("maps/other.png", _ramp(2000))
    files.write("scene.toml", HEAD + LAYERS.replace("maps/relief.png", "maps/other.png"))
    poll()
    assert (tmp_path / "maps/other.png").resolve() in loop.files.paths
    assert (tmp_path / "maps/relief.png").resolve() not in loop.files.paths
    reloaded = loop.scene
    files.write("maps/relief.png", _ramp(10))  # no longer part of the scene
    poll()
    assert loop.scene is reloaded
    files.write("maps/other.png", _ramp(20))
    poll()
    assert loop.scene is not reloaded and loop.error is None


def test_a_file_named_by_a_failed_edit_is_watched_until_it_is_mended(demo, tmp_path):
    """The edit names a clip that is not valid yet: mending the clip alone reloads."""
    loop, files, poll = demo
    files.write("new.ahap", _ahap(2.0))
    files.write("scene.toml", HEAD + LAYERS.replace("tap.ahap", "new.ahap"))
    first = loop.scene
    poll()
    assert loop.scene is first and "new.ahap" in loop.error
    files.write("new.ahap", _ahap(0.3))
    poll()
    assert loop.error is None and _layer(loop.scene, ClipLayer).clip.events[0].intensity == 0.3


def test_a_texture_file_caught_half_written_is_not_loaded(demo, tmp_path):
    """An editor that truncates the file, then writes it: a poll in between sees an empty
    file, which is neither loaded nor shown as an error; the written file is."""
    loop, files, poll = demo
    first = loop.scene
    files.write("scene.toml", "")
    poll(looks=1)
    files.write("scene.toml", HEAD + LAYERS.replace("rise_mm = 1.0", "rise_mm = 2.0"))
    poll(looks=1)
    assert loop.scene is first and loop.error is None
    poll(looks=1)
    assert loop.scene is not first and loop.error is None
    assert _events(tmp_path, "reload-failed") == []
    files.write("scene.toml", "")  # emptied and left so: that is an edit, shown as one
    poll()
    assert "is empty" in loop.error and len(_events(tmp_path, "reload-failed")) == 1


def test_a_texture_file_being_saved_is_waited_for(demo, tmp_path, capsys):
    """An editor that deletes the file before writing it: no reload and no error while it
    is missing; written again, the scene reloads, said once on stderr."""
    loop, files, poll = demo
    first = loop.scene
    (tmp_path / "scene.toml").unlink()
    poll()
    assert loop.scene is first and loop.error is None
    files.write("scene.toml", HEAD + LAYERS.replace("rise_mm = 1.0", "rise_mm = 2.0"))
    poll()
    assert loop.scene is not first and loop.error is None
    assert _layer(loop.scene, HeightLayer).shape.heights_mm.max() == pytest.approx(2.0 * 39000 / 65535)
    assert capsys.readouterr().err.splitlines() == [
        f"frictex demo: reloaded {loop.scene.name} (scene.toml changed)"]


@pytest.mark.parametrize("empty_first", [False, True])
def test_a_texture_file_moved_away_is_said_gone_and_the_scene_kept(demo, tmp_path, capsys,
                                                                  empty_first):
    """Moved away (or emptied, then deleted): after GONE_S the banner and stderr say the
    file is gone, once; the last good scene stays; back, it reloads."""
    loop, files, poll = demo
    first = loop.scene
    path = tmp_path / "scene.toml"
    text = path.read_text()
    if empty_first:
        files.write("scene.toml", "")
        poll()
        assert "is empty" in loop.error
    path.rename(tmp_path / "elsewhere.toml")
    poll()
    assert "is gone" not in (loop.error or "")
    poll(GONE_S, looks=2)
    assert loop.error.startswith("scene.toml is gone (moved or deleted), keeping the last good "
                                 "scene") and loop.scene is first
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == f"frictex demo: {loop.error}"
    assert len(err) == 1 + empty_first and all(line.count("\n") == 0 for line in err)
    files.write("scene.toml", text)
    poll()
    assert loop.error is None and loop.scene is not first
    assert capsys.readouterr().err == f"frictex demo: reloaded {loop.scene.name} (scene.toml changed)\n"


def test_a_texture_file_turned_into_a_link_loop_is_said_so(demo, tmp_path, capsys):
    """Before, a link to itself was said 'gone (moved or deleted)'."""
    loop, files, poll = demo
    first = loop.scene
    path = tmp_path / "scene.toml"
    path.unlink()
    path.symlink_to("scene.toml")
    poll()
    poll(GONE_S, looks=2)
    assert loop.error.startswith("scene.toml is a symbolic link that leads to no file (a loop, "
                                 "or its target gone), keeping the last good scene")
    assert loop.scene is first
