"""An AR texture model's compiled kernels: the blend at a speed and force, line spectral
frequencies to A(z), and the noise-driven all-pole synthesis of one finger's output.

They are one module because numba's on-disk cache (``cache=True``) is keyed on the
cached function's own file: a kernel that compiles in a jitted function of another
module would keep running that function's old code after it changed
(``tests/test_numba_cache.py``). ``textures.hatt`` builds and fits models with them;
``rendering.layers.ar_texture`` renders with :func:`render_finger`.

The noise of output sample k is a function of (seed, finger id, touch id, k) only, so
live and replay, and any split into blocks, give the same texture: a counter hashed by
the splitmix64 finaliser into 64 random bits, turned into a standard normal by the
ziggurat method (Marsaglia and Tsang, J. Stat. Softw. 5(8), 2000, 256 layers; the layer,
the sign and the 53-bit abscissa from independent bits, as Doornik 2005 advises). 99 %
of samples take a table look-up and a multiply; the rest take more bits from a splitmix64
sequence seeded by the same counter (Box-Muller took a logarithm and a cosine per
sample, 23 of the synthesis's 31 ns).
"""

from __future__ import annotations

import math

import numpy as np

from frictex.device.jit import njit

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1, _M2 = np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_TWO, _ONE = np.uint64(2), np.uint64(1)


@njit(cache=True)
def twiddles(order):
    """e^(j 2 pi i / n), i = 0 .. n - 1, at the n points :func:`lsf_to_poly` evaluates an
    A(z) of that order: the smallest power of 2 from 8 above order + 1."""
    n = 8
    while n < order + 2:
        n *= 2
    return np.exp(2j * np.pi * np.arange(n) / n)


@njit(cache=True)
def lsf_to_poly(lsf, twiddle=None) -> np.ndarray:
    """A(z) = [1, a_1 .. a_p] from p line spectral frequencies (the inverse of
    :func:`poly_to_lsf`): P's roots are the 1st, 3rd, ... LSFs, Q's the others, with the
    trivial roots at z = -1 (P) and z = +1 (Q) for p even, z = +1 and -1 (Q) for p odd.
    P and Q are evaluated as products of their sections at n > p + 1 points of the unit
    circle, A = (P + Q) / 2 there, and its coefficients are the inverse DFT. ``twiddle``:
    ``twiddles(lsf.size)``, if the caller keeps it (a model's blends are computed per run
    of samples, and the exponentials were a third of a blend's time)."""
    p = lsf.size
    if twiddle is None:
        twiddle = twiddles(p)
    n = twiddle.size
    cos_w = -2.0 * np.cos(lsf)
    values = np.empty(n, dtype=np.complex128)
    for i in range(n):
        z1 = np.conj(twiddle[i])  # z^-1 at w = 2 pi i / n
        z2 = z1 * z1
        pv, qv = 1.0 + 0.0j, 1.0 + 0.0j
        for k in range(0, p, 2):
            pv *= 1.0 + cos_w[k] * z1 + z2
        for k in range(1, p, 2):
            qv *= 1.0 + cos_w[k] * z1 + z2
        if p % 2 == 0:
            pv *= 1.0 + z1
            qv *= 1.0 - z1
        else:
            qv *= 1.0 - z2
        values[i] = (pv + qv) / 2.0
    a = np.empty(p + 1)
    for d in range(p + 1):
        acc = 0.0 + 0.0j
        for i in range(n):
            acc += values[i] * twiddle[(i * d) % n]
        a[d] = acc.real / n
    return a


def pole_radius(poly) -> float:
    """The largest |z| of the poles of 1 / A(z), A(z) = ``poly`` ([a_0, a_1 .. a_p]): the
    roots of the float64 coefficients the synthesis runs (the companion matrix's
    eigenvalues, exact for coefficients within rounding of these); 0 for p = 0."""
    a = np.asarray(poly, dtype=np.float64)
    return float(np.abs(np.roots(a)).max()) if a.size > 1 else 0.0


#: :func:`output_power_gain` stops once a further IMPULSE_CHUNK samples of the impulse
#: response add less than IMPULSE_TAIL of its energy so far, and gives inf past
#: IMPULSE_MAX_CHUNKS chunks (16.8 million samples; a pole at 0.9999 takes 2e5): a pole
#: that rounds to just inside the circle (np.poly of a pair on it: 0.9999999999999999)
#: would never meet the tail test
IMPULSE_CHUNK = 1 << 12
IMPULSE_TAIL = 1e-17
IMPULSE_MAX_CHUNKS = 1 << 12


