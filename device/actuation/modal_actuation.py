"""Modal actuation: wanted amplitudes under the fingers -> modal amplitudes -> channel commands.

For the modal profiles (``device.profile.MODAL_PROFILES``): seed 000's beam (two
flexural modes, two transducers, eq 10: ``c = Phi_act Phi_f^{-1} W_f``) and seed 001's
2D plate (X and Y modes, channels V_AC and V_BD; eqs 4-5 for m fingers and p modes).
Everything that does not depend on the fingers is built once, at scene load: the mode
shapes (modelled or measured), the actuator matrix (shapes at the transducers, or the
plate's wiring) and the channel limits.

Per block, vectorised over all samples: compiled passes, and for two modes with a
closed-form method ("exact", "regularised") steps 2-4 in one (``device.actuation.modal.
serve_two_modes``); otherwise one batched ``device.actuation.modal.solve``:

1. Finger positions on the display -> structure coordinates (beam: x along its length
   from its end; plate: x, y from its corner). Positions off the structure (a predicted
   position overshooting the display) are held at its edge and counted (``off_structure``).
   The mode shapes are evaluated there for the finger samples touching only.
2. The fingers touching are numbered in order of touch-down (``device.actuation.base.
   touch_rank``); the p longest-touching are served (p = number of modes). Their rows
   of Phi_f, in that order, fill a p x p system whose remaining rows are zero. A zero row
   adds a zero singular value, which every method of ``device.actuation.modal`` ignores (gain 0),
   so the padded system has exactly the solution of the m x p one (m <= p): one batched
   solve covers every count of fingers, including none (all commands 0). The finger
   samples touching beyond the p served are counted (``unserved``): nothing controls
   what they feel.
3. Commands ``c = A W_M`` are complex: channel amplitude |c| (um zero-to-peak) and
   phase arg(c) (rad; 0 for a zero command). Channels meeting their limit are scaled as ``device.actuation.modal``
   documents and counted (``limited``).
4. Achieved amplitude under every finger touching, served or not, is |Phi(x) W_M| (the
   forward model, seed 001 eq 5); 0 for fingers not touching.

Wanted amplitudes are taken with phase 0 under every finger, as in seed 000's worked
example (eqs 12-14). Friction depends only on |W|, so another sign under one finger
can need smaller commands (two-finger-beam-seed000, fingers at 113 and 260 mm wanting
0.369 um: commands of 3.5 and 4.5 um in phase, which the 0.75 um limits scale to 0.062
um under each finger; 0.21 and 0.97 um in antiphase, 0.285 um), but switching the sign
as the fingers move would swing that finger's amplitude through 0 over the plate's
settling time, a click at every switch.
"""

from __future__ import annotations

import math
import string
from collections.abc import Callable

import numpy as np

from frictex.device.actuation.base import Actuated, touch_rank
from frictex.device.jit import njit
from frictex.device.safe_text import escape
from frictex.device.profile import BeamStructure
from frictex.device.structures.beam import FreeFreeBeam, ModesError
from frictex.device.actuation.modal import (NEAR_SINGULAR, NODE_FLOOR, achieved_magnitude, check_settings, gain_threshold,
                                    magnitude, serve_two_modes, solve)
from frictex.device.structures.plate2d import ACTUATOR_NAMES, ACTUATORS, Plate2D

#: largest condition number accepted for the actuator matrix (an actuator on a node of a
#: driven mode cannot excite it: seed 000 section V)
MAX_ACTUATOR_CONDITION = 1e6


