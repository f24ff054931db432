"""Stimuli as scenes: a base texture file with one parameter set, or two side by side.

A stimulus is a texture file's document (``tomllib``'s dict) with a change: the varied
layer's period, depth or clip level set (:data:`PARAMETERS`), its periodic layers'
``render`` set, and its name and description say so (``grating-5mm-period_mm=6.6``:
the base scene with that key changed). The changed document is written as a texture
file (``toml_text``) and loaded by the texture loader, so a stimulus is checked exactly
as any scene and the file is what ``frictex replay`` reads to play it again. The files a
base file names (maps, clip files, measured modes: relative to it, in its folder or
below) are linked (or copied) beside every scene file written from it, under the same
names.

Side by side: the two stimuli's layers in one scene, the first's confined to the left
half of the display and the second's to the right half (each layer gets that half as
its ``[layer.region]``; a layer with a region of its own cannot be confined).
"""

from __future__ import annotations

import copy
import math
import os
import re
import shutil
import tempfile
import tomllib
from dataclasses import dataclass
from pathlib import Path

from frictex.app.experiment.toml_text import toml_text
from frictex.device.errors import InputError
from frictex.textures.keys import TOP
from frictex.textures.loader import check_scene
from frictex.textures.library import read_utf8
from frictex.textures.model import Scene

#: vary -> layer type -> what the value sets in that layer's table
PARAMETERS: dict[str, dict[str, str]] = {
    "period_mm": {"grating": "period_mm", "waveform": "period_mm"},
    "depth": {"grating": "mu_low = mu_high - depth", "waveform": "mu_min = mu_max - depth",
              "rectangle": "mu = 1 - depth", "disc": "mu = 1 - depth", "line": "mu = 1 - depth",
              "clip": "depth"},
    "level": {"clip": "intensity (tick, envelope) or level_to (ramp)"},
}
PERIODIC = ("grating", "waveform")
#: keys whose value is a file path relative to the texture file
PATH_KEYS = ("image", "model", "file", "modes_file")
MAX_SCENE_BYTES = 1 << 20
#: the longest scene name (``textures.keys.TOP["name"]``), in characters
NAME_LIMIT = TOP["name"].max_len
_PLAIN = re.compile(r"^[A-Za-z0-9._=+-]{1,200}$")


@dataclass(frozen=True)
class Base:
    """A checked base scene: its file, its document and the scene."""

    path: Path
    doc: dict
    scene: Scene

    @property
    def folder(self) -> Path:
        """Where the files the base names are."""
        return Path(os.path.realpath(self.path)).parent


def load_base(path: Path) -> Base:
    """The scene file at ``path``, checked (``TextureError`` listing its problems)."""
    from frictex.textures.loader import load_scene
    scene = load_scene(path)
    return Base(Path(path), tomllib.loads(read_utf8(path, MAX_SCENE_BYTES)), scene)


def referenced(value) -> list[str]:
    """The file names (relative) a scene document names, under :data:`PATH_KEYS`."""
    if isinstance(value, dict):
        return [name for key, inner in value.items()
                for name in ([inner] if key in PATH_KEYS and isinstance(inner, str)
                             else referenced(inner))]
    if isinstance(value, list):
        return [name for inner in value for name in referenced(inner)]
    return []


def place_files(doc: dict, source: Path, target: Path) -> None:
    """Link (or, across file systems, copy) the files ``doc`` names from folder
    ``source`` into folder ``target``, under the same relative names."""
    for name in referenced(doc):
        src, dst = source / name, target / name
        if dst.exists() or not src.is_file() or os.path.realpath(src) == os.path.realpath(dst):
            continue
        dst.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.link(src, dst)
        except OSError:
            shutil.copyfile(src, dst)


def plain_name(name: str) -> bool:
    """Whether ``name`` can name a stimulus in results and file names."""
    return bool(_PLAIN.match(name))


def name_of(vary: str | None, value: float | None, renderer: str | None) -> str:
    """The stimulus name of a parametric stimulus: ``period_mm=5.5``, ``depth=0.3-sht``."""
    parts = [] if vary is None else [f"{vary}={value:.10g}"]
    return "-".join(parts + ([renderer] if renderer else [])) or "base"


def _layers(doc: dict) -> list[dict]:
    layers = doc.get("layer", [])
    return layers if isinstance(layers, list) else []


