"""What a finger can tell apart in a protocol: its stimuli compared pair by pair
(``rendering.perception``'s thresholds), and each scene it plays checked on its own.

Pairs compared:

- parametric stimuli (``[stimuli]`` with ``vary`` and ``levels``): the reference against
  its farthest level (by the relative difference the threshold bounds: a same-different
  or magnitude design's levels may lie on either side of the reference), by ``vary``'s
  threshold (``perception.compare_values``: periods 14 % of the smaller, the friction
  levels of depths and clip levels 11 % of the higher, from the varied layer's own mu'
  and clip depth: the Weber fraction's source measured a change of friction relative to
  its level; the simulated participant, ``observer``, judges a depth's contrast instead,
  and ``PROTOCOL_FORMAT.md`` says how the two differ).
  Constant stimuli measure a threshold, so levels under it are expected (answered
  correctly less often than at the threshold, the nearest near chance); only a design
  with none beyond it warns: its psychometric function stays below the threshold's point
  and cannot place it. A staircase has no fixed levels: the reference is compared with
  the largest comparison it can present (``protocol.reachable``: the reference plus its
  ``max``, or as far as its steps go within ``max_trials``); below the threshold, the
  staircase would sit at its ceiling and its threshold be extrapolated.
- each scene under each renderer its stimuli play it with (a stimulus's ``renderer``
  rules its periodic layers: a 0.6 mm grating is played by SHT but aliased by SHO-held),
  naming the stimuli a note applies to.
- listed stimuli (``[[stimulus]]``, or renderers crossed): every pair of stimuli from
  different scene files, their layers matched one to one, by their periods, friction
  contrasts and clip events' lengths (``perception.compare_scenes``); two renderings
  of one scene differ by their renderer, for which no threshold is published, and are
  not compared.
"""

from __future__ import annotations

import math
from itertools import combinations

from frictex.app.experiment.protocol import Protocol, reachable
from frictex.rendering.perception import (VARY_THRESHOLD, Finding, compare_scenes,
                                          compare_values, friction_level, relative_difference,
                                          scene_findings)
from frictex.textures.loader import load_scene


def _distance(vary: str, reference: float, value: float, levels: dict[str, float]) -> float:
    """How far ``value`` lies from ``reference`` (units of ``vary``) by the measure
    ``compare_values`` sets against ``vary``'s threshold: periods by dp/p, depths and clip
    levels by dmu'/mu' of the friction levels they play (``levels``: :func:`_varied_levels`);
    inf where one plays mu' 0 or below, a step beyond any fraction of friction."""
    kind = VARY_THRESHOLD[vary]
    if kind == "period":
        return relative_difference(kind, reference, value)
    mu = [friction_level(vary, v, **levels) for v in (reference, value)]
    return math.inf if min(mu) <= 0.0 else relative_difference(kind, *mu)


def _farthest(protocol: Protocol, levels: dict[str, float]) -> tuple[float, str] | None:
    """The comparison farthest from the reference (units of ``vary``; :func:`_distance`,
    ``levels`` the varied layer's) a parametric design can present, and what it means
    when even that is below the threshold; None for listed stimuli."""
    st, sc = protocol.stimuli, protocol.staircase
    if st.vary is None:
        return None
    if sc is not None:
        high = reachable(sc)[1]
        bound = "its max" if sc.max == high else f"its steps within {sc.max_trials} trials"
        return (st.reference + high,
                f"the staircase's largest comparison ({bound}): below the threshold, it "
                f"would sit at its ceiling and extrapolate its threshold")
    if not st.levels:
        return None
    count = len(st.levels)
    return (max(st.levels, key=lambda v: _distance(st.vary, st.reference, v, levels)),
            f"the farthest of {count} level{'s' * (count != 1)}: none reaches the threshold, "
            f"and a design that measures it needs levels on both sides")


def _scene_notes(protocol: Protocol, scenes: dict) -> list[Finding]:
    """Each scene's findings (``scene_findings``) under each renderer its stimuli play
    it with, a finding alike under several renderers once, naming the listed stimuli it
    applies to: ``grating-0.6mm.toml (stimulus "0.6mm-sho"): ...``."""
    st = protocol.stimuli
    uses: dict[tuple, list[str]] = {}  # (scene file, renderer) -> the stimuli's names
    for stimulus in st.listed:
        uses.setdefault((stimulus.scene, stimulus.renderer), []).append(stimulus.name)
    if not st.listed:
        uses[(st.scene, None)] = []
    applies: dict[tuple, list[str]] = {}  # (scene file, finding) -> the stimuli's names
    for (path, renderer), names in uses.items():
        for found in scene_findings(scenes[path], renderer):
            applies.setdefault((path, found), []).extend(names)
    return [Finding(f.kind, f.where, f.value, f"{path.name}{_naming(names)}: {f.message}")
            for (path, f), names in applies.items()]


def _naming(names: list[str]) -> str:
    """`` (stimuli "a", "b")`` for the stimuli a finding applies to; "" for none."""
    if not names:
        return ""
    quoted = ", ".join(f'"{name}"' for name in names)
    return f" (stimul{'i' if len(names) > 1 else 'us'} {quoted})"


def _varied_levels(scene, layer: int | None) -> dict[str, float]:
    """``compare_values``'s ``mu_high``, ``clip_depth`` and ``clip_level`` of the varied
    layer (index ``layer`` of the base ``scene``): the friction its depth is taken from (a
    grating's mu_high, a waveform's mu_max, 1 for a shape), a clip's depth (its levels
    scale it) and its weakest event's intensity (which scales its depth: the smallest
    step a depth makes)."""
    varied = None if scene is None or layer is None else scene.layers[layer]
    clip = getattr(varied, "clip", None)
    return {"mu_high": getattr(varied, "mu_high", getattr(varied, "mu_max", 1.0)),
            "clip_depth": 1.0 if clip is None else clip.depth,
            "clip_level": 1.0 if clip is None else min(
                (min(e.intensity, 1.0) for e in clip.events), default=1.0)}


def protocol_findings(protocol: Protocol) -> list[Finding]:
    """The scenes' features and the pairs of stimuli below a threshold (module
    docstring), scenes first, in the protocol's order."""
    st = protocol.stimuli
    paths = list(dict.fromkeys([st.scene] if st.scene is not None and not st.listed
                               else [s.scene for s in st.listed]))
    scenes = {path: load_scene(path) for path in paths}
    out = _scene_notes(protocol, scenes)
    levels = _varied_levels(scenes.get(st.scene), st.layer)
    farthest = _farthest(protocol, levels)
    if farthest is not None:
        value, why = farthest
        found = compare_values(st.vary, st.reference, value,
                               f"stimuli {st.reference:g} and {value:g}", **levels)
        if found is not None:
            out.append(Finding(found.kind, found.where, found.value, f"{found.message}; {why}"))
    for a, b in combinations(st.listed, 2):
        if a.scene != b.scene:
            found = compare_scenes(scenes[a.scene], scenes[b.scene],
                                   f'stimuli "{a.name}" and "{b.name}"')
            out += [found] if found is not None else []
    return out
