"""Friction maps whose PNG says some pixels are transparent through a tRNS chunk (palette
alpha, or one transparent grey level or colour), and palettes a pixel indexes past: refused
in one sentence, as an alpha channel is, with no Pillow warning on the way."""

import struct
import warnings
import zlib

import numpy as np
import pytest
from numpy.testing import assert_allclose
from PIL import Image

from frictex.textures.errors import TextureError
from frictex.textures.raster_io import read_grey

TRANSPARENT = r"image mode {} has transparent pixels \(alpha down to {}\)"


def chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def raw_png(path, depth, colour, rows, *chunks):
    """A PNG written byte by byte (Pillow writes no 2-bit grey and no bad palette index):
    ``rows`` the packed bytes of each row, ``chunks`` (type, body) pairs before the data."""
    header = struct.pack(">IIBBBBB", len(rows[0]) * 8 // depth, len(rows), depth, colour, 0, 0, 0)
    data = zlib.compress(b"".join(b"\0" + row for row in rows))
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + b"".join(chunk(kind, body) for kind, body in chunks)
                     + chunk(b"IDAT", data) + chunk(b"IEND", b""))
    return path


def read_quietly(path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return read_grey(path)


def half_transparent_rgba():
    rgba = np.full((4, 4, 4), 200, np.uint8)
    rgba[:, :2, 3] = 0
    return Image.fromarray(rgba, mode="RGBA")


def test_quantized_rgba_with_transparency_is_refused_without_a_warning(tmp_path):
    path = tmp_path / "q.png"
    half_transparent_rgba().quantize().save(path)
    with pytest.raises(TextureError, match=TRANSPARENT.format("P", 0)):
        read_quietly(path)


def test_palette_alpha_on_unused_entries_is_no_transparency(tmp_path):
    path = raw_png(tmp_path / "p.png", 8, 3, [bytes([1, 1])],
                   (b"PLTE", bytes([0, 0, 0, 255, 255, 255])), (b"tRNS", bytes([0, 255])))
    grey, kind = read_quietly(path)
    assert kind == "RGB as Rec. 601 luma"
    assert_allclose(grey, [[1.0, 1.0]], rtol=1e-12)


def test_one_transparent_palette_entry_is_refused(tmp_path):
    path = tmp_path / "p.png"
    image = Image.fromarray(np.array([[0, 1]], np.uint8), mode="P")
    image.putpalette([0, 0, 0, 255, 255, 255])
    image.save(path, transparency=1)
    with pytest.raises(TextureError, match=TRANSPARENT.format("P", 0)):
        read_quietly(path)


@pytest.mark.parametrize("pixels, key", [(np.array([[5, 9]], np.uint8), 5),
                                         (np.array([[300, 9]], np.uint16), 300),
                                         (np.array([[[1, 2, 3], [1, 2, 4]]], np.uint8), (1, 2, 3))])
def test_a_transparent_grey_level_or_colour_is_refused_where_a_pixel_has_it(tmp_path, pixels, key):
    path = tmp_path / "k.png"
    image = Image.fromarray(pixels)
    image.save(path, transparency=key)
    with pytest.raises(TextureError, match=TRANSPARENT.format(image.mode, 0)):
        read_quietly(path)
    Image.fromarray(pixels[:, 1:]).save(path, transparency=key)
    read_quietly(path)  # no pixel has the transparent value: opaque


def test_two_bit_grey_key_is_compared_on_the_raw_level(tmp_path):
    two_bit_row = [bytes([0b10_01_00_00])]  # levels 2, 1, 0, 0 (decoded 170, 85, 0, 0)
    opaque = raw_png(tmp_path / "o.png", 2, 0, two_bit_row, (b"tRNS", struct.pack(">H", 3)))
    grey, _ = read_quietly(opaque)
    assert_allclose(grey, [[2 / 3, 1 / 3, 0, 0]], rtol=1e-12)
    hidden = raw_png(tmp_path / "t.png", 2, 0, two_bit_row, (b"tRNS", struct.pack(">H", 1)))
    with pytest.raises(TextureError, match=TRANSPARENT.format("L", 0)):
        read_quietly(hidden)


def test_a_palette_index_past_the_palette_is_refused(tmp_path):
    path = raw_png(tmp_path / "p.png", 8, 3, [bytes([0, 5])], (b"PLTE", bytes([0, 0, 0, 255, 255, 255])))
    with pytest.raises(TextureError, match=r"palette index 5, and the palette has 2 entries"):
        read_quietly(path)