def varied_layer(base: Base, vary: str, name: str | None) -> int | str:
    """Index of the layer ``vary`` acts on (the one named ``name``, or the first of a type
    it applies to), or a message saying why there is none."""
    types = PARAMETERS[vary]
    for index, layer in enumerate(base.scene.layers):
        kind = _layers(base.doc)[index].get("type")
        if name is not None and layer.name != name:
            continue
        if kind in types and vary == "level" and _layers(base.doc)[index].get("clip") == "ahap":
            if name is not None:
                return f"layer {layer.name!r} plays an AHAP file, whose levels the file sets"
            continue
        if kind in types:
            return index
        if name is not None:
            return (f"layer {name!r} is a {kind}; {vary} applies to "
                    f"{', '.join(types)} layers")
    if name is not None:
        names = ", ".join(layer.name for layer in base.scene.layers)
        return f"no layer {name!r} in {base.path.name} (its layers: {names})"
    return f"{base.path.name} has no layer that {vary} applies to ({', '.join(types)})"


def stimulus_doc(base: Base, vary: str | None, layer: int | None, value: float | None,
                 renderer: str | None) -> dict:
    """The base document with ``vary`` set to ``value`` on layer ``layer`` and every
    periodic layer rendered by ``renderer`` (None: as the base has them)."""
    doc = copy.deepcopy(base.doc)
    layers = _layers(doc)
    if vary is not None:
        table = layers[layer]
        kind = table["type"]
        if vary == "period_mm":
            table["period_mm"] = value
        elif vary == "depth" and kind == "grating":
            table["mu_low"] = table.get("mu_high", 1.0) - value
        elif vary == "depth" and kind == "waveform":
            table["mu_min"] = table.get("mu_max", 1.0) - value
        elif vary == "depth" and kind == "clip":
            table["depth"] = value
        elif vary == "depth":
            table["mu"] = 1.0 - value
        elif table.get("clip") == "ramp":
            table["level_to"] = value
        else:
            table["intensity"] = value
    if renderer is not None:
        for table in layers:
            if table.get("type") in PERIODIC:
                table["render"] = renderer
    _name_as_changed(doc, base, vary, layer, value, renderer)
    return doc


def _name_as_changed(doc: dict, base: Base, vary: str | None, layer: int | None,
                     value: float | None, renderer: str | None) -> None:
    """Give ``doc`` (``base`` with ``vary`` set to ``value`` on layer ``layer`` and its
    periodic layers rendered by ``renderer``) a name and description saying so: the base's
    name and the stimulus name (:func:`name_of`, e.g. ``grating-5mm-period_mm=6.6``,
    within a scene name's :data:`NAME_LIMIT` characters). Unchanged when nothing is set."""
    changes = []
    if vary is not None:
        kind = _layers(doc)[layer].get("type")
        sets = PARAMETERS[vary][kind]
        how = "" if sets == vary else f" ({sets})"
        changes.append(f'{vary} = {value:.10g} on layer "{base.scene.layers[layer].name}"{how}')
    if renderer is not None:
        changes.append(f"its periodic layers rendered {renderer}")
    if not changes:
        return
    suffix = f"-{name_of(vary, value, renderer)}"
    doc["name"] = base.scene.name[:NAME_LIMIT - len(suffix)] + suffix
    doc["description"] = (f"An experiment stimulus: the scene {base.scene.name} with "
                          f"{' and '.join(changes)}.")


def side_by_side(left: dict, right: dict) -> dict:
    """One scene document: ``left``'s layers on the left half of the display, ``right``'s
    on the right half. InputError when they cannot be (:func:`side_by_side_problem`)."""
    problem = side_by_side_problem(left, right)
    if problem:
        raise InputError(problem)
    doc = copy.deepcopy(left)
    width = float(left["display"]["width_mm"]) / 2
    height = float(left["display"]["height_mm"])
    names = (left.get("name", "left"), right.get("name", "right"))
    doc["name"] = " | ".join(names)[:NAME_LIMIT]
    doc["description"] = f"Two stimuli side by side: {names[0]} on the left half of the " \
                         f"display, {names[1]} on the right half."
    layers = []
    for side, source in (("left", left), ("right", right)):
        for index, layer in enumerate(_layers(source)):
            table = copy.deepcopy(layer)
            default = f"{layer.get('type')}-{index + 1}"
            table["name"] = f"{layer.get('name', default)}-{side}"
            table["region"] = {"x_mm": 0.0 if side == "left" else width, "y_mm": 0.0,
                               "width_mm": width, "height_mm": height}
            layers.append(table)
    doc["layer"] = layers
    return doc


def side_by_side_problem(left: dict, right: dict) -> str | None:
    """Why two scene documents cannot be shown side by side, or None."""
    if left.get("display") != right.get("display") or left.get("device") != right.get("device"):
        return "side by side needs the two scenes to share [display] and [device]"
    for doc in (left, right):
        for layer in _layers(doc):
            if "region" in layer:
                return (f"layer {layer.get('name', layer.get('type'))!r} has a region of its "
                        f"own; side by side confines each layer to a half of the display")
    return None


