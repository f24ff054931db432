"""Hostile files, one kind per row: texture files, images, traces and recordings with
pathological structure all end in exit 2 and one line ``frictex: error: ...`` naming the
file, never a traceback, a hang or a memory blow-up.

Each case runs ``frictex`` in a child process under an address-space limit of 1 GiB
(``RLIMIT_AS``) and a generous wall-clock timeout, so that a hang or a blow-up fails the
test instead of hanging or killing it. The timeout is a guard, not a speed claim.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import zlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from struct import pack
from typing import Callable

from frictex.device.safe_text import escape

ROOT = Path(__file__).resolve().parents[1]
ADDRESS_SPACE = 1 << 30
TIMEOUT_S = 60.0
RUN = "import sys; from frictex.app.commands.cli import main; sys.exit(main(sys.argv[1:]))"

HEAD = ("format = 1\n[display]\nwidth_mm = 108.0\nheight_mm = 64.8\nwidth_px = 800\n"
        "height_px = 480\n")
GRATING = '[[layer]]\ntype = "grating"\nperiod_mm = {period}\nmu_low = 0.7\n'
RASTER = ('[[layer]]\ntype = "raster"\nimage = "{image}"\nwidth_mm = 10\nheight_mm = 10\n'
          'mu_black = 0.7\n')
TRACE_HEAD = "t_s,finger,x_mm,y_mm,force_n,event\n"
GOOD_ROW = "0.0,0,10,10,0.5,down\n"


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def _png(width: int, height: int, rows: int) -> bytes:
    """An 8-bit greyscale PNG whose header says width x height, holding ``rows`` rows."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return pack(">I", len(data)) + kind + data + pack(">I", zlib.crc32(kind + data))
    ihdr = pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    idat = zlib.compress(b"\0" * ((width + 1) * rows))
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def _flip_idat(png: bytes) -> bytes:
    """``png`` with one byte of its compressed pixels inverted."""
    data = bytearray(png)
    data[data.index(b"IDAT") + 10] ^= 0xFF
    return bytes(data)


def _nested(opening: str, closing: str, depth: int) -> str:
    return opening * depth + "1" + closing * depth


@dataclass(frozen=True)
class Case:
    """``make(folder) -> (argv, name)``: the command to run and the file name that the
    error line must contain."""

    kind: str
    make: Callable[[Path], tuple[list[str], str]]


Content = str | bytes | Callable[[Path], None]


def _put(path: Path, content: Content) -> None:
    """Write text or bytes at ``path``, or make it with ``content(path)`` (a FIFO, a link)."""
    if callable(content):
        content(path)
    elif isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)


def _texture(content: Content):
    def make(folder: Path):
        _put(folder / "hostile.toml", content)
        return ["validate", str(folder / "hostile.toml")], "hostile.toml"
    return make


def _special_texture(create: Callable[[Path], None], command: str = "validate"):
    def make(folder: Path):
        path = folder / "special.toml"
        create(path)
        argv = ["validate", str(path)] if command == "validate" else \
            ["replay", str(path), "swipe-40mms-50hz", "--out", str(folder / "out"), "--quiet"]
        return argv, "special.toml"
    return make


def _image(create: Callable[[Path], None], command: str = "validate"):
    """A raster scene whose image is made by ``create(path of the image)``."""
    def make(folder: Path):
        image = folder / "map.png"
        create(image)
        scene = folder / "scene.toml"
        scene.write_text(HEAD + RASTER.format(image="map.png"))
        argv = {"validate": ["validate", str(scene)],
                "replay": ["replay", str(scene), "swipe-40mms-50hz", "--out", str(folder / "out"),
                           "--quiet", "--rate", "1000"],
                "preview": ["preview", str(scene), "-o", str(folder / "p.png")]}[command]
        return argv, "map.png"
    return make


BEAM = ('format = 1\n[display]\nwidth_mm = 108.0\nheight_mm = 6\nwidth_px = 800\nheight_px = 48\n'
        '[device]\nprofile = "beam-seed000"\n[device.structure]\nmodes_file = "modes.csv"\n'
        'actuators_mm = [60, 290]\n[[layer]]\ntype = "bump"\ncx_mm = 50\ncy_mm = 3\n'
        'sigma_mm = 2\nmu = 0.7\n')


