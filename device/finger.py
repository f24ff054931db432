"""A simulated fingertip on seed 003's plate: what the finger gets and what the sensors see.

One person's finger (:class:`FingerParams`) on the plate, per output sample:

1. The plate's amplitude loop (seed 003, section 4.2, Fig. 3b: a PI loop with a -3 dB
   bandwidth of 400 Hz at 2 um) is a first-order low-pass at ``plate_bw_hz`` on the
   commanded amplitude, clamped to the amplifier limit first.
2. The friction the finger gets, relative to its friction at rest (seed 003, eqs 1-2)::

       mu'(w) = (1 - A) exp(-b_eff w) + A,   A = k_eff F_n

   with this person's ``b`` and ``k`` instead of seed 003's 1.67 /um and 1.13 /N, a
   sliding-speed dependence ``b_eff = b / (1 + v / v_c)`` (a faster finger gets less
   reduction) and a moisture drift ``k_eff = k (1 + k_drift m(t))``.
3. Friction at rest ``mu0(t) = mu0 (1 + mu0_drift m(t))``, with the moisture state
   ``m(t) = 1 - exp(-(t0 + t) / tau)``: the stratum corneum softening as the fingertip
   sweats under occlusion over minutes.
4. The lateral force ``F_t = mu0(t) mu'(t) F_n`` reaches the sensor through the
   fingertip's own tangential compliance (seed 003, section 3: a rise time of 3.84 ms,
   about 90 Hz, ``skin_bw_hz``), then the sensor (``sensor_bw_hz`` low-pass,
   ``sensor_delay_s`` transport delay, white noise of ``lateral_noise_n`` and
   ``normal_noise_n`` standard deviation, full scale ``full_scale_n``).

A finger that does not slide (|v| < ``SLIDE_MM_S``) sticks: the plate carries no
friction force across it and the sensor reads only noise laterally.

Where each range of :func:`draw_finger` comes from (the figures we could not read in a
source are our assumptions, stated as such):

- ``b``, ``k``: seed 003 gives one pair (1.67 /um, 1.13 /N) and says mu' is "the invariant
  for similar conditions between different subjects" (Fig. 1b) while its section 3
  stresses that friction "is greatly variable for different subjects". Huloux, Monnoyer,
  Boyron and Wiertlewski, "Overcoming the variability of fingertip friction with
  surface-haptic force-feedback", EuroHaptics 2018 (LNCS 10894, doi
  10.1007/978-3-319-93399-3_29; abstract and introduction read at
  https://cupdf.com/document/overcoming-the-variability-of-ngertip-friction-with-overcoming-the-variability-of.html)
  say the open-loop transfer "varies with a wide range of external parameters such as
  velocity of exploration or moisture" without a figure we could read. Our assumption:
  b uniform in [1.1, 2.4] /um and k in [0.75, 1.35] /N (seed 003's values +-35 %
  and +-20 %; a larger k puts seed 003's gratings, mu' = 0.6 at 0.5 N, out of reach).
- ``mu0``: friction at rest of a finger on glass. Pasumarty, Johnson, Watson and Adams,
  "Friction of the human finger pad: influence of moisture, occlusion and velocity",
  Tribology Letters 44 (2011), and Tomlinson, Lewis and Carre's review (Proc. IMechE J
  221, 2007) report coefficients from about 0.3 to beyond 1 and several-fold between
  people (titles and abstracts read; no table). Our assumption: log-uniform in [0.3, 1.5].
- moisture drift: Dzidek, Bochereau, Johnson, Hayward and Adams, "Why pens have rubbery
  grips", PNAS 114 (2017) 10864-10869, doi 10.1073/pnas.1706233114 (abstract read):
  contact with glass grows by first-order kinetics driven by sweat, saturating within
  about 20 s of loading; Dzidek, Adams, Andrews, Zhang and Johnson, "Contact mechanics of
  the human finger pad under compressive loads", J. R. Soc. Interface 14 (2017) 20160935
  (abstract read): against glass the friction coefficient rises at contact times over
  10 s, put down to occluded sweat; Huloux et al. name "sweating and the
  subsequent softening of the stratum corneum" as inducing "large changes in the
  friction with time". Gueorguiev, Vezzoli, Mouraux, Lemaire-Semail and Thonnard, "The
  tactile perception of transient changes in friction", J. R. Soc. Interface 14 (2017)
  20170641 (abstract read): "humid fingers experienced less friction reduction than drier
  ones for the same intensity of ultrasonic vibration". Our assumption: mu0 rises by
  ``mu0_drift`` in [0.1, 0.6] with
  ``tau`` in [30, 240] s, and the reduction weakens with it, ``k_drift`` in [0, 0.15].
- speed: Huloux et al. (above) name velocity; Pasumarty et al. study it. Our assumption:
  ``v_c`` in [150, 600] mm/s (at 100 mm/s, b drops by 14-40 %).
- sensor: Huloux et al.'s sensor picks up "subtle fluctuations of the frictional force
  on a wide frequency bandwidth that includes static forces"; our assumption: 2 mN
  lateral and 5 mN normal noise (standard deviation per sample), 1 kHz bandwidth,
  0.5 ms delay, 5 N full scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

#: below this sliding speed (mm/s) the finger sticks: no measurable friction
SLIDE_MM_S = 2.0


@dataclass(frozen=True)
class FingerParams:
    """One person's fingertip (see the module docstring for every range and its source).

    mu0 : friction coefficient at rest at the start of the session. b_per_um (1/um),
    k_per_n (1/N): seed 003 eq 2's constants for this person. mu0_drift, k_drift :
    relative rise of mu0 and of k once fully moist. tau_s : moisture time constant (s).
    t0_s : how long the session has already run when the simulation starts (s).
    v_c_mm_s : sliding speed at which b is halved (mm/s).
    """

    mu0: float = 0.8
    b_per_um: float = 1.67
    k_per_n: float = 1.13
    mu0_drift: float = 0.0
    k_drift: float = 0.0
    tau_s: float = 120.0
    t0_s: float = 0.0
    v_c_mm_s: float = np.inf


@dataclass(frozen=True)
class SensorParams:
    """The plate's amplitude loop and the force sensors (module docstring, steps 1 and 4)."""

    plate_bw_hz: float = 400.0
    skin_bw_hz: float = 90.0
    sensor_bw_hz: float = 1000.0
    sensor_delay_s: float = 0.0005
    lateral_noise_n: float = 0.002
    normal_noise_n: float = 0.005
    full_scale_n: float = 5.0


