"""Data-driven texture models in the form of the Penn Haptic Texture Toolkit (HaTT).

Culbertson, Lopez Delgado and Kuchenbecker (IEEE Haptics Symposium 2014, "One hundred
data-driven haptic texture models and open-source methods for rendering on 3D
objects") model a texture's recorded tool acceleration as a piecewise autoregressive
process: one AR model per segment of the recording, stored at the normal force and
scanning speed of that segment, the models joined by a Delaunay triangulation of
force-speed space. To render, the measured (speed, force) is located in a triangle,
the three vertex models are blended with barycentric weights -- their line spectral
frequencies (LSF), which keep the blended filter stable, and their variances -- and the
blended filter is driven with white Gaussian noise of the blended variance:

    y[n] = -sum_k a_k y[n-k] + e[n],   e ~ N(0, variance),   A(z) = 1 + sum_k a_k z^-k

so y has the two-sided power spectral density S(f) = variance / (fs |A(e^{j 2 pi f / fs})|^2)
(units^2 per Hz; HaTT's unit is m/s^2).

The file form, as the toolkit's own renderer reads it: its C++ sources (Penn Haptic
Texture Toolkit, 2013: ``autoGenHashMatrix.cpp`` reads a file, ``AccSynthHashMatrix.cpp``
blends, the demo's ``vibrations()`` synthesises) and its model files, as published in
the toolkit's MLHD port (github.com/ralee9/PennHaTT_MLHD, ``src/`` and ``build/XML/``)::

    <modelSet>
      <SpeedUnits>mm/s</SpeedUnits> <ForceUnits>N</ForceUnits>
      <AccelUnits>m/s^2</AccelUnits> <SampleRate>1000</SampleRate>   (Hz)
      <numMod>M</numMod> <numTri>T</numTri> <maxSpeed>..</maxSpeed> <maxForce>..</maxForce>
      <speedList><value>..</value> x M</speedList> <forceList>.. x M</forceList>
      <tri><value>i</value><value>j</value><value>k</value></tri> x T   (1-based)
      <numARCoeff>p</numARCoeff> <numMACoeff>q</numMACoeff>
      <model> x M: <ARcoeff>1, a_1 .. a_p</ARcoeff> <ARlsf>p values (rad)</ARlsf>
                   <MAcoeff>1, b_1 .. b_q</MAcoeff> <MAlsf>q values</MAlsf> <gain>..</gain>
                   <var>..</var> <speedMod>..</speedMod> <forceMod>..</forceMod>

- speeds in mm/s (the demo multiplies the tool's m/s by 1000 "because texture models
  are in mm/s"), normal forces in N, the output in m/s^2; the files say so;
- ``<tri>``: model numbers counted from 1 (the renderer reads model ``t - 1``);
- ``<ARlsf>``: the line spectral frequencies of A(z); the renderer blends them with
  barycentric weights, rebuilds A(z) = [1, a_1 .. a_p] (the 1st, 3rd, ... LSFs are the
  roots of the sum polynomial) and runs ``output = sum_i -a_i y[n-i] + excitation``:
  the convention above, A(z) with a +. ``<ARcoeff>`` is the same A(z) written out:
  in the toolkit's Book model, a_1 = -1.337, and frictex's A(z) from its ARlsf
  matches the file's ARcoeff to 4e-6 (the LSFs are written with 6 decimals);
- ``<var>``: the variance of the white Gaussian excitation (the renderer draws it with
  standard deviation sqrt(var)), blended with the same weights.

Numbers are ASCII decimal (``device/numbers.py``: no Unicode digits, no underscores,
no nan or inf), white space around; an element frictex reads appears at most once where
it is one (a second ``<numARCoeff>`` is an error, not ignored).

frictex reads ``SampleRate`` (10 kHz, the rate of the recordings, when a file has
none), checks the unit elements a file has (speeds in mm/s or m/s, forces in N,
acceleration in m/s^2: the layer's gain is per m/s^2) and, where a model has
``ARcoeff``, that it is the A(z) of its ``ARlsf`` (within 1e-3 of its largest
coefficient: a file written with the other sign convention differs by about 2 |a_1|),
and that each vertex's A(z), rebuilt from its ARlsf in float64 as the synthesis rebuilds
it, has its poles within radius exp(-1 / (MAX_RING_S rate)) and a finite output
variance: increasing LSFs in (0, pi) make a stable A(z) only in exact arithmetic (order
20, LSFs 0.02 rad apart from 0.30 rad: a float64 pole at 1.064, the output NaN from
sample 12,887).
ARMA models (``numMACoeff`` q > 0; the toolkit's models resampled for its 1 kHz
renderer are ARMA, p = 19 and q = 17): the renderer runs
``output = sum_i -a_i y[n-i] + gain (e[n] + sum_i b_i e[n-i])``, so
S(f) = var gain^2 |B|^2 / (fs |A|^2); frictex replaces each vertex by the AR(100) model
of that spectrum (``fit_ar``), so vertices are exact to the fit and the blend between
them is of those models' LSFs, where the toolkit blends A's and B's LSFs and the gains
(both continuous). The toolkit's Book vertex (p = 19, q = 17, 1 kHz) is fitted within
0.26 dB over 20-450 Hz, and within 0.75, 1.68 and 2.67 dB once refitted at 2, 5 and
10 kHz.

The rate: the paper describes resampling the models for rates other than the 10 kHz of
the recordings. frictex resamples each vertex model to its output rate from the
model's exact spectrum: S(f) up to the lower of the two Nyquist frequencies (nothing
above), its autocorrelation at the new rate, and a Levinson-Durbin fit of order 4p,
times the ratio of the rates when going up (at most 100; ``TextureModel.resampled``): an
AR(p) process seen at another rate is not AR(p), and a fit of order p misses the
spectrum by 2.5 dB where 4p stays within 0.1 dB (test models, 10 to 5 kHz); at 48 and
96 kHz, 4p missed it by 3.0 and 9.6 dB over 20-800 Hz, its resonances squeezed into the
lowest few percent of the band, which the scaled order follows (within 0.2 dB); from
1 kHz to 10 kHz an order-20 test model stays within 4.6 dB below 450 Hz (the fit follows
the cliff at the old Nyquist frequency badly). This is frictex's own procedure, not a
copy of the toolkit's MATLAB code.

Outside the triangulation the toolkit saturates speed and force at ``maxSpeed`` and
``maxForce``; frictex blends at the point of the triangulation nearest to (speed, force),
speed and force each in units of the span of the vertices' values
(``TextureModel.weights``): continuous, as a Delaunay triangulation covers a convex
region, and the same inside. (Taking the triangle the point was least outside of, its
negative weights set to 0, jumped where that triangle changed: by up to 10 dB in the
toolkit's Book model at 400 mm/s.)

Other elements (``mu``, ``material``, pictures) are ignored. frictex ships none of the
toolkit's data: its licence is for non-commercial research only; users bring their
own files.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from frictex.device.numbers import ascii_float
from frictex.device.safe_text import escape, escape_path, quoted
from frictex.textures.ar_synthesis import (barycentric, blend_at, lsf_to_poly, output_power_gain,
                                          pole_radius, twiddles)
from frictex.textures.errors import TextureError
from frictex.textures.library import UnreadableText, read_utf8
from frictex.textures.dynamic import DynamicLayer

HATT_RATE_HZ = 10_000.0
RATE_RANGE_HZ = (100.0, 1e6)
#: the unit elements a file may have: {element: {unit: factor to frictex's unit}}
UNITS = {"SpeedUnits": {"mm/s": 1.0, "m/s": 1000.0}, "ForceUnits": {"N": 1.0},
         "AccelUnits": {"m/s^2": 1.0, "m/s2": 1.0}}
ARCOEFF_TOLERANCE = 1e-3
FIT_FLOOR = 1e-9  # fit_ar adds this share of the peak: nulls and empty bands stay fittable
MAX_HATT_BYTES = 8 << 20
MAX_ORDER = 100
#: Most vertices (``<model>`` elements) read from an AR file: reading one costs about
#: 0.1 ms, and checking its filter (``_check_filters``, once per distinct vertex) 0.3 ms
#: at order 10 to 13 ms at order 100: 2,000 distinct order-100 vertices about 26 s.
MAX_MODELS = 2_000
#: Most vertices refitted, which costs FIT_COST_MS each (``fit_ar``: 11 ms measured on the
#: test machine, 27 ms on a slower one, where 1,800 ARMA vertices took 48 s to validate):
#: an ARMA file's vertices are all refitted when read, and any file's when played at a rate
#: other than its own (``TextureModel.resampled``). 150 refits: about 2 to 4 s of CPU.
MAX_FIT_VERTICES = 150
FIT_COST_MS = 30
#: largest excitation variance read ((m/s^2)^2, after an ARMA model's gain): far above any
#: recording, and low enough that the synthesis's sums stay finite
MAX_VARIANCE = 1e100
#: longest time constant (s) of a vertex filter's poles: its radius at most
#: exp(-1 / (MAX_RING_S * rate)), 0.9999 at 10 kHz. A recorded texture's resonances die
#: out in milliseconds (poles at 0.9 to 0.96 at 10 kHz: 1 to 2.5 ms); LSFs packed close
#: together put A(z)'s float64 poles near or past the circle (order 10, 0.001 rad apart
#: from 0.3 rad: 1.0026, the synthesis inf from sample 486,329), and a vertex that rings
#: for a second is none that was recorded
MAX_RING_S = 1.0


# ---------------------------------------------------------------------------
# AR polynomials and line spectral frequencies


# Both directions work on the unit circle, never through the coefficients of P(z) and
# Q(z): with LSFs crowded at low frequencies (a model refitted at a higher rate, order
# 4p) those coefficients grow like C(p, p/2) and their sum A = (P + Q) / 2 cancels every
# digit (an order-76 refit came back 100 dB wrong), and numpy.roots of P and Q loses the
# roots' angles. On the circle |P|, |Q| <= 2 |A|: nothing cancels.

#: points over (0, pi) where poly_to_lsf looks for sign changes, finer if it must
LSF_GRIDS = (1 << 14, 1 << 17, 1 << 20)
#: poly_to_lsf refuses LSFs that bring |A| back (lsf_to_poly) further than this (dB) at
#: any of LSF_CHECK_POINTS angles over [0, pi]: a 1 dB synthesis target, with room
LSF_ROUND_TRIP_DB = 0.05
LSF_CHECK_POINTS = 4097


def _on_circle(c: np.ndarray, w: np.ndarray) -> np.ndarray:
    """C(e^jw) = sum_k c_k e^(-j k w) at the angles w (rad), by Horner's rule (stable on
    the unit circle, and no table of exponentials)."""
    z = np.exp(-1j * np.asarray(w, dtype=np.float64))
    acc = np.zeros_like(z)
    for coefficient in np.asarray(c, dtype=np.float64)[::-1]:
        acc = acc * z + coefficient
    return acc


def _rotated(a: np.ndarray, w: np.ndarray) -> np.ndarray:
    """F(w) = A(e^jw) e^(j (p+1) w / 2): P(e^jw) e^(j (p+1) w / 2) = 2 Re F and
    Q(e^jw) e^(j (p+1) w / 2) = 2j Im F, so P's roots on the circle are the zeros of
    Re F and Q's those of Im F."""
    return _on_circle(a, w) * np.exp(0.5j * a.size * w)


