"""Friction maps from image files: grey levels as float64 in [0, 1].

The convention is that of commercial friction displays: a greyscale image where
brightness is friction (black = most slippery, white = most friction). PNG files only (the
signature is checked first; Pillow decodes with its PNG plugin alone), read with Pillow:

- 8-bit greyscale (mode ``L``): g = value / 255;
- 16-bit greyscale (modes ``I;16``, ``I;16B``, ``I`` with values in 0..65535): g = value / 65535;
- 1-bit (mode ``1``): g = 0 or 1;
- colour (``RGB``, palette ``P``): converted to luma with the Rec. 601 weights
  g = (0.299 R + 0.587 G + 0.114 B) / 255 on the stored (gamma-encoded) values, the
  same weights as Pillow's own ``convert("L")`` but kept in float64 without rounding;
- with an alpha channel (``LA``, ``RGBA``, ``PA``), or a transparency chunk (``tRNS``: alpha
  per palette entry, or one grey level or colour that is transparent): accepted only if every
  pixel is fully opaque (transparency has no friction meaning); the alpha is then ignored;
- a palette pixel must index an entry the palette has.

Row 0 is the top of the image (screen y points down).
"""

from __future__ import annotations

import io
import re
import struct
import warnings
from pathlib import Path

import numpy as np

from frictex.device.safe_files import UnsafeFile, read_bytes
from frictex.device.safe_text import escape, escape_path
from frictex.textures.errors import TextureError

#: Largest image accepted (pixels), checked from the PNG header before any pixel is
#: decoded: a friction map is sampled at finger positions only, and a 16 Mpx float64
#: map already takes 128 MB.
MAX_PIXELS = 16_000_000
#: Largest image file read (bytes): a 16 Mpx 16-bit RGBA PNG stored uncompressed.
MAX_FILE_BYTES = 128 << 20
#: Decoded maps one scene may hold (bytes of float64 planes, all its images and height
#: maps together): a raster map keeps 8 bytes per pixel (32 Mpx in all), a height map 32
#: (``textures.heights.HeightMap``: heights and three planes; 8 Mpx in all). Charged from
#: each PNG's header before it is decoded, so 32 layers of small files that decode to
#: 16 Mpx each are refused at the first that does not fit, having decoded none of it.
MAX_SCENE_BYTES = 256 << 20
#: Bytes a decoded raster map keeps per pixel (its float64 grey levels).
RASTER_BYTES_PER_PX = 8

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_IHDR = struct.Struct(">I4sIIBB")  # chunk length, type, width, height, bit depth, colour type

_REC601 = np.array([0.299, 0.587, 0.114])


#: The image kinds :func:`read_grey` accepts, for error messages.
ACCEPTED = "8- or 16-bit greyscale PNG (colour is converted to Rec. 601 luma)"


class PixelBudget:
    """What is left of a scene's :data:`MAX_SCENE_BYTES` of decoded maps."""

    def __init__(self, max_bytes: int = MAX_SCENE_BYTES):
        self.max_bytes = max_bytes
        self.spent = 0

    def charge(self, where: str, pixels: int, bytes_per_px: int) -> None:
        """Take ``pixels`` x ``bytes_per_px`` from the budget, or raise TextureError
        (its message starting with ``where``) if that does not fit."""
        cost = pixels * bytes_per_px
        if self.spent + cost > self.max_bytes:
            raise TextureError(
                f"{where}: decoding it would take {cost / 2**20:,.0f} MiB ({pixels:,} px x "
                f"{bytes_per_px} bytes) where the scene has {(self.max_bytes - self.spent) / 2**20:,.0f} "
                f"MiB left of the {self.max_bytes / 2**20:,.0f} MiB its images and height maps "
                f"may take together; scale the image down")
        self.spent += cost


