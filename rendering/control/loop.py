"""Closed-loop friction on seed 003's plate: feed-forward, feedback, adaptation, fallback.

Per block, for the one finger touching (the plate's sensors measure the total force, so
with several fingers down the loop holds its state and the block is fed forward only):

0. **Pair.** A device's force reports come back late: a real plate's link plays a block
   about 10 ms after it is sent and reports its forces in windows of a few ms, so a
   block's report reaches the host several blocks later. Every block sent is kept
   (``ControlState.pending``) until the reports cover all of its samples
   (``forces(index0, n)``: ``device.link.host.CommandSink.force_report`` on a link,
   ``device.link.forces.ForceHistory.window`` in simulation); blocks are folded in order,
   oldest first, each with its own report, and one whose report has not come
   ``max_wait_s`` after its end is folded as missed (stale, 4). The delay D, in whole
   blocks between a block's end and the block being computed when its report is folded,
   is measured; the integrator's gain ``ki`` is ``rendering.control.margins``'
   ``scheduled_ki`` at the largest D seen lately (``delay_blocks``), so that its stated
   gain margin holds at the delay the loop actually has. "Lately": a D below the one
   scheduled lowers it by one block once ``delay_hold_s`` has passed without a report that
   late, so one burst of late reports (a busy host, a collection of the garbage
   collector) does not slow the loop for the rest of the session, while a link that is
   late every few seconds keeps its gain scheduled on that delay.
1. **Measure.** The device's force report for a block sent gives the ratio
   F_t / F_n, of the friction's magnitude |F_t|: the report's F_t is signed by the
   direction the finger slides along x (PROTOCOL.md 4.9), and friction opposes sliding
   whichever way. Not F_t times the sign of the tracker's x velocity: the tracker lags a
   reversal by tens of ms (a 50 Hz touch trace), so that product would read every
   reversal as negative friction, and a sensor wired backwards reads the same magnitude.
   The friction at rest mu0 is its level where the plate has been still long enough for
   the sensor to see it (``Chain`` of the commanded amplitude below
   ``still_um``) while the finger slides (median over the block of the samples at a
   speed of at least ``slide_mm_s`` reading a ratio of at least ``min_rest_mu``: the
   tracker sees a stop late, and a stuck finger reads no friction); the measured
   relative friction is mu'_m = F_t / (F_n mu0) (seed 003, eq 1).
   Until mu0 has been measured the loop has nothing to compare with, and a plate moving
   under a finger hides mu0. So from touch-down until then (once per session: mu0 is
   kept), the plate stays still while the tracker sees the finger slower than
   ``probe_mm_s`` -- as a stroke starts -- and the first estimate is the ratio's median
   over the second half of a block whose two halves agree within ``settled`` (the
   fingertip has finished rising into sliding), among still samples at ``creep_mm_s``
   or faster reading at least ``min_rest_mu``. Without it, a finger whose stroke starts
   on a reduced band is open loop until it first crosses an unreduced one (tried:
   holding from the start only where the hold is not felt, as after the release below,
   found mu0 at 0.32 s instead of 0.095 s, median over the report's population in 10 s
   runs, and left grating-15mm at 2.99x instead of 5.16x). The tracker
   (a 50 Hz touch trace) lags a stroke's start by tens of ms: it read 1.5 mm/s while
   the finger slid at 10-16 mm/s (finger 9 of the report's population on grating-15mm),
   or jumps past ``probe_mm_s`` a block after the force report first shows sliding.
   So ``creep_mm_s`` only asks that the tracker has seen the finger move, and once a
   report shows the finger sliding on the still plate (at least ``min_still`` / 2 still
   samples of its second half reading ``min_rest_mu`` or more) the plate stays still
   until ``probe_s`` after the end of the first block whose report showed it
   (``probe_from``: its output index; the time counts on the output clock, so a report
   that comes late does not hold the plate longer) whatever the tracker's speed, so
   that the ratio can settle. The tracker's speed is noisy as a stroke starts (50 Hz
   touch samples with 0.05 mm of noise read as several mm/s, up and down): once it has
   read the finger at ``probe_mm_s`` or faster the probe is released, and a slower
   reading after that holds the plate again only where the reduction the hold withholds
   is at most ``rehold_reduction`` (0.11: the Weber fraction for a change of friction,
   Gueorguiev et al., J. R. Soc. Interface 14 (2017) 20170641, so a hold the finger does
   not feel). A hold taken up again on a reduced band costs more than the open loop it
   saves: on the report's population (10 s runs, reports 3 blocks late) such holds were
   46 % of the closed loop's squared error on grating-15mm (closed 4.26x -> 4.75x without them,
   grating-5mm 4.20x -> 4.64x, the object scene 3.48x either way).
   The hold is worth its cost only if the held blocks' reports come back. Until a usable
   report has come in the session, a report missed (not back ``max_wait_s`` after its
   block's end: late or lost) ends the hold, and the plate is fed forward open loop (c = 1)
   until a usable report comes, which lets the probe start again: not the stale
   fallback's further ``stale_s`` (4), since the link has not shown that its reports come,
   and a hold withholds the whole reduction asked where open loop misses only by the
   model's error. Once a report has come, a missed one is the stale rule's (4). A session
   that starts with the finger down still holds for up to ``max_wait_s`` and a block: the
   first block's report may yet come in time. (Reports 30 blocks late, grating-15mm, a
   finger with b 1.17 /um against the model's 1.67: over a human motion's first second 212 -> 112
   samples asking a reduction held, RMS against the reachable 0.097 -> 0.075, open loop
   0.037; none fewer where the tracker had read the finger fast within the wait.)
   A finger that touches down already sliding (a stroke that starts in the air) reads the
   same rise: its lateral force climbs from 0 through the fingertip's compliance (3.84 ms
   rise time, ``device.finger``) while its normal force is there at once, which reads as
   friction reduced far more than asked. So a finger's samples less than ``probe_s`` (the
   time the probe gives the ratio to settle once the finger slides) after its touch-down
   (the tracker's contact, per finger) count as not sliding yet for the gain and the
   model, and a block holding any does not move mu0 (what the host measured,
   ``report``, still counts them); not those of the touch-down the first estimate came
   from, whose rise that estimate waited out (``mu0_from``). Learnt from, the
   touch-down block's report (nominal finger at 100 mm/s on a 0.7 band, reports one
   block late) cut the closed gain by 8 % and made the adaptive model ask the amplitude
   limit, 2.5 um, for two blocks (mu' 0.57 against 0.70), then undershoot for 15 blocks.
2. **Feedback** on the depth of modulation: the reduction asked, 1 - mu'_target, passed
   through the same chain, against the reduction measured, 1 - mu'_m, gives the block's
   delivered/asked ratio g (the median over the samples asking for at least
   ``min_reduction`` at a tracker speed of at least ``creep_mm_s``, leaving out samples
   reading mu'_m < ``min_mu``: no finger of the model gets that low, a finger that stuck
   does). An integrator on the log of a gain c, ``log c <- log c - ki log g``, makes
   the feed-forward ask for
   ``1 - c (1 - mu'_target)``. A finger's reduction depends on how fast it slides
   (Huloux et al., above; ``device.finger``'s ``b / (1 + v / v_c)``), so the gain is
   scheduled on the tracker's speed v (mean over the block, mm/s):
   ``log c = log_c + log_c_slope v / speed_ref_mm_s``, and each step of the integrator
   is spread over the two as normalised LMS, ``(log_c, log_c_slope) += step (1, p) /
   (1 + p^2)`` with p = v / ``speed_ref_mm_s`` of the measured block: at that speed the
   gain moves by exactly ``step``, the scalar integrator's, so the margins below hold at
   any steady speed. On the report's population (10 s runs, reports 3 blocks late) a
   gain that does not follow the speed left grating-15mm at 4.75x (closed; 5.16x with it),
   grating-5mm 4.64x (5.03x); with fingers whose reduction does not depend on speed the
   same loop reached 6.51x on grating-15mm. In the log domain the loop gain is ``ki``
   for a finger G times more or less slippery than the model (g = G c), ``s ki`` for
   one whose reduction grows s times as fast with the reduction asked; the margins of
   ``rendering.control.margins`` (with the sensor chain's and the report's delays) say
   how large s may be. The first measurement starts the gain instead of stepping it:
   ``log c`` at the block's speed moves ``first_step`` of the way (through ``log_c``)
   to where it would have put g at 1 for a finger with s = 1 (``log c_sent - log g``,
   c_sent the gain the measured block was asked with), once per session; the blocks
   already on their way were asked with the old gain, so they are not fed back
   (``fed_from``). It waits for a block asking a root-mean-square reduction of at least
   ``first_reduction`` (over its samples asking ``min_reduction`` or more; until then the
   integrator steps as it does after it, so a scene that never asks that much gets only
   the integrator): the measured
   reduction is 1 - F_t / (F_n mu0), so an error d in the estimate of mu0 errs log g by
   about d (1 - R) / R at an asked reduction R, and the first estimate of mu0 is good to
   about a per cent (-1.5 % to +1.0 % over the report's 20 fingers): on a block asking
   R = 0.021 a -1.1 % error made g 0.32, the step tripled c, and the integrator took
   seconds to bring it back (the object scene's finger 4: 3.2x open loop's error over
   4 s, 2.5x with the wait; the scene's median gain over open loop on 20 fingers, 4 s
   runs with reports 3 blocks late, 2.46x -> 3.23x; the gratings' unchanged). An
   integrator scheduled for a
   late report needs tens of blocks to get there, and the error of a whole session's
   start is spent meanwhile. It is one step, not a loop, so it cannot oscillate; a
   finger with s > 1 overshoots it, and the integrator takes that back. Closed mode
   only: in adaptive mode the model fitted to the same reports corrects the
   feed-forward too, and the two together overshoot (the report's population, 10 s
   runs, reports 3 blocks late: adaptive 4.08x -> 3.77x on grating-15mm, 3.83x -> 2.88x on the
   object scene with it; closed 3.86x -> 4.26x and 3.60x -> 3.48x).
   Where the probe held the plate still there is nothing asked to compare with: those
   samples are no reduction asked.
   Anti-windup: c does not grow in a block where the amplitude limit cut the reduction
   the feedback compares with on more than a tenth of its samples (the reduction asked
   where the limit cut it passes through the same chain as the whole reduction asked, so
   a sample whose lagged reduction came mostly from cut samples counts as cut: the block
   after a cut band carries its lag), and that time counts as the gain at its limit;
   nor move at all while the finger rests (no sliding, no friction to measure); it
   stays within ``[1/4, 4]`` at any speed (``log_c``, ``log_c_slope`` and their sum
   each within ``log_c_max``).
3. **Feed-forward** through seed 003's inverse (eq 3, ``device.friction``), with the
   device's constants (``closed``) or their online estimate (``adaptive``,
   ``rendering.control.adapt``: RLS on every ``decimate``-th sliding sample, the model's
   mu' and its Jacobian passed through the same chain as the reference, so that the
   plate loop's, the fingertip's and the sensor's lags cancel).
4. **Fallback.** Reports missed for more than ``stale_s`` of blocks in a row (stale;
   without force reports at all, ``forces`` None, every block is missed at once:
   absent), a report that reaches the sensor's full scale (saturated), or one that is
   not a finger (non-finite, F_n below ``min_normal_n`` while touching, |F_t| / F_n
   above ``max_ratio``) drops the loop to open loop with the
   latest model and c = 1; said once (``messages``) and counted (``fallbacks``,
   ``fallback_samples``). The loop resumes after ``recover_s`` of good reports. A dead
   sensor is open loop after at most ``max_wait_s`` + ``stale_s`` plus one block.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from frictex.device.errors import InputError
from frictex.device.finger import SensorParams
from frictex.device.link.forces import ForceReport
from frictex.device.friction import ASYMPTOTE_MARGIN, MIN_NORMAL_N, SeedFrictionModel
from frictex.device.profile import FRICTION_LOOP_PROFILES, DeviceProfile
from frictex.rendering.control.adapt import Rls, RlsState
from frictex.rendering.control.block_stats import (chain_input, feed_forward, feedback_stats,
                                           report_peak, rest_stats, sent_rows, touch_downs)
from frictex.rendering.control.chain import Chain, ChainState
from frictex.rendering.control.margins import COVER_SLOPE, scheduled_ki
from frictex.rendering.control.swings import OSCILLATION_STEPS, SWING, Swings
from frictex.textures.model import CONTROL_MODES

_NONE = np.zeros(0)  # chain_input's model rows left out (closed mode)


@dataclass(frozen=True)
class LoopConfig:
    """The loop's constants (module docstring); units s, um, N, mm/s. ``ki``: the
    integrator's gain per block, or None to schedule it on the measured report delay
    (``rendering.control.margins.scheduled_ki`` with ``cover_slope``)."""

    ki: float | None = None
    first_step: float = 1.0
    first_reduction: float = 0.1
    cover_slope: float = COVER_SLOPE
    max_wait_s: float = 0.05
    delay_hold_s: float = 2.0
    log_c_max: float = math.log(4.0)
    speed_ref_mm_s: float = 100.0
    slide_mm_s: float = 5.0
    probe_mm_s: float = 8.0
    probe_s: float = 0.015
    rehold_reduction: float = 0.11
    creep_mm_s: float = 0.5
    min_rest_mu: float = 0.1
    settled: float = 0.03
    still_um: float = 0.005
    still_seen: float = 0.01
    mu0_tau_s: float = 0.3
    min_still: int = 10
    min_reduction: float = 0.02
    min_mu: float = 0.15
    stale_s: float = 0.02
    recover_s: float = 0.1
    min_normal_n: float = MIN_NORMAL_N
    max_ratio: float = 3.0
    decimate: int = 10
    sensor: SensorParams = field(default_factory=SensorParams)
    rls: Rls = field(default_factory=Rls)

    def __post_init__(self):
        positive = ("cover_slope", "delay_hold_s", "slide_mm_s", "probe_mm_s", "probe_s",
                    "creep_mm_s", "still_um", "mu0_tau_s", "stale_s", "recover_s", "min_normal_n",
                    "max_ratio", "log_c_max", "speed_ref_mm_s")
        bad = [f"{name} = {getattr(self, name)!r} (expected a finite value > 0)"
               for name in positive
               if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0)]
        fractions = ("rehold_reduction", "min_rest_mu", "settled", "still_seen",
                     "min_reduction", "first_reduction", "min_mu")
        bad += [f"{name} = {getattr(self, name)!r} (expected 0 to 1)" for name in fractions
                if not 0.0 <= getattr(self, name) <= 1.0]
        if not 0.0 <= self.first_step <= 1.0:
            bad.append(f"first_step = {self.first_step!r} (expected 0 to 1)")
        if self.ki is not None and not (math.isfinite(self.ki) and self.ki > 0):
            bad.append(f"ki = {self.ki!r} (expected None or a finite value > 0)")
        if not 0.0 <= self.max_wait_s <= 0.5:  # a link's reports keep 1 s of samples
            bad.append(f"max_wait_s = {self.max_wait_s!r} (expected 0 to 0.5 s)")
        if not (isinstance(self.min_still, int) and self.min_still >= 2):
            bad.append(f"min_still = {self.min_still!r} (expected an integer >= 2: the "
                       "first estimate takes the median of min_still // 2 samples)")
        if not (isinstance(self.decimate, int) and self.decimate >= 1):
            bad.append(f"decimate = {self.decimate!r} (expected an integer >= 1)")
        if bad:
            raise InputError("loop configuration: " + "; ".join(bad))


@dataclass(frozen=True, eq=False)
class Sent:
    """What the loop asked for in a block sent (the report that comes back pairs with
    it sample by sample): output index, the log gain it was asked with, amplitude (um),
    target mu' (1 where the probe held the plate still), speed (mm/s), whether the limit
    cut it, the output index its finger touched down at, per sample (-1: none; module
    docstring, 1), whether it was a one-finger block, and the normal force (N, mean over
    the block) the inverse model was given for its finger (0 with none touching)."""

    index0: int
    log_c: float
    w_um: np.ndarray
    target: np.ndarray
    speed: np.ndarray
    cut: np.ndarray
    down: np.ndarray
    single: bool
    force_n: float = 0.0


@dataclass(frozen=True)
class ControlState:
    """Everything the loop carries between blocks (module docstring)."""

    log_c: float
    rls: RlsState
    log_c_slope: float = 0.0
    mu0: float = math.nan
    mu0_from: int = -1  # index0 of the block the first estimate of mu0 came from
    chain: ChainState | None = None
    pending: tuple[Sent, ...] = ()
    delay_blocks: int = 0
    delay_seen_at: int = 0
    delay_max_blocks: int = 0
    fed_from: int = 0
    since_report_s: float = 0.0
    good_s: float = 0.0
    probe_from: int | None = None
    probe_released: bool = False
    down_at: np.ndarray | None = None  # per finger, its touch-down's output index (-1: lifted)
    fallback: bool = False
    fallbacks: int = 0
    fallback_samples: int = 0
    updates: int = 0
    started: bool = False
    messages: tuple[str, ...] = ()
    swings: Swings = Swings()
    limit_s: float = 0.0
    reports: int = 0
    reports_missed: int = 0
    reports_late: int = 0  # of those missed, reports that came after ``max_wait_s``
    delay_counts: tuple[int, ...] = ()
    measured_sq: float = 0.0
    measured_n: int = 0
    input_force_blocks: int = 0
    touch_blocks: int = 0
    reports_rejected: tuple[tuple[str, int], ...] = ()


class ClosedLoop:
    """The loop for one device at ``rate_hz`` with blocks of ``block_size`` samples."""

    def __init__(self, device: DeviceProfile, rate_hz: float, block_size: int,
                 mode: str = "adaptive", config: LoopConfig = LoopConfig()):
        if mode not in CONTROL_MODES[1:]:
            raise InputError(f"control mode {mode!r}: expected one of {', '.join(CONTROL_MODES)} "
                             f"(open loop builds no loop)")
        if device.calibration is not None:
            raise InputError("closed-loop control inverts seed 003's eq 2, and this scene's "
                             "[device] has a measured [device.calibration] table (frictex "
                             "calibrate writes one where the model does not fit): play it "
                             "with --control open, or remove the table to use "
                             "[device.friction]")
        if device.profile not in FRICTION_LOOP_PROFILES:
            raise InputError(f"closed-loop control needs profile "
                             f"{' or '.join(FRICTION_LOOP_PROFILES)} with seed 003's "
                             f"model; got {device.profile!r}")
        self.device = device
        self.mode = mode
        self.rate_hz = float(rate_hz)
        self.block_s = block_size / self.rate_hz
        self.config = replace(config, rls=replace(config.rls, block_s=self.block_s))
        self.chain = Chain(config.sensor, rate_hz)
        self.block_size = int(block_size)
        self.first_step = config.first_step if mode == "closed" else 0.0  # docstring, 2
        self.wait_samples = config.max_wait_s * self.rate_hz
        self.hold_samples = config.delay_hold_s * self.rate_hz
        self.rise_samples = config.probe_s * self.rate_hz  # module docstring, 1
        #: the integrator's gain for reports 0, 1, ... blocks late (module docstring, 0)
        self.ki_by_delay = tuple(
            config.ki if config.ki is not None else
            scheduled_ki(d, config.sensor, self.rate_hz, self.block_size, config.cover_slope)
            for d in range(int(config.max_wait_s / self.block_s + 1e-9) + 1))
        self.limit_um = float(device.amplitude_limit_um)
        self._cut_um = self.limit_um * (1.0 - 1e-9)  # a command at the limit: cut by it
        friction = device.friction
        #: (b, k), the model of those constants
        self._model_of = ((friction.b_per_um, friction.asymptote_per_n), SeedFrictionModel(device))
        self._load_kernels()

    def _load_kernels(self) -> None:
        """Call the kernels that read a report once, on a block of zeros: numba loads them
        from its cache on their first call (or compiles them), which belongs to building
        the loop, not to the first block whose report comes back (the pipeline's warm-up
        block has no report). The arguments have the types the loop passes."""
        cfg, z = self.config, np.zeros(self.block_size)
        seen = np.zeros((6 if self.mode == "adaptive" else 3, self.block_size))
        report_peak(z, z)
        touch_downs(np.ones((1, self.block_size), dtype=np.bool_), np.full(1, -1), 0, 0)
        ratio, *_ = rest_stats(z, z, z, seen[1], cfg.min_normal_n, cfg.creep_mm_s,
                               cfg.slide_mm_s, cfg.still_seen, cfg.min_rest_mu,
                               cfg.min_still // 2, True)
        feedback_stats(ratio, 1.0, z, z, seen, cfg.min_normal_n, cfg.creep_mm_s,
                       cfg.slide_mm_s, cfg.min_mu, cfg.min_reduction, cfg.min_still,
                       cfg.decimate)

    def initial_state(self) -> ControlState:
        # chain rows: reduction asked, plate moving, (adaptive) the model's mu', d/db, d/dk,
        # and the reduction asked where the limit cut the command
        rows = [0.0, 0.0] + ([1.0, 0.0, 0.0] if self.mode == "adaptive" else []) + [0.0]
        return ControlState(log_c=0.0, rls=self.config.rls.initial_state(self.device.friction),
                            chain=self.chain.initial_state(rows))

    def _model(self, state: ControlState) -> SeedFrictionModel:
        """The inverse model: the device's constants, or (adaptive) the current RLS
        estimate's, built once per estimate."""
        if self.mode != "adaptive":
            return self._model_of[1]
        if state.rls.theta != self._model_of[0]:
            self._model_of = (state.rls.theta, SeedFrictionModel(self.device, state.rls.params))
        return self._model_of[1]

    def invert(self, mu_target: np.ndarray, fingers, state: ControlState, forces=None):
        """Amplitudes for this block: (wanted_um (F, n), clamps, state after).

        ``fingers``: the tracker's block (contact, force, vx, vy, (F, n)); ``forces``:
        ``forces(index0, n) -> ForceReport | None``, the device's forces over output
        samples ``index0 .. index0 + n - 1`` if its reports have covered them so far, or
        None for a device without force reports (module docstring, 0).
        """
        state, pending = self._pair(state, int(fingers.index0), forces)
        contact = fingers.contact
        # the first finger touching (-1: none) and the tracker's speed of it (mm/s): the
        # loop's, if it is alone
        touching = contact.any(axis=1)
        count = int(touching.sum())
        row = int(np.argmax(touching)) if count else -1
        n = mu_target.shape[1]
        speed = np.hypot(fingers.vx[row], fingers.vy[row]) if count else np.zeros(n)
        single = count == 1
        c = 1.0  # the gain asked with: 1 with several fingers down
        if single and not state.fallback and math.isfinite(state.mu0):
            c = math.exp(self._log_gain(state, float(np.mean(speed))))
        asked = feed_forward(mu_target, c)
        # the probe waits max_wait_s for the link's first usable report (module docstring, 1)
        waiting = state.reports > 0 or not state.reports_missed
        if single and not state.fallback and waiting and not math.isfinite(state.mu0):
            # probe (module docstring, 1): the plate still while the finger starts to slide
            slow = speed < self.config.probe_mm_s
            # released once the tracker has read the finger fast: slow again (its noise, a
            # pause) holds the plate only where what the hold withholds is not felt
            unreleased = (np.cumsum(~slow) == 0) & (not state.probe_released)
            slow &= unreleased | (1.0 - mu_target[row] <= self.config.rehold_reduction)
            # once a report has shown the finger sliding on the still plate, only the
            # probe's window holds it: the blocks held since are on their way back
            hold = (slow & (state.probe_from is None)) | self._probing(state, int(fingers.index0))
            asked[row] = np.where(hold, np.maximum(asked[row], 1.0), asked[row])
            state = replace(state, probe_released=not unreleased[-1])
        wanted, clamps = self._model(state).invert(asked, fingers.force)
        # the feedback compares with the reduction asked of the plate: none where the
        # probe held it still (a report that comes late would otherwise read the
        # probe as a finger that gets no reduction, and wind the gain up)
        wanted, target, cut = sent_rows(wanted, contact, asked, mu_target, row, self._cut_um)
        down_at = state.down_at
        if down_at is None or down_at.size != contact.shape[0]:
            down_at = np.full(contact.shape[0], -1, dtype=np.int64)
        down, down_at = touch_downs(contact, down_at, int(fingers.index0), row)
        w = wanted[row] if count else np.zeros(n)
        force = float(np.mean(fingers.force[row])) if count else 0.0
        sent = Sent(index0=int(fingers.index0), log_c=math.log(c), w_um=w, target=target,
                    speed=speed, cut=cut, down=down, single=single, force_n=force)
        held = state.fallback_samples + (n if state.fallback else 0)
        return wanted, clamps, replace(state, pending=pending + (sent,), fallback_samples=held,
                                       down_at=down_at)

    def _pair(self, state: ControlState, now: int,
              forces) -> tuple[ControlState, tuple[Sent, ...]]:
        """Fold the blocks sent whose reports have come, oldest first, and any whose report
        is more than ``max_wait_s`` late as missed (module docstring, 0); ``now``: the
        output index of the block being computed. The blocks folded behind a missed one
        waited for it, not for their reports: their wait is not taken as the delay, so
        one lost report does not slow the gain for good. Returns the state after them
        and the blocks still pending (the state's ``pending`` left for the caller to set)."""
        behind_missed = False
        pending, folded = state.pending, 0
        for sent in pending:
            n = sent.w_um.size
            late = now - (sent.index0 + n)  # samples from its end to now
            report = None if forces is None else forces(sent.index0, n)
            if report is None and forces is not None and late <= self.wait_samples:
                break  # still on its way
            if report is not None and late > self.wait_samples:
                # missed, as one that never came: used, its delay would be past the gains
                # scheduled (``ki_by_delay``)
                report, state = None, replace(state, reports_late=state.reports_late + 1)
            delay = (state.delay_blocks if behind_missed else
                     min(max(late, 0) // self.block_size, len(self.ki_by_delay) - 1))
            behind_missed = behind_missed or report is None
            folded += 1
            state = self._learn(state, sent, report, delay, now,
                                "stale" if forces is not None else
                                "absent (no force reports: no device, or one without a "
                                "lateral force sensor)")
        return state, pending[folded:]

    def played(self, state: ControlState, gain) -> ControlState:
        """The block just sent played at ``gain`` (scalar or (n,)) times its amplitude
        (an emergency stop: 0; a ramp or crossfade: rising): its report then shows what
        the plate did, not what the loop asked, so the feedback leaves it out (no
        reduction asked) and the chain sees the amplitude played."""
        if not state.pending:
            return state
        sent = state.pending[-1]
        sent = replace(sent, w_um=sent.w_um * gain, target=np.ones_like(sent.target),
                       cut=np.zeros_like(sent.cut))
        return replace(state, pending=state.pending[:-1] + (sent,))

    def _log_gain(self, state: ControlState, speed_mm_s: float) -> float:
        """log c at a tracker speed (mm/s), within ``log_c_max`` (module docstring, 2)."""
        lim = self.config.log_c_max
        log_c = state.log_c + state.log_c_slope * speed_mm_s / self.config.speed_ref_mm_s
        return min(max(log_c, -lim), lim)

    def report(self, state: ControlState, late_hint: str = "") -> dict:
        """The loop's figures after a run, for a summary (JSON-able; module docstring, 2).

        ``mode``; ``report_delay_blocks``: the largest report delay seen (blocks);
        ``scheduled_delay_blocks`` and ``ki``: the delay the integrator is scheduled on at
        the end and its step there (the share of one block's log error that moves log c);
        ``gain``: the depth gain c where the run ended, at rest (the reduction of friction
        asked is c times the texture's, ``1 - c (1 - mu'_target)``), and
        ``log_gain_per_speed_ref``: its log's slope per ``speed_ref_mm_s``; ``mu0``;
        ``updates``: steps of c; ``fallbacks``, ``fallback_samples``: falls to open loop and
        the samples fed forward open loop meanwhile; ``gain_oscillations``,
        ``gain_swings_max``, ``gain_at_limit_s``: oscillations of c seen, the longest run of
        its swings (``rendering.control.swings``) and the time (s) log c spent at its limit
        or held by the amplitude limit's (anti-windup: a step up not taken);
        ``input_force_implausible_blocks``: blocks inverted with a touch input's force
        below ``min_normal_n`` under a finger the device measured (``_input_force``);
        ``reports_rejected``: per reason ("saturated", "not finite", "implausible"), force
        reports that came but read no finger (any drops the loop to open loop);
        ``measured``: what the host measured from the device's force reports (``reports``
        used, ``reports_missed``, ``reports_pending_at_end``: the blocks sent whose
        reports were still due when the run ended (not yet back, nor ``max_wait_s``
        late), so that with ``reports_rejected`` every block the loop sent is counted
        once; the delay the good ones came with, p50 and p99 in blocks, and once mu0 is
        known, the RMS of the measured mu'_m = F_t / (F_n mu0) against the target mu' the
        block asked for, over ``samples`` sliding and pressed, None with none);
        ``messages``: what the loop said, and what the reports' delays say
        (``_late_messages``; ``late_hint``: what the caller can do about late reports,
        appended to those) and, where a finger touched but mu0 was never measured, that
        the loop stayed open (``_open_message``)."""
        return {"mode": self.mode, "report_delay_blocks": state.delay_max_blocks,
                "scheduled_delay_blocks": state.delay_blocks,
                "ki": self.ki_by_delay[state.delay_blocks], "gain": math.exp(state.log_c),
                "log_gain_per_speed_ref": state.log_c_slope,
                "speed_ref_mm_s": self.config.speed_ref_mm_s,
                "mu0": state.mu0 if math.isfinite(state.mu0) else None,
                "updates": state.updates, "fallbacks": state.fallbacks,
                "fallback_samples": state.fallback_samples,
                "gain_oscillations": state.swings.oscillations,
                "gain_swings_max": state.swings.longest_with_current(),
                "gain_at_limit_s": state.limit_s,
                "input_force_implausible_blocks": state.input_force_blocks,
                "reports_rejected": dict(state.reports_rejected),
                "measured": {
                    "reports": state.reports, "reports_missed": state.reports_missed,
                    "reports_pending_at_end": len(state.pending),
                    "report_delay_p50_blocks": _quantile(state.delay_counts, 0.5),
                    "report_delay_p99_blocks": _quantile(state.delay_counts, 0.99),
                    "samples": state.measured_n,
                    "rms_mu_vs_target": (math.sqrt(state.measured_sq / state.measured_n)
                                         if state.measured_n else None)},
                "messages": (list(state.messages) + self._late_messages(state, late_hint)
                             + self._open_message(state))}

    def _open_message(self, state: ControlState) -> list[str]:
        """One line when a finger touched (alone) but the loop never measured mu0, the
        friction at rest it compares with: it stayed open loop all along, whatever its
        figures say (a finger that never slid, or no usable report); else none."""
        if math.isfinite(state.mu0) or not state.touch_blocks:
            return []
        rejected = sum(count for _, count in state.reports_rejected)
        return [f"closed loop: never measured the friction at rest mu0 ({state.touch_blocks} "
                f"blocks with one finger touching; {state.reports} usable reports, {rejected} "
                f"rejected, {state.reports_missed} missed): it stayed open loop (the finger "
                f"must slide at {self.config.slide_mm_s:g} mm/s or faster on the still "
                "plate, under a sensor that reports it)"]

    def _late_messages(self, state: ControlState, hint: str) -> list[str]:
        """One line each when the force reports came back too late for the loop: more
        than ``MISSED_SHARE`` of them missed (not back within ``max_wait_s`` of their
        block's end), and a median delay at that wait limit (the integrator then steps at
        the smallest ki the scheduler has). None (an empty list) when no report came, not even
        late (the fallback has said why), or the loop waits less than a block."""
        if not state.reports and not state.reports_late:
            return []
        wait_ms = self.config.max_wait_s * 1e3
        said = []
        folded = state.reports + state.reports_missed
        if state.reports_missed > MISSED_SHARE * folded:
            said.append(f"closed loop: {state.reports_missed / folded:.0%} of the force "
                        f"reports ({state.reports_missed} of {folded}) were missed (not back "
                        f"within max_wait_s, {wait_ms:g} ms, of their block's end): the gain "
                        f"learnt from the rest only{hint}")
        limit = len(self.ki_by_delay) - 1
        median = _quantile(state.delay_counts, 0.5)
        if limit and median is not None and median >= limit:
            said.append(f"closed loop: the force reports' median delay ({median} blocks) is "
                        f"the longest the loop waits (max_wait_s, {wait_ms:g} ms): its "
                        f"integrator steps at ki {self.ki_by_delay[limit]:.3g} per block "
                        f"against {self.ki_by_delay[1]:.3g} at 1 block, so the gain follows "
                        f"the finger that much slower{hint}")
        return said

    def _probing(self, state: ControlState, now: int) -> bool:
        """Whether the probe holds the plate still whatever the tracker's speed (module
        docstring, 1): the force report shows the finger sliding on the still plate
        (``probe_from``) and less than ``probe_s`` has passed since that block ended;
        ``now``: the output index of the block being computed."""
        if state.probe_from is None:
            return False
        ended = state.probe_from + self.block_size
        return now < ended + self.config.probe_s * self.rate_hz - 0.5 * self.block_size

    def _learn(self, state: ControlState, sent: Sent, report: ForceReport | None,
               delay: int, now: int, missed: str) -> ControlState:
        """Fold block ``sent``'s report (None: missed, for the reason ``missed``),
        ``delay`` blocks late, into the state (module docstring, 1, 2, 4); ``now``: the
        output index of the next block to be sent."""
        n = sent.w_um.size
        touched = state.touch_blocks + sent.single
        fresh = report is not None and report.index0 == sent.index0 and report.lateral_n.size == n
        seen, chain = self.chain.run(self._chain_rows(state, sent, report if fresh else None),
                                     state.chain)
        if not fresh:
            return self._bad(replace(state, chain=chain, touch_blocks=touched,
                                     reports_missed=state.reports_missed + 1),
                             missed, stale=True)
        # friction opposes sliding: its magnitude, whichever way the finger slides (the
        # report's sign is the direction, PROTOCOL.md 4.9)
        lat = np.abs(np.asarray(report.lateral_n, dtype=np.float64))
        nor = np.asarray(report.normal_n, dtype=np.float64)
        problem = _problem(lat, nor, sent.single and bool(n), self.config)
        if problem:
            return self._bad(replace(state, chain=chain, touch_blocks=touched,
                                     reports_rejected=_counted(state.reports_rejected,
                                                               problem.split(" (")[0])),
                             problem, stale=False)
        good_s = state.good_s + self.block_s
        counts = state.delay_counts or (0,) * len(self.ki_by_delay)
        changes = dict(chain=chain, since_report_s=0.0, good_s=good_s, touch_blocks=touched,
                       fallback=state.fallback and good_s < self.config.recover_s,
                       reports=state.reports + 1,
                       delay_counts=counts[:delay] + (counts[delay] + 1,) + counts[delay + 1:],
                       **self._held_delay(state, delay, now))
        if sent.single:  # several fingers: nothing to learn
            state = self._input_force(state, sent, nor)
            changes.update(self._learn_finger(state, sent, lat, nor, seen, changes, now))
        return replace(state, **changes)

    def _input_force(self, state: ControlState, sent: Sent, nor: np.ndarray) -> ControlState:
        """Counts (and says once) a block whose finger the inverse model was given a
        normal force below ``min_normal_n`` (the touch input's: a trace whose force is 0)
        while the device's sensors measured a pressing finger: the model's asymptote is
        k F_n, so it inverts for a finger that is not there, and the loop's gain makes up
        for it (to 2.2 on grating-15mm with a 0 N trace and the device's 0.5 N)."""
        measured = float(nor.sum()) / max(nor.size, 1)
        low = self.config.min_normal_n
        if not sent.force_n < low <= measured:
            return state
        said = (f"closed loop: the touch input's normal force ({sent.force_n:.2g} N) is "
                f"implausible under a finger the device measures at {measured:.2g} N; the "
                "model's inversion uses the input's (give the trace its finger's force_n, or "
                "leave the column out for 0.5 N)")
        return replace(state, input_force_blocks=state.input_force_blocks + 1,
                       messages=_said(state.messages, said))

    def _chain_rows(self, state: ControlState, sent: Sent, report: ForceReport | None):
        """The block statistics' input rows for ``sent``: in adaptive mode the model's mu'
        and Jacobian as the sensor sees them (at the report's normal force; the device's
        without a report); last, the reduction asked where the amplitude limit cut the
        command (0 elsewhere)."""
        cfg = self.config
        if self.mode != "adaptive":
            rows = chain_input(sent.target, sent.w_um, cfg.still_um, _NONE, _NONE, 0.0, 1.0)
        else:
            normal = (np.asarray(report.normal_n, dtype=np.float64) if report is not None
                      else np.full(sent.w_um.size, self.device.normal_force_n))
            b, k = state.rls.theta
            rows = chain_input(sent.target, sent.w_um, cfg.still_um, normal,
                               np.exp(-b * sent.w_um), k, 1.0 - ASYMPTOTE_MARGIN)
        # the reduction the limit cut lags as the whole reduction asked (row 0) does
        return np.vstack((rows, np.where(sent.cut, rows[0], 0.0)))

    def _learn_finger(self, state: ControlState, sent: Sent, lat: np.ndarray,
                      nor: np.ndarray, seen, changes: dict, now: int) -> dict:
        """What one finger's good report teaches (module docstring, 1-3): the first mu0
        and the probe, then mu0, the gain and the RLS model; the state's changes."""
        cfg = self.config
        first_estimate = not math.isfinite(state.mu0)
        ratio, *rest = rest_stats(lat, nor, sent.speed, seen[1], cfg.min_normal_n,
                                  cfg.creep_mm_s, cfg.slide_mm_s, cfg.still_seen,
                                  cfg.min_rest_mu, cfg.min_still // 2, first_estimate)
        if first_estimate:
            return self._first_mu0(state, sent, *rest)
        moving, count, m = rest
        if not moving:
            return {}  # at rest: nothing to learn
        out = {}
        mu0 = state.mu0
        rise = self._rising(state, sent)
        rising = bool(rise.any())
        if count >= cfg.min_still and not rising:  # m: a median, robust to a late-seen stop
            alpha = -math.expm1(-count / (self.rate_hz * cfg.mu0_tau_s))
            mu0 = out["mu0"] = mu0 + alpha * (m - mu0)
        if math.isfinite(mu0):  # what the host measured against the target (``report``)
            # a non-finite target (clamped by the inverse model) has nothing to compare with
            keep = ((sent.speed >= cfg.slide_mm_s) & (nor >= cfg.min_normal_n)
                    & np.isfinite(sent.target))
            err = ratio[keep] / mu0 - sent.target[keep]
            out["measured_sq"] = state.measured_sq + float(err @ err)
            out["measured_n"] = state.measured_n + int(np.count_nonzero(keep))
        if not math.isfinite(mu0) or changes["fallback"]:
            return out
        # feedback from the tracker's first sight of motion: at a stroke's start it lags
        # the finger by tens of ms; a finger that stuck reads friction near 0 (min_mu);
        # in the fingertip's rise after a touch-down it is not sliding yet (docstring, 1)
        speed = np.where(rise, 0.0, sent.speed) if rising else sent.speed
        asked, g, cut, jac, resid = feedback_stats(
            ratio, mu0, nor, speed, seen, cfg.min_normal_n, cfg.creep_mm_s,
            cfg.slide_mm_s, cfg.min_mu, cfg.min_reduction, cfg.min_still, cfg.decimate)
        if asked >= cfg.min_still and sent.index0 >= state.fed_from:
            out.update(self._gain_step(state, sent, g, cut > 0.1 * sent.w_um.size,
                                       changes.get("delay_blocks", state.delay_blocks), now))
        if self.mode == "adaptive":  # one RLS step (module docstring, 3)
            out["rls"] = cfg.rls.update(state.rls, jac, resid)
        return out

    def _rising(self, state: ControlState, sent: Sent) -> np.ndarray:
        """The samples of ``sent`` (n,) bool less than ``probe_s`` after their finger's
        touch-down, where it touched down after the block the first estimate of mu0 came
        from: that touch-down's rise the first estimate waited out (module docstring, 1)."""
        since = sent.index0 + np.arange(sent.down.size) - sent.down
        return (sent.down > state.mu0_from) & (since < self.rise_samples)

    def _first_mu0(self, state: ControlState, sent: Sent, early: float, late: float,
                   quiet_late: int) -> dict:
        """The first estimate of mu0 (module docstring, 1): the later half's median once
        it agrees with the earlier half's (``early``, ``late``: nan with too few samples;
        not the fingertip's rise into sliding), and where the probe started when the
        finger slides on the still plate (``quiet_late`` still samples)."""
        cfg = self.config
        out = {}
        if math.isfinite(late) and abs(late - early) <= cfg.settled * late:
            out["mu0"], out["mu0_from"] = late, sent.index0
        rising = quiet_late >= cfg.min_still // 2
        first = sent.index0 if state.probe_from is None else state.probe_from
        out["probe_from"] = first if rising else None
        return out

    def _held_delay(self, state: ControlState, delay: int, now: int) -> dict:
        """The report delay (blocks) the gain is scheduled on after a report ``delay``
        blocks late folded at output index ``now`` (module docstring, 0): raised to it at
        once, lowered by one block once ``delay_hold_s`` has passed since a report was
        last as late as the scheduled delay; and the largest delay seen."""
        if delay >= state.delay_blocks:
            return dict(delay_blocks=delay, delay_seen_at=now,
                        delay_max_blocks=max(state.delay_max_blocks, delay))
        if now - state.delay_seen_at >= self.hold_samples:
            return dict(delay_blocks=state.delay_blocks - 1, delay_seen_at=now)
        return {}

    def _asked_rms(self, sent: Sent) -> float:
        """The root-mean-square reduction 1 - mu' a block asked over its samples asking at
        least ``min_reduction`` (0 where none did)."""
        asked = 1.0 - sent.target
        asked = asked[asked >= self.config.min_reduction]
        return float(np.sqrt(np.mean(asked * asked))) if asked.size else 0.0

    def _gain_step(self, state: ControlState, sent: Sent, g: float, cut: bool, delay: int,
                   now: int) -> dict:
        """One step of the loop's log gain (module docstring, 2) from ``g``, the median of
        per-sample delivered / asked (robust to the few samples of a stop); ``cut``: the
        amplitude limit cut the reduction ``g`` compares with (as the chain lags it) on
        more than a tenth of the block's samples; ``delay``: the report delay (blocks) the gain is
        scheduled on."""
        cfg = self.config
        error = math.log(min(max(g, 0.25), 4.0))
        # the first measurement asking enough starts the gain (module docstring, 2)
        first = (not state.started and self.first_step > 0
                 and self._asked_rms(sent) >= cfg.first_reduction)
        speed = float(np.mean(sent.speed))
        step = (self.first_step * (sent.log_c - error - self._log_gain(state, speed))
                if first else -self.ki_by_delay[delay] * error)
        held = step > 0 and cut
        if held:
            step = 0.0  # anti-windup: the limit already cuts what is asked
        p = 0.0 if first else speed / cfg.speed_ref_mm_s  # the first step: log_c alone
        lim = cfg.log_c_max
        out = {"log_c": min(max(state.log_c + step / (1.0 + p * p), -lim), lim),
               "log_c_slope": min(max(state.log_c_slope + step * p / (1.0 + p * p), -lim), lim),
               "updates": state.updates + 1}
        if first:
            out["started"] = True
            if step:
                out["fed_from"] = now  # blocks on their way were asked with the old gain
        out.update(self._watch_gain(state, out["log_c"], held))
        return out

    def _watch_gain(self, state: ControlState, log_c: float, held: bool) -> dict:
        """The gain's swings after a step to ``log_c`` (``rendering.control.swings``: an
        oscillation is said once and counted) and the time it has spent at its limit,
        its own or (``held``) the amplitude limit's holding it (anti-windup)."""
        swings = state.swings.step(log_c - state.log_c)
        out = {"swings": swings}
        if held or abs(log_c) >= self.config.log_c_max:
            out["limit_s"] = state.limit_s + self.block_s
        if swings.oscillations > state.swings.oscillations:
            ki = self.ki_by_delay[state.delay_blocks]
            out["messages"] = _said(state.messages, (
                f"closed loop: the gain oscillates ({OSCILLATION_STEPS} swings over "
                f"{SWING:.0%} in a row at ki {ki:.3g} per block): the loop is unstable, "
                "lower ki or leave it to the scheduler"))
        return out

    def _bad(self, state: ControlState, problem: str, stale: bool) -> ControlState:
        since = state.since_report_s + self.block_s if stale else state.since_report_s
        state = replace(state, since_report_s=since, good_s=0.0)
        if stale and since <= self.config.stale_s:
            return state
        if state.fallback:
            return state
        messages = state.messages
        if not any(m.startswith(_FALLBACK) for m in messages):  # said once
            messages += (f"{_FALLBACK} {problem}; open loop with the latest model until the "
                         f"signal is good for {self.config.recover_s:g} s",)
        return replace(state, fallback=True, fallbacks=state.fallbacks + 1, messages=messages)


_FALLBACK = "closed loop: force signal"
#: the share of force reports missed above which the loop's report says so
MISSED_SHARE = 0.05


def _said(messages: tuple[str, ...], message: str) -> tuple[str, ...]:
    """``messages`` with ``message`` added, unless said already (its text up to the first
    figure: each kind of message is said once)."""
    kind = message.split("(")[0]
    return messages if any(m.startswith(kind) for m in messages) else messages + (message,)


def _counted(counts: tuple[tuple[str, int], ...], key: str) -> tuple[tuple[str, int], ...]:
    """``counts`` (key, count) pairs with ``key``'s count one higher (added at 1)."""
    table = dict(counts)
    table[key] = table.get(key, 0) + 1
    return tuple(table.items())


def _quantile(counts: tuple[int, ...], q: float) -> int | None:
    """The smallest delay (blocks) with at least ``q`` of the reports at it or earlier
    (``counts``: reports per delay 0, 1, ...); None without reports."""
    total = sum(counts)
    if not total:
        return None
    return int(np.searchsorted(np.cumsum(counts), q * total))


def _problem(lat: np.ndarray, nor: np.ndarray, touching: bool, cfg: LoopConfig) -> str:
    """Why a report is not a finger ("" if it is); see the module docstring, 4."""
    peak = report_peak(lat, nor)
    if not math.isfinite(peak):
        return "not finite"
    if peak >= 0.999 * cfg.sensor.full_scale_n:
        return "saturated"
    if touching:
        mean_nor = float(nor.sum()) / nor.size  # as ndarray.mean, without its overhead
        if mean_nor < cfg.min_normal_n:
            return "implausible (no normal force under a finger)"
        ratio = float(lat.sum()) / lat.size / mean_nor  # of |F_t|: a finger at rest reads noise
        if ratio > cfg.max_ratio:
            return f"implausible (F_t / F_n = {ratio:.3g})"
    return ""

