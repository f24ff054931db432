"""Reading friction maps from images: every accepted kind, and clear refusals."""

import numpy as np
import pytest
from numpy.testing import assert_allclose
from PIL import Image

from frictex.textures import raster_io
from frictex.textures.errors import TextureError
from frictex.textures.raster_io import read_grey


def save(tmp_path, image, name="m.png"):
    path = tmp_path / name
    image.save(path)
    return path


def test_8bit(tmp_path):
    a = np.array([[0, 1, 254, 255]], dtype=np.uint8)
    grey, kind = read_grey(save(tmp_path, Image.fromarray(a)))
    assert kind == "8-bit greyscale" and grey.dtype == np.float64
    assert_allclose(grey, a / 255.0, rtol=0, atol=0)


def test_16bit_keeps_all_levels(tmp_path):
    a = np.array([[0, 1, 32768, 65535]], dtype=np.uint16)
    grey, kind = read_grey(save(tmp_path, Image.fromarray(a)))
    assert kind == "16-bit greyscale"
    assert_allclose(grey, a / 65535.0, rtol=0, atol=0)
    assert grey[0, 1] > 0.0  # one 16-bit step survives (8 bits would lose it)


def test_rows_are_top_down(tmp_path):
    a = np.array([[0], [255]], dtype=np.uint8)
    grey, _ = read_grey(save(tmp_path, Image.fromarray(a)))
    assert grey[:, 0].tolist() == [0.0, 1.0]


def test_palette_and_opaque_rgba_become_luma(tmp_path):
    rgb = np.array([[[255, 0, 0], [0, 0, 255]]], dtype=np.uint8)
    expected = [0.299, 0.114]
    rgba = np.concatenate([rgb, np.full((1, 2, 1), 255, np.uint8)], axis=2)
    grey, kind = read_grey(save(tmp_path, Image.fromarray(rgba), "a.png"))
    assert kind == "RGB as Rec. 601 luma"
    assert_allclose(grey[0], expected, rtol=1e-12)
    grey, _ = read_grey(save(tmp_path, Image.fromarray(rgb).convert("P"), "p.png"))
    assert_allclose(grey[0], expected, rtol=1e-12)


def test_one_bit(tmp_path):
    grey, kind = read_grey(save(tmp_path, Image.fromarray(np.array([[0, 255]], np.uint8)).convert("1")))
    assert kind == "1-bit" and grey.tolist() == [[0.0, 1.0]]


def test_transparent_pixels_are_refused(tmp_path):
    la = Image.fromarray(np.array([[[10, 255], [20, 128]]], dtype=np.uint8), mode="LA")
    with pytest.raises(TextureError, match=r"image mode LA has transparent pixels \(alpha down to 128\)"):
        read_grey(save(tmp_path, la))


def test_other_formats_are_refused_before_pillow_sees_them(tmp_path, monkeypatch):
    """A float TIFF, and an EPS named .png (which Pillow would hand to Ghostscript), are
    refused from their first bytes; Pillow is never asked to open them."""
    from PIL import Image as PILImage
    path = save(tmp_path, Image.fromarray(np.zeros((2, 2), np.float32)), "f.tiff")
    eps = tmp_path / "map.png"
    eps.write_bytes(b"%!PS-Adobe-3.0 EPSF-3.0\n%%BoundingBox: 0 0 10 10\nshowpage\n")
    opened = []
    monkeypatch.setattr(PILImage, "open", lambda *a, **k: opened.append(a))
    with pytest.raises(TextureError, match=r"f\.tiff: a TIFF file, not a PNG; expected 8- or 16-bit greyscale PNG"):
        read_grey(path)
    with pytest.raises(TextureError, match=r"map\.png: a PostScript \(EPS\) file, not a PNG"):
        read_grey(eps)
    assert opened == []


def test_not_an_image_and_too_big(tmp_path, monkeypatch):
    junk = tmp_path / "j.png"
    junk.write_bytes(b"\x89PNG but not really")
    with pytest.raises(TextureError, match=r"19 bytes that do not start with the PNG signature, not a PNG"):
        read_grey(junk)
    cut = tmp_path / "cut.png"
    noise = np.random.default_rng(0).integers(0, 255, (40, 40), dtype=np.uint8)
    cut.write_bytes(save(tmp_path, Image.fromarray(noise)).read_bytes()[:800])
    with pytest.raises(TextureError, match=r"cut\.png: truncated PNG: .* of the 40 rows"):
        read_grey(cut)
    with pytest.raises(TextureError, match=r"none\.png: No such file or directory; expected 8- or 16-bit"):
        read_grey(tmp_path / "none.png")
    monkeypatch.setattr(raster_io, "MAX_PIXELS", 10)
    with pytest.raises(TextureError, match=r"image is 4 x 3 px, more than the 10 px frictex reads"):
        read_grey(save(tmp_path, Image.fromarray(np.zeros((3, 4), np.uint8))))


