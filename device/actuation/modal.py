"""Modal inversion: wanted amplitudes under m fingers -> p modal amplitudes -> actuator commands.

The forward model (seed 000, eq 7; seed 001, eqs 4-5) is ``W_f = Phi_f W_M`` with
``Phi_f`` (m, p) the mode shapes at the fingers, and the actuators follow
``c = A W_M`` (seed 000, eq 9: ``A = Phi_act``, the shapes at the actuators; seed 001's
plate: ``A`` from the V_AC / V_BD wiring, see ``device.structures.plate2d``). Seed 000, eq 10 is
``c = A Phi_f^{-1} W_f``. Amplitudes are complex (magnitude um zero-to-peak, phase rad).

Every method works from the SVD ``Phi_f = U diag(s) V^H`` (batched over any leading
axes) and returns ``W_M = V g(s) U^H W_f`` for a gain ``g`` (``exact`` and
``regularised`` in closed form for real 2 x 2 ``Phi_f``, the two-mode devices):

- ``"exact"``: g = 1/s, the inverse (m = p) or the minimum-norm pseudo-inverse
  (p > m, seed 001). Singular values below 1e-12 s_max get g = 0 so the output stays
  finite. Near a singular locus the commands grow without bound and flip sign across it.
- ``"regularised"``: g = 1/s for s >= rcond s_max and s / (rcond s_max)^2 below, i.e.
  exact where the problem is well conditioned and a gain that falls to 0 at a singular
  locus. It is the only method whose commands are continuous as fingers cross a locus
  (seed 001, eq 8; coincident fingers; a finger on a node): what cannot be controlled
  there fades out instead of switching sign.
- ``"bounded"``: least squares within the actuator limits, min ||Phi_f W_M - W_f||^2
  subject to |c_j| <= limit_j (seed 001: the amplifiers saturate at 300 V peak-to-peak
  near singular positions): exactly, by active sets, for two actuators
  (``device.actuation.bounded_two``); else by projected accelerated gradient (FISTA with restart)
  in command space, started from the exact solution. The exact solution is returned as
  is when it is within limits. The closest achievable amplitudes, but like every
  residual-optimal method the commands jump across a singular locus.

With limits, ``exact`` and ``regularised`` commands that exceed a limit are scaled down
together (keeping their ratio and phases) until the largest reaches its limit. Every
sample reports what was achieved under each finger (forward model of the commands) and
the error; ``limited`` marks samples whose commands met a limit, ``capped`` those where
a singular value was below the method's threshold or below :data:`NEAR_SINGULAR` of the
largest (near a singular locus ``exact`` and ``bounded`` keep their gains but spend the
limits on a difference they cannot deliver), and those where every finger is on a node of
every mode (no mode shape under any finger above :data:`NODE_FLOOR`) or whose modal
amplitudes would overflow a float: these get none, whatever the method (the plate at rest).
Mode shapes are taken as normalised to a peak of about 1, as every structure gives them.
Singular loci are normal operation, never an error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from frictex.device.jit import njit
from frictex.device.safe_text import escape
from frictex.device.structures.beam import MAX_MODES, ModesError
from frictex.device.actuation.bounded_two import bounded_two
from frictex.device.profile import DEFAULT_METHOD, DEFAULT_RCOND, METHODS

#: singular values below this fraction of the largest are treated as zero by "exact"
_EXACT_RCOND = 1e-12
#: a system whose smallest / largest singular value is below this counts as capped
#: whatever the method: there a difference of 1 nm between the fingers' amplitudes
#: costs over 1 um of command, beyond any channel's limit (about 1 um), so the
#: fingers cannot be given independent amplitudes even where no gain was cut
NEAR_SINGULAR = 1e-3
#: every finger is on a node of every mode where no mode shape under a finger exceeds
#: this (shapes of peak about 1: the plate's and measured tables' peak 1, the beam's RMS
#: 1). There 1 um of command, about a channel's limit, moves the fingers by a few
#: picometres at most, nothing a finger feels; the system left is rounding noise (a
#: computed node is 1e-16, a node written to 10 decimals 1e-11), whose inverse would
#: drive the channels to their limits in a direction set by that noise. 1e-6 is 5 nm
#: from a node of the seed 001 plate's mode (slope 0.19 / mm): only fingers placed on it.
NODE_FLOOR = 1e-6
#: "bounded" gives no command where every command within the limits reaches the fingers
#: with less than this (um): nothing a plate could show
_LEAST_REACH_UM = 1e-100
#: the largest wanted amplitude accepted (um): a plate vibrates a few um, and past about
#: 1e155 um the solvers' squares overflow, which broke the limits ("bounded" gave |c| 0.98
#: under a 0.75 um limit) and left inf in the error
MAX_WANTED_UM = 1e6
_FISTA_MAX_ITER = 3000
_FISTA_TOL = 1e-13


@dataclass(frozen=True, eq=False)
class ModalSolution:
    """The result of :func:`solve`; leading axes (...) are those of the inputs.

    modal_um : complex128 (..., p)  modal amplitudes W_M (um).
    commands_um : complex128 (..., q)  actuator commands c = A W_M (um zero-to-peak).
    achieved_um : complex128 (..., m)  amplitudes under the fingers, Phi_f W_M (um).
    error_um : float64 (..., m)  |achieved - wanted| (um).
    limited : bool (...)  commands met an actuator limit (scaled or constrained).
    capped : bool (...)  a singular value of Phi_f was below the method's threshold or
        below NEAR_SINGULAR of the largest.
    sigma_min_ratio : float64 (...)  smallest / largest singular value of Phi_f.
    """

    modal_um: np.ndarray
    commands_um: np.ndarray
    achieved_um: np.ndarray
    error_um: np.ndarray
    limited: np.ndarray
    capped: np.ndarray
    sigma_min_ratio: np.ndarray

    def counts(self) -> dict[str, int]:
        """How many samples met a limit and how many had their gain capped."""
        return {"limited": int(np.count_nonzero(self.limited)),
                "capped": int(np.count_nonzero(self.capped))}


def forward(phi_fingers, modal_um) -> np.ndarray:
    """Amplitudes under the fingers (..., m) = Phi_f (..., m, p) @ W_M (..., p) (seed 001, eq 5).

    Also any matrix applied to a batch of vectors (leading axes broadcast)."""
    phi, modal = np.asarray(phi_fingers), np.asarray(modal_um)
    if np.iscomplexobj(phi):  # numpy's SIMD complex products fuse their roundings: kept
        out = phi[..., 0] * modal[..., None, 0]
        for j in range(1, phi.shape[-1]):
            out = out + phi[..., j] * modal[..., None, j]
        return out
    batch = np.broadcast_shapes(phi.shape[:-2], modal.shape[:-1])
    m, p = phi.shape[-2:]
    phi3 = (phi.reshape(1, m, p) if phi.ndim == 2
            else np.broadcast_to(phi, batch + (m, p)).reshape(-1, m, p))
    modal2 = np.broadcast_to(modal.astype(np.complex128, copy=False), batch + (p,)).reshape(-1, p)
    out = np.empty((modal2.shape[0], m), dtype=np.complex128)
    _forward_kernel(phi3, modal2, out)
    out = out.reshape(batch + (m,))
    # real amplitudes: the real parts are the real products, signed zeros included
    return out if np.iscomplexobj(modal) else out.real.copy()


@njit(cache=True, nogil=True)
def _forward_kernel(phi, modal, out):
    """out[k] = phi[k or 0] @ modal[k] for real phi (:func:`_forward_row`)."""
    for k in range(out.shape[0]):
        _forward_row(phi, 0 if phi.shape[0] == 1 else k, modal, k, out)


@njit(cache=True, nogil=True, inline="always")
def _forward_row(phi, kp, modal, k, out):
    """out[k] = phi[kp] @ modal[k] (real phi, complex modal)."""
    for i in range(out.shape[1]):
        out[k, i] = _combination(phi[kp, i], modal, k)


@njit(cache=True, nogil=True, inline="always")
def _combination(row, modal, k):
    """row @ modal[k] for a real row, summed over the modes in order, as numpy sums it."""
    acc = _times_real(modal[k, 0], row[0])
    for j in range(1, row.shape[0]):
        acc = acc + _times_real(modal[k, j], row[j])
    return acc


def magnitude(z) -> np.ndarray:
    """|z| (um, float64, the shape of ``z``) of amplitudes ``z`` (um).

    Complex amplitudes as sqrt(re^2 + im^2): within an ulp or two of ``np.abs``, which
    goes through scalar ``hypot`` and is ~10x slower (amplitudes in um never over- or
    underflow when squared). Real amplitudes as ``np.abs``, exact: the same bits as
    sqrt(x^2) wherever x^2 neither over- nor underflows (1.5e-154 < |x| < 1.3e154)."""
    z = np.asarray(z)
    if not np.iscomplexobj(z):
        return np.abs(z.astype(np.float64, copy=False))
    out = np.empty(z.shape)
    _magnitude_kernel(z.reshape(-1), out.reshape(-1))
    return out


@njit(cache=True, nogil=True)
def _magnitude_kernel(z, out):
    for i in range(z.size):
        out[i] = _abs(z[i])


@njit(cache=True, nogil=True, inline="always")
def _times_real(z, x):
    """z x for complex z and real x as numpy computes it, x entering as x + 0j (the zero
    products only decide the signs of zeros; numba's own complex product is slower). Only
    a product that underflows (below 1e-308) can differ: numpy's SIMD product fuses its
    roundings and may give that zero the other sign."""
    return complex(z.real * x - z.imag * 0.0, z.real * 0.0 + z.imag * x)


@njit(cache=True, nogil=True, inline="always")
def _abs(z):
    """:func:`magnitude` of one complex number."""
    return math.sqrt(z.real * z.real + z.imag * z.imag)


def achieved_magnitude(phi, where, modal) -> np.ndarray:
    """|Phi(x_f) W_M| under each finger where touching, else 0, as :func:`forward` and
    :func:`magnitude` compute it (bit for bit).

    Parameters
    ----------
    phi : float64 (k, p)
        Mode shapes of the p modes at the k finger samples touching.
    where : int64 (F, n)
        Row of ``phi`` of each finger and sample; -1 where the finger does not touch.
    modal : complex128 (n, p)
        Modal amplitudes W_M of each sample (um).

    Returns
    -------
    float64 (F, n)
        Amplitude under each finger (um zero-to-peak).
    """
    out = np.zeros(np.shape(where))
    _achieved_kernel(np.asarray(phi, dtype=np.float64), np.asarray(where, dtype=np.int64),
                     np.asarray(modal, dtype=np.complex128), out)
    return out


# here, not in its caller's module: numba's cache checks only the file of the cached
# function, so a kernel elsewhere inlining _abs / _combination would run stale code
# after an edit to this file
@njit(cache=True, nogil=True)
def _achieved_kernel(phi, where, modal, out):
    """:func:`achieved_magnitude` into ``out`` (zeros), sample by sample."""
    for i in range(where.shape[1]):
        _achieved_at(phi, where, modal, i, out)


@njit(cache=True, nogil=True, inline="always")
def _achieved_at(phi, where, modal, i, out):
    """out[f, i] = |phi[where[f, i]] @ modal[i]| for every finger f touching at sample i."""
    for f in range(where.shape[0]):
        row = where[f, i]
        if row >= 0:
            out[f, i] = _abs(_combination(phi[row], modal, i))


def serve_two_modes(phi, where, served, wanted_um, actuators, limits_um, rcond: float,
                    regularised: bool):
    """Two modes through q channels, sample by sample, in one compiled pass.

    For each sample the padded 2 x 2 system (``device.actuation.modal_actuation``, step 2:
    row r holds the shapes and wanted amplitude of the finger ``served[i, r]``, zeros
    where none), then what :func:`solve` returns for it with method ``"exact"`` or
    ``"regularised"`` (the closed form of :func:`_gains_2x2`, c = A W_M, both scaled to
    the limits), |c| clipped to the limits, and :func:`achieved_magnitude` under every
    finger touching; each bit for bit as those compute it.

    Parameters
    ----------
    phi : float64 (k, 2)
        Mode shapes at the k finger samples touching.
    where : int64 (F, n)
        Row of ``phi`` of each finger and sample; -1 where the finger does not touch.
    served : int64 (n, 2)
        Finger (row of ``where``) whose shapes fill row r of sample i's system; -1: a zero row.
    wanted_um : float64 (F, n)
        Wanted amplitude under each finger (um zero-to-peak, phase 0).
    actuators : float64 (q, 2)
        Modal amplitudes -> channel commands (seed 000, eq 9).
    limits_um : float64 (q,)
        Largest |command| of each channel (um zero-to-peak), > 0.
    rcond : float
        The singular-value threshold :func:`solve` applies for the method (relative).
    regularised : bool
        Method ``"regularised"`` (else ``"exact"``).

    Returns
    -------
    tuple or None
        amplitude float64 (n, q) (um, |c| at most its limit); commands complex128 (n, q)
        (um; +0.0 for a zero part, so that a zero command has phase 0); achieved float64
        (F, n) (um, 0 where not touching); how many samples met a limit; how many served
        two fingers with a capped gain (their system's smaller singular value below the
        threshold or :data:`NEAR_SINGULAR` of the larger: the fingers could not be given
        independent amplitudes, seed 001 eq 8; or both on nodes of both modes, every
        shape below :data:`NODE_FLOOR`: no command).
        None where a served shape or wanted amplitude is not finite (what :func:`solve`
        refuses).
    """
    n, q = served.shape[0], len(limits_um)
    modal = np.empty((n, 2), dtype=np.complex128)
    commands = np.empty((n, q), dtype=np.complex128)
    amplitude = np.empty((n, q))
    achieved = np.zeros(np.shape(where))
    limited, capped = _two_modes_kernel(phi, where, served, wanted_um,
                                        actuators.reshape((1,) + actuators.shape), limits_um, rcond,
                                        regularised, modal, commands, amplitude, achieved)
    return None if limited < 0 else (amplitude, commands, achieved, limited, capped)


@njit(cache=True, nogil=True, error_model="numpy")
def _two_modes_kernel(phi, where, served, wanted, actuators, limits, rcond, regularised,
                      modal, commands, amplitude, achieved):
    """:func:`serve_two_modes` into its output arrays; returns the counts of samples that
    met a limit (-1 at the first sample whose system is not finite) and of samples serving
    two fingers whose gain was capped.

    Where every |c_j| is within its limit the scale is exactly 1 (|c_j| <= L_j gives
    |c_j| / L_j <= 1 after rounding) and is not applied: times 1 + 0j changes at most the
    signs of zeros (finite c_j, hence finite W_M), which neither |.| nor the + 0.0 that
    follows can see. That spares most samples two square roots and three divisions."""
    limited, capped = 0, 0
    for i in range(served.shape[0]):
        a, b, w0, finite0 = _served_row(phi, where, served, wanted, i, 0)
        c, d, w1, finite1 = _served_row(phi, where, served, wanted, i, 1)
        if not (finite0 and finite1):
            return -1, capped
        modal[i, 0], modal[i, 1], full, s1, s2 = _gains_2x2_one(a, b, c, d, w0, w1, rcond, regularised)
        rest = max(abs(a), abs(b), abs(c), abs(d)) < NODE_FLOOR  # solve's _at_rest
        if rest:
            modal[i, 0], modal[i, 1] = 0j, 0j
        # one finger's zero row caps the gain too, but leaves nothing to tell apart
        if (rest or not full or s2 < NEAR_SINGULAR * s1) and served[i, 1] >= 0:
            capped += 1
        _forward_row(actuators, 0, modal, i, commands)
        within = True
        for j in range(commands.shape[1]):
            amplitude[i, j] = _abs(commands[i, j])
            within = within and amplitude[i, j] <= limits[j]
        if not within:  # NaN included
            if _scale_row(commands, modal, limits, i):
                limited += 1
            for j in range(commands.shape[1]):
                amplitude[i, j] = _minimum(_abs(commands[i, j]), limits[j])
        for j in range(commands.shape[1]):
            z = commands[i, j]
            commands[i, j] = complex(z.real + 0.0, z.imag + 0.0)
        _achieved_at(phi, where, modal, i, achieved)
    return limited, capped


@njit(cache=True, nogil=True, inline="always")
def _served_row(phi, where, served, wanted, i, r):
    """Row r of sample i's padded system: the two shapes and wanted amplitude (+ 0j) of
    the finger serving it, zeros if none; and whether the three are finite."""
    f = served[i, r]
    if f < 0:
        return 0.0, 0.0, 0j, True
    k = where[f, i]
    x, y, w = phi[k, 0], phi[k, 1], wanted[f, i]
    return x, y, complex(w, 0.0), math.isfinite(x) and math.isfinite(y) and math.isfinite(w)


def solve(phi_fingers, wanted_um, method: str = DEFAULT_METHOD, *, actuators=None,
          limits_um=None, rcond: float = DEFAULT_RCOND) -> ModalSolution:
    """Modal amplitudes and actuator commands giving ``wanted_um`` under the fingers.

    Parameters
    ----------
    phi_fingers : array_like, float or complex, shape (..., m, p)
        Mode shapes of the p modes at the m fingers (seed 001, eq 4), p >= m; leading
        axes batch many finger configurations (e.g. a block of samples) in one call.
    wanted_um : array_like, complex, shape (..., m)
        Wanted amplitude under each finger (um zero-to-peak, phase in the argument);
        broadcast against the leading axes of ``phi_fingers``.
    method : {"exact", "regularised", "bounded"}
        See the module docstring.
    actuators : array_like, float or complex, shape (q, p), optional
        Modal amplitudes -> actuator commands (seed 000, eq 9; dimensionless); default
        identity, so the commands are the modal amplitudes. Complex entries drive a mode
        with a phase shift. ``"bounded"`` needs it square, invertible.
    limits_um : float or array_like (q,), optional
        Largest |command| of each actuator (um zero-to-peak); default none. Required by
        ``"bounded"``.
    rcond : float
        ``"regularised"`` threshold relative to the largest singular value, in (0, 1).

    Returns
    -------
    ModalSolution
    """
    phi, wanted = _check_inputs(phi_fingers, wanted_um)
    a, limits = check_settings(method, actuators, limits_um, rcond, phi.shape[-1])
    threshold = gain_threshold(method, rcond)
    # "bounded" keeps LAPACK's start: its iterations amplify last-bit differences where
    # the least-squares problem is flat
    closed = phi.shape[-2:] == (2, 2) and not np.iscomplexobj(phi) and method != "bounded"
    modal, capped, ratio = (_gains_2x2 if closed else _gains_svd)(
        phi, wanted, threshold, regularised=method == "regularised")
    modal, at_rest = _at_rest(modal, phi)
    capped = capped | (ratio < NEAR_SINGULAR) | at_rest
    if method != "bounded" and not np.iscomplexobj(phi) and not np.iscomplexobj(a):
        commands, modal, achieved, error, limited = _finish(phi, wanted, modal, a, limits)
        return ModalSolution(modal, commands, achieved, error, limited, capped, ratio)
    commands = forward(a, modal)  # c = A W_M; no BLAS call for a few modes

    limited = np.zeros(commands.shape[:-1], dtype=bool)
    if limits is not None:
        commands, modal, limited = _scale_to_limits(commands, modal, limits)
        if method == "bounded" and np.any(limited):
            a_inv = np.linalg.inv(a)
            commands[limited], unreached = _bounded(
                _without_weak_directions(phi[limited]) @ a_inv, wanted[limited],
                commands[limited], limits)
            reached_none = np.zeros(limited.shape, dtype=bool)
            reached_none[limited] = unreached
            capped = capped | reached_none
            modal[limited] = commands[limited] @ a_inv.T
            limited = _at_limit(commands, limits)
    achieved = forward(phi, modal)
    return ModalSolution(modal, commands, achieved, magnitude(achieved - wanted),
                         limited, capped, ratio)


def _bounded(m_cmd, wanted, start, limits) -> tuple[np.ndarray, np.ndarray]:
    """The "bounded" commands (k, q) of k problems (:func:`_bounded_commands`, or
    ``bounded_two`` for two actuators), and where they are 0 because every command within
    the limits moves the fingers by less than :data:`_LEAST_REACH_UM` (k,) (counted
    capped, as an overflow is).

    Each problem's ``m_cmd`` and ``wanted`` are first scaled by the power of two that
    brings its largest entry to [0.5, 1): the same commands (exactly), but the solvers'
    squares of M (M^H M) neither underflow nor overflow (mode shapes of 1e-200 gave a
    division by zero)."""
    commands = np.zeros_like(start)
    largest = np.abs(m_cmd).max(axis=(-2, -1))
    reach = largest * np.max(limits) >= _LEAST_REACH_UM
    scale = np.ldexp(1.0, -np.frexp(largest[reach])[1])  # within range: reach's bound
    m_cmd, wanted = m_cmd[reach] * scale[:, None, None], wanted[reach] * scale[:, None]
    if m_cmd.shape[-1] == 2:
        commands[reach] = bounded_two(m_cmd, wanted, limits)
    else:
        commands[reach] = _bounded_commands(m_cmd, wanted, start[reach], limits)
    return commands, ~reach


def _at_rest(modal, phi) -> tuple[np.ndarray, np.ndarray]:
    """``modal`` (..., p) set to 0 where every finger is on a node of every mode (each
    |Phi_f| entry below :data:`NODE_FLOOR`) or the amplitudes are not finite (shapes below
    about 1e-308 need amplitudes past the largest float), and where that was. No command
    reaches the fingers there; the plate's rest (mu' = 1) is the safe answer."""
    rest = ~np.isfinite(modal).all(axis=-1) | (np.abs(phi).max(axis=(-2, -1)) < NODE_FLOOR)
    if rest.any():
        modal = np.where(rest[..., None], 0, modal)
    return modal, rest


def _without_weak_directions(phi) -> np.ndarray:
    """``phi`` (k, m, p) with its singular values below :data:`NEAR_SINGULAR` of the
    largest set to 0. What they could add to the fingers' amplitudes is below 1e-3 of the
    command spent on it: "bounded" would drive a channel to its limit for a gain of
    microns' thousandths; dropped, the minimum-norm solution serves the rest with the
    smallest commands (beam fingers 0.1 um apart: [0.20, 0.06] um, not [0.197, 0.75])."""
    u, s, vh = np.linalg.svd(phi, full_matrices=False)
    s = np.where(s >= NEAR_SINGULAR * s[..., :1], s, 0.0)
    return np.einsum("...ij,...j,...jk->...ik", u, s, vh)


def _at_limit(commands, limits) -> np.ndarray:
    """Where some |c_j| (um) reached its limit (um), up to a relative 1e-12: what
    ``limited`` counts once "bounded" has solved (a solution can stay within limits)."""
    return np.any(magnitude(commands) >= limits * (1 - 1e-12), axis=-1)


def check_settings(method: str, actuators, limits_um, rcond: float, p: int):
    """The checks :func:`solve` makes of its settings for p modes (a ``ModesError`` naming
    the bad one); returns the actuator matrix (q, p) and the limits (q,) or None as it
    uses them."""
    if method not in METHODS:
        raise ModesError(f"modal method must be one of {', '.join(METHODS)}, got {escape(method)}")
    if not 1 <= p <= MAX_MODES:
        raise ModesError(f"modal inversion takes 1 to {MAX_MODES} modes, got {p}")
    a = _check_actuators(actuators, p)
    limits = _check_limits(limits_um, a.shape[0])
    if method == "bounded" and (limits is None or a.shape[0] != p or np.linalg.cond(a) > 1e12):
        raise ModesError(f"method 'bounded' needs limits_um and a square, invertible "
                         f"(p, p) actuator matrix, got limits {_shown(limits_um)} and actuators of shape {a.shape}")
    if not (0 < rcond < 1):
        raise ModesError(f"rcond must be in (0, 1), got {escape(rcond)}")
    return a, limits


def _shown(values) -> str:
    """``values`` (a number, a sequence, an array) for a one-line message: as a flat list,
    escaped and cut to :data:`~frictex.device.safe_text.MAX_SHOWN` characters."""
    try:
        flat = np.asarray(values).ravel()
    except (TypeError, ValueError):
        return escape(values)
    # a bounded prefix: never a repr of a whole large array
    text = ", ".join(str(v) for v in flat[:8].tolist())
    return escape(f"{flat.size} values [{text}, ...]" if flat.size > 8 else f"[{text}]")


def gain_threshold(method: str, rcond: float) -> float:
    """Singular values below this fraction of the largest get less than 1/s as gain
    (module docstring): ``rcond`` for "regularised", 1e-12 otherwise."""
    return rcond if method == "regularised" else _EXACT_RCOND


def _finish(phi, wanted, modal, a, limits):
    """The end of :func:`solve` for real ``phi`` and methods but ``"bounded"``, in one
    compiled pass: c = A W_M, both scaled to the limits (if any), achieved = Phi_f W_M
    and |achieved - wanted|, each as :func:`forward`, :func:`_scale_to_limits` and
    :func:`magnitude` compute it. Returns (commands, modal, achieved, error, limited)."""
    batch = modal.shape[:-1]
    m, p = phi.shape[-2:]
    modal2 = np.ascontiguousarray(modal, dtype=np.complex128).reshape(-1, p)
    k = modal2.shape[0]
    out = (np.empty((k, a.shape[0]), dtype=np.complex128), modal2.copy(),
           np.empty((k, m), dtype=np.complex128), np.empty((k, m)), np.zeros(k, dtype=np.bool_))
    _finish_kernel(np.broadcast_to(phi, batch + (m, p)).reshape(-1, m, p),
                   np.broadcast_to(wanted, batch + (m,)).reshape(-1, m), a.reshape((1,) + a.shape),
                   np.empty(0) if limits is None else limits, *out)
    return tuple(x.reshape(batch + x.shape[1:]) for x in out)


@njit(cache=True, nogil=True, error_model="numpy")
def _finish_kernel(phi, wanted, a, limits, commands, modal, achieved, error, limited):
    """:func:`_finish`; ``modal`` is scaled in place, no limits if ``limits`` is empty."""
    for k in range(modal.shape[0]):
        _forward_row(a, 0, modal, k, commands)
        if limits.size:
            limited[k] = _scale_row(commands, modal, limits, k)
        _forward_row(phi, k, modal, k, achieved)
        for i in range(achieved.shape[1]):
            error[k, i] = _abs(achieved[k, i] - wanted[k, i])


def _scale_to_limits(commands, modal, limits):
    """Commands and modal amplitudes scaled by 1 / max(1, max_j |c_j| / limit_j), and
    where that was below 1 (module docstring); any leading axes."""
    batch = commands.shape[:-1]
    c = np.ascontiguousarray(commands, dtype=np.complex128).reshape(-1, commands.shape[-1])
    w = np.ascontiguousarray(modal, dtype=np.complex128).reshape(-1, modal.shape[-1])
    c, w, limited = c.copy(), w.copy(), np.empty(len(c), dtype=np.bool_)
    _scale_kernel(c, w, limits, limited)
    return c.reshape(batch + c.shape[-1:]), w.reshape(batch + w.shape[-1:]), limited.reshape(batch)


@njit(cache=True, nogil=True, error_model="numpy")
def _scale_kernel(commands, modal, limits, limited):
    """:func:`_scale_to_limits` in place, row by row (:func:`_scale_row`)."""
    for k in range(commands.shape[0]):
        limited[k] = _scale_row(commands, modal, limits, k)


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _scale_row(commands, modal, limits, k):
    """Scale row k of ``commands`` and ``modal`` in place by 1 / max(1, max_j |c_j| / limit_j);
    True if that was below 1. numpy's operations in their order (np.maximum's NaN rule;
    the real scale enters complex products as s + 0j)."""
    over = 0.0
    for j in range(commands.shape[1]):
        ratio = _abs(commands[k, j]) / limits[j]
        over = ratio if j == 0 else _maximum(over, ratio)
    scale = 1 / _maximum(over, 1.0)
    for j in range(commands.shape[1]):
        commands[k, j] = _times_real(commands[k, j], scale)
    for j in range(modal.shape[1]):
        modal[k, j] = _times_real(modal[k, j], scale)
    return over > 1


@njit(cache=True, nogil=True, inline="always")
def _maximum(a, b):
    """np.maximum of two floats: the larger, or NaN if either is."""
    return a if (a >= b or a != a) else b


@njit(cache=True, nogil=True, inline="always")
def _minimum(a, b):
    """np.minimum of two floats: the smaller, or NaN if either is."""
    return a if (a <= b or a != a) else b


def _gains_svd(phi, wanted, rcond: float, regularised: bool):
    """``W_M = V g(s) U^H W_f`` from the batched SVD (module docstring); any (..., m, p).

    Returns ``(modal, capped, sigma_min_ratio)`` as :class:`ModalSolution` names them.
    """
    u, s, vh = np.linalg.svd(phi, full_matrices=False)
    s_max = s[..., :1]
    ratio = np.divide(s[..., -1], s_max[..., 0], out=np.zeros(s.shape[:-1]), where=s_max[..., 0] > 0)
    threshold = rcond * s_max
    above = ((s >= threshold) if regularised else (s > threshold)) & (s > 0)
    capped = ~np.all(above, axis=-1)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):  # solve's _at_rest
        inverse = np.divide(1.0, s, out=np.zeros_like(s), where=above)
        if regularised:
            inverse += np.divide(s, threshold ** 2, out=np.zeros_like(s),
                                 where=~above & (threshold > 0))
        coeff = inverse * np.einsum("...ji,...j->...i", u.conj(), wanted)
        modal = np.einsum("...ji,...j->...i", vh.conj(), coeff)
    return modal, capped, ratio


def _gains_2x2(phi, wanted, rcond: float, regularised: bool):
    """:func:`_gains_svd` in closed form for real 2 x 2 ``Phi_f`` (two modes, two fingers
    or one finger and a zero row): the same ``V g(s) U^T`` without a LAPACK call per matrix.

    Singular values: with E = (a + d)/2, F = (a - d)/2, G = (c + b)/2, H = (c - b)/2 of
    Phi = [[a, b], [c, d]], s1 = Q + R and s2 = |Q - R|, Q = |(E, H)|, R = |(F, G)|.
    Where every gain is 1/s the result is the inverse, adj(Phi) W_f / det. Elsewhere the
    gain is 1/s1 on the first singular pair and s2 / t^2 ("regularised", t the threshold)
    or 0 ("exact") on the second: with A = Phi^T Phi (eigenvalues s1^2 > s2^2) that is
    ``h(A) Phi^T W_f`` for h(s^2) = g(s)/s, and on two eigenvalues h(A) = alpha I + beta A
    (Lagrange interpolation; s1^2 - s2^2 = 4 Q R is at least 0.99 s1^2 there, since
    s2 < t = 0.1 s1 with the default threshold). Agreement with LAPACK: 1e-15 relative
    for the inverse (times the condition number, as for any solve), 1e-13 in the
    regularised zone, where alpha and beta A cancel by up to 1/rcond^2 = 100
    (tests/test_speedups.py).
    """
    batch = phi.shape[:-2]
    modal, capped, ratio = _gains_2x2_kernel(phi.reshape(-1, 2, 2), wanted.reshape(-1, 2),
                                             rcond, regularised)
    return modal.reshape(batch + (2,)), capped.reshape(batch), ratio.reshape(batch)


@njit(cache=True, nogil=True, error_model="numpy")
def _gains_2x2_kernel(phi, wanted, rcond, regularised):
    """:func:`_gains_2x2` on (k, 2, 2) and (k, 2), one pass (:func:`_gains_2x2_one`)."""
    k = phi.shape[0]
    modal = np.empty((k, 2), dtype=np.complex128)
    capped = np.empty(k, dtype=np.bool_)
    ratio = np.zeros(k)
    for i in range(k):
        modal[i, 0], modal[i, 1], full, s1, s2 = _gains_2x2_one(
            phi[i, 0, 0], phi[i, 0, 1], phi[i, 1, 0], phi[i, 1, 1], wanted[i, 0], wanted[i, 1],
            rcond, regularised)
        if s1 > 0:
            ratio[i] = s2 / s1
        capped[i] = not full
    return modal, capped, ratio


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _gains_2x2_one(a, b, c, d, w0, w1, rcond, regularised):
    """W_M = G W_f of one real system [[a, b], [c, d]] and complex wanted (w0, w1) (um);
    the numpy operations :func:`_gains_2x2` replaced, in their order (complex products,
    G + 0j). Returns (W_M0, W_M1, full, s1, s2): full where every gain is 1/s, and the
    singular values s1 >= s2.

    The system is first scaled by the power of two nearest its largest entry (exact, so
    the result is unchanged wherever nothing overflows): unscaled, E^2 + H^2 and the
    determinant overflow or underflow past about 1e154 (a [[1e200, 0], [0, 1e-200]]
    system gave NaN)."""
    exponent = _exponent(max(abs(a), abs(b), abs(c), abs(d)))
    a, b, c, d = math.ldexp(a, -exponent), math.ldexp(b, -exponent), \
        math.ldexp(c, -exponent), math.ldexp(d, -exponent)
    e, h = (a + d) / 2, (c - b) / 2
    f, g = (a - d) / 2, (c + b) / 2
    q = np.sqrt(e * e + h * h)
    r = np.sqrt(f * f + g * g)
    s1, s2 = q + r, abs(q - r)
    threshold = rcond * s1
    full = ((s2 >= threshold) if regularised else (s2 > threshold)) and s2 > 0
    inv_det = 1.0 / (a * d - b * c) if full else 0.0
    g00, g01, g10, g11 = d * inv_det, -b * inv_det, -c * inv_det, a * inv_det
    if not full and s1 > 0:  # h(A) Phi^T = alpha Phi^T + beta Phi^T (Phi Phi^T)
        b00, b01, b11 = a * a + b * b, a * c + b * d, c * c + d * d
        lam1 = s1 * s1
        h2 = 1.0 / (threshold * threshold) if regularised else 0.0
        beta = (1.0 / lam1 - h2) / (4.0 * q * r)
        alpha = 1.0 / lam1 - beta * lam1
        g00 = alpha * a + beta * (a * b00 + c * b01)
        g01 = alpha * c + beta * (a * b01 + c * b11)
        g10 = alpha * b + beta * (b * b00 + d * b01)
        g11 = alpha * d + beta * (b * b01 + d * b11)
    # the unscaled system's gains are G / 2^exponent, its singular values s 2^exponent
    return (_ldexp_complex(_times_real(w0, g00) + _times_real(w1, g01), -exponent),
            _ldexp_complex(_times_real(w0, g10) + _times_real(w1, g11), -exponent),
            full, math.ldexp(s1, exponent), math.ldexp(s2, exponent))


@njit(cache=True, nogil=True, inline="always")
def _exponent(x):
    """The binary exponent e of a float x >= 0 (x = m 2^e, 0.5 <= m < 1); 0 for 0, inf or NaN."""
    return math.frexp(x)[1] if (x > 0 and math.isfinite(x)) else 0


@njit(cache=True, nogil=True, inline="always")
def _ldexp_complex(z, exponent):
    """z 2^exponent, exactly (real and imaginary parts apart: no inf times 0)."""
    return complex(math.ldexp(z.real, exponent), math.ldexp(z.imag, exponent))


def _bounded_commands(m_cmd, wanted, start, limits) -> np.ndarray:
    """min ||M c - w||^2 + eps ||c||^2 subject to |c_j| <= limits_j, for (k, m, q) M.

    FISTA with gradient restart (O'Donoghue and Candes 2015); eps = 1e-12 ||M||^2 only
    breaks ties where M is singular. Each problem stops on its own, once the gradient
    mapping bounds its distance to the optimum (2 L / mu times the last step, L and mu the
    objective's smoothness and strong convexity) below ``_FISTA_TOL`` of the largest limit:
    a step-size test alone stops flat problems up to cond(M)^2 times too early, and a
    shared test would make one problem's answer depend on the others in its batch.
    Returns the best iterate per problem.
    """
    s = np.linalg.svd(m_cmd, compute_uv=False)
    s_max, s_min = s[:, 0], s[:, -1] if m_cmd.shape[-2] >= m_cmd.shape[-1] else np.zeros(len(s))
    eps = 1e-12 * s_max ** 2
    lipschitz, convexity = 2 * (s_max ** 2 + eps), 2 * (s_min ** 2 + eps)
    step = (1 / lipschitz)[:, None]
    bound = 2 * lipschitz / convexity  # distance to the optimum per unit of step
    mh = np.conj(np.swapaxes(m_cmd, -1, -2))

    def objective(c):
        r = np.einsum("kij,kj->ki", m_cmd, c) - wanted
        return np.sum(np.abs(r) ** 2, axis=-1) + eps * np.sum(np.abs(c) ** 2, axis=-1)

    def project(c):
        mag = np.abs(c)
        return c * np.minimum(1, limits / np.where(mag > 0, mag, 1))

    c = y = start.copy()
    t = np.ones(len(c))
    best, best_obj = c.copy(), objective(c)
    active = np.ones(len(c), dtype=bool)
    for _ in range(_FISTA_MAX_ITER):
        grad = 2 * np.einsum("kij,kj->ki", mh, np.einsum("kij,kj->ki", m_cmd, y) - wanted) + 2 * eps[:, None] * y
        c_new = project(y - step * grad)
        restart = np.real(np.sum(np.conj(y - c_new) * (c_new - c), axis=-1)) > 0
        t_new = np.where(restart, 1.0, (1 + np.sqrt(1 + 4 * t * t)) / 2)
        momentum = np.where(restart, 0.0, (t - 1) / t_new)[:, None]
        y_new = c_new + momentum * (c_new - c)
        active &= bound * np.max(np.abs(y - c_new), axis=-1) >= _FISTA_TOL * np.max(limits)
        keep = active[:, None]
        c, y, t = np.where(keep, c_new, c), np.where(keep, y_new, y), np.where(active, t_new, t)
        obj = objective(c_new)
        better = obj < best_obj
        best[better], best_obj[better] = c_new[better], obj[better]
        if not np.any(active):
            break
    return best


def _check_inputs(phi_fingers, wanted_um) -> tuple[np.ndarray, np.ndarray]:
    phi = np.asarray(phi_fingers)
    if phi.ndim < 2 or phi.shape[-2] < 1 or phi.shape[-1] < phi.shape[-2]:
        raise ModesError(f"phi_fingers must have shape (..., m, p) with p >= m >= 1 "
                         f"(fingers x modes), got {phi.shape}")
    phi = phi.astype(np.complex128 if np.iscomplexobj(phi) else np.float64)
    wanted = np.asarray(wanted_um, dtype=np.complex128)
    if wanted.ndim < 1 or wanted.shape[-1] != phi.shape[-2]:
        raise ModesError(f"wanted_um must have shape (..., m) with m = {phi.shape[-2]} "
                         f"fingers, got {wanted.shape}")
    batch = np.broadcast_shapes(phi.shape[:-2], wanted.shape[:-1])
    phi = np.broadcast_to(phi, batch + phi.shape[-2:])
    wanted = np.broadcast_to(wanted, batch + wanted.shape[-1:])
    for name, arr in (("phi_fingers", phi), ("wanted_um", wanted)):
        if not np.all(np.isfinite(arr)):
            raise ModesError(f"{name} has non-finite values (first at index "
                             f"{np.argwhere(~np.isfinite(arr))[0].tolist()}); expected finite numbers")
    too_large = np.abs(wanted) > MAX_WANTED_UM
    if np.any(too_large):
        first = np.argwhere(too_large)[0]
        raise ModesError(f"wanted_um has {abs(wanted[tuple(first)]):.3g} um at index "
                         f"{first.tolist()}: expected at most {MAX_WANTED_UM:g} um (a plate "
                         "vibrates a few um; amplitudes are um zero-to-peak)")
    return phi, wanted


def _check_actuators(actuators, p: int) -> np.ndarray:
    if actuators is None:
        return np.eye(p)
    a = np.asarray(actuators)
    if a.ndim != 2 or a.shape[1] != p or not np.all(np.isfinite(a)):
        raise ModesError(f"actuators must be a finite (q, p) matrix with p = {p} modes, "
                         f"got shape {a.shape}")
    # complex (phased drives) stays complex and takes solve's numpy path; the compiled
    # end is typed for float64
    return a.astype(np.complex128 if np.iscomplexobj(a) else np.float64)


def _check_limits(limits_um, q: int) -> np.ndarray | None:
    if limits_um is None:
        return None
    lim = np.broadcast_to(np.asarray(limits_um, dtype=np.float64), (q,)) if np.ndim(limits_um) == 0 \
        else np.asarray(limits_um, dtype=np.float64)
    if lim.shape != (q,) or not np.all(np.isfinite(lim) & (lim > 0)):
        raise ModesError(f"limits_um must be one finite value > 0 or one per actuator "
                         f"({q}), got {_shown(limits_um)}")
    return lim