def png_header(data: bytes, where: str, expected: str) -> tuple[int, int, int, int]:
    """(width, height, bit depth, colour type) from a PNG's IHDR chunk, or TextureError if
    ``data`` does not start as a PNG file does (any other format is refused here, before
    an image library sees the bytes)."""
    if not data.startswith(PNG_SIGNATURE):
        return _not_png(data, where, expected)
    if len(data) < len(PNG_SIGNATURE) + _IHDR.size:
        raise TextureError(f"{where}: a PNG file cut short ({len(data)} bytes, no header); "
                           f"expected {expected}")
    length, kind, width, height, depth, colour = _IHDR.unpack_from(data, len(PNG_SIGNATURE))
    if length != 13 or kind != b"IHDR":
        raise TextureError(f"{where}: a PNG file whose first chunk is not its header (IHDR); "
                           f"expected {expected}")
    return width, height, depth, colour


#: PNG colour types (IHDR): name and samples per pixel
_COLOUR_TYPES = {0: ("greyscale", 1), 2: ("RGB", 3), 3: ("palette", 1), 4: ("greyscale with alpha", 2),
                 6: ("RGBA", 4)}
#: Adam7 passes: first column, first row, column step, row step
_ADAM7 = ((0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2))
_INFLATE_STEP = 1 << 20  # bytes inflated at a time when counting the image data
#: how Python shows an in-memory file object in a message (its type and address)
_IN_MEMORY = re.compile(r"<_io\.BytesIO object at 0x[0-9a-f]+>")
#: most a PNG's text or ICC chunk may inflate to (MiB): Pillow's ``MAX_TEXT_CHUNK``
_METADATA_MIB = 1.0


def header_kind(depth: int, colour: int) -> str:
    """What a PNG header says its pixels are, e.g. ``"8-bit RGB"``."""
    name = _COLOUR_TYPES.get(colour, (f"colour type {colour}", 1))[0]
    return f"{depth}-bit {name}"