def poly_to_lsf(a) -> np.ndarray:
    """Line spectral frequencies (rad, increasing, in (0, pi)) of a minimum-phase
    A(z) = [1, a_1 .. a_p]: the angles in (0, pi) of the roots of
    P(z) = A(z) + z^-(p+1) A(1/z) and Q(z) = A(z) - z^-(p+1) A(1/z), which interlace, P's
    first: the sign changes of Re F and Im F (``_rotated``) on a grid of LSF_GRIDS
    points, each refined by 40 bisections (to 2e-16 rad). Raises ValueError where
    they cannot be told apart (13 identical pole pairs at radius 0.75 put |A| below
    rounding at their frequency), or where A(z) made from them again differs from ``a``
    by more than LSF_ROUND_TRIP_DB anywhere on the circle: with poles crowding the
    circle at nearby frequencies (0.984 at 0.156 rad, 0.994 at 0.172 rad and 0.875 at
    0.188 rad among ten others, |A| over 230 dB) rounding moves the roots of P and Q
    enough to bring |A| back 0.28 dB wrong at its deepest, which a texture would play as
    a resonance 0.28 dB off."""
    a = np.asarray(a, dtype=np.float64)
    p = a.size - 1
    for grid in LSF_GRIDS:  # a finer grid where roots near the circle crowd together
        w = np.linspace(0.0, np.pi, grid + 1)
        f = np.fft.fft(a, 2 * grid)[:grid + 1] * np.exp(0.5j * (p + 1) * w)  # _rotated(a, w)
        lo, parts = [], []
        for part in (np.real, np.imag):
            v = part(f)[1:-1]  # the open interval: w = 0 and pi are trivial roots
            cross = np.flatnonzero(np.signbit(v[:-1]) != np.signbit(v[1:])) + 1
            lo.append(w[cross])
            parts.append(np.full(cross.size, part is np.imag))
        lo, imag = np.concatenate(lo), np.concatenate(parts)
        if lo.size == p:
            break
    else:
        raise ValueError(f"found {lo.size} line spectral frequencies of an order-{p} A(z), "
                         f"expected {p}: its roots are outside the unit circle, or so close to "
                         f"it or to each other that rounding hides them")
    hi = lo + w[1]
    f_lo = _rotated(a, lo)
    sign_lo = np.signbit(np.where(imag, f_lo.imag, f_lo.real))
    for _ in range(40):  # a grid cell (at most pi / 2^14) halved 40 times: below 2e-16 rad
        mid = (lo + hi) / 2
        fm = _rotated(a, mid)
        same = np.signbit(np.where(imag, fm.imag, fm.real)) == sign_lo
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    lsf = np.sort((lo + hi) / 2)
    n = 2 * (LSF_CHECK_POINTS - 1)
    gap_db = 20 * np.log10(np.abs(np.fft.rfft(lsf_to_poly(lsf), n)) / np.abs(np.fft.rfft(a, n)))
    worst = float(np.max(np.abs(gap_db)))
    if not worst <= LSF_ROUND_TRIP_DB:
        raise ValueError(f"the {p} line spectral frequencies found bring A(z) back within "
                         f"{worst:.3g} dB only (at most {LSF_ROUND_TRIP_DB} dB asked): its "
                         f"roots are outside the unit circle (1 / A(z) unstable), or crowd so "
                         f"close to it and to each other that rounding moves them")
    return lsf


