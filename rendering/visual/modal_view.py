"""The vibration of a modal device under the fingers, live: seed 000's beam, seed 001's plate.

A modal actuation (``device.actuation.modal_actuation``) sends channel commands c = A W_M, with A the
actuator matrix (q channels x p modes) and W_M the complex modal amplitudes (seed 000
eq 9). The window recovers W_M = A^+ c from the latest commands sent and draws the
superposed amplitude |W(x)| = |sum_k Phi_k(x) W_M,k| (seed 000 eq 3, seed 001 eq 5):
along the beam as a curve, over the plate as a low-resolution heat map, with each
finger's position and the amplitude there. The mode shapes Phi come from the
actuation's own ``shapes`` (modelled or measured), evaluated once per scene on a fixed
grid; an update is one small matrix product, cheap enough for several per second.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from frictex.device.profile import BeamStructure, PlateStructure
from frictex.textures.model import Scene

BEAM_SAMPLES = 512  # points along the display's width
PLATE_CELLS = 64  # heat-map cells along the plate's longer side


@dataclass(frozen=True, eq=False)
class Envelope:
    """|W| at one instant. kind : "beam" or "plate". x_mm : (nx,) display x of the
    samples; y_mm : (ny,) display y (plate) or None. amplitude_um : (nx,) or (ny, nx), um
    zero-to-peak, NaN off the structure. fingers : (finger id, x mm, y mm, |W| um) of each
    finger touching."""

    kind: str
    x_mm: np.ndarray
    y_mm: np.ndarray | None
    amplitude_um: np.ndarray
    fingers: tuple[tuple[int, float, float, float], ...]

    @property
    def peak_um(self) -> float:
        """The largest |W| shown (0 if all is still)."""
        values = [a for *_, a in self.fingers]
        if np.isfinite(self.amplitude_um).any():
            values.append(float(np.nanmax(self.amplitude_um)))
        return max(values, default=0.0)


class ModalEnvelope:
    """Mode shapes of ``actuation`` sampled once over ``scene``'s display; see the module doc.

    Parameters
    ----------
    scene : a scene whose device profile is modal (``BeamStructure`` or ``PlateStructure``).
    actuation : its ``device.actuation.modal_actuation.ModalActuation``.
    """

    def __init__(self, scene: Scene, actuation):
        d = scene.display
        self.actuation = actuation
        self.kind = "beam" if isinstance(scene.device.structure, BeamStructure) else "plate"
        if self.kind == "beam":
            self.x_mm = (np.arange(BEAM_SAMPLES) + 0.5) * d.width_mm / BEAM_SAMPLES
            self.y_mm = None
            x, y = self.x_mm, np.full(BEAM_SAMPLES, 0.5 * d.height_mm)
        else:
            step = max(d.width_mm, d.height_mm) / PLATE_CELLS
            nx, ny = max(1, round(d.width_mm / step)), max(1, round(d.height_mm / step))
            self.x_mm = (np.arange(nx) + 0.5) * d.width_mm / nx
            self.y_mm = (np.arange(ny) + 0.5) * d.height_mm / ny
            x, y = np.meshgrid(self.x_mm, self.y_mm)
        sx, sy, off = actuation.structure_position(x, y)
        self.phi = actuation.shapes(sx, sy)  # (..., p), once per scene
        self.off = off
        self.unmix = np.linalg.pinv(actuation.actuators)  # (p, q)

    def modal_um(self, commands: np.ndarray) -> np.ndarray:
        """Complex modal amplitudes W_M (p,) (um) from channel commands (q,) complex (um)."""
        return self.unmix @ np.asarray(commands, dtype=np.complex128)

    def at(self, commands: np.ndarray | None,
           fingers: list[tuple[int, float, float, bool]]) -> Envelope:
        """|W| over the grid and under each touching finger (``OverlayState.current()``),
        for ``commands`` (q,) complex um (None: nothing sent yet, all still)."""
        modal = np.zeros(self.unmix.shape[0], complex) if commands is None else self.modal_um(commands)
        amplitude = np.abs(self.phi @ modal)
        amplitude[self.off] = np.nan
        marks = []
        if fingers:
            ids, xs, ys, _ = zip(*fingers)
            sx, sy, _ = self.actuation.structure_position(np.array(xs), np.array(ys))
            under = np.abs(self.actuation.shapes(sx, sy) @ modal)
            marks = [(fid, x, y, float(a)) for fid, x, y, a in zip(ids, xs, ys, under)]
        return Envelope(self.kind, self.x_mm, self.y_mm, amplitude, tuple(marks))


def modal_envelope(scene: Scene, actuation) -> ModalEnvelope | None:
    """The envelope view for ``scene`` driven by ``actuation``, or None if its device is
    not modal (a single-mode plate vibrates the same everywhere; travelling waves are drawn
    as forces)."""
    if not isinstance(scene.device.structure, (BeamStructure, PlateStructure)):
        return None
    return ModalEnvelope(scene, actuation)


#: the heat map's colours (linear RGB) at 0, 1/3, 2/3 and 1 of the scale: black, purple,
#: orange, pale yellow (dark = still, bright = vibrating)
HEAT_STOPS = np.array([[0.0, 0.0, 0.0], [0.25, 0.02, 0.35], [0.9, 0.3, 0.04], [1.0, 0.95, 0.55]])


def heat_rgb(u: np.ndarray) -> np.ndarray:
    """Linear RGB (..., 3) of the heat map at ``u`` in [0, 1] (NaN: dark grey)."""
    u = np.asarray(u, dtype=np.float64)
    grid = np.linspace(0.0, 1.0, len(HEAT_STOPS))
    c = np.clip(np.nan_to_num(u, nan=0.0), 0.0, 1.0)
    rgb = np.stack([np.interp(c, grid, HEAT_STOPS[:, k]) for k in range(3)], axis=-1)
    rgb[np.isnan(u)] = 0.05
    return rgb
