"""Composition of layers into one mu' target per finger (seed 003, section 4.4.3).

The seed composes SHO and SHT by linear superposition of the two signals. frictex
composes relative friction *multiplicatively*: mu' = prod_i mu'_i over the layers
covering the finger. For small reductions this is the seed's linear superposition to
first order ((1 - a)(1 - b) = 1 - a - b + ab), and unlike a sum it can never leave
(0, 1]: two layers at 0.6 give 0.36 instead of the meaningless 0.2, and a fine texture
inside a coarse object keeps its relative depth. A layer with ``blend = "replace"`` is
opaque instead: where it covers, its mu' replaces what the layers below gave (the
painter's rule the visual layer uses for the same file).

Fingers not touching get mu' = 1: no vibration is asked on their behalf.
"""

from __future__ import annotations

import numpy as np


def compose(layer_outputs, blends, contact: np.ndarray, finger_masks=None) -> np.ndarray:
    """Compose per-layer (mu, covers) arrays of shape (F, n) into mu' (F, n).

    Parameters
    ----------
    layer_outputs : sequence of (mu, covers) pairs, in drawing order.
    blends : sequence of "multiply" | "replace", one per layer.
    contact : (F, n) bool, fingers touching.
    finger_masks : optional sequence, one per layer, of (F, n) bool: which fingers the
        layer applies to at each sample (None = all); see ``rendering.tracking.finger_select``.
    """
    mu = np.ones(contact.shape)
    for k, ((layer_mu, covers), blend) in enumerate(zip(layer_outputs, blends)):
        if finger_masks is not None and finger_masks[k] is not None:
            covers = covers & finger_masks[k]
        # numpy's masked loops take 2.5x as long as plain ones, even with every sample in
        where = True if covers.all() else covers
        if where is covers and not covers.any():
            continue
        if blend == "replace":
            np.copyto(mu, layer_mu, where=where)
        else:
            np.multiply(mu, layer_mu, out=mu, where=where)
    if not contact.all():
        np.copyto(mu, 1.0, where=~contact)
    return mu


def ideal_mu(scene, x, y) -> np.ndarray:
    """The scene's mu' map evaluated at positions (x, y) mm: what a perfect renderer
    would give a finger there (used as the reference mu'* in accuracy checks)."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    outputs = [(layer.mu_at(x, y), layer.covers(x, y)) for layer in scene.layers]
    shape = np.broadcast(x, y).shape
    flat = [(np.broadcast_to(m, shape).reshape(1, -1), np.broadcast_to(c, shape).reshape(1, -1))
            for m, c in outputs]
    mu = compose(flat, [layer.blend for layer in scene.layers], np.ones((1, int(np.prod(shape))), bool))
    return mu.reshape(shape)