def output_power_gain(poly) -> float:
    """The output variance of the all-pole filter 1 / A(z) per unit variance of its white
    excitation: sum h^2 over its impulse response h, run by the direct-form recursion the
    synthesis runs, until a further IMPULSE_CHUNK samples add less than IMPULSE_TAIL of the
    sum. inf where a pole of A(z) = ``poly`` ([a_0, a_1 .. a_p]) is on or outside the unit
    circle (:func:`pole_radius`), the recursion overflows, or the sum has not settled
    within IMPULSE_MAX_CHUNKS chunks (a pole within about 1e-6 of the circle). Its cost grows as
    1 / (1 - radius): 2e5 samples for a pole at 0.9999. (The step-down recursion, 1 /
    prod(1 - k_i^2), loses every digit near the circle: LSFs 0.001 rad apart from 1.0 rad,
    order 10, gave a |k| >= 1 for poles within 0.99984.)"""
    a = np.asarray(poly, dtype=np.float64) / poly[0]
    if not pole_radius(a) < 1.0:
        return math.inf
    return _impulse_energy(a, IMPULSE_CHUNK, IMPULSE_TAIL, IMPULSE_MAX_CHUNKS)


@njit(cache=True)
def _impulse_energy(a, chunk, tail, max_chunks):
    """sum h^2 of 1 / A(z), ``a`` = [1, a_1 .. a_p], in chunks of ``chunk`` samples until
    one adds less than ``tail`` of the sum; inf where it overflows or ``max_chunks`` pass
    first."""
    p = a.size - 1
    h = np.zeros(p + chunk)  # h[:p]: the p samples before the chunk
    h[p] = 1.0
    total, start = 0.0, 1
    for _ in range(max_chunks):
        added = 0.0
        for j in range(p + start, p + chunk):
            acc = 0.0
            for k in range(1, p + 1):
                acc -= a[k] * h[j - k]
            h[j] = acc
        for j in range(p, p + chunk):
            added += h[j] * h[j]
        total += added
        if not math.isfinite(total):
            return math.inf
        if added <= tail * total:
            return total
        h[:p] = h[chunk:]
        start = 0
    return math.inf


@njit(cache=True)
def barycentric(s0, f0, inv, corners, scale, speed, force):
    """(triangle, weights (3,)) of (speed, force); see ``TextureModel.weights``. ``s0``,
    ``f0`` (T,): each triangle's vertex 0; ``inv`` (T, 2, 2): the inverse of its edge
    matrix; ``corners`` (T, 3, 2): its vertices in units scaled by ``scale`` (2,) (per mm/s,
    per N). Inside: the triangle holding the point (its smallest weight the largest) and
    the point's weights. Outside: the point of the triangulation nearest to it, in the
    scaled units, and that point's weights. A non-finite speed or force is refused
    (ValueError): it has no nearest point."""
    if not (math.isfinite(speed) and math.isfinite(force)):
        raise ValueError("a texture model is blended only at a finite speed and force")
    best, best_t = -np.inf, 0
    w = np.zeros(3)
    for t in range(s0.size):
        ds, df = speed - s0[t], force - f0[t]
        u = inv[t, 0, 0] * ds + inv[t, 0, 1] * df
        v = inv[t, 1, 0] * ds + inv[t, 1, 1] * df
        lowest = min(1.0 - u - v, u, v)
        if lowest > best:
            best, best_t = lowest, t
            w[0], w[1], w[2] = 1.0 - u - v, u, v
    if not best >= 0.0:  # outside every triangle
        px = _held_near(speed * scale[0], corners[:, :, 0])
        py = _held_near(force * scale[1], corners[:, :, 1])
        nearest, on_edge = np.inf, np.zeros(3)
        for t in range(s0.size):
            d2 = _nearest_on_edges(px, py, corners[t], on_edge)
            if d2 < nearest:
                nearest, best_t = d2, t
                w[:] = on_edge
    w = np.maximum(w, 0.0)
    return best_t, w / w.sum()


#: how many spans of the vertices' range a point outside is held within before its
#: nearest point is sought (:func:`_held_near`)
_FAR_SPANS = 1e3


@njit(cache=True)
def _held_near(value, coordinates):
    """``value`` held within ``_FAR_SPANS`` spans of the range of ``coordinates`` (one
    axis of the triangles' corners). Further out, the squared distances to the edges
    (1e18 at 1e9 spans) round away the differences that tell the nearest point (a
    (50 mm/s, 1e9 N) point took a vertex 50 mm/s from the edge point straight below
    it); within, they are below 1e6, their rounding 1e-10, and the nearest point is
    already the one in that direction from the range (to 1e-3 rad)."""
    low, high = coordinates.min(), coordinates.max()
    margin = _FAR_SPANS * (high - low)
    return min(max(value, low - margin), high + margin)