#: the population's ranges (module docstring): name -> (low, high, "uniform" | "log")
RANGES = {
    "mu0": (0.3, 1.5, "log"),
    "b_per_um": (1.1, 2.4, "uniform"),
    "k_per_n": (0.75, 1.35, "uniform"),
    "mu0_drift": (0.1, 0.6, "uniform"),
    "k_drift": (0.0, 0.15, "uniform"),
    "tau_s": (30.0, 240.0, "log"),
    "t0_s": (0.0, 60.0, "uniform"),
    "v_c_mm_s": (150.0, 600.0, "uniform"),
}


def draw_finger(seed: int) -> FingerParams:
    """Person ``seed`` of the simulated population (each parameter drawn from ``RANGES``)."""
    rng = np.random.default_rng([seed, 16])
    values = {}
    for name, (lo, hi, scale) in RANGES.items():
        u = rng.uniform()
        values[name] = float(np.exp(np.log(lo) + u * np.log(hi / lo)) if scale == "log"
                             else lo + u * (hi - lo))
    return FingerParams(**values)


def moisture(t_s, finger: FingerParams) -> np.ndarray:
    """Moisture state m(t) in [0, 1) at simulation time ``t_s`` (s)."""
    return -np.expm1(-(finger.t0_s + np.asarray(t_s, dtype=np.float64)) / finger.tau_s)


def true_mu(w_um, normal_n, speed_mm_s, t_s, finger: FingerParams) -> np.ndarray:
    """The relative friction mu' this finger gets (module docstring, step 2); arrays broadcast.

    w_um : plate amplitude (um). normal_n : normal force (N). speed_mm_s : sliding speed.
    t_s : simulation time (s). Returns mu' in (0, 1].
    """
    a, b = _constants(normal_n, speed_mm_s, t_s, finger)
    return (1.0 - a) * np.exp(-b * np.asarray(w_um, dtype=np.float64)) + a  # seed 003, eq 2


def _constants(normal_n, speed_mm_s, t_s, finger: FingerParams):
    """This finger's asymptote A and decay b (1/um) now (module docstring, step 2)."""
    m = moisture(t_s, finger)
    a = np.minimum(finger.k_per_n * (1.0 + finger.k_drift * m) * np.asarray(normal_n), 0.98)
    return a, finger.b_per_um / (1.0 + np.abs(np.asarray(speed_mm_s)) / finger.v_c_mm_s)


def true_amplitude(mu, normal_n, speed_mm_s, t_s, finger: FingerParams, limit_um: float
                   ) -> np.ndarray:
    """The amplitude (um, in [0, limit]) giving this finger mu' (seed 003, eq 3 with its
    own constants): what a controller knowing the finger exactly would ask for."""
    a, b = _constants(normal_n, speed_mm_s, t_s, finger)
    reduction = np.clip((1.0 - np.asarray(mu, dtype=np.float64)) / (1.0 - a), 0.0, 1.0)
    with np.errstate(divide="ignore"):
        w = -np.log1p(-reduction) / b
    return np.minimum(w, limit_um)