def image_data_bytes(width: int, height: int, depth: int, colour: int, interlaced: bool) -> int:
    """Bytes of filtered scanlines a PNG of this header inflates to (PNG spec 7.2, 8.2):
    per row of each pass, a filter byte and the row's packed samples."""
    bits = depth * _COLOUR_TYPES.get(colour, ("", 1))[1]
    passes = _ADAM7 if interlaced else ((0, 0, 1, 1),)
    total = 0
    for x0, y0, dx, dy in passes:
        cols, rows = -(-(width - x0) // dx), -(-(height - y0) // dy)
        if cols > 0 and rows > 0:
            total += rows * (1 + -(-cols * bits // 8))
        # an empty pass has no rows at all
    return total


def check_image_data(data: bytes, where: str, expected: str) -> None:
    """Refuse a PNG whose image data (its IDAT chunks, inflated) is shorter than its
    header's size needs: Pillow would decode the rows there are and pad the rest with
    black (a 4000 x 4000 header over one row of data), whatever LOAD_TRUNCATED_IMAGES
    says. Counts without keeping: memory stays at :data:`_INFLATE_STEP`."""
    import zlib

    width, height, depth, colour = png_header(data, where, expected)
    interlaced = len(data) > 28 and data[28] == 1
    need = image_data_bytes(width, height, depth, colour, interlaced)
    inflater, got, pos = zlib.decompressobj(), 0, len(PNG_SIGNATURE)
    while pos + 8 <= len(data) and got < need:
        length, kind = struct.unpack_from(">I4s", data, pos)
        if kind == b"IDAT":
            pending = data[pos + 8:pos + 8 + length]
            while pending and got < need:
                try:
                    got += len(inflater.decompress(pending, _INFLATE_STEP))
                except zlib.error as exc:
                    raise TextureError(f"{where}: corrupt PNG, its image data does not inflate "
                                       f"({escape(exc)}); expected {expected}") from None
                pending = inflater.unconsumed_tail
        elif kind == b"IEND":
            break
        pos += 12 + length
    if got < need:
        row = need / max(height, 1)
        raise TextureError(f"{where}: truncated PNG: its image data holds about {got / row:,.0f} "
                           f"of the {height:,} rows its header says ({got:,} of {need:,} bytes); "
                           f"expected {expected}")


def _not_png(data: bytes, where: str, expected: str):
    known = ((b"%!PS", "PostScript (EPS)"), (b"\xc5\xd0\xd3\xc6", "PostScript (EPS)"),
             (b"\xff\xd8\xff", "JPEG"), (b"GIF8", "GIF"), (b"BM", "BMP"), (b"II*\x00", "TIFF"),
             (b"MM\x00*", "TIFF"), (b"RIFF", "RIFF (WebP)"), (b"%PDF", "PDF"))
    name = next((label for magic, label in known if data.startswith(magic)), None)
    what = f"a {name} file" if name else (f"{len(data):,} bytes that do not start with the PNG "
                                           f"signature" if data else "an empty file")
    raise TextureError(f"{where}: {what}, not a PNG; expected {expected} (frictex opens PNG "
                       f"files only)")


def read_grey(path: str | Path, expected: str = ACCEPTED, budget: PixelBudget | None = None,
              bytes_per_px: int = RASTER_BYTES_PER_PX,
              header: tuple[int, int] | None = None) -> tuple[np.ndarray, str]:
    """Read a PNG file as grey levels.

    Parameters
    ----------
    path : the image file (PNG only: the signature is checked before an image library
        sees the bytes, and Pillow is allowed only its PNG plugin).
    expected : what the caller takes, said by the errors (default :data:`ACCEPTED`).
    budget : the scene's budget of decoded maps, charged ``bytes_per_px`` per pixel from
        the header before decoding (None: only :data:`MAX_PIXELS` applies).
    bytes_per_px : what the caller keeps per pixel once decoded (bytes).
    header : the one (bit depth, PNG colour type) the caller takes, e.g. (16, 0) for
        16-bit greyscale: any other is refused from the header, before decoding
        (None: every kind above).

    Returns
    -------
    grey : float64 array (rows, cols), values in [0, 1], row 0 at the top.
    kind : how the pixels were read, e.g. ``"8-bit greyscale"`` (for reports).

    Raises
    ------
    TextureError, its message starting with the file's (escaped) path: not a regular
    file (checked before opening: a FIFO would block), larger than ``MAX_FILE_BYTES``,
    not a PNG, not of the ``header`` kind, more than ``MAX_PIXELS`` or more than the
    budget has left (from the header, before decoding), corrupt, or truncated (image
    data shorter than the header's size: :func:`check_image_data`).
    """
    from PIL import Image

    path = Path(path)
    where = escape_path(path)
    try:
        data = read_bytes(path, MAX_FILE_BYTES)
    except UnsafeFile as exc:
        raise TextureError(f"{where}: {exc}; expected {expected}") from None
    width, height, depth, colour = png_header(data, where, expected)
    if header is not None and (depth, colour) != header:
        raise TextureError(f"{where}: its header says {header_kind(depth, colour)} pixels; "
                           f"expected {expected}")
    if width == 0 or height == 0:
        raise TextureError(f"{where}: image is empty ({width} x {height} px)")
    if width * height > MAX_PIXELS:
        raise TextureError(f"{where}: image is {width} x {height} px, more than the "
                           f"{MAX_PIXELS:,} px frictex reads; scale it down")
    if budget is not None:
        budget.charge(where, width * height, bytes_per_px)
    check_image_data(data, where, expected)
    try:
        with warnings.catch_warnings():
            # Pillow's own bomb guard warns from 89 Mpx; the header check above refuses
            # anything over MAX_PIXELS first, with a sentence instead of a warning
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            # Pillow's advice on palette transparency: _to_grey checks transparency itself
            warnings.simplefilter("ignore", UserWarning)
            with Image.open(io.BytesIO(data), formats=["PNG"]) as image:
                if image.size != (width, height):  # should Pillow read another header
                    raise TextureError(f"{where}: image size {image.size} differs from its header's")
                image.load()
                return _to_grey(image, where, expected, depth)
    except (TextureError, MemoryError):
        raise
    except Exception as exc:  # noqa: BLE001 - decoders raise anything on a corrupt file
        if "Decompressed data too large" in str(exc):  # Pillow's bound, not a broken file
            raise TextureError(f"{where}: a metadata chunk (text or ICC profile) inflates to "
                               f"over {_METADATA_MIB:g} MiB, more than is read; strip the "
                               "PNG's metadata (e.g. optipng -strip all); expected "
                               f"{expected}") from None
        # Pillow names its in-memory file by its repr (<_io.BytesIO object at 0x...>)
        said = _IN_MEMORY.sub("", str(exc)).strip()
        raise TextureError(f"{where}: corrupt PNG, decoding failed ({type(exc).__name__}: "
                           f"{escape(said)}); expected {expected}") from None


def _to_grey(image, where: str, expected: str, depth: int) -> tuple[np.ndarray, str]:
    """Grey levels of a decoded image (``depth``: the PNG's bits per sample)."""
    mode = image.mode
    if mode == "P":
        _check_palette_indices(image, where)
    alpha = _alpha(image, depth)
    if alpha is not None and alpha.min() < 255:
        raise TextureError(f"{where}: image mode {mode} has transparent pixels "
                           f"(alpha down to {int(alpha.min())}); transparency has no "
                           f"friction meaning: flatten the image onto a background")
    if mode in ("LA", "RGBA", "PA"):
        image = image.convert("RGB" if mode != "LA" else "L")
        mode = image.mode
    if mode == "L":
        return np.asarray(image, dtype=np.float64) / 255.0, "8-bit greyscale"
    if mode in ("I;16", "I;16B", "I;16L", "I"):
        values = np.asarray(image).astype(np.float64)
        if values.min() < 0 or values.max() > 65535:
            raise TextureError(f"{where}: 32-bit integer image with values from {values.min():g} "
                               f"to {values.max():g}; expected 16-bit greyscale (0..65535)")
        return values / 65535.0, "16-bit greyscale"
    if mode == "1":
        return np.asarray(image, dtype=np.float64), "1-bit"
    if mode == "P":
        image = image.convert("RGB")
        mode = "RGB"
    if mode == "RGB":
        rgb = np.asarray(image, dtype=np.float64)
        return rgb @ _REC601 / 255.0, "RGB as Rec. 601 luma"
    raise TextureError(f"{where}: image mode {mode} is not supported; expected {expected}")


def _check_palette_indices(image, where: str) -> None:
    """TextureError if a pixel of palette image ``image`` indexes past its palette's end
    (a PNG decoder would read it as black)."""
    entries = len(image.palette.palette) // 3
    largest = int(np.asarray(image).max())
    if largest >= entries:
        raise TextureError(f"{where}: a pixel takes palette index {largest}, and the palette "
                           f"has {entries} entries (0 to {entries - 1}); the file is corrupt")


def _alpha(image, depth: int) -> np.ndarray | None:
    """Alpha (0 transparent .. 255 opaque) of each pixel of ``image``, or None if it
    carries none: its alpha channel, or what its PNG transparency chunk (Pillow's
    ``info["transparency"]``) says."""
    if image.mode in ("LA", "RGBA", "PA"):
        return np.asarray(image.getchannel("A"))
    key = image.info.get("transparency")
    if key is None:
        return None
    pixels = np.asarray(image.convert("L") if image.mode == "1" else image)
    if isinstance(key, bytes):  # one alpha per palette entry; entries past its end are opaque
        alphas = np.full(256, 255, np.uint8)
        alphas[:len(key)] = np.frombuffer(key[:256], np.uint8)
        return alphas[pixels]
    hidden = pixels == _decoded_key(key, image.mode, depth)
    return np.where(hidden.all(axis=-1) if pixels.ndim == 3 else hidden, 0, 255)


def _decoded_key(key, mode: str, depth: int):
    """The transparent grey level or colour ``key`` (as the PNG stores it) on the scale
    Pillow decodes ``mode`` pixels to: 1-, 2- and 4-bit grey are spread over 0..255 (Pillow
    has already done so for 1-bit), and 16-bit colour keeps only its high bytes, so a
    pixel whose high bytes match counts as transparent (a safe overestimate)."""
    if mode == "L" and depth < 8:
        return key * 255 // ((1 << depth) - 1)
    if mode == "RGB" and depth == 16:
        return tuple(part >> 8 for part in key)
    return key