@njit(cache=True)
def _nearest_on_edges(px, py, abc, w):
    """The squared distance from (px, py) to the nearest point of the edges of the
    triangle ``abc`` (3, 2), that point's weights on the vertices written into ``w`` (3,):
    for a point outside the triangle, its nearest point. Each edge's nearest point is the
    projection onto it, held to its ends."""
    nearest = np.inf
    for i in range(3):
        j = (i + 1) % 3
        ex, ey = abc[j, 0] - abc[i, 0], abc[j, 1] - abc[i, 1]
        along = ((px - abc[i, 0]) * ex + (py - abc[i, 1]) * ey) / (ex * ex + ey * ey)
        along = min(max(along, 0.0), 1.0)
        d2 = (px - abc[i, 0] - along * ex) ** 2 + (py - abc[i, 1] - along * ey) ** 2
        if d2 < nearest:
            nearest = d2
            w[:] = 0.0
            w[i], w[j] = 1.0 - along, along
    return nearest


@njit(cache=True)
def blend_at(s0, f0, inv, corners, scale, triangles, lsf, variances, twiddle, speed, force):
    """The toolkit's blend at (speed, force): barycentric weights (:func:`barycentric`) on
    the three vertices' LSFs and variances (``twiddle``: ``twiddles(lsf.shape[1])``).
    Returns (A(z) = [1, a_1 .. a_p], variance)."""
    t, w = barycentric(s0, f0, inv, corners, scale, speed, force)
    mixed = np.zeros(lsf.shape[1])
    variance = 0.0
    for k in range(3):
        row = lsf[triangles[t, k]]
        for i in range(mixed.size):  # numpy's mixed += w[k] * row, without its temporary
            mixed[i] += w[k] * row[i]
        variance += w[k] * variances[triangles[t, k]]
    return lsf_to_poly(mixed, twiddle), variance


@njit(cache=True)
def _mix(x):
    """The splitmix64 finaliser: a uint64 hashed to a well-spread uint64."""
    x = (x ^ (x >> _S30)) * _M1
    x = (x ^ (x >> _S27)) * _M2
    return x ^ (x >> _S31)


#: the ziggurat's base: where the normal's tail starts and each of the 256 layers' area
#: (Marsaglia and Tsang 2000)
_ZIG_R, _ZIG_V = 3.6541528853610088, 0.00492867323399


def _ziggurat_tables() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(k, w, f) (256,) each: layer i spans |x| < x_i (x_0 the base strip's q = v / f(r),
    x_255 = r); a 53-bit abscissa u gives x = u w[i] (w = x_i / 2^53) and is accepted at
    once if u < k[i] (x inside the layer above's edge, k = floor(x_{i-1} / x_i 2^53); 0
    for layer 1); f[i] = exp(-x_i^2 / 2). Marsaglia and Tsang's zigset, 53 bits."""
    m = 2.0 ** 53
    k, w, f = np.zeros(256, dtype=np.uint64), np.empty(256), np.empty(256)
    dn = tn = _ZIG_R
    q = _ZIG_V / math.exp(-0.5 * dn * dn)
    k[0] = int(dn / q * m)
    w[0], w[255] = q / m, dn / m
    f[0], f[255] = 1.0, math.exp(-0.5 * dn * dn)
    for i in range(254, 0, -1):
        dn = math.sqrt(-2.0 * math.log(_ZIG_V / dn + math.exp(-0.5 * dn * dn)))
        k[i + 1] = int(dn / tn * m)
        tn = dn
        f[i], w[i] = math.exp(-0.5 * dn * dn), dn / m
    return k, w, f


_ZIG_K, _ZIG_W, _ZIG_F = _ziggurat_tables()
_BYTE, _S8 = np.uint64(255), np.uint64(8)


@njit(cache=True)
def _uniform(bits):
    """A uniform in (0, 1) from a uint64's top 53 bits."""
    return (np.float64(bits >> _S11) + 0.5) * 2.0 ** -53


@njit(cache=True)
def _normal(key, index):
    """A standard normal sample, a function of (key, index) only (module docstring)."""
    c = np.uint64(key) + np.uint64(index) * _TWO * _GOLDEN  # (int64 + uint64 is float64 in numba)
    bits = _mix(c)
    layer, u = bits & _BYTE, bits >> _S11
    if u < _ZIG_K[layer]:
        x = np.float64(u) * _ZIG_W[layer]
        return -x if (bits >> _S8) & _ONE else x
    # the edge's further bits from a hashed start: c + G, c + 2G, ... would run into the
    # next samples' own counters (c + 2G is sample index + 1's) and tie them together
    return _normal_edge(_mix(c + _GOLDEN), bits)