def rest_mu(t_s, finger: FingerParams) -> np.ndarray:
    """Friction coefficient at rest mu0(t) (module docstring, step 3)."""
    return finger.mu0 * (1.0 + finger.mu0_drift * moisture(t_s, finger))


def pole(bw_hz: float, rate_hz: float) -> float:
    """Pole of the one-pole low-pass with -3 dB near ``bw_hz`` sampled at ``rate_hz``."""
    return float(np.exp(-2.0 * np.pi * bw_hz / rate_hz))


@dataclass(frozen=True)
class FingerState:
    """Filter states carried between blocks: plate amplitude (um), skin lateral force (N),
    sensor lateral and normal force (N), and the sensor's delay line (N, 2 x d)."""

    plate: float = 0.0
    skin: float = 0.0
    sensor_t: float = 0.0
    sensor_n: float = 0.0
    delay: tuple = ()


@dataclass(frozen=True, eq=False)
class FingerBlock:
    """One block at the finger, every array (n,): plate amplitude (um), delivered mu',
    and what the sensors report: lateral and normal force (N)."""

    amplitude_um: np.ndarray
    delivered_mu: np.ndarray
    lateral_n: np.ndarray
    normal_n: np.ndarray


class FingerPlant:
    """Seed 003's plate under one finger, block by block (see the module docstring).

    ``step(index0, commands_um, speed_mm_s, normal_n, state)`` runs ``n`` samples starting
    at output index ``index0`` (time ``index0 / rate_hz``). The sensor noise of a block is
    drawn from (``seed``, ``index0``): a run with the same blocks is the same run.
    """

    def __init__(self, finger: FingerParams, rate_hz: float, limit_um: float,
                 sensor: SensorParams = SensorParams(), seed: int = 0):
        self.finger = finger
        self.sensor = sensor
        self.rate_hz = float(rate_hz)
        self.limit_um = float(limit_um)
        self.seed = int(seed)
        self.plate_pole = pole(sensor.plate_bw_hz, rate_hz)
        self._skin = pole(sensor.skin_bw_hz, rate_hz)
        self._sensor = pole(sensor.sensor_bw_hz, rate_hz)
        self.delay_samples = int(round(sensor.sensor_delay_s * rate_hz))

    def initial_state(self) -> FingerState:
        return FingerState(delay=((0.0,) * self.delay_samples, (0.0,) * self.delay_samples))

    def step(self, index0: int, commands_um, speed_mm_s, normal_n, state: FingerState
             ) -> tuple[FingerBlock, FingerState]:
        """Run one block; arrays (n,). Returns (what happened, the state after)."""
        cmd = np.clip(np.nan_to_num(np.asarray(commands_um, dtype=np.float64)), 0.0, self.limit_um)
        n = cmd.size
        t = (index0 + np.arange(n)) / self.rate_hz
        w, zp = lowpass(cmd, self.plate_pole, state.plate)
        speed = np.abs(np.asarray(speed_mm_s, dtype=np.float64))
        force = np.maximum(np.asarray(normal_n, dtype=np.float64), 0.0)
        mu = true_mu(w, force, speed, t, self.finger)
        sliding = speed >= SLIDE_MM_S
        lateral = np.where(sliding, rest_mu(t, self.finger) * mu * force, 0.0)
        skin, zs = lowpass(lateral, self._skin, state.skin)
        lat_s, zt = lowpass(skin, self._sensor, state.sensor_t)
        nor_s, zn = lowpass(force, self._sensor, state.sensor_n)
        d = self.delay_samples
        lat_d = np.concatenate([state.delay[0], lat_s])
        nor_d = np.concatenate([state.delay[1], nor_s])
        rng = np.random.default_rng([self.seed, index0])
        s = self.sensor
        lat_out = lat_d[:n] + s.lateral_noise_n * rng.standard_normal(n)
        nor_out = nor_d[:n] + s.normal_noise_n * rng.standard_normal(n)
        lat_out = np.clip(lat_out, -s.full_scale_n, s.full_scale_n)
        nor_out = np.clip(nor_out, -s.full_scale_n, s.full_scale_n)
        delay = (tuple(lat_d[n:n + d] if d else ()), tuple(nor_d[n:n + d] if d else ()))
        out = FingerBlock(amplitude_um=w, delivered_mu=mu, lateral_n=lat_out, normal_n=nor_out)
        return out, FingerState(plate=zp, skin=zs, sensor_t=zt, sensor_n=zn, delay=delay)


def lowpass(x: np.ndarray, pole: float, y0: float) -> tuple[np.ndarray, float]:
    """One-pole low-pass y[i] = p y[i-1] + (1 - p) x[i] from y[-1] = ``y0``; (y, y[-1])."""
    if x.size == 0:
        return x.copy(), y0
    y, _ = lfilter([1.0 - pole], [1.0, -pole], x, zi=[pole * y0])
    return y, float(y[-1])
