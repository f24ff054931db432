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
    with pytest.raises(TextureError, match=r"cut\.png: corrupt PNG, decoding failed"):
        read_grey(cut)
    with pytest.raises(TextureError, match=r"none\.png: No such file or directory; expected 8- or 16-bit"):
        read_grey(tmp_path / "none.png")
    monkeypatch.setattr(raster_io, "MAX_PIXELS", 10)
    with pytest.raises(TextureError, match=r"image is 4 x 3 px, more than the 10 px frictex reads"):
        read_grey(save(tmp_path, Image.fromarray(np.zeros((3, 4), np.uint8))))
