"""Friction maps from image files: grey levels as float64 in [0, 1].

The convention is that of commercial friction displays: a greyscale image where
brightness is friction (black = most slippery, white = most friction). Read with Pillow:

- 8-bit greyscale (mode ``L``): g = value / 255;
- 16-bit greyscale (modes ``I;16``, ``I;16B``, ``I`` with values in 0..65535): g = value / 65535;
- 1-bit (mode ``1``): g = 0 or 1;
- colour (``RGB``, palette ``P``): converted to luma with the Rec. 601 weights
  g = (0.299 R + 0.587 G + 0.114 B) / 255 on the stored (gamma-encoded) values, the
  same weights as Pillow's own ``convert("L")`` but kept in float64 without rounding;
- with an alpha channel (``LA``, ``RGBA``, ``PA``): accepted only if every pixel is fully
  opaque (transparency has no friction meaning); the alpha is then ignored.

Row 0 is the top of the image (screen y points down).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from frictex.textures.errors import TextureError
from frictex.textures.library import file_problem

#: Largest image accepted (pixels), checked from the file's header before any pixel is
#: decoded: a friction map is sampled at finger positions only, and a 16 Mpx float64
#: map already takes 128 MB.
MAX_PIXELS = 16_000_000
#: Largest image file read (bytes): a 16 Mpx 16-bit RGBA PNG stored uncompressed.
MAX_FILE_BYTES = 128 << 20

_REC601 = np.array([0.299, 0.587, 0.114])


#: The image kinds :func:`read_grey` accepts, for error messages.
ACCEPTED = "8- or 16-bit greyscale PNG (colour is converted to Rec. 601 luma)"


def read_grey(path: str | Path, expected: str = ACCEPTED) -> tuple[np.ndarray, str]:
    """Read an image file as grey levels.

    Parameters
    ----------
    path : the image file (PNG; any format Pillow reads is accepted).
    expected : what the caller takes, said by the errors (default :data:`ACCEPTED`).

    Returns
    -------
    grey : float64 array (rows, cols), values in [0, 1], row 0 at the top.
    kind : how the pixels were read, e.g. ``"8-bit greyscale"`` (for reports).

    Raises
    ------
    OSError if the file cannot be read; TextureError if it is not a usable image: not a
    regular file (checked before opening: a FIFO would block), larger than
    ``MAX_FILE_BYTES``, more than ``MAX_PIXELS`` (from the header, before decoding),
    corrupt or truncated.
    """
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    problem = file_problem(path, MAX_FILE_BYTES)
    if problem is not None:
        raise TextureError(f"{path}: {problem}; expected {expected}")
    try:
        with warnings.catch_warnings():
            # Pillow's own bomb guard warns from 89 Mpx; the header check below refuses
            # anything over MAX_PIXELS first, with a sentence instead of a warning
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as image:
                width, height = image.size
                if width * height > MAX_PIXELS:
                    raise TextureError(f"{path}: image is {width} x {height} px, more than the "
                                       f"{MAX_PIXELS:,} px frictex reads; scale it down")
                if width == 0 or height == 0:
                    raise TextureError(f"{path}: image is empty ({width} x {height} px)")
                image.load()
                return _to_grey(image, path, expected)
    except UnidentifiedImageError:
        raise TextureError(f"{path}: not an image Pillow can read; expected {expected}") from None
    except Image.DecompressionBombError as exc:
        raise TextureError(f"{path}: {exc}") from None
    except (TextureError, MemoryError):
        raise
    except Exception as exc:  # noqa: BLE001 - decoders raise anything on a corrupt file
        raise TextureError(f"{path}: corrupt image, decoding failed ({type(exc).__name__}: "
                           f"{exc}); expected {expected}") from None


def _to_grey(image, path: Path, expected: str) -> tuple[np.ndarray, str]:
    mode = image.mode
    if mode in ("LA", "RGBA", "PA"):
        alpha = np.asarray(image.getchannel("A"))
        if alpha.min() < 255:
            raise TextureError(f"{path}: image mode {mode} has transparent pixels "
                               f"(alpha down to {int(alpha.min())}); transparency has no "
                               f"friction meaning: flatten the image onto a background")
        image = image.convert("RGB" if mode != "LA" else "L")
        mode = image.mode
    if mode == "L":
        return np.asarray(image, dtype=np.float64) / 255.0, "8-bit greyscale"
    if mode in ("I;16", "I;16B", "I;16L", "I"):
        values = np.asarray(image).astype(np.float64)
        if values.min() < 0 or values.max() > 65535:
            raise TextureError(f"{path}: 32-bit integer image with values from {values.min():g} "
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
    raise TextureError(f"{path}: image mode {mode} is not supported; expected {expected}")