class ModalActuation:
    """Modal control of p modes through q channels (see the module docstring).

    Parameters
    ----------
    shapes : callable (x, y) -> float64 (..., p)
        Mode shapes at structure coordinates ``x``, ``y`` (mm, same shape), already
        within the structure.
    bounds : ((x_min, x_max), (y_min, y_max))
        The structure's extent in its own coordinates (mm); positions are clipped to it.
    offset_mm : (x0, y0)
        Display position of the structure's origin: structure = display - offset.
    actuators : (q, p) array
        Modal amplitudes -> channel commands (seed 000 eq 9).
    channels : q channel names.
    limits_um : (q,) largest |command| of each channel (um zero-to-peak).
    method, rcond : passed to ``device.actuation.modal.solve``.
    """

    has_phases = True

    def __init__(self, shapes: Callable, bounds, offset_mm, actuators, channels, limits_um,
                 method: str, rcond: float):
        self.shapes = shapes
        self.bounds = tuple(tuple(float(v) for v in b) for b in bounds)
        self.offset_mm = tuple(float(v) for v in offset_mm)
        self.channels = tuple(channels)
        self.method = method
        self.rcond = float(rcond)
        self.n_modes = np.shape(actuators)[1]
        self.actuators, self.limits_um = check_settings(
            method, np.asarray(actuators, dtype=np.float64),
            np.ascontiguousarray(np.broadcast_to(np.asarray(limits_um, dtype=np.float64), (len(self.channels),))),
            self.rcond, self.n_modes)
        self.threshold = gain_threshold(method, self.rcond)
        # two modes and a closed-form method: one compiled pass per block (serve_two_modes)
        self.closed_form = self.n_modes == 2 and method != "bounded"
        cond = np.linalg.cond(self.actuators)
        if self.actuators.shape[0] != len(self.channels) or not cond < MAX_ACTUATOR_CONDITION:
            raise ModesError(f"actuator matrix of shape {self.actuators.shape} (channels "
                             f"{escape(', '.join(self.channels))}) has condition number {cond:.3g}; expected "
                             f"one channel per row and below {MAX_ACTUATOR_CONDITION:g} (is an "
                             f"actuator on a node of a driven mode?)")

    def structure_position(self, x_mm, y_mm) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Display positions (mm, broadcast together) -> structure coordinates clipped to
        it (mm), and where clipped."""
        shape = np.broadcast_shapes(np.shape(x_mm), np.shape(y_mm))
        # writable C arrays, as the pipeline's: the kernel compiled at setup serves both
        x, y = (np.array(np.broadcast_to(v, shape), dtype=np.float64).reshape(1, -1) for v in (x_mm, y_mm))
        xs, ys, clipped, _ = self._on_structure(x, y, np.ones(x.shape, dtype=np.bool_))
        return xs.reshape(shape), ys.reshape(shape), clipped.reshape(shape)

    def _on_structure(self, x_mm, y_mm, contact):
        """:func:`_touching_positions` with this structure's offset and extent."""
        (x_lo, x_hi), (y_lo, y_hi) = self.bounds
        return _touching_positions(x_mm, y_mm, contact, self.offset_mm[0], self.offset_mm[1],
                                   x_lo, x_hi, y_lo, y_hi)

    def command(self, wanted_um: np.ndarray, fingers) -> Actuated:
        """Channel commands for a block; see the module docstring.

        Parameters
        ----------
        wanted_um : float64 (F, n)
            Amplitude each finger's friction target asks for (um zero-to-peak).
        fingers : rendering.tracking.tracks.FingerBlock
            Uses contact, x_pred, y_pred and touch_start, all (F, n).

        Returns
        -------
        Actuated
            commands_um, phases_rad (n, q); achieved_um (F, n); ``limited`` samples
            whose commands met a channel limit; ``capped`` samples whose served
            fingers could not be given independent amplitudes; ``off_structure`` finger
            samples held at the structure's edge; ``unserved`` finger samples touching
            but not among the p served.
        """
        contact = np.ascontiguousarray(fingers.contact, dtype=np.bool_)
        x, y, clipped, where = self._on_structure(np.ascontiguousarray(fingers.x_pred, dtype=np.float64),
                                                  np.ascontiguousarray(fingers.y_pred, dtype=np.float64),
                                                  contact)
        _check_block(wanted_um, x, y, where)
        phi = np.ascontiguousarray(self.shapes(x, y), dtype=np.float64)  # (k, p) where touching
        served = _served_fingers(touch_rank(contact, fingers.touch_start), self.n_modes)
        wanted = np.ascontiguousarray(wanted_um, dtype=np.float64)
        solved = (serve_two_modes(phi, where, served, wanted, self.actuators, self.limits_um,
                                  self.threshold, self.method == "regularised")
                  if self.closed_form else None)
        amplitude, commands, achieved, limited, capped = solved or self._solve(phi, where, served, wanted)
        return Actuated(commands_um=amplitude, phases_rad=np.angle(commands), achieved_um=achieved,
                        limited=limited, capped=capped, off_structure=int(np.count_nonzero(clipped)),
                        unserved=x.size - int(np.count_nonzero(served >= 0)))

    def _solve(self, phi, where, served, wanted):
        """Steps 2-4 of the module docstring through ``device.actuation.modal.solve``: any
        number of modes and every method. Returns what ``serve_two_modes`` does."""
        phi_f, wanted_f = _serve_rows(phi, where, served, wanted)
        sol = solve(phi_f, wanted_f, self.method, actuators=self.actuators, limits_um=self.limits_um,
                    rcond=self.rcond)
        # the solver scales to the limits; this only removes its last-bit rounding above them
        amplitude = np.minimum(magnitude(sol.commands_um), self.limits_um)
        # + 0.0 turns -0.0 into 0.0: a zero command has phase 0, whatever the sign of
        # the zeros the solve happened to produce
        return (amplitude, sol.commands_um + 0.0, achieved_magnitude(phi, where, sol.modal_um),
                int(np.count_nonzero(sol.limited)), self._capped(phi_f, served))

    def _capped(self, phi_f, served) -> int:
        """Samples serving m >= 2 fingers whose m x p system has rank below m: its m-th
        singular value under the method's threshold or ``NEAR_SINGULAR`` of the largest
        (``device.actuation.modal.solve``'s ``capped``, less the zero singular values the
        padding rows add), or on nodes of every mode (``NODE_FLOOR``: the plate at rest). There the fingers
        cannot be given independent amplitudes (seed 001, eq 8)."""
        fingers = np.count_nonzero(served >= 0, axis=1)
        several = fingers >= 2
        if not np.any(several):
            return 0
        s = np.linalg.svd(phi_f[several], compute_uv=False)  # descending, (k, p)
        s_m = np.take_along_axis(s, (fingers[several] - 1)[:, None], axis=1)[:, 0]
        floor = self.threshold * s[:, 0]
        full = (((s_m >= floor) if self.method == "regularised" else (s_m > floor)) & (s_m > 0)
                & (s_m >= NEAR_SINGULAR * s[:, 0])
                & (np.abs(phi_f[several]).max(axis=(-2, -1)) >= NODE_FLOOR))  # on nodes: rest
        return int(np.count_nonzero(~full))


