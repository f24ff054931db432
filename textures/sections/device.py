"""``[display]`` and ``[device]`` with its sub-tables (friction, calibration, structure,
driving): checked into ``textures.model.Display`` and ``device.profile.DeviceProfile``."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from frictex.device import profile as profiles
from frictex.device.calibration_identity import outside_fit
from frictex.device.friction import ASYMPTOTE_MARGIN
from frictex.device.structures.beam import MAX_MODES, ModesError
from frictex.textures import model
from frictex.device.safe_text import escape, escape_path
from frictex.textures.errors import KeyPath, TextureError
from frictex.textures.keys import (CALIBRATION, DEVICE, DISPLAY, DRIVING, FITTED, FRICTION,
                                   STRUCTURES)
from frictex.textures.schema import BAD, Reader, Retired, show
from frictex.textures.sections.common import strictly_increasing
from frictex.textures.sections.files import Files
from frictex.textures.toml_safe import MAX_FILE_BYTES


def parse_display(r: Reader, doc: dict) -> model.Display | None:
    if "display" not in doc:
        r.report(("display",), "missing [display] table (width_mm, height_mm, width_px, height_px)")
        return None
    v = r.table(doc["display"], ("display",), DISPLAY)
    if v is None or BAD in v.values():
        return None
    return model.Display(**v)


def parse_device(r: Reader, doc: dict, display, files: Files) -> profiles.DeviceProfile | None:
    raw = doc.get("device", {})
    if isinstance(raw, dict):
        _refuse_broken_plugin(raw.get("profile"))
    v = r.table(raw, ("device",), DEVICE,
                tables=("friction", "fitted", "calibration", "structure", "driving"))
    if v is None:
        return None
    friction = r.table(raw.get("friction", {}), ("device", "friction"), FRICTION)
    fitted = None
    if "fitted" in raw:
        fitted = r.table(raw["fitted"], ("device", "fitted"), FITTED)
        fitted = BAD if fitted is None or BAD in fitted.values() else profiles.FittedOn(**fitted)
    calibration = None
    if "calibration" in raw:
        calibration = _calibration(r, raw["calibration"], ("device", "calibration"))
    structure = None
    if v["profile"] in STRUCTURES:
        structure = _structure(r, v["profile"], raw.get("structure", {}), display, files)
    elif "structure" in raw and v["profile"] is not BAD:
        r.report(("device", "structure"), f"not used with profile {show(v['profile'])}; only "
                                          f"the modal profiles have one: "
                                          f"{', '.join(profiles.MODAL_PROFILES)}")
        structure = BAD
    if (friction is None or BAD in friction.values() or BAD in v.values()
            or BAD in (calibration, structure, fitted)):
        return None
    device = profiles.DeviceProfile(friction=profiles.FrictionParams(**friction), calibration=calibration,
                                 fitted=fitted, structure=structure, **v)
    if structure is not None and not _actuation_builds(r, device):
        return None
    return device


def _refuse_broken_plugin(name) -> None:
    """Raise the :class:`~frictex.device.registry.PluginError` (naming its package) of
    another package's device profile ``name`` that is installed but cannot be loaded or
    is no profile: the profiles a file may name leave it out (with a warning, once a
    process), and "is not one of" would hide why."""
    if isinstance(name, str) and name not in DEVICE["profile"].options and name in profiles.PROFILES:
        profiles.PROFILES.get(name)


def _structure(r: Reader, profile: str, raw, display, files: Files):
    """``[device.structure]`` of a modal profile -> BeamStructure | PlateStructure, or BAD."""
    path: KeyPath = ("device", "structure")
    v = r.table(raw, path, STRUCTURES[profile])
    if v is None or BAD in v.values():
        return BAD
    if profiles.PROFILES.get(profile).structure is profiles.PlateStructure:
        ok = _structure_holds_display(r, path, display, ("x0_mm", "width_mm", "width_mm"),
                                      v["x0_mm"], v["width_mm"])
        ok &= _structure_holds_display(r, path, display, ("y0_mm", "height_mm", "height_mm"),
                                       v["y0_mm"], v["height_mm"])
        return profiles.PlateStructure(**v) if ok else BAD
    ok = _structure_holds_display(r, path, display, ("x0_mm", "length_mm", "width_mm"),
                                  v["x0_mm"], v["length_mm"])
    orders, actuators = v["orders"], v["actuators_mm"]
    shown = [int(o) if o == int(o) else o for o in orders]  # as written: 16, not 16.0
    broken = next((f"{o:g} is not a whole mode order" for o in orders if o != int(o)), None)
    twice = next((o for i, o in enumerate(shown) if o in shown[:i]), None)
    if broken is None and twice is not None:
        broken = f"{twice} is given twice; expected distinct mode orders"
    if broken is None and len(orders) > MAX_MODES:
        broken = f"{len(orders)} orders; at most {MAX_MODES}"
    if broken is not None:
        r.report(path + ("orders",), f"{show(shown)}: {broken}")
        ok = False
    modes = modes_path = None
    if v["modes_file"] is not None:
        got = _modes_table(r, path, v["modes_file"], raw, files)
        ok &= got is not None
        modes_path, modes = got if got is not None else (None, None)
    n_modes = len(modes.names) if modes is not None else len(orders)
    if len(actuators) != n_modes:
        r.report(path + ("actuators_mm",), f"has {len(actuators)} positions, expected one per mode "
                                           f"({n_modes})")
        ok = False
    off = [a for a in actuators if not 0.0 <= a <= v["length_mm"]]
    if off:
        r.report(path + ("actuators_mm",), f"{off[0]:g} mm is off the {v['length_mm']:g} mm beam")
        ok = False
    if not ok:
        return BAD
    v.pop("modes_file")
    return profiles.BeamStructure(**{**v, "orders": tuple(int(o) for o in orders)},
                               modes_path=modes_path, modes=modes)


def _structure_holds_display(r: Reader, path: KeyPath, display, keys, start: float, size: float) -> bool:
    """Report (False) if the display's span along one axis leaves the structure."""
    offset_key, size_key, display_key = keys
    if display is None:
        return True
    extent = getattr(display, display_key)
    if start <= 1e-9 and start + size >= extent - 1e-9:
        return True
    r.report(path + (offset_key,), f"the display's {display_key} (0 to {extent:g} mm) must lie on "
                                   f"the structure, which spans {start:g} to {start + size:g} mm "
                                   f"({offset_key} {start:g}, {size_key} {size:g})")
    return False


