"""What a calibration was fitted on, and a warning when it is used on something else.

``frictex calibrate`` writes, beside the fitted constants, a ``[device.fitted]`` table: the
device's name from its handshake (``device.link.protocol.Info.name``) and, for the
simulated device, its simulated finger (``device.profile.FittedOn``). Friction differs
several-fold from one finger to the next (``device.finger``), so constants fitted on one
finger or plate misdescribe another; a replay to a device checks the scene's record
against the device it streams to (:func:`mismatch`). A file written before the table
existed has none, and is used as before, unchecked.

The fit's bounds (``B_BOUNDS``, ``K_BOUNDS``) are here, beside what a calibration was
fitted on, so a texture file's loader can say where its constants lie beyond anything
the fit gives (:func:`outside_fit`) without importing the fit (and scipy).
"""

from __future__ import annotations

from frictex.device.profile import FittedOn, FrictionParams

#: bounds of the fit (``device.calibration_fit``): b (1/um), k (1/N)
B_BOUNDS = (0.05, 20.0)
K_BOUNDS = (0.0, 5.0)
#: seed 003's measured constants (eq 2)
_SEED = FrictionParams()


def outside_fit(params: FrictionParams) -> list[tuple[str, str]]:
    """(key, one-line warning) for each constant of seed 003's eq 2 beyond what the fit
    allows: b outside ``B_BOUNDS`` (1/um), k above ``K_BOUNDS`` (1/N; below 0 the loader
    refuses it)."""
    found = []
    low, high = B_BOUNDS
    if not low <= params.b_per_um <= high:
        found.append(("b_per_um", f"{params.b_per_um:g} /um is outside the {low:g} to {high:g} "
                                  f"/um frictex calibrate's fit allows (seed 003 measured "
                                  f"{_SEED.b_per_um:g} /um): a typo or a wrong unit?"))
    if params.asymptote_per_n > K_BOUNDS[1]:
        found.append(("asymptote_per_n", f"{params.asymptote_per_n:g} /N is above the "
                                         f"{K_BOUNDS[1]:g} /N frictex calibrate's fit allows "
                                         f"(seed 003 measured {_SEED.asymptote_per_n:g} /N): "
                                         f"a typo or a wrong unit?"))
    return found


def toml_lines(fitted: FittedOn) -> list[str]:
    """The ``[device.fitted]`` table's lines."""
    lines = ["[device.fitted]          # what the constants above were fitted on",
             f"device = {_quoted(fitted.device)}"]
    if fitted.finger is not None:
        lines.append(f"finger = {int(fitted.finger)}")
    if fitted.speed_mm_s is not None:
        lines.append(f"speed_mm_s = {float(fitted.speed_mm_s)!r}")
    return lines


def _quoted(text: str) -> str:
    """A TOML basic string of ``text`` (backslashes, quotes and control characters escaped)."""
    out = []
    for c in text:
        if c in '"\\':
            out.append("\\" + c)
        elif ord(c) < 0x20 or ord(c) == 0x7F:
            out.append(f"\\u{ord(c):04x}")
        else:
            out.append(c)
    return '"' + "".join(out) + '"'


def simulated_finger(device: str | None, sim_args=()) -> int | None:
    """The simulated finger a ``--device`` spec and ``frictex sim-device`` flags start
    (the last ``finger`` given; person number), or None: another device, or none given."""
    if device is None:
        return None
    import importlib
    importlib.import_module("frictex.device.link.host")  # registers the built-in devices
    from frictex.device.link.devices import DEVICES, resolve, sim_pairs
    factory, arg = resolve(device)
    if factory is not DEVICES.get("sim"):
        return None
    fingers = [value for name, value in sim_pairs(arg, tuple(sim_args)) if name == "finger"]
    try:
        return int(fingers[-1]) if fingers else None
    except ValueError:
        return None  # the device refuses it itself, naming it


def mismatch(fitted: FittedOn | None, device_name: str, finger: int | None) -> str | None:
    """A one-line warning when the scene's friction constants were fitted on another device
    (handshake name) or another simulated finger than the one streamed to; None when they
    match, or the scene records nothing (a file from before ``[device.fitted]``)."""
    if fitted is None:
        return None
    other = []
    if fitted.device and device_name and fitted.device != device_name:
        other.append(f"device {fitted.device!r} (this is {device_name!r})")
    if fitted.finger is not None and finger != fitted.finger:
        now = "a finger not simulated" if finger is None else f"simulated finger {finger}"
        other.append(f"simulated finger {fitted.finger} (this is {now})")
    if not other:
        return None
    return ("[device.friction] was fitted by frictex calibrate on " + " and ".join(other)
            + ": friction differs from finger to finger and plate to plate; calibrate "
              "again on this one")