def test_a_corrupt_header_is_said_without_pythons_words_for_a_file_in_memory(tmp_path):
    """An IHDR whose CRC is wrong: Pillow's message named its in-memory file by its repr
    (<_io.BytesIO object at 0x7f...>)."""
    good = save(tmp_path, Image.fromarray(np.zeros((8, 8), np.uint8))).read_bytes()
    bad = tmp_path / "crc.png"
    bad.write_bytes(good[:30] + bytes([good[30] ^ 0xFF]) + good[31:])
    with pytest.raises(TextureError, match=r"crc\.png: corrupt PNG, decoding failed") as caught:
        read_grey(bad)
    assert "object at 0x" not in str(caught.value) and "BytesIO" not in str(caught.value)


def test_a_png_whose_metadata_inflates_too_far_is_said_so_not_corrupt(tmp_path):
    """A valid 10 x 10 PNG with a zTXt chunk inflating past 1 MiB was 'corrupt PNG,
    decoding failed (ValueError: Decompressed data too large for PngImagePlugin.MAX_TEXT_C...'."""
    from PIL.PngImagePlugin import PngInfo
    info = PngInfo()
    info.add_text("comment", "x" * (2 << 20), zip=True)  # deflates to about 2 kB
    path = tmp_path / "meta.png"
    Image.fromarray(np.zeros((10, 10), np.uint8)).save(path, pnginfo=info)
    assert path.stat().st_size < 20_000
    with pytest.raises(TextureError, match=r"meta\.png: a metadata chunk \(text or ICC profile\) "
                                           r"inflates to over 1 MiB, more than is read; strip "
                                           r"the PNG's metadata") as caught:
        read_grey(path)
    assert "corrupt" not in str(caught.value) and "MAX_TEXT" not in str(caught.value)


def _png(width, height, depth, colour, raw, interlace=0):
    """A PNG written from the specification: IHDR, one IDAT of ``raw`` (filtered
    scanlines) deflated, IEND."""
    import struct
    import zlib

    def chunk(kind, body):
        return (struct.pack(">I", len(body)) + kind + body
                + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))
    ihdr = struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, interlace)
    return (raster_io.PNG_SIGNATURE + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw))
            + chunk(b"IEND", b""))


def test_image_data_shorter_than_the_header_is_refused(tmp_path):
    """A header of 4000 x 4000 over one row of data: Pillow pads with black; refused,
    and Pillow's LOAD_TRUNCATED_IMAGES stays False."""
    from PIL import ImageFile
    path = tmp_path / "lie.png"
    path.write_bytes(_png(4000, 4000, 8, 0, b"\x00" + b"\x80" * 4000))
    with pytest.raises(TextureError, match=r"truncated PNG: .* 1 of the 4,000 rows"):
        read_grey(path)
    path.write_bytes(_png(40, 30, 8, 0, (b"\x00" + b"\x80" * 40) * 29))  # one row short
    with pytest.raises(TextureError, match="truncated PNG"):
        read_grey(path)
    path.write_bytes(_png(40, 30, 8, 0, (b"\x00" + b"\x80" * 40) * 30))
    assert_allclose(read_grey(path)[0], 128 / 255)
    assert ImageFile.LOAD_TRUNCATED_IMAGES is False


@pytest.mark.parametrize("size, depth, mode", [((37, 23), 8, "L"), ((37, 23), 16, "I;16"),
                                               ((5, 3), 8, "RGB"), ((9, 9), 1, "1")])
def test_the_expected_image_data_matches_what_pillow_writes(tmp_path, size, depth, mode):
    """image_data_bytes is what a whole PNG inflates to, so whole files are never taken
    for truncated ones."""
    import zlib
    arr = np.random.default_rng(1).integers(0, 2 ** min(depth, 8), size[::-1])
    image = Image.fromarray(arr.astype(np.uint16 if depth == 16 else np.uint8))
    image = image.convert(mode) if mode in ("RGB", "1") else image
    data = save(tmp_path, image).read_bytes()
    width, height, d, colour = raster_io.png_header(data, "w", "")
    idat, pos = b"", 8
    while pos < len(data):
        length = int.from_bytes(data[pos:pos + 4], "big")
        if data[pos + 4:pos + 8] == b"IDAT":
            idat += data[pos + 8:pos + 8 + length]
        pos += 12 + length
    assert raster_io.image_data_bytes(width, height, d, colour, False) == len(zlib.decompress(idat))


@pytest.mark.parametrize("width, height", [(13, 11), (1, 1), (8, 3), (3, 8)])
def test_an_interlaced_png_is_whole_at_its_adam7_size_and_truncated_below(tmp_path, width, height):
    """Adam7 scanlines written by hand (pass by pass, filter 0), decoded by Pillow: the
    whole file reads back exactly; one byte less is refused as truncated."""
    grid = np.arange(width * height, dtype=np.uint8).reshape(height, width)
    raw = b"".join(b"\x00" + grid[y, x0::dx].tobytes()
                   for x0, y0, dx, dy in raster_io._ADAM7 if x0 < width
                   for y in range(y0, height, dy))
    assert len(raw) == raster_io.image_data_bytes(width, height, 8, 0, True)
    path = tmp_path / "a7.png"
    path.write_bytes(_png(width, height, 8, 0, raw, interlace=1))
    assert_allclose(read_grey(path)[0], grid / 255)
    path.write_bytes(_png(width, height, 8, 0, raw[:-1], interlace=1))
    with pytest.raises(TextureError, match="truncated PNG"):
        read_grey(path)