def _modes(content: Content):
    """A beam scene whose measured mode table (``modes_file``) is hostile."""
    def make(folder: Path):
        _put(folder / "modes.csv", content)
        (folder / "beam.toml").write_text(BEAM)
        return ["validate", str(folder / "beam.toml")], "modes.csv"
    return make


def _trace(content: Content):
    def make(folder: Path):
        _put(folder / "hostile.csv", content)
        return ["replay", "grating-5mm", str(folder / "hostile.csv"), "--out", str(folder / "out"),
                "--quiet", "--rate", "1000"], "hostile.csv"
    return make


def _recording(content: Content):
    def make(folder: Path):
        _put(folder / "hostile.txt", content)
        return ["trace", "import", str(folder / "hostile.txt"), "-o", str(folder / "o.csv")], \
            "hostile.txt"
    return make


def _loop(path: Path) -> None:
    os.symlink(path.name, path)


def _to_dev_zero(path: Path) -> None:
    os.symlink("/dev/zero", path)


def _rows(row: str) -> str:
    return TRACE_HEAD + GOOD_ROW + row


BINARY = bytes(range(256)) * 64
EVEMU = "# EVEMU 1.3\nN: pad\nA: 35 0 1000 0 0 0\nA: 36 0 1000 0 0 0\n"