def response2(c, f_hz, rate_hz: float) -> np.ndarray:
    """|C(e^(j 2 pi f / fs))|^2 of the polynomial c = [c_0 .. c_n] in z^-1, at f_hz."""
    return np.abs(_on_circle(c, 2 * np.pi * np.asarray(f_hz, dtype=np.float64) / rate_hz)) ** 2


def ar_psd(a, variance: float, f_hz, rate_hz: float) -> np.ndarray:
    """Two-sided power spectral density (units^2/Hz) of the AR process at f_hz."""
    return variance / (rate_hz * response2(a, f_hz, rate_hz))


def levinson(r: np.ndarray, order: int) -> tuple[np.ndarray, float]:
    """AR coefficients [1, a_1 .. a_order] and innovation variance from autocorrelations r[0..order]."""
    a = np.zeros(order + 1)
    a[0] = 1.0
    err = float(r[0])
    for k in range(1, order + 1):
        acc = r[k] + np.dot(a[1:k], r[k - 1:0:-1])
        refl = -acc / err
        a[1:k] = a[1:k] + refl * a[k - 1:0:-1]
        a[k] = refl
        err *= 1.0 - refl * refl
    return a, err




# ---------------------------------------------------------------------------
# The model


@dataclass(frozen=True, eq=False)
class TextureModel:
    """AR models at the vertices of a force-speed triangulation (see the module docstring).

    speeds_mm_s, forces_n : (M,) vertex positions. triangles : (T, 3) 0-based vertex
    indices. lsf : (M, p) line spectral frequencies (rad). variances : (M,) innovation
    variances. rate_hz : the rate the models were made at (Hz). source : where the model
    came from (its file's path), for error messages.
    """

    speeds_mm_s: np.ndarray
    forces_n: np.ndarray
    triangles: np.ndarray
    lsf: np.ndarray
    variances: np.ndarray
    rate_hz: float = HATT_RATE_HZ
    source: str = "HaTT model"
    _tri: tuple = field(init=False, repr=False)

    def __post_init__(self):
        # per triangle: vertex 0 and the inverse of the 2x2 edge matrix, for barycentrics
        # (a degenerate triangle gives inf: parse_hatt_xml refuses it), and its corners in
        # units of the vertices' span of speed and of force, for the nearest point outside
        s, f = self.speeds_mm_s[self.triangles], self.forces_n[self.triangles]
        a, b = s[:, 1] - s[:, 0], s[:, 2] - s[:, 0]
        c, d = f[:, 1] - f[:, 0], f[:, 2] - f[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.stack([np.stack([d, -b], -1), np.stack([-c, a], -1)], 1) / (a * d - b * c)[:, None, None]
            scale = 1.0 / np.array([np.ptp(self.speeds_mm_s), np.ptp(self.forces_n)])
        corners = np.stack([s * scale[0], f * scale[1]], -1)
        object.__setattr__(self, "_tri", (s[:, 0], f[:, 0], inv, corners, scale))

    @property
    def order(self) -> int:
        return int(self.lsf.shape[1])

    def weights(self, speed_mm_s: float, force_n: float) -> tuple[np.ndarray, np.ndarray]:
        """The three vertices (indices) and barycentric weights of (speed, force). Outside
        the triangulation: those of its point nearest to (speed, force), speed and force
        each in units of the vertices' span (continuous where the triangles cover a convex
        region, as a Delaunay triangulation's do)."""
        t, w = barycentric(*self._tri, float(speed_mm_s), float(force_n))
        return self.triangles[t], w

    @property
    def arrays(self) -> tuple:
        """What :func:`blend_at` needs, in its order."""
        return (*self._tri, self.triangles, self.lsf, self.variances,
                twiddles(self.lsf.shape[1]))

    def at(self, speed_mm_s: float, force_n: float) -> tuple[np.ndarray, float]:
        """AR polynomial [1, a_1 .. a_p] and variance blended at (speed, force)."""
        return blend_at(*self.arrays, float(speed_mm_s), float(force_n))

    def check_rate(self, rate_hz: float) -> None:
        """TextureError naming :attr:`source` where playing the model at ``rate_hz`` (Hz)
        would refit more than :data:`MAX_FIT_VERTICES` vertices (:meth:`resampled`)."""
        if rate_hz != self.rate_hz:
            _refits_bounded(len(self.lsf), self.source, f"made at {self.rate_hz:g} Hz to play "
                                                        f"at {rate_hz:g} Hz")

    def resampled(self, rate_hz: float) -> "TextureModel":
        """The same textures as AR models at ``rate_hz`` (Hz; see the module docstring).

        Raises TextureError naming :attr:`source` and the model where a fit has no line
        spectral frequencies (:func:`poly_to_lsf`) or its filter fails
        :func:`_check_filters`."""
        if rate_hz == self.rate_hz:
            return self
        self.check_rate(rate_hz)
        order = min(math.ceil(4 * self.order * max(1.0, rate_hz / self.rate_hz)), MAX_ORDER)
        fits = []
        for k, w in enumerate(self.lsf):
            try:
                fits.append(fit_ar(lambda f, a=lsf_to_poly(w): ar_psd(a, 1.0, f, self.rate_hz),
                                   self.rate_hz, rate_hz, order))
            except ValueError as exc:
                raise TextureError(f"{self.source}: model {k + 1}: its AR({order}) fit at "
                                   f"{rate_hz:g} Hz failed: {exc}") from None
        with np.errstate(over="ignore"):
            variances = np.array([gain * v for (_, gain), v in zip(fits, self.variances)])
        if not np.isfinite(variances).all():
            k = int(np.flatnonzero(~np.isfinite(variances))[0])
            raise TextureError(f"{self.source}: model {k + 1}: its variance at {rate_hz:g} Hz "
                               f"is not finite ({self.variances[k]:g} at {self.rate_hz:g} Hz)")
        lsf = np.array([lsf for lsf, _ in fits])
        fit = f"its AR({order}) fit at {rate_hz:g} Hz"
        _check_filters(lsf, variances, rate_hz, lambda k: f"{self.source}: model {k + 1}: {fit}")
        return TextureModel(self.speeds_mm_s, self.forces_n, self.triangles, lsf, variances,
                            float(rate_hz), self.source)


def fit_ar(psd, from_rate_hz: float, rate_hz: float, order: int, grid: int = 1 << 14,
           ) -> tuple[np.ndarray, float]:
    """The AR(``order``) model at ``rate_hz`` of the spectrum ``psd(f_hz)`` (two-sided,
    units^2/Hz, of a model made at ``from_rate_hz``), kept below the lower of the two
    Nyquist frequencies and empty above: its autocorrelation by inverse FFT, then
    Levinson-Durbin. Returns (LSFs, innovation variance). Fit a unit-variance spectrum
    and scale the variance after: a silent vertex (variance 0, as the toolkit's
    zero-speed models are) has a shape but nothing to fit."""
    f = np.fft.fftfreq(grid, 1.0 / rate_hz)
    s = np.where(np.abs(f) < min(rate_hz, from_rate_hz) / 2, psd(np.abs(f)), 0.0)
    s += FIT_FLOOR * s.max()  # keeps Levinson regular
    a, err = levinson(np.fft.ifft(s).real * rate_hz, order)
    return poly_to_lsf(a), err


def model_from_coefficients(speeds_mm_s, forces_n, triangles, coefficients, variances,
                            rate_hz: float = HATT_RATE_HZ) -> TextureModel:
    """A model from AR polynomials (rows [1, a_1 .. a_p]) instead of LSFs, each vertex's
    filter checked as a file's are (``_check_filters``: TextureError for an unstable or
    nearly unstable one)."""
    lsf = np.array([poly_to_lsf(a) for a in coefficients])
    variances = np.asarray(variances, dtype=np.float64)
    _check_filters(lsf, variances, rate_hz, lambda k: f"coefficients[{k}]")
    return TextureModel(np.asarray(speeds_mm_s, dtype=np.float64), np.asarray(forces_n, dtype=np.float64),
                        np.asarray(triangles, dtype=np.intp), lsf, variances, rate_hz)


# ---------------------------------------------------------------------------
# The toolkit's XML files


def _values(node, where: str, what: str) -> np.ndarray:
    if node is None:
        raise TextureError(f"{where}: missing <{what}>")
    out = []
    for v in node.findall("value"):
        try:
            x = _number(v.text)
        except ValueError:
            raise TextureError(f"{where}: <{what}> value {quoted(v.text or '')} is not a number") from None
        if not math.isfinite(x):
            raise TextureError(f"{where}: <{what}> value {quoted(v.text or '')} is not finite")
        out.append(x)
    return np.array(out)


def _number(text: str | None) -> float:
    """The number an element holds: ASCII decimal (``device.numbers``), XML white space
    (space, tab, line breaks) around it; ValueError for anything else."""
    return ascii_float((text or "").strip(" \t\r\n"))


def _one(root, tag: str, where: str):
    """The one ``<tag>`` child of ``root``, or None; a second one is an error (it would
    be ignored silently)."""
    found = root.findall(tag)
    if len(found) > 1:
        raise TextureError(f"{where}: <{tag}> appears {len(found)} times; expected one")
    return found[0] if found else None


def _scalar(root, tag: str, where: str) -> float:
    node = _one(root, tag, where)
    try:
        x = _number(node.text) if node is not None else None
    except ValueError:
        x = None
    if x is None or not math.isfinite(x):
        raise TextureError(f"{where}: <{tag}> missing or not a finite number (ASCII decimal, "
                           "e.g. 0.25 or 1e-3)")
    return x


def _count(root, tag: str, where: str, lowest: int) -> int:
    """The whole number ``lowest`` .. MAX_ORDER in ``<tag>``."""
    x = _scalar(root, tag, where)
    if x != round(x) or not lowest <= x <= MAX_ORDER:
        raise TextureError(f"{where}: {tag} is {x:g}, expected a whole number {lowest} to "
                           f"{MAX_ORDER}")
    return int(x)


def _polynomial(node, here: str, part: str, order: int) -> np.ndarray:
    """The LSFs of a model's ``part`` ("AR": A(z), "MA": B(z)) from ``<ARlsf>`` or
    ``<MAlsf>``, checked against ``<ARcoeff>`` / ``<MAcoeff>`` where the model has it."""
    w = _values(_one(node, f"{part}lsf", here), here, f"{part}lsf")
    if w.size != order or not ((w > 0) & (w < np.pi)).all() or (np.diff(w) <= 0).any():
        raise TextureError(f"{here}: {part}lsf must be {order} increasing values in (0, pi)")
    coeff = _one(node, f"{part}coeff", here)
    if coeff is not None:
        written = _values(coeff, here, f"{part}coeff")
        name, c = ("A", "a") if part == "AR" else ("B", "b")
        expected = f"expected {order + 1}: [1, {c}_1 .. {c}_{order}]"
        if written.size != order + 1:
            raise TextureError(f"{here}: {part}coeff has {written.size} values; {expected}")
        rebuilt = lsf_to_poly(w)
        gap = _gap(written, rebuilt)
        if not gap <= ARCOEFF_TOLERANCE:
            flipped = np.concatenate(([written[0]], -written[1:]))
            why = (f"its {c}_1 .. {c}_{order} have the other sign: the file is written for "
                   f"y[n] = sum {c}_k y[n-k] + e[n], where the toolkit and frictex run "
                   f"y[n] = -sum {c}_k y[n-k] + e[n]; negate them"
                   if _gap(flipped, rebuilt) <= ARCOEFF_TOLERANCE else
                   f"largest difference {gap:.3g} of the largest coefficient")
            raise TextureError(f"{here}: {part}coeff is not the {name}(z) = 1 + sum {c}_k z^-k "
                               f"of its {part}lsf ({why})")
    return w


def _gap(written: np.ndarray, rebuilt: np.ndarray) -> float:
    """How far a file's coefficients are from those rebuilt from its LSFs: the largest
    difference over the largest rebuilt coefficient (at least 1)."""
    return float(np.abs(written - rebuilt).max() / max(1.0, np.abs(rebuilt).max()))


def _refits_bounded(m: int, where: str, why: str) -> None:
    """TextureError unless ``m`` vertices fit in :data:`MAX_FIT_VERTICES` refits."""
    if m > MAX_FIT_VERTICES:
        raise TextureError(f"{where}: {m} vertices {why}, each refitted as an AR model "
                           f"(about {FIT_COST_MS:g} ms each); at most {MAX_FIT_VERTICES} are "
                           f"refitted: fewer vertices, or models already AR at the output rate")


def _root(text: str, where: str):
    """The ``<modelSet>`` element of the file's text (no DTD, no entities)."""
    if re.search(r"<!(DOCTYPE|ENTITY)", text):
        raise TextureError(f"{where}: DOCTYPE or ENTITY declarations are not accepted in a model file")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise TextureError(f"{where}:{exc.position[0]}: not well-formed XML ({escape(exc)})") from None
    if root.tag != "modelSet":
        raise TextureError(f"{where}: top element is <{escape(root.tag)}>, expected <modelSet>")
    return root


def _units(root, where: str) -> tuple[dict[str, float], float]:
    """The unit factors (``UNITS``) and the sample rate (Hz) a file states."""
    scale = {}
    for tag, known in UNITS.items():
        node = _one(root, tag, where)
        unit = (node.text or "").strip() if node is not None else next(iter(known))
        if unit not in known:
            raise TextureError(f"{where}: <{tag}> is {quoted(unit)}, expected one of {', '.join(known)}")
        scale[tag] = known[unit]
    rate = _scalar(root, "SampleRate", where) if _one(root, "SampleRate", where) is not None else HATT_RATE_HZ
    if not RATE_RANGE_HZ[0] <= rate <= RATE_RANGE_HZ[1]:
        raise TextureError(f"{where}: <SampleRate> is {rate:g} Hz, expected {RATE_RANGE_HZ[0]:g} "
                           f"to {RATE_RANGE_HZ[1]:g}")
    return scale, rate


def _vertex(node, here: str, order: int, ma_order: int, rate: float) -> tuple[np.ndarray, float]:
    """One ``<model>``: its LSFs (AR, refitted from ARMA) and its excitation variance."""
    w = _polynomial(node, here, "AR", order)
    v = _scalar(node, "var", here)
    if ma_order:  # y = gain B(z) / A(z) e: its AR(MAX_ORDER) fit (module docstring)
        gain = _scalar(node, "gain", here)
        b, a = lsf_to_poly(_polynomial(node, here, "MA", ma_order)), lsf_to_poly(w)
        try:
            w, shape = fit_ar(lambda f: ar_psd(a, 1.0, f, rate) * response2(b, f, rate),
                              rate, rate, MAX_ORDER)
        except ValueError as exc:
            raise TextureError(f"{here}: its ARMA model has no AR({MAX_ORDER}) fit: {exc}") from None
        with np.errstate(over="ignore"):
            v *= gain * gain * shape
    if not 0.0 <= v <= MAX_VARIANCE:
        raise TextureError(f"{here}: var{' times gain^2' if ma_order else ''} is {v:g}, "
                           f"expected 0 to {MAX_VARIANCE:g}")
    return w, v


def _triangles(root, where: str, m: int) -> np.ndarray:
    """The ``<tri>`` elements as 0-based vertex indices (n, 3)."""
    tris = [_values(t, where, "tri") for t in root.findall("tri")]
    if not tris or any(t.size != 3 for t in tris):
        raise TextureError(f"{where}: expected <tri> elements of three vertex numbers")
    tri = np.array(tris)
    if (tri != np.round(tri)).any() or tri.min() < 1 or tri.max() > m:
        raise TextureError(f"{where}: <tri> vertex numbers must be integers 1 to {m}")
    return tri.astype(np.intp) - 1


def _check_filters(lsf: np.ndarray, variances: np.ndarray, rate: float, name) -> None:
    """TextureError where a vertex's filter 1 / A(z), A(z) rebuilt from its LSFs (rows of
    ``lsf``) as the synthesis rebuilds it, has a pole beyond radius exp(-1 / (MAX_RING_S
    * rate)) (``rate`` in Hz), or an output variance (its ``variances`` entry times the
    filter's power gain) that is not finite. ``name(k)`` names vertex k in the message.
    A blend of vertices that pass keeps its LSFs interlaced (a convex combination of
    increasing rows is increasing); one whose float64 A(z) is still unstable is caught
    by the synthesis (``ar_synthesis._synthesise``)."""
    limit = math.exp(-1.0 / (MAX_RING_S * rate))
    _, first = np.unique(lsf, axis=0, return_index=True)  # a vertex repeated: checked once
    for k in np.sort(first):
        a = lsf_to_poly(lsf[k])
        radius = pole_radius(a)
        if not radius <= limit:
            raise TextureError(f"{name(k)} gives A(z) a pole at radius {radius:.6g}, expected at "
                               f"most {limit:.6g} (a resonance ringing at most {MAX_RING_S:g} s "
                               f"at {rate:g} Hz): its line spectral frequencies are packed so "
                               f"close together that the filter is unstable or nearly so")
        gain = output_power_gain(a)
        with np.errstate(over="ignore"):
            output = variances[k] * gain
        if not (math.isfinite(gain) and math.isfinite(output)):
            raise TextureError(f"{name(k)} gives an output variance that is not finite (var "
                               f"{variances[k]:g} through 1 / A(z)); expected a filter whose "
                               f"output stays finite")


def parse_hatt_xml(text: str, where: str = "HaTT model") -> TextureModel:
    """A :class:`TextureModel` from the text of a toolkit XML file (module docstring).
    Its cost is bounded before any fit: an ARMA file has at most :data:`MAX_FIT_VERTICES`
    vertices (each is refitted), an AR file at most :data:`MAX_MODELS`."""
    root = _root(text, where)
    scale, rate = _units(root, where)
    speeds = _values(_one(root, "speedList", where), where, "speedList") * scale["SpeedUnits"]
    forces = _values(_one(root, "forceList", where), where, "forceList")
    models = root.findall("model")
    m = len(models)
    if not 3 <= m <= MAX_MODELS or speeds.size != m or forces.size != m:
        raise TextureError(f"{where}: {m} <model>, {speeds.size} speeds and {forces.size} forces; "
                           f"expected the same number, 3 to {MAX_MODELS}")
    order = _count(root, "numARCoeff", where, 1)
    ma_order = _count(root, "numMACoeff", where, 0) if _one(root, "numMACoeff", where) is not None else 0
    if ma_order:
        _refits_bounded(m, where, "hold ARMA models")
    lsf, var = [], []
    for k, node in enumerate(models):
        here = f"{where}: model {k + 1}"
        w, v = _vertex(node, here, order, ma_order, rate)
        sp = _scalar(node, "speedMod", here) * scale["SpeedUnits"]
        fo = _scalar(node, "forceMod", here)
        if not (np.isclose(sp, speeds[k]) and np.isclose(fo, forces[k])):
            raise TextureError(f"{here}: speedMod/forceMod ({sp:g}, {fo:g}) differ from the "
                               f"speedList/forceList entry ({speeds[k]:g}, {forces[k]:g})")
        lsf.append(w)
        var.append(v)
    lsf, var = np.array(lsf), np.array(var)
    made = f"AR({MAX_ORDER}) fit" if ma_order else "ARlsf"
    _check_filters(lsf, var, rate, lambda k: f"{where}: model {k + 1}: its {made}")
    model = TextureModel(speeds, forces, _triangles(root, where, m), lsf, var, rate, where)
    if not np.isfinite(model._tri[2]).all():
        raise TextureError(f"{where}: a <tri> triangle is degenerate (its vertices are in a line)")
    return model


def read_hatt_xml(path: str | Path) -> TextureModel:
    """:func:`parse_hatt_xml` on a file (regular UTF-8, at most 8 MiB)."""
    try:
        text = read_utf8(path, MAX_HATT_BYTES)
    except UnreadableText as exc:
        line = f":{exc.line}" if exc.line else ""
        raise TextureError(f"{escape_path(path)}{line}: {exc}") from None
    return parse_hatt_xml(text, escape_path(path))


# ---------------------------------------------------------------------------
# The layer


@dataclass(frozen=True)
class ArTextureLayer(DynamicLayer):
    """A recorded texture synthesised from the finger's speed and normal force
    (``rendering.layers.ar_texture``): mu' = mu_mean + gain * y, y the model's output
    (m/s^2 for the toolkit's models), limited to [mu_min, mu_max] (clipped samples are
    counted in the renderer's state and reported in a replay's ``layer_clipped``). Below ``v_rest_mm_s`` the texture is silent
    (mu' = mu_mean): a still finger on a real texture feels no vibration. ``seed``
    makes the noise, and so every replay, reproducible."""

    renderer_kind = "ar"
    FILE_TYPE = "recorded"

    model: TextureModel = None  # type: ignore[assignment]
    mu_mean: float = 0.8
    gain: float = 0.02
    mu_min: float = 0.6
    mu_max: float = 1.0
    v_rest_mm_s: float = 2.0
    seed: int = 0

    @property
    def mu_range(self) -> tuple[float, float]:
        return self.mu_min, self.mu_max

    @property
    def rest_mu(self) -> float:
        return self.mu_mean