def write_scene(doc: dict, path: Path, files_from: Path) -> Scene:
    """Write ``doc`` as the texture file ``path``, the files it names placed beside it
    from folder ``files_from``, and load it back (``TextureError`` if the stimulus is not
    a valid scene)."""
    path.write_text(toml_text(doc), encoding="utf-8")
    return load_written(doc, path, files_from)


def load_written(doc: dict, path: Path, files_from: Path) -> Scene:
    """The scene of the texture file ``path`` (written from ``doc``), the files ``doc``
    names placed beside it from folder ``files_from`` (``TextureError`` if invalid)."""
    from frictex.textures.errors import TextureError
    place_files(doc, files_from, path.parent)
    scene, problems, _ = check_scene(path)
    if scene is None:
        raise TextureError(problems)
    return scene


def value_problem(base: Base, vary: str, layer: int, value: float) -> str | None:
    """Why ``vary = value`` does not make a valid scene of ``base``, or None."""
    doc = stimulus_doc(base, vary, layer, value, None)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"{base.path.stem}.toml"
        path.write_text(toml_text(doc), encoding="utf-8")
        place_files(doc, base.folder, Path(folder))
        _, problems, _ = check_scene(path)
    if not problems:
        return None
    first = problems[0]
    return f"{vary} = {value:g} makes {first.field or 'the scene'} invalid: {first.message}"


#: the relative difference below which a played scene file's number is the same as the
#: stimulus's (a session written before levels were computed from a grid index reached
#: one level by different float paths, e.g. mu_low 0.669857362821885 and ...851)
SAME_NUMBER_REL = 1e-9


def _same_values(played, wanted) -> bool:
    """Whether two parsed scene documents are equal, numbers within SAME_NUMBER_REL."""
    if isinstance(played, dict) and isinstance(wanted, dict):
        return played.keys() == wanted.keys() and all(
            _same_values(played[key], wanted[key]) for key in played)
    if isinstance(played, list) and isinstance(wanted, list):
        return len(played) == len(wanted) and all(map(_same_values, played, wanted))
    numbers = (int, float)
    if isinstance(played, numbers) and isinstance(wanted, numbers) and not isinstance(
            played, bool) and not isinstance(wanted, bool):
        return math.isclose(played, wanted, rel_tol=SAME_NUMBER_REL)
    return played == wanted


def _keep_played(path: Path, doc: dict) -> bool:
    """Whether the stimulus file ``path`` (of a session's earlier trials) holds the scene
    ``doc`` (numbers within SAME_NUMBER_REL): it is then played again as it is. False when
    there is no such file; InputError when it holds another scene: it records what those
    trials played, so it is never overwritten."""
    if not path.is_file():
        return False
    text = path.read_text(encoding="utf-8")
    if text != toml_text(doc) and not _same_values(tomllib.loads(text), doc):
        raise InputError(f"{path}: this session played another scene under the name "
                         f"{path.stem}; it is kept, and the session does not go on")
    return True


class StimulusBank:
    """The scenes of a protocol's stimuli, each written once into ``folder`` as
    ``NAME.toml`` with the files it names, and loaded from there (side-by-side pairs as
    ``LEFT+RIGHT.toml``).

    ``get(stimulus)`` gives ``(scene, text)``: the checked scene and its file's text.
    """

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        self._bases: dict[Path, Base] = {}
        self._made: dict[str, tuple[Scene, str, dict]] = {}

    def _base(self, path: Path) -> Base:
        if path not in self._bases:
            self._bases[path] = load_base(path)
        return self._bases[path]

    def _make(self, name: str, doc: dict, files_from: Path) -> tuple[Scene, str, dict]:
        if name not in self._made:
            self.folder.mkdir(parents=True, exist_ok=True)
            path = self.folder / f"{name}.toml"
            scene = (load_written(doc, path, files_from) if _keep_played(path, doc)
                     else write_scene(doc, path, files_from))
            self._made[name] = (scene, path.read_text(encoding="utf-8"), doc)
        return self._made[name]

    def get(self, stimulus, vary: str | None, layer: int | None) -> tuple[Scene, str]:
        """The scene of ``stimulus`` (a ``protocol.Stimulus``) with ``vary`` acting on
        layer ``layer`` of its base."""
        base = self._base(stimulus.scene)
        doc = stimulus_doc(base, vary if stimulus.value is not None else None, layer,
                           stimulus.value, stimulus.renderer)
        scene, text, _ = self._make(stimulus.name, doc, base.folder)
        return scene, text

    def pair(self, left, right, vary: str | None, layer: int | None) -> tuple[Scene, str]:
        """``left`` and ``right`` side by side in one scene."""
        docs = []
        for stimulus in (left, right):
            self.get(stimulus, vary, layer)
            docs.append(self._made[stimulus.name][2])
        scene, text, _ = self._make(f"{left.name}+{right.name}", side_by_side(*docs),
                                    self.folder)
        return scene, text
