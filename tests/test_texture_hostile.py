"""Texture files from strangers: the files they name stay in their folder, images are PNG
only and within the scene's budget, special files are refused, and every message is one
escaped line. Each case runs ``frictex`` in a child process under 1 GiB of address space
(``test_hostile_files``' harness): exit 2, one line ``frictex: error: ...`` naming the file
and the key, printable (no ESC, BEL or line break from the file), never a hang."""

from __future__ import annotations

import os
import zlib
from pathlib import Path
from struct import pack

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from test_hostile_files import HEAD, Case, run_all

from frictex.app.commands.cli import main
from frictex.device.safe_text import escape
from frictex.textures.loader import check_scene
from frictex.textures.outside import ALLOW_OUTSIDE_ENV

RASTER = ('[[layer]]\ntype = "raster"\nimage = "{name}"\nwidth_mm = 10\nheight_mm = 10\n'
          'mu_black = 0.7\n')
HEIGHT = ('[[layer]]\ntype = "height"\nshape = "map"\nimage = "{name}"\nrise_mm = 0.1\n'
          'width_mm = 10\nheight_mm = 10\n')
RECORDED = '[[layer]]\ntype = "recorded"\nmodel = "{name}"\n'
CLIP = '[[layer]]\ntype = "clip"\ntrigger = "down"\nclip = "ahap"\nfile = "{name}"\n'
MODES = ('[device]\nprofile = "beam-seed000"\n[device.structure]\nmodes_file = "{name}"\n'
         'actuators_mm = [60, 290]\n[[layer]]\ntype = "bump"\ncx_mm = 50\ncy_mm = 3\n'
         'sigma_mm = 2\nmu = 0.7\n')
BEAM_HEAD = 'format = 1\n[display]\nwidth_mm = 108.0\nheight_mm = 6\nwidth_px = 800\nheight_px = 48\n'
#: (layer template, the key that names the file) of every kind of file a texture names
NAMING = {"image": (RASTER, "image"), "height map": (HEIGHT, "image"),
          "HaTT model": (RECORDED, "model"), "AHAP clip": (CLIP, "file"),
          "mode table": (MODES, "modes_file")}
ESC_KEY = '"\\u001b]0;owned\\u0007\\u001b[2J" = 1\n'