CASES = [
    # texture files: structure, size, encoding
    Case("toml nested arrays 3000 deep", _texture("a = " + _nested("[", "]", 3000) + "\n")),
    Case("toml nested inline tables 3000 deep", _texture("a = " + _nested("{b=", "}", 3000) + "\n")),
    Case("toml dotted key of 300,000 parts", _texture("a" + ".a" * 300_000 + " = 1\n" + HEAD)),
    Case("toml quoted dotted key of 17 parts", _texture(".".join(['"k"'] * 17) + " = 1\n" + HEAD)),
    Case("toml inline table of 60,000 keys", _texture(
        "x = {" + ", ".join(f"k{i} = 1" for i in range(60_000)) + "}\n" + HEAD
        + GRATING.format(period=5))),
    Case("toml nested arrays 40 deep", _texture("a = " + _nested("[", "]", 40) + "\n")),
    Case("toml file of 3 MiB", _texture(HEAD + "#" * (3 << 20) + "\n")),
    Case("toml name of 500 kB on one line", _texture('name = "' + "x" * 500_000 + '"\n' + HEAD
                                                     + GRATING.format(period=5))),
    Case("toml key of 900 kB", _texture(HEAD + GRATING.format(period=5) + "k" * 900_000 + " = 1\n")),
    Case("toml with 3000 layers", _texture(HEAD + GRATING.format(period=5) * 3000)),
    Case("toml binary content", _texture(BINARY)),
    Case("toml UTF-16", _texture((HEAD + GRATING.format(period=5)).encode("utf-16"))),
    Case("toml Latin-1 byte", _texture(HEAD.encode() + b'name = "caf\xe9"\n')),
    Case("toml NUL byte", _texture(HEAD.encode() + b"\0\n")),
    Case("toml integer of 5000 digits", _texture(HEAD + "x = " + "9" * 5000 + "\n")),
    Case("toml syntax garbage", _texture("format = = 1\n[[[layer\n")),
    Case("toml empty file", _texture("")),
    Case("period 1e308", _texture(HEAD + GRATING.format(period="1e308"))),
    Case("period 1e-300", _texture(HEAD + GRATING.format(period="1e-300"))),
    Case("period inf", _texture(HEAD + GRATING.format(period="inf"))),
    Case("period nan", _texture(HEAD + GRATING.format(period="nan"))),
    Case("width_px 1e26", _texture(HEAD.replace("800", "100000000000000000000000000")
                                   + GRATING.format(period=5))),
    Case("negative size", _texture(HEAD.replace("108.0", "-108.0") + GRATING.format(period=5))),
    Case("zero size", _texture(HEAD.replace("64.8", "0") + GRATING.format(period=5))),
    Case("angle 1e308", _texture(HEAD + GRATING.format(period=5) + "angle_deg = 1e308\n")),
    Case("amplitude limit 1e308", _texture(HEAD + '[device]\namplitude_limit_um = 1e308\n'
                                           + GRATING.format(period=5))),
    Case("plate order 10**6", _texture(HEAD + '[device]\nprofile = "plate-seed001"\n'
                                       '[device.structure]\norder = 1000000\n'
                                       + GRATING.format(period=5))),
    Case("NUL in a layer name", _texture(HEAD + GRATING.format(period=5) + 'name = "a\\u0000b"\n')),
    Case("toml is a FIFO", _special_texture(os.mkfifo)),
    Case("toml is a FIFO, replay", _special_texture(os.mkfifo, "replay")),
    Case("toml is a folder", _special_texture(os.mkdir)),
    Case("toml is a symlink loop", _special_texture(_loop)),
    Case("toml is /dev/zero", _special_texture(_to_dev_zero)),
    # raster images
    Case("image missing", _image(lambda p: None)),
    Case("image is a symlink loop", _image(_loop)),
    Case("image is a FIFO", _image(os.mkfifo)),
    Case("image is a FIFO, replay", _image(os.mkfifo, "replay")),
    Case("image is a FIFO, preview", _image(os.mkfifo, "preview")),
    Case("image is a folder", _image(os.mkdir)),
    Case("image is /dev/zero", _image(_to_dev_zero)),
    Case("image is not an image", _image(lambda p: p.write_text("hello"))),
    Case("image truncated", _image(lambda p: p.write_bytes(_png(100, 100, 100)[:60]))),
    Case("image data flipped", _image(lambda p: p.write_bytes(_flip_idat(_png(100, 100, 100))))),
    Case("image 12000 x 12000 px", _image(lambda p: p.write_bytes(_png(12000, 12000, 4)))),
    Case("image 12000 x 12000 px, replay", _image(lambda p: p.write_bytes(_png(12000, 12000, 4)),
                                                  "replay")),
    # measured mode tables
    Case("modes table is a FIFO", _modes(os.mkfifo)),
    Case("modes table binary", _modes(BINARY[128:])),
    Case("modes table 1e308", _modes("x_mm,A,B\n0,0,1\n100,1e308,0\n200,1,1\n350,0,1\n")),
    # trace files
    Case("trace is a FIFO", _trace(os.mkfifo)),
    Case("trace is a folder", _trace(os.mkdir)),
    Case("trace is a symlink loop", _trace(_loop)),
    Case("trace is /dev/zero", _trace(_to_dev_zero)),
    Case("trace empty", _trace("")),
    Case("trace header only", _trace(TRACE_HEAD)),
    Case("trace binary", _trace(BINARY)),
    Case("trace UTF-16", _trace((TRACE_HEAD + GOOD_ROW).encode("utf-16"))),
    Case("trace Latin-1 byte", _trace(TRACE_HEAD.encode() + b"0,0,1\xe9,1,0.5,down\n")),
    Case("trace line of 2 MB without newline", _trace(TRACE_HEAD + "9" * 2_000_000)),
    Case("trace field over the csv limit", _trace(_rows('1,0,1,1,0.5,"' + "x" * 200_000 + '"\n'))),
    Case("trace missing column", _trace("t_s,finger,x_mm\n0,0,1\n")),
    Case("trace short row", _trace(_rows("1,0,1\n"))),
    Case("trace time 1e308", _trace(_rows("1e308,0,10,10,0.5,move\n"))),
    Case("trace time nan", _trace(_rows("nan,0,10,10,0.5,move\n"))),
    Case("trace time -inf", _trace(_rows("-inf,0,10,10,0.5,move\n"))),
    Case("trace x 1e308", _trace(_rows("0.01,0,1e308,10,0.5,move\n"))),
    Case("trace y -1e308", _trace(_rows("0.01,0,10,-1e308,0.5,move\n"))),
    Case("trace x of 4000 digits", _trace(_rows("0.01,0," + "9" * 4000 + ",10,0.5,move\n"))),
    Case("trace force 1e308", _trace(_rows("0.01,0,10,10,1e308,move\n"))),
    Case("trace force negative", _trace(_rows("0.01,0,10,10,-1,move\n"))),
    Case("trace finger 1e20", _trace(_rows("0.01,1e20,10,10,0.5,move\n"))),
    Case("trace finger 2^63-1", _trace(_rows("0.01,9223372036854775807,10,10,0.5,move\n"))),
    Case("trace finger -1", _trace(_rows("0.01,-1,10,10,0.5,move\n"))),
    Case("trace finger 1.5", _trace(_rows("0.01,1.5,10,10,0.5,move\n"))),
    Case("trace 2000 fingers at once", _trace(TRACE_HEAD + "".join(
        f"0.0,{k},{k % 100},10,0.5,down\n" for k in range(2000)))),
    Case("trace unknown event", _trace(_rows("0.01,0,10,10,0.5,slide\n"))),
    Case("trace NUL byte", _trace(_rows("0.01,0,1\0,10,0.5,move\n"))),
    # recordings for trace import
    Case("recording is a FIFO", _recording(os.mkfifo)),
    Case("recording binary", _recording(BINARY)),
    Case("recording evemu value of 30 digits", _recording(EVEMU + "E: 0.000001 0003 0035 "
                                                          + "9" * 30 + "\n")),
    Case("recording getevent time of 400 digits", _recording(
        "[ " + "9" * 400 + ".000001] EV_ABS ABS_MT_POSITION_X 0000000a\n")),
]


