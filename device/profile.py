"""The device vocabulary: which actuation a scene is for, its structure and its limits.

Frozen dataclasses built by ``textures.loader`` from a scene's ``[device]`` table and
trusted by the rest of frictex (units of DESIGN.md: mm, N, um zero-to-peak). They live
here, beside the hardware they describe, so that ``device`` never needs the texture
file format. ``device.friction`` evaluates the friction model with these constants.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

from frictex.device.registry import Expect, Registry

V = TypeVar("V")

#: How the modal profiles turn wanted amplitudes into actuator commands
#: (``device.actuation.modal.solve``).
METHODS = ("exact", "regularised", "bounded")
#: the beam theories ``device.structures.beam`` computes a beam's modes with
THEORIES = ("euler-bernoulli", "timoshenko")
#: chosen by measurement (``frictex bench modal``, device/MODES.md)
DEFAULT_METHOD = "regularised"
#: regularisation threshold, relative to the largest singular value (device/MODES.md)
DEFAULT_RCOND = 0.1

#: the profile of a ``[device]`` table that names none
DEFAULT_PROFILE = "plate-seed003"


@dataclass(frozen=True)
class FrictionParams:
    """Constants of the seed 003 friction model (eq 2).

    ``b_per_um`` is the decay constant b (1/um); the asymptote is
    ``asymptote_per_n * F_n`` (seed 003: 1.13 F_n). The model holds while that
    asymptote is below 1 (F_n < 0.885 N with seed 003's constants); ``device.friction``
    says what frictex does beyond.
    """

    b_per_um: float = 1.67
    asymptote_per_n: float = 1.13


@dataclass(frozen=True)
class Calibration:
    """A measured friction curve: mu' against amplitude at one or more normal forces.

    ``mu[i][j]`` is mu' at ``forces_n[i]`` and ``amplitudes_um[j]``; each row starts
    at amplitude 0 (mu' = 1) and decreases monotonically.
    """

    amplitudes_um: tuple[float, ...]
    forces_n: tuple[float, ...]
    mu: tuple[tuple[float, ...], ...]


@dataclass(frozen=True)
class DrivingForceParams:
    """Constants of the tangential model (defaults: seed 004, Fig. 3c; seed 002 finger).

    mu0 : friction coefficient of the finger on the plate at rest (F_f = mu0 F_n mu').
    slope_per_um : k_p, driving force per um of travelling amplitude per N of normal
        force (seed 004: 0.13 N/um at 1 N), 1/um.
    threshold_um : w_th, travelling amplitude below which there is no driving force
        (seed 004: "near 1 um").
    v_hold_mm_s : speed below which the finger's direction of motion is held, and below
        which a finger counts as still (only the driving force acts on it).
    """

    mu0: float = 0.5
    slope_per_um: float = 0.13
    threshold_um: float = 1.0
    v_hold_mm_s: float = 2.0


@dataclass(frozen=True)
class BeamStructure:
    """Seed 000's free-free beam for ``profile = "beam-seed000"``; defaults from its Table I.

    Material and size as ``device.structures.beam.FreeFreeBeam`` takes them; ``orders`` the
    flexural modes driven (seed 000: 16 and 17); ``actuators_mm`` the transducer
    positions along the beam, one per mode (seed 000 section III.C: 60 mm from each
    end); ``x0_mm`` the display x of the beam's end x = 0 (the beam runs along the
    display's x axis; display y is across the beam and does not enter its modes).
    ``channel_limit_um`` the largest amplitude each transducer is asked for (um
    zero-to-peak): seed 001's amplifiers stop at 300 V peak-to-peak, about 0.75 um if
    seed 000's 160 V peak-to-peak (Fig. 11) drove exactly eq 14's actuator A amplitude,
    0.41 um (frictex's assumption: the paper gives the voltage, not that pairing).
    ``method`` and ``rcond`` are ``device.actuation.modal.solve``'s. ``modes``: a measured mode table
    (``device.structures.measured_modes.MeasuredModes``, one column per mode) that replaces the
    modelled shapes, read from ``modes_path``.
    """

    length_mm: float = 350.0
    width_mm: float = 6.0
    thickness_mm: float = 6.0
    youngs_gpa: float = 57.0
    density_kg_m3: float = 2561.0
    poisson: float = 0.33
    theory: str = "euler-bernoulli"
    orders: tuple[int, ...] = (16, 17)
    actuators_mm: tuple[float, ...] = (60.0, 290.0)
    x0_mm: float = 0.0
    channel_limit_um: float = 0.75
    method: str = DEFAULT_METHOD
    rcond: float = DEFAULT_RCOND
    modes_path: Path | None = None
    modes: object | None = None


@dataclass(frozen=True)
class PlateStructure:
    """Seed 001's 2D plate for ``profile = "plate-seed001"``: modes X and Y of order k.

    Size and order from seed 001 section 4 (140 x 140 x 4 mm, k = 8). Seed 001 does not
    name the material: the default is seed 000's aluminium (Table I, same laboratory),
    whose strip estimate (``device.structures.plate2d``) gives 33.4 kHz against the 33.0 kHz seed 001
    measured. (x0_mm, y0_mm) is the display position of the plate's corner (0, 0).
    ``channel_limit_um``: largest |V_AC|, |V_BD| (um of modal amplitude, unit gain);
    None means the device's ``amplitude_limit_um`` (seed 001 gives no figure for the plate).
    """

    width_mm: float = 140.0
    height_mm: float = 140.0
    thickness_mm: float = 4.0
    youngs_gpa: float = 57.0
    density_kg_m3: float = 2561.0
    poisson: float = 0.33
    order: int = 8
    x0_mm: float = 0.0
    y0_mm: float = 0.0
    channel_limit_um: float | None = None
    method: str = DEFAULT_METHOD
    rcond: float = DEFAULT_RCOND


StructureSpec = BeamStructure | PlateStructure


@dataclass(frozen=True)
class ProfileSpec:
    """What frictex knows of one device profile, besides a scene's own ``[device]`` values.

    summary : one line for listings.
    actuation : the name of its actuation (``device.actuation.factory.ACTUATIONS``).
    structure : the class of its ``[device.structure]`` table (modal profiles), else None.
    surface_length_mm : travelling-wave profiles, the only ones that push a finger (they
        take force layers and ``[device.driving]``): touch-surface length along x (mm),
        which the display must fit on; else None.
    friction_loop : seed 003's friction loop can run on it (the lateral force is sensed
        and seed 003's model applies: ``rendering.control.loop``).
    carrier_hz : the plate's working resonance (Hz), the carrier an audio interface
        synthesises for it (``device.audio``).
    um_per_volt : vibration amplitude (um zero-to-peak) per volt (zero-to-peak) of drive
        at the carrier; ``frictex calibrate`` fits it where a sensor reports.
    voltage_limit_v : the largest drive (V zero-to-peak) the amplifier may be asked for;
        the audio output clamps there and counts the clamps.
    amplitude_is_drive : the amplitude under a finger is one channel's drive (one mode,
        all actuators together), so :attr:`drive_reach_um` bounds it (``frictex
        validate`` warns on a scene's ``amplitude_limit_um`` above); False where the
        amplitude under a finger combines channels (modal, travelling-wave profiles),
        whose ``channel_limit_um`` (modal) and ``amplitude_limit_um`` (travelling wave:
        each mode is driven up to the wave's amplitude) ``validate`` compares with it.
    """

    summary: str
    actuation: str
    structure: type | None = None
    surface_length_mm: float | None = None
    friction_loop: bool = False
    carrier_hz: float = 0.0
    um_per_volt: float = 0.0
    voltage_limit_v: float = 0.0
    amplitude_is_drive: bool = False

    @property
    def drive_reach_um(self) -> float:
        """The largest amplitude (um zero-to-peak) one channel's drive reaches:
        ``um_per_volt`` at ``voltage_limit_v``."""
        return self.um_per_volt * self.voltage_limit_v

    def __post_init__(self):
        # a plugin's profile that names no drive figures gets the documented defaults
        for name, default in (("carrier_hz", DEFAULT_CARRIER_HZ),
                              ("um_per_volt", DEFAULT_UM_PER_VOLT),
                              ("voltage_limit_v", DEFAULT_VOLTAGE_LIMIT_V)):
            if not getattr(self, name) > 0:
                object.__setattr__(self, name, default)


#: Drive figures of a profile that gives none (a plugin's). 30 kHz sits in the 26-40 kHz
#: band of the plates of seeds 000, 001, 002 and 004. Seed 003 names its plate's resonance
#: (:data:`SEED003_CARRIER_HZ`) but not its drive voltage: 0.02 um/V puts the default
#: 2.5 um limit at 125 V zero-to-peak, inside the 150 V of seed 001's amplifiers (300 V
#: peak-to-peak). Measure a real plate and set its own.
DEFAULT_CARRIER_HZ = 30_000.0
#: seed 003, section 4.2: "a glass plate 154 x 81 x 1.6 mm^3 resonating at 60750 Hz"; at
#: the audio output's 0.4 share of the rate it needs a rate above 151.875 kHz (192 kHz)
SEED003_CARRIER_HZ = 60_750.0
DEFAULT_UM_PER_VOLT = 0.02
DEFAULT_VOLTAGE_LIMIT_V = 150.0
#: seed 000: eq 14's actuator A amplitude, 0.4093 um (eq 10 from eqs 12-13 for 0.4 um
#: zero-to-peak under one finger and 0 under the other), over the 160 V peak-to-peak (80 V
#: zero-to-peak) of Fig. 11; assumes that voltage produced exactly that amplitude, which
#: the paper does not say
SEED000_UM_PER_VOLT = 0.41 / 80.0
#: seed 004, sections III.A and IV.B: its amplifiers at most +-80 V, its amplitude at most
#: +-3 um (the default 0.02 um/V reached only 1.6 um there)
SEED004_UM_PER_VOLT = 3.0 / 80.0


#: The device profiles a scene's ``[device] profile`` may name: the one table of them.
#: Another package adds one under entry-point group ``frictex.profiles`` (a
#: :class:`ProfileSpec` naming an actuation it registers under ``frictex.actuations``); an
#: entry that is not a :class:`ProfileSpec` is refused (a warning naming it, an error where
#: a scene names it).
PROFILES: Registry[ProfileSpec] = Registry("device profile", "frictex.profiles",
                                           expect=Expect.instance_of(ProfileSpec))
PROFILES.register(DEFAULT_PROFILE, ProfileSpec(
    "single-mode glass plate of seed 003, one channel", "single-mode", friction_loop=True,
    carrier_hz=SEED003_CARRIER_HZ, amplitude_is_drive=True))
PROFILES.register("beam-seed000", ProfileSpec(
    "free-free aluminium beam of seed 000, modes 16 and 17, two actuators", "modal",
    structure=BeamStructure, carrier_hz=28_000.0, um_per_volt=SEED000_UM_PER_VOLT,
    voltage_limit_v=150.0))  # seed 000: "resonance of the beam is around 28 kHz"
PROFILES.register("plate-seed001", ProfileSpec(
    "2D plate of seed 001, X and Y modes, channels V_AC and V_BD", "modal",
    structure=PlateStructure, carrier_hz=33_000.0, um_per_volt=SEED000_UM_PER_VOLT,
    voltage_limit_v=150.0))  # seed 001: 33.0 kHz measured; same laboratory as seed 000
PROFILES.register("travelling-beam-seed002", ProfileSpec(
    "600 mm aluminium beam of seed 002, travelling wave from modes 28 and 29, two actuators",
    "travelling-beam", surface_length_mm=600.0, carrier_hz=28_300.0))  # seed 002: 28.3 kHz
PROFILES.register("ring-seed004", ProfileSpec(
    "Ultraloop ring of seed 004, degenerate 24th-order pair, phase-shift control",
    "travelling-ring", surface_length_mm=140.0, carrier_hz=39_500.0,
    um_per_volt=SEED004_UM_PER_VOLT, voltage_limit_v=80.0))  # seed 004: 39.5 kHz, +-80 V


class ProfileTable(Mapping[str, V]):
    """A table derived from :data:`PROFILES`: ``value(spec)`` of each profile that loads,
    by name, where that is not None. It is read from the registry each time it is used
    (``in``, a lookup, a listing: load-time checks and messages), so that a profile
    registered after frictex was imported, or after a scene was read, is in it, also
    where the table was imported by name; importing this module imports no plugin. A
    plugin's profile that cannot be loaded is left out with a warning (an error where a
    scene names it)."""

    def __init__(self, value: Callable[[ProfileSpec], V | None]):
        self._value = value

    def now(self) -> dict[str, V]:
        """The table as it is now."""
        table = {name: self._value(spec) for name, spec in PROFILES.loaded().items()}
        return {name: value for name, value in table.items() if value is not None}

    def __getitem__(self, name: str) -> V:
        return self.now()[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self.now())

    def __len__(self) -> int:
        return len(self.now())

    def __repr__(self) -> str:
        return f"ProfileTable({self.now()})"


#: every profile, with its one line
DEVICE_PROFILES: ProfileTable[str] = ProfileTable(lambda spec: spec.summary)
#: the travelling-wave profiles (seed 002, seed 004), the only ones that can push a finger,
#: so the only ones that accept force layers and ``[device.driving]``, with the
#: touch-surface length along x (mm) of each
FORCE_PROFILES: ProfileTable[float] = ProfileTable(lambda spec: spec.surface_length_mm)
#: the same table, read for each one's touch-surface length along x (mm)
SURFACE_LENGTH_MM = FORCE_PROFILES
#: the profiles driven by modal control (seed 000 eq 10, seed 001 eqs 4-5), with the class
#: of the ``[device.structure]`` table of each (:class:`BeamStructure` or
#: :class:`PlateStructure`)
MODAL_PROFILES: ProfileTable[type] = ProfileTable(lambda spec: spec.structure)
#: the profiles seed 003's friction loop runs on (``rendering.control.loop``), with their
#: one line
FRICTION_LOOP_PROFILES: ProfileTable[str] = ProfileTable(
    lambda spec: spec.summary if spec.friction_loop else None)


@dataclass(frozen=True)
class FittedOn:
    """What a ``frictex calibrate`` fit was measured on (``[device.fitted]``): the
    device's name from its handshake (``device.link.protocol.Info.name``) and, for the
    simulated device, the simulated finger (person number; None for a real finger); the
    finger's sliding speed during the sweep (mm/s; None: not recorded), at which the
    fitted b holds (seed 003's b falls as the finger speeds up)."""

    device: str
    finger: int | None = None
    speed_mm_s: float | None = None


@dataclass(frozen=True)
class DeviceProfile:
    """Which actuation the scene is for, and the limits of that device.

    ``profile`` names the device (one of :data:`PROFILES`: :data:`DEFAULT_PROFILE`, the
    single-mode glass plate of seed 003, one channel; the modal profiles of
    :data:`MODAL_PROFILES`; the travelling-wave ones of :data:`FORCE_PROFILES`).
    ``amplitude_limit_um`` is the zero-to-peak amplitude the host never asks for under a
    finger; ``normal_force_n`` the nominal finger force used where a trace gives none and
    for ``frictex validate``'s reachability warnings. ``structure`` describes the
    vibrating structure of a modal profile (None for the others).
    """

    profile: str = DEFAULT_PROFILE
    amplitude_limit_um: float = 2.5
    normal_force_n: float = 0.5
    friction: FrictionParams = field(default_factory=FrictionParams)
    calibration: Calibration | None = None
    #: what the friction constants were fitted on (None: not by ``frictex calibrate``, or
    #: by a version that did not record it)
    fitted: FittedOn | None = None
    structure: StructureSpec | None = None
    #: the driving-force model of the travelling-wave profiles (:data:`FORCE_PROFILES`)
    driving: DrivingForceParams = field(default_factory=DrivingForceParams)