def _png(width: int, height: int, depth: int = 8) -> bytes:
    """A greyscale PNG of width x height zero pixels (a few kB: zeros compress well)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return pack(">I", len(data)) + kind + data + pack(">I", zlib.crc32(kind + data))
    row = b"\0" * (1 + width * depth // 8)
    compressor = zlib.compressobj(9)
    idat = b"".join(compressor.compress(row) for _ in range(height)) + compressor.flush()
    ihdr = pack(">IIBBBBB", width, height, depth, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def _scene(layers: str, head: str = HEAD, files: dict | None = None):
    """A texture file ``scene.toml`` holding ``layers``, with ``files`` (name -> bytes or a
    function making the path) beside it."""
    def make(folder: Path):
        for name, content in (files or {}).items():
            path = folder / name
            path.parent.mkdir(parents=True, exist_ok=True)
            content(path) if callable(content) else path.write_bytes(content)
        (folder / "scene.toml").write_text(head + layers)
        return ["validate", str(folder / "scene.toml")], "scene.toml"
    return make


def _outside(kind: str, how: str) -> Case:
    """A scene whose ``kind`` of file is named ``how``: absolute, through ``..``, or
    through a link in its folder that leads out (the target exists, readable)."""
    template, _ = NAMING[kind]
    head = BEAM_HEAD if kind == "mode table" else HEAD

    def make(folder: Path):
        secret = folder.parent / f"secret-{folder.name}.txt"
        secret.write_text("root:*:19000:0:99999:7:::\n")
        name = {"absolute": str(secret), "dotdot": f"../{secret.name}", "link": "inside.png"}[how]
        if how == "link":
            os.symlink(secret, folder / "inside.png")
        return _scene(template.format(name=name), head)(folder)
    return Case(f"{kind} {how}", make)


def _fifo_named(kind: str) -> Case:
    template, _ = NAMING[kind]
    head = BEAM_HEAD if kind == "mode table" else HEAD
    return Case(f"{kind} is a FIFO", _scene(template.format(name="f.dat"), head, {"f.dat": os.mkfifo}))


#: 9 Mpx x 8 bytes each: 3 fit the scene's 256 MiB, and validate lists the other 29 (every
#: problem of a file, one line each), none of them decoded
MANY = "32 raster layers of 3000 x 3000 px"
EPS = b"%!PS-Adobe-3.0 EPSF-3.0\n%%BoundingBox: 0 0 10 10\n0 0 moveto (owned) show\nshowpage\n"

CASES = [
    *(_outside(kind, how) for kind in NAMING for how in ("absolute", "dotdot", "link")),
    *(_fifo_named(kind) for kind in NAMING),
    Case("EPS named .png", _scene(RASTER.format(name="map.png"), files={"map.png": EPS})),
    Case("EPS named .png as a height map", _scene(HEIGHT.format(name="h.png"), files={"h.png": EPS})),
    Case("2 KB PNG of 4096 x 4096 px", _scene(RASTER.format(name="big.png"),
                                              files={"big.png": _png(4096, 4096)})),
    Case("16-bit height map of 3000 x 3000 px, over the scene's budget",
         _scene(HEIGHT.format(name="h.png"), files={"h.png": _png(3000, 3000, 16)})),
    Case(MANY, _scene(
        "".join(RASTER.format(name=f"m{k}.png") for k in range(32)),
        files={f"m{k}.png": _png(3000, 3000) for k in range(32)})),
    Case("unknown key of ESC and BEL", _scene(RASTER.format(name="m.png").replace(
        "mu_black", ESC_KEY + "mu_black"), files={"m.png": _png(4, 4)})),
    Case("layer name with ESC", _scene('[[layer]]\ntype = "bump"\nname = "\\u001b[31mred"\n'
                                       'cx_mm = 5\ncy_mm = 5\nsigma_mm = 1\nmu = 0.5\n')),
    Case("mode table row with ESC", _scene(MODES.format(name="m.csv"), BEAM_HEAD, {
        "m.csv": b"x_mm,A,B\n0,1,1\n1,\x1b]0;owned\x07,1\n2,1,1\n3,1,1\n"})),
    Case("mode table header with ESC", _scene(MODES.format(name="m.csv"), BEAM_HEAD, {
        "m.csv": b"x_mm,\x1b[2J,B\n0,1,1\n1,1,1\n2,1,1\n3,1,1\n"})),
    Case("HaTT unit with ESC", _scene(RECORDED.format(name="t.xml"), files={
        "t.xml": b"<modelSet><SpeedUnits>\x1b]0;owned\x07</SpeedUnits></modelSet>"})),
]


def test_every_case_is_one_escaped_line_and_exit_2(tmp_path):
    run_all(CASES, tmp_path, lambda case, lines, name, code: (
        code == 2 and len(lines) == (29 if case.kind == MANY else 1) and name in lines[0]
        and all(x.startswith("frictex: error: ") and x.isprintable() and "root:*" not in x
                for x in lines)))


@pytest.mark.parametrize("kind", list(NAMING))
def test_a_name_leading_out_is_a_problem_naming_its_key(tmp_path, kind, monkeypatch):
    monkeypatch.delenv(ALLOW_OUTSIDE_ENV, raising=False)
    template, key = NAMING[kind]
    folder = tmp_path / "scene"
    folder.mkdir()
    (tmp_path / "elsewhere.png").write_bytes(_png(4, 4))
    for name, what in (("../elsewhere.png", "through '..'"),
                       (str(tmp_path / "elsewhere.png"), "is an absolute path")):
        path = folder / "t.toml"
        path.write_text((BEAM_HEAD if kind == "mode table" else HEAD) + template.format(name=name))
        scene, problems, _ = check_scene(path)
        assert scene is None
        assert [p.field.rsplit(".", 1)[-1] for p in problems] == [key]
        assert what in problems[0].message and "--allow-outside" in problems[0].message


def test_links_inside_the_folder_and_dotdot_that_stays_inside_are_followed(tmp_path, monkeypatch):
    monkeypatch.delenv(ALLOW_OUTSIDE_ENV, raising=False)
    (tmp_path / "maps").mkdir()
    (tmp_path / "maps" / "m.png").write_bytes(_png(4, 4))
    os.symlink("maps/m.png", tmp_path / "link.png")
    for name in ("link.png", "maps/../maps/m.png", "./maps/m.png"):
        path = tmp_path / "t.toml"
        path.write_text(HEAD + RASTER.format(name=name))
        scene, problems, _ = check_scene(path)
        assert scene is not None, [str(p) for p in problems]
        assert scene.layers[0].image_path == (tmp_path / "maps" / "m.png").resolve()


def test_allow_outside_by_option_keyword_or_environment(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv(ALLOW_OUTSIDE_ENV, raising=False)
    (tmp_path / "elsewhere.png").write_bytes(_png(4, 4))
    folder = tmp_path / "scene"
    folder.mkdir()
    path = folder / "t.toml"
    path.write_text(HEAD + RASTER.format(name="../elsewhere.png"))
    assert check_scene(path)[0] is None
    assert check_scene(path, allow_outside=True)[0] is not None
    monkeypatch.setenv(ALLOW_OUTSIDE_ENV, "1")
    assert check_scene(path)[0] is not None
    monkeypatch.setenv(ALLOW_OUTSIDE_ENV, "0")
    assert main(["validate", str(path)]) == 2
    assert main(["validate", "--allow-outside", str(path)]) == 0  # sets the variable to 1
    assert os.environ[ALLOW_OUTSIDE_ENV] == "0"  # for that run only
    assert main(["validate", str(path)]) == 2


@pytest.mark.parametrize("command", ["replay", "preview", "demo", "batch"])
def test_every_command_that_loads_scenes_takes_the_option(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    assert "--allow-outside" in capsys.readouterr().out


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(key=st.text(st.characters(blacklist_categories=("Cs",)), min_size=1, max_size=300))
def test_unknown_keys_are_shown_escaped_and_cut(tmp_path, key):
    """Whatever characters an unknown key holds, its problem is one printable line that
    shows the key escaped and cut (at most 40 characters of it)."""
    key = "zz" + key  # never a known key
    quoted = '"' + "".join(c if c.isascii() and c.isalnum() else f"\\U{ord(c):08x}" for c in key) + '"'
    path = tmp_path / "t.toml"
    path.write_text(HEAD + '[[layer]]\ntype = "bump"\ncx_mm = 5\ncy_mm = 5\nsigma_mm = 1\n'
                    f'mu = 0.5\n{quoted} = 1\n')
    scene, problems, _ = check_scene(path)
    assert scene is None
    line = str(problems[0])
    assert line.isprintable() and "\n" not in line
    assert problems[0].field == "layer[1]." + escape(key, 40)


def test_preview_takes_allow_outside(tmp_path, monkeypatch):
    monkeypatch.setenv(ALLOW_OUTSIDE_ENV, "0")  # restored after the test
    (tmp_path / "elsewhere.png").write_bytes(_png(4, 4))
    folder = tmp_path / "scene"
    folder.mkdir()
    path = folder / "t.toml"
    path.write_text(HEAD + RASTER.format(name="../elsewhere.png"))
    assert main(["preview", str(path), "-o", str(tmp_path / "p.png")]) == 2
    assert not (tmp_path / "p.png").exists()
    assert main(["preview", str(path), "-o", str(tmp_path / "p.png"), "--allow-outside"]) == 0
    assert (tmp_path / "p.png").stat().st_size > 0


@settings(max_examples=200, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(parts=st.lists(st.sampled_from(["a", "b", "..", ".", "up"]), min_size=1, max_size=8))
def test_a_relative_name_is_refused_exactly_when_it_leads_out(tmp_path, parts):
    """Names of folders, '.', '..' and a link 'up' (to the folder above) resolve inside
    the texture file's folder, or are refused; never read outside."""
    from frictex.textures.errors import TextureError
    from frictex.textures.sections.files import Files
    root = tmp_path / "root"
    for sub in ("a", "b", "a/b", "b/a", "a/a", "b/b"):
        (root / sub).mkdir(parents=True, exist_ok=True)
    if not (root / "up").exists():
        os.symlink("..", root / "up")
    name = "/".join(parts)
    real = Path(os.path.realpath(root / name))
    inside = real == root.resolve() or root.resolve() in real.parents
    try:
        located = Files(root).locate(name)
    except TextureError:
        assert not inside or os.path.normpath(name).split(os.sep)[0] == ".."
    else:
        assert inside and located == real


@pytest.mark.parametrize("kind", list(NAMING))
@pytest.mark.parametrize("make, phrase", [
    (os.mkfifo, "is a FIFO (named pipe), not a regular file (frictex reads only regular files)"),
    (os.mkdir, "is a folder, not a file"),
])
def test_a_named_fifo_or_folder_is_refused_in_the_words_used_for_the_texture_file(
        tmp_path, kind, make, phrase):
    """A FIFO or a folder named by a scene: the sentence a texture file of that kind gets
    (``device.safe_files``), not the system's 'Illegal seek' or 'Is a directory'."""
    template, key = NAMING[kind]
    make(tmp_path / "f.dat")
    path = tmp_path / "t.toml"
    path.write_text((BEAM_HEAD if kind == "mode table" else HEAD) + template.format(name="f.dat"))
    _, problems, _ = check_scene(path)
    assert [p.field.rsplit(".", 1)[-1] for p in problems] == [key]
    assert f'"f.dat": {tmp_path / "f.dat"}: {phrase}' in problems[0].message
    make(tmp_path / "scene.toml")
    _, problems, _ = check_scene(tmp_path / "scene.toml")
    assert phrase in problems[0].message