def _run(case: Case, folder: Path) -> tuple[Case, list[str] | None, str, int | None]:
    folder.mkdir()
    argv, name = case.make(folder)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MALLOC_ARENA_MAX="2",
               NUMBA_NUM_THREADS="1")
    try:
        done = subprocess.run([sys.executable, "-c", RUN, *argv], cwd=ROOT, env=env,
                              preexec_fn=_limit_memory, capture_output=True, text=True,
                              timeout=TIMEOUT_S, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return case, None, name, None
    return case, done.stderr.splitlines(), name, done.returncode


def run_all(cases: list[Case], tmp_path: Path, is_clean) -> None:
    """Run every case (4 at a time, each in a folder of its own); fail listing each case
    that hung or whose ``is_clean(case, stderr lines, name, exit code)`` is False."""
    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(lambda ic: _run(ic[1], tmp_path / f"case{ic[0]}"),
                                enumerate(cases)))
    failures = []
    for case, lines, name, code in results:
        if lines is None:
            failures.append(f"{case.kind}: still running after {TIMEOUT_S:g} s")
        elif not is_clean(case, lines, name, code):
            failures.append(f"{case.kind}: exit {code}, stderr {[escape(x, 300) for x in lines[-12:]]}")
    assert not failures, "\n".join(failures)


def test_at_least_forty_distinct_kinds():
    kinds = [c.kind for c in CASES]
    assert len(set(kinds)) == len(kinds) >= 40


def test_every_hostile_file_is_one_line_and_exit_2(tmp_path):
    run_all(CASES, tmp_path, lambda case, lines, name, code: (
        code == 2 and len(lines) == 1 and lines[0].startswith("frictex: error: ")
        and name in lines[0] and len(lines[0]) <= 1000 and lines[0].isprintable()))


def test_a_bom_at_the_start_just_works(tmp_path):
    from frictex.app.commands.cli import main
    scene = tmp_path / "bom.toml"
    scene.write_bytes(b"\xef\xbb\xbf" + (HEAD + GRATING.format(period=5)).encode())
    trace = tmp_path / "bom.csv"
    trace.write_bytes(b"\xef\xbb\xbf" + (TRACE_HEAD + GOOD_ROW + "0.1,0,20,10,0.5,up\n").encode())
    assert main(["validate", str(scene)]) == 0
    assert main(["replay", str(scene), str(trace), "--out", str(tmp_path / "o"), "--quiet",
                 "--rate", "1000"]) == 0