@njit(cache=True)
def _normal_edge(state, bits):
    """:func:`_normal` outside the layers' rectangles (1 % of samples): the wedge or the
    tail test, and new draws until one is accepted; further bits come from the splitmix64
    sequence of ``state``."""
    while True:
        layer, u = bits & _BYTE, bits >> _S11
        negative = (bits >> _S8) & _ONE
        x = np.float64(u) * _ZIG_W[layer]
        if u < _ZIG_K[layer]:
            return -x if negative else x
        if layer == 0:  # beyond r: Marsaglia's tail method
            while True:
                state += _GOLDEN
                tail = -math.log(_uniform(_mix(state))) / _ZIG_R
                state += _GOLDEN
                if -2.0 * math.log(_uniform(_mix(state))) > tail * tail:
                    return -(_ZIG_R + tail) if negative else _ZIG_R + tail
        state += _GOLDEN
        top, bottom = _ZIG_F[layer - 1], _ZIG_F[layer]
        if bottom + _uniform(_mix(state)) * (top - bottom) < math.exp(-0.5 * x * x):
            return -x if negative else x
        state += _GOLDEN
        bits = _mix(state)


@njit(cache=True)
def _synthesise(poly, scale, key, index0, history, out, counted):
    """out[j] = scale * noise(index0 + j) - sum_k poly[k] out[j - k] (poly[0] = 1), the
    earlier outputs taken from ``history`` (most recent first, updated in place). The
    newest output, which each sample's sum waits for first, stays in a register: through
    ``history`` it waited for its store too (a quarter more time per sample).

    An output that is not finite (a blend of stable vertices whose float64 A(z) is not)
    is 0 and the filter restarts from rest; returns how many restarts fell on samples
    where ``counted`` (bool, as ``out``)."""
    p = poly.size - 1
    newest = history[0] if p > 0 else 0.0
    restarts = 0
    for j in range(out.size):
        acc = scale * _normal(key, index0 + j)
        if p > 0:
            acc -= poly[1] * newest
        for k in range(1, p):
            acc -= poly[k + 1] * history[k]
        if not math.isfinite(acc):
            acc = newest = 0.0
            history[:] = 0.0
            restarts += counted[j]
        for k in range(p - 1, 1, -1):
            history[k] = history[k - 1]
        if p > 1:
            history[1] = newest
        newest = acc
        out[j] = acc
    if p > 0:
        history[0] = newest
    return restarts


@njit(cache=True)
def noise_key(seed, finger, touch):
    """The noise stream of one touch of one finger (uint64)."""
    return _mix(np.uint64(seed) * _GOLDEN + np.uint64(finger) * _M1 + np.uint64(touch) * _M2)


def gaussian_noise(seed: int, finger: int, touch: int, index0: int, n: int) -> np.ndarray:
    """The standard normal samples of output indices index0 .. index0 + n - 1."""
    out = np.empty(n)
    key = np.uint64(noise_key(seed, finger, touch))  # a Python int: 2^63 and up fail as int64
    _synthesise(np.ones(1), 1.0, key, index0, np.zeros(0), out, np.zeros(n, dtype=np.bool_))
    return out


@njit(cache=True)
def render_finger(contact, touch_id, vx, vy, force, v_rest, seed, finger, index0, model,
                   touch, history, y, counted):
    """Model output y (n,) of one finger row; see the module docstring. ``touch`` and
    ``history`` (most recent first) come from the previous block; returns the touch id
    after the block (``history`` is updated in place) and how many samples where
    ``counted`` (bool (n,)) the filter restarted from rest after an output that was not
    finite (:func:`_synthesise`). A sample of non-finite speed or force (no such sample
    leaves a trace's checks) is not moving: its output is 0."""
    s0, f0, inv, corners, scale, triangles, lsf, variances, twiddle = model
    n = y.size
    a = 0
    restarts = 0
    while a < n:
        speed = math.hypot(vx[a], vy[a])  # vx^2 overflows from 1.3e154 mm/s
        b = a + 1  # the run of samples with this touch, speed and force
        while (b < n and touch_id[b] == touch_id[a] and contact[b] == contact[a]
               and vx[b] == vx[a] and vy[b] == vy[a] and force[b] == force[a]):
            b += 1
        moving = (contact[a] and speed >= v_rest and math.isfinite(speed)
                  and math.isfinite(force[a]))
        if touch_id[a] != touch or not moving:
            touch = touch_id[a]
            history[:] = 0.0
        if moving:
            poly, variance = blend_at(s0, f0, inv, corners, scale, triangles, lsf, variances,
                                      twiddle, speed, force[a])
            restarts += _synthesise(poly / poly[0], np.sqrt(variance),
                                    noise_key(seed, finger, touch), index0 + a, history, y[a:b],
                                    counted[a:b])
        else:
            y[a:b] = 0.0
        a = b
    return touch, restarts