def _modes_table(r: Reader, path: KeyPath, name: str, raw: dict, files: Files):
    """(real path, MeasuredModes) of ``modes_file``, or None with the problem reported."""
    if "orders" in raw:
        r.report(path + ("orders",), "not used with modes_file (the table's columns are the "
                                     "modes); remove one of them")
        return None
    return files.read(r, path + ("modes_file",), name, _read_modes)


def _read_modes(modes_path):
    """``MeasuredModes.from_csv``, its problems as TextureError starting with the path."""
    from frictex.device.structures.measured_modes import MeasuredModes

    try:
        # the table's reader checks its grammar; values that overflow the spline fit come
        # out as ValueError or (with errstate) FloatingPointError
        with np.errstate(all="raise"):
            return MeasuredModes.from_csv(modes_path, MAX_FILE_BYTES)
    except ModesError as exc:  # its message starts with the file's path
        raise TextureError(str(exc)) from None
    except (ValueError, FloatingPointError) as exc:
        raise TextureError(f"{escape_path(modes_path)}: deflections too large to fit splines "
                           f"through ({escape(exc)})") from None


def _actuation_builds(r: Reader, device: profiles.DeviceProfile) -> bool:
    """Build the modal actuation once (modes solved, actuator matrix checked)."""
    from frictex.device.actuation.modal_actuation import make_modal_actuation

    try:
        make_modal_actuation(device)
    except ModesError as exc:
        r.report(("device", "structure"), str(exc))
        return False
    return True


def _calibration(r: Reader, raw, path: KeyPath):
    v = r.table(raw, path, CALIBRATION)
    if v is None or BAD in v.values():
        return BAD
    amps, forces, mu = v["amplitudes_um"], v["forces_n"], v["mu"]
    ok = True
    if amps[0] != 0.0:
        r.report(path + ("amplitudes_um",), f"starts at {amps[0]:g}, expected 0 (um)")
        ok = False
    if not strictly_increasing(amps):
        r.report(path + ("amplitudes_um",), f"{show(list(amps))} is not strictly increasing")
        ok = False
    if not strictly_increasing(forces):
        r.report(path + ("forces_n",), f"{show(list(forces))} is not strictly increasing")
        ok = False
    if len(mu) != len(forces):
        r.report(path + ("mu",), f"has {len(mu)} rows, expected one per force ({len(forces)})")
        ok = False
    for i, row in enumerate(mu):
        where = path + ("mu",)
        label = f"row {i + 1}"
        if len(row) != len(amps):
            r.report(where, f"{label} has {len(row)} values, expected one per amplitude ({len(amps)})")
            ok = False
        elif row[0] != 1.0:
            r.report(where, f"{label} starts at {row[0]:g}, expected 1 (mu' at amplitude 0)")
            ok = False
        elif not strictly_increasing([-m for m in row]):
            r.report(where, f"{label} {show(list(row))} is not strictly decreasing")
            ok = False
    if not ok:
        return BAD
    return profiles.Calibration(amps, forces, mu)