def _check_block(wanted_um, x_mm, y_mm, where) -> None:
    """Refuse a negative wanted amplitude (um zero-to-peak, phase 0: a sign has no
    meaning) and a touching finger's position that is not finite, naming the finger
    (row) and sample (column) of the block."""
    negative = np.argwhere(np.asarray(wanted_um) < 0)
    if len(negative):
        f, i = negative[0].tolist()
        raise ModesError(f"wanted amplitude {float(wanted_um[f, i]):g} um of finger {f} at sample "
                         f"{i} is negative; amplitudes are zero-to-peak, 0 or more")
    bad = np.flatnonzero(~(np.isfinite(x_mm) & np.isfinite(y_mm)))
    if len(bad):
        f, i = np.argwhere(where == bad[0])[0].tolist()
        raise ModesError(f"finger {f} at sample {i} is touching at a position that is not "
                         f"finite (x, y = {x_mm[bad[0]]:g}, {y_mm[bad[0]]:g} mm on the structure)")


# compiled kernels cached here call no compiled function of another module: numba's cache
# checks only this file, so one inlining another module's helpers (modal.py's _abs,
# _combination) would keep running the old code after that module changed; those live
# in modal.py (achieved_magnitude, serve_two_modes)
@njit(cache=True, nogil=True)
def _touching_positions(x_mm, y_mm, contact, x0, y0, x_lo, x_hi, y_lo, y_hi):
    """Step 1 of the module docstring for the finger samples touching.

    x_mm, y_mm : float64 (F, n) display positions (mm); contact : bool (F, n).
    Returns x, y (k,) structure coordinates (mm) of the k samples touching (finger by
    finger), clipped to [x_lo, x_hi] x [y_lo, y_hi] as np.clip clips; clipped (k,) bool,
    where that moved them; where (F, n) int64, each sample's index in those, -1 where
    not touching.
    """
    f_count, n = contact.shape
    k = 0
    for f in range(f_count):
        for i in range(n):
            k += contact[f, i]
    x, y = np.empty(k), np.empty(k)
    clipped = np.empty(k, dtype=np.bool_)
    where = np.full((f_count, n), -1, dtype=np.int64)
    k = 0
    for f in range(f_count):
        for i in range(n):
            if contact[f, i]:
                xf, yf = x_mm[f, i] - x0, y_mm[f, i] - y0
                x[k], y[k] = _clip(xf, x_lo, x_hi), _clip(yf, y_lo, y_hi)
                clipped[k] = x[k] != xf or y[k] != yf
                where[f, i] = k
                k += 1
    return x, y, clipped, where


