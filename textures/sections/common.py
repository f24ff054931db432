"""What every layer builder shares: the context it builds in and the checks between keys.

A builder is ``build(reader, path, values, given keys, context) -> (layer, low key) | None``:
``values`` are the checked keys of its type (``textures.keys.LAYER_KEYS``), ``given`` the
keys the file wrote, and the low key names the key of the layer's lowest mu' (for the
reach warning). None means problems were reported.
"""

from __future__ import annotations

from dataclasses import dataclass

from frictex.textures import model
from frictex.textures.errors import KeyPath
from frictex.textures.schema import Reader
from frictex.textures.sections.files import Files


@dataclass
class Context:
    display: model.Display | None
    files: Files
    common: dict  # name, render, blend, region, visual, resolved


def forbid(r: Reader, path: KeyPath, given, keys, reason: str) -> bool:
    """Report keys that make no sense here; True if none was given."""
    extra = [k for k in keys if k in given]
    for k in extra:
        r.report(path + (k,), f"not used {reason}; remove it")
    return not extra


def ordered(r: Reader, path: KeyPath, low_key: str, high_key: str, v: dict) -> bool:
    if v[low_key] > v[high_key]:
        r.report(path + (low_key,), f"{v[low_key]:g} is above {high_key} {v[high_key]:g}")
        return False
    return True



def chosen_keys(r, path, v, given, table: dict, choice_key: str, optional=()) -> bool:
    """Keys of the chosen variant (``table[v[choice_key]]``) without a default are
    required unless ``optional``; keys only other variants take are refused."""
    choice = v[choice_key]
    ok = True
    for key in table[choice]:
        if v[key] is None and key not in optional:
            r.report(path + (key,), f'missing (required with {choice_key} = "{choice}")')
            ok = False
    others = {k for keys in table.values() for k in keys} - set(table[choice])
    return forbid(r, path, given, sorted(others), f'with {choice_key} = "{choice}"') and ok


def strictly_increasing(values) -> bool:
    return all(b > a for a, b in zip(values, values[1:]))