def device_warnings(r: Reader, device: profiles.DeviceProfile) -> None:
    spec = profiles.PROFILES.get(device.profile)
    reach = spec.drive_reach_um
    path, limit_um = _channel_limit(device, spec)
    if path is not None and limit_um > reach * (1.0 + 1e-9):
        r.report(path, f"{limit_um:g} um is above the {reach:.3g} um the drive of profile "
                       f"{show(device.profile)} reaches ({spec.um_per_volt:g} um/V at its "
                       f"{spec.voltage_limit_v:g} V limit): the audio output clamps each "
                       "channel there; a link device (sim, serial) only at its own declared "
                       "limit", warning=True)
    a = device.friction.asymptote_per_n * device.normal_force_n
    if device.calibration is None and a >= 1.0 - ASYMPTOTE_MARGIN:
        r.report(("device", "normal_force_n"),
                 f"{device.normal_force_n:g} N puts seed 003's asymptote (eq 2) at {a:.3g}: the "
                 f"model does not hold there (it needs A < 1) and friction cannot be modulated",
                 warning=True)
    for key, message in outside_fit(device.friction):
        r.report(("device", "friction", key), message, warning=True)


def unused_friction_warnings(r: Reader, doc: dict, device: profiles.DeviceProfile, built) -> None:
    """Warn at each ``[device.friction]`` key given beside ``[device.calibration]``: the
    table replaces seed 003's eq 2, so the key changes nothing unless a force layer's
    tangential force uses it. Not refused: ``frictex calibrate`` writes both where the
    model does not fit, the constants kept for when the table is removed."""
    if device.calibration is None or any(isinstance(layer, model.FORCE_LAYERS)
                                          for layer, _ in built):
        return
    for key in doc["device"].get("friction", {}):
        if key in FRICTION and not isinstance(FRICTION[key], Retired):
            r.report(("device", "friction", key),
                     "has no effect: the [device.calibration] table replaces seed 003's eq 2 "
                     "(remove the table to use this value, or remove the key)", warning=True)


def _channel_limit(device: profiles.DeviceProfile, spec) -> tuple[KeyPath | None, float]:
    """The key and value (um zero-to-peak) of the limit on every channel's command, the
    amplitude one channel's drive must reach: ``[device.structure] channel_limit_um`` of a
    modal profile, ``amplitude_limit_um`` of a one-channel or travelling-wave profile;
    (None, 0) for the others (seed 001's plate without a ``channel_limit_um``, a plugin's)."""
    structure = device.structure
    if structure is not None:
        limit_um = structure.channel_limit_um
        return (None, 0.0) if limit_um is None else (
            ("device", "structure", "channel_limit_um"), limit_um)
    if spec.amplitude_is_drive or spec.surface_length_mm is not None:
        return ("device", "amplitude_limit_um"), device.amplitude_limit_um
    return None, 0.0


def force_device(r: Reader, doc: dict, device, display, built):
    """``[device.driving]`` and the force layers: only on a travelling-wave profile whose
    surface holds the display. Returns the device with its driving model, or None."""
    raw = doc.get("device", {})
    force_profile = device is not None and device.profile in profiles.FORCE_PROFILES
    if device is not None and not force_profile:
        if isinstance(raw, dict) and "driving" in raw:
            r.report(("device", "driving"), f"not used with profile {show(device.profile)}, which "
                                            f"cannot push; travelling-wave profiles: "
                                            f"{', '.join(profiles.FORCE_PROFILES)}")
        for index, (layer, _) in enumerate(built or ()):
            if isinstance(layer, model.FORCE_LAYERS):
                kind = type(layer).__name__.lower()
                r.report(("layer", index, "type"),
                         f'"{kind}" needs a travelling wave to push the finger; profile '
                         f"{show(device.profile)} only modulates friction (use one of "
                         f"{', '.join(profiles.FORCE_PROFILES)})")
        return device
    if not force_profile:
        return device
    surface = profiles.SURFACE_LENGTH_MM[device.profile]
    if display is not None and display.width_mm > surface + 1e-9:
        r.report(("display", "width_mm"), f"{display.width_mm:g} mm is longer than the "
                                          f"{surface:g} mm surface of {device.profile} (display "
                                          f"x runs along it from its end)")
    driving = r.table(raw.get("driving", {}), ("device", "driving"), DRIVING)
    if driving is None or BAD in driving.values():
        return None
    return replace(device, driving=profiles.DrivingForceParams(**driving))