@njit(cache=True, nogil=True, inline="always")
def _clip(v, lo, hi):
    """np.clip of one float: lo below it, hi above it, else v itself (its signed zero, NaN)."""
    v = lo if v < lo else v
    return hi if v > hi else v


@njit(cache=True, nogil=True)
def _served_fingers(rank, p):
    """(n, p) int64: the finger (row of ``rank``) that fills row r of each sample's padded
    system, the one with rank r (step 2 of the module docstring); -1 for a zero row."""
    f_count, n = rank.shape
    served = np.full((n, p), -1, dtype=np.int64)
    for f in range(f_count):
        for i in range(n):
            row = rank[f, i]
            if 0 <= row < p:
                served[i, row] = f
    return served


@njit(cache=True, nogil=True)
def _serve_rows(phi, where, served, wanted_um):
    """The padded p x p systems (n, p, p) and wanted amplitudes (n, p): row r of sample i
    holds the shapes (``phi[where[f, i]]``) and wanted amplitude of finger f = served[i, r],
    zeros where served[i, r] is -1."""
    n, p = served.shape
    phi_f = np.zeros((n, p, p))
    wanted = np.zeros((n, p))
    for i in range(n):
        for row in range(p):
            f = served[i, row]
            if f >= 0:
                phi_f[i, row, :] = phi[where[f, i], :]
                wanted[i, row] = wanted_um[f, i]
    return phi_f, wanted


def beam_actuation(spec, amplitude_limit_um: float) -> ModalActuation:
    """The actuation for ``profile = "beam-seed000"`` (``device.profile.BeamStructure``).

    Shapes from the measured table if the spec has one, else from the free-free beam
    model; the actuator matrix is the shapes at the transducers (seed 000, eq 9).
    """
    if spec.modes is not None:
        table = spec.modes
        span = (float(table.positions_mm[0]), float(table.positions_mm[-1]))

        def shapes(x, y):
            return table.phi(x)
    else:
        beam = FreeFreeBeam(spec.length_mm, spec.width_mm, spec.thickness_mm, spec.youngs_gpa,
                            spec.density_kg_m3, theory=spec.theory, poisson=spec.poisson)
        for order in spec.orders:
            beam.frequency_hz(order)  # solves each mode once, here; refuses bad orders
        span = (0.0, beam.length_mm)

        def shapes(x, y):
            return beam.phi(spec.orders, x)
    positions = np.asarray(spec.actuators_mm, dtype=np.float64)
    actuators = shapes(positions, np.zeros_like(positions))
    names = tuple(f"x{letter}" for letter in string.ascii_uppercase[:len(positions)])
    return ModalActuation(shapes, (span, (-math.inf, math.inf)), (spec.x0_mm, 0.0), actuators,
                          names, spec.channel_limit_um, spec.method, spec.rcond)


def plate_actuation(spec, amplitude_limit_um: float) -> ModalActuation:
    """The actuation for ``profile = "plate-seed001"`` (``device.profile.PlateStructure``):
    shapes of seed 001 eq 6, channels V_AC and V_BD (section 4.1)."""
    plate = Plate2D(spec.width_mm, spec.height_mm, spec.thickness_mm, spec.youngs_gpa,
                    spec.density_kg_m3, poisson=spec.poisson, order=spec.order)
    limit = spec.channel_limit_um if spec.channel_limit_um is not None else amplitude_limit_um
    return ModalActuation(plate.phi, ((0.0, plate.width_mm), (0.0, plate.height_mm)),
                          (spec.x0_mm, spec.y0_mm), ACTUATORS, ACTUATOR_NAMES, limit,
                          spec.method, spec.rcond)


def make_modal_actuation(device) -> ModalActuation:
    """The modal actuation of a device profile (``device.profile.DeviceProfile``), by
    its structure: a beam or a 2D plate."""
    build = beam_actuation if isinstance(device.structure, BeamStructure) else plate_actuation
    return build(device.structure, device.amplitude_limit_um)
