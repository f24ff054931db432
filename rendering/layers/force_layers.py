"""Force layers: from the scene's friction and force targets to one travelling wave per sample.

For the travelling-wave profiles (``device.profile.FORCE_PROFILES``) this stage replaces
the friction inversion and the amplitude-only actuation. Per finger and output sample:

1. Direction of motion m (+1/-1 along x, held below ``v_hold_mm_s``,
   ``rendering.layers.tangential.finger_motion``); the finger is *moving* at or above that speed,
   *still* below it.
2. Wanted net tangential force F_t (N, positive resisting the finger, seed 002's sign):
   mu0 F_n mu', mu' the composed friction layers; ``directional`` layers with mu' targets
   multiply it by their value for the finger's direction (like ``blend = "multiply"``),
   those with force targets replace F_t by theirs (later layers on top).
3. Wanted active push P (N along +x on the finger): the sum of ``guidance`` pulls and
   ``keyclick`` pushes (``rendering.layers.keyclick``) covering the finger. A push helps a finger
   moving its way: F_t <- F_t - m P.
4. Amplitude and direction. A moving finger: ``invert_tangential`` on F_t (seed 002
   eqs 7-8 with seed 004's driving force; direction hysteresis carried between blocks).
   A still finger feels no sliding friction, only the drive (seed 004, Fig. 3: force on
   a fixed finger): |P| = k_p F_n (tau w - w_th), the wave travelling against P (the drive
   pushes against the wave's travel), w = 0 for P = 0. Both work on the local envelope w
   under the finger; the wave amplitude is W = w / g(x) (``device.actuation.push_actuation``).
   w is planned within what the channels give there (``PushActuation.envelope_limit_at``:
   on seed 002's beam the actuators' references peak at 1.164 W, so at most 2.58 um
   where g = 1, not the amplifier's 3 um), and within ``amplitude_limit_um``.
   Out of reach (beyond that limit, tau = 0 near a beam end, F_n = 0): clamped
   to the nearest reachable force and counted as ``unreachable``, never silently. A
   moving finger given an amplitude at a normal force beyond seed 003's friction model
   (F_n >= 0.885 N: ``device.friction.asymptote``) is counted as ``force_beyond_model``
   instead, as the friction inversion counts it.
5. One wave serves every finger: the finger touching longest decides W and d
   (``device.actuation.base.primary_finger``); the force every finger gets is computed from
   that wave by the same model (the forward model), which is what summary.json compares
   with what each finger wanted.

The wanted force vector includes the guidance pull across x (the waves push only along
x, so it is never achieved; it is exposed for the visual layer's arrows).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from frictex.device.actuation.base import Actuated, primary_finger
from frictex.device.actuation.travelling import driving_force
from frictex.device.friction import ClampCounts
from frictex.rendering.layers.keyclick import button_states
from frictex.rendering.layers.tangential import TangentialState, finger_motion, invert_tangential, tangential_force
from frictex.textures.model import FORCE_LAYERS, Directional, Guidance, KeyClick, Scene


@dataclass(frozen=True, eq=False)
class ForceBlock:
    """The force stage's output for a block; per-finger arrays are (F, n).

    wanted_n, achieved_n : (F, n, 2) force on each finger (N, x and y of the display).
    unreachable : bool, wanted forces out of the wave's reach there (clamped, counted);
        not where the normal force is beyond the friction model (counted as
        ``force_beyond_model`` instead, as the friction inversion counts them).
    button : int8 key-click state (0 idle, 1 on, 2 clicked; the highest over the
        buttons), or None if the scene has no key-click.
    clicks : int (F, n), phase flips (a key-click's idle/on -> clicked) at each sample.
    wave_um : (n,) wave amplitude W (um zero-to-peak); direction : (n,) int8 d.
    ratio : (F, n) local travelling-wave ratio under each finger.
    """

    wanted_n: np.ndarray
    achieved_n: np.ndarray
    unreachable: np.ndarray
    button: np.ndarray | None
    clicks: np.ndarray
    wave_um: np.ndarray
    direction: np.ndarray
    ratio: np.ndarray


@dataclass(frozen=True)
class ForceState:
    """Per finger id: the tangential inversion's held directions and each button's state."""

    tangential: dict = field(default_factory=dict)  # finger id -> TangentialState
    buttons: dict = field(default_factory=dict)     # (layer index, finger id) -> ButtonState


class ForceStage:
    """The stage for one scene on a travelling-wave profile (see the module docstring)."""

    def __init__(self, scene: Scene, rate_hz: float, actuation):
        self.layers = tuple(layer for layer in scene.layers if isinstance(layer, FORCE_LAYERS))
        self.device = scene.device
        self.params = scene.device.driving
        self.actuation = actuation
        self.rate_hz = float(rate_hz)
        self.has_buttons = any(isinstance(layer, KeyClick) for layer in self.layers)

    def initial_state(self) -> ForceState:
        return ForceState()

    def render(self, fingers, mu_target: np.ndarray, state: ForceState
               ) -> tuple[ForceBlock, Actuated, np.ndarray, ClampCounts, ForceState]:
        """Targets, inversion and wave for one block.

        Parameters
        ----------
        fingers : the block's tracks (``rendering.tracking.tracks.FingerBlock``), F fingers, n samples.
        mu_target : (F, n) composed mu' of the friction layers.
        state : from the previous block.

        Returns
        -------
        (ForceBlock, Actuated, wanted_um (F, n) local envelope each finger asks for,
        ClampCounts, ForceState)
        """
        contact = fingers.contact
        count, n = contact.shape
        clamps = ClampCounts()
        fn = np.asarray(fingers.force, dtype=np.float64)
        bad = contact & ~(np.isfinite(fn) & (fn >= 0))
        clamps.bad_force = int(bad.sum())
        fn = np.where(bad, self.device.normal_force_n, np.where(contact, fn, 0.0))
        x = fingers.x_pred
        tau = np.where(contact, self.actuation.ratio_at(x), 0.0)
        gain = np.where(contact, self.actuation.gain_at(x), 1.0)
        limit = np.minimum(self.device.amplitude_limit_um, self.actuation.envelope_limit_at(x))

        present = set(fingers.ids)  # a finger that lifted and left the tracks is forgotten
        tangential = {fid: s for fid, s in state.tangential.items() if fid in present}
        buttons = {key: s for key, s in state.buttons.items() if key[1] in present}
        wanted_um = np.zeros((count, n))
        direction = np.ones((count, n), dtype=np.int8)
        moving = np.zeros((count, n), dtype=bool)
        motion = np.ones((count, n), dtype=np.int8)
        push_x, push_y = np.zeros((count, n)), np.zeros((count, n))
        target_t = np.zeros((count, n))
        unreachable = np.zeros((count, n), dtype=bool)
        button = np.zeros((count, n), dtype=np.int8) if self.has_buttons else None
        clicks = np.zeros((count, n), dtype=np.int64)
        for row, fid in enumerate(fingers.ids):
            t_state = tangential.get(fid, TangentialState())
            moving[row], motion[row] = finger_motion(fingers.vx[row], self.params.v_hold_mm_s,
                                                     t_state.motion)
            target_t[row], push_x[row], push_y[row] = self._targets(
                row, fid, fingers, fn[row], mu_target[row], motion[row], buttons, button, clicks)
            wanted_um[row], direction[row], unreachable_row, nonfinite, beyond, tangential[fid] = \
                self._invert(target_t[row] - motion[row] * push_x[row], push_x[row], moving[row],
                             fingers.vx[row], fn[row], tau[row], limit[row], t_state)
            clamps.nonfinite_target += int((nonfinite & contact[row]).sum())
            clamps.force_beyond_model += int((beyond & contact[row]).sum())
            moving[row] &= contact[row]
            wanted_um[row] = np.where(contact[row], wanted_um[row], 0.0)
            unreachable[row] = unreachable_row & ~beyond & contact[row]

        primary = primary_finger(contact, fingers.touch_start)
        served = primary >= 0
        cols = np.flatnonzero(served)
        wave = np.zeros(n)
        wave_dir = np.ones(n, dtype=np.int8)
        wave[served] = wanted_um[primary[served], cols] / gain[primary[served], cols]
        wave_dir[served] = direction[primary[served], cols]
        wave, limited = self.actuation.within_limit(wave, wave_dir)
        act = self.actuation.drive(wave, wave_dir, fingers, limited)

        local = wave * gain
        sliding = tangential_force(local, wave_dir, motion, fn, tau, self.device.friction, self.params)
        drive = driving_force(tau * local, fn, self.params)
        achieved_x = np.where(moving, -motion * sliding, -wave_dir * drive)
        achieved_x = np.where(contact, achieved_x, 0.0)
        clamps.unreachable = int(unreachable.sum())
        wanted_x = np.where(moving, -motion * (target_t - motion * push_x), push_x)
        block = ForceBlock(
            wanted_n=np.stack([np.where(contact, wanted_x, 0.0), np.where(contact, push_y, 0.0)], axis=-1),
            achieved_n=np.stack([achieved_x, np.zeros_like(achieved_x)], axis=-1),
            unreachable=unreachable,
            button=button, clicks=clicks, wave_um=wave, direction=wave_dir, ratio=tau)
        return block, act, wanted_um, clamps, ForceState(tangential, buttons)

    def _targets(self, row, fid, fingers, fn, mu, motion, buttons, button, clicks):
        """(F_t target, push x, push y) for one finger over the block, N."""
        x, y = fingers.x_pred[row], fingers.y_pred[row]
        touching = fingers.contact[row]
        relative = np.array(mu, dtype=np.float64)
        override = np.full(relative.shape, np.nan)
        push_x, push_y = np.zeros_like(relative), np.zeros_like(relative)
        for index, layer in enumerate(self.layers):
            covers = layer.covers(x, y) & touching
            if isinstance(layer, Directional):
                value = layer.value(motion)
                if layer.target == "mu":
                    relative = np.where(covers, relative * value, relative)
                else:
                    override = np.where(covers, value, override)
            elif isinstance(layer, Guidance):
                px, py = layer.pull(x, y)
                push_x += np.where(covers, px, 0.0)
                push_y += np.where(covers, py, 0.0)
            else:
                key = (index, fid)
                states, flips, buttons[key] = button_states(
                    fn, covers, layer.press_n, layer.click_n, layer.release_n,
                    max(1, int(round(layer.dwell_s * self.rate_hz))), buttons.get(key))
                clicks[row] += flips
                sign = np.where(states == 2, -1.0, np.where(states == 1, 1.0, 0.0))
                push_x += sign * layer.first_push * layer.force_n
                button[row] = np.maximum(button[row], states)
        f_t = np.where(np.isnan(override), self.params.mu0 * fn * relative, override)
        return f_t, push_x, push_y

    def _invert(self, target_t, push, moving, vx, fn, tau, limit, t_state):
        """(w, d, unreachable, nonfinite, beyond model, new state) for one finger: moving
        samples by ``invert_tangential``, still samples by inverting the drive alone (no
        friction model there), each w within ``limit`` (n,) um."""
        cmd, new_state = invert_tangential(target_t, vx, fn, tau, limit, self.device.friction,
                                           self.params, t_state)
        k = self.params.slope_per_um * fn
        with np.errstate(divide="ignore", invalid="ignore"):
            w_push = (np.abs(push) / k + self.params.threshold_um) / tau
        w_push = np.where(push == 0.0, 0.0, w_push)
        over = ~(w_push <= limit)  # also NaN/inf: tau = 0 or F_n = 0 with a push asked
        # with no travelling wave (tau = 0) or no normal force no drive can push: rest
        w_still = np.where(over, np.where((fn > 0.0) & (tau > 0.0), limit, 0.0), w_push)
        d_still = np.where(push > 0, -1, np.where(push < 0, 1, cmd.direction))
        w = np.where(moving, cmd.amplitude_um, w_still)
        d = np.where(moving, cmd.direction, d_still).astype(np.int8)
        unreachable = np.where(moving, cmd.unreachable, over)
        new_state = TangentialState(new_state.motion, int(d[-1])) if d.size else new_state
        return w, d, unreachable, cmd.nonfinite & moving, cmd.beyond_model & moving, new_state
