"""What a finger can tell apart in a protocol: its stimuli compared pair by pair
(``rendering.perception``'s thresholds), and each scene it plays checked on its own.

Pairs compared:

- parametric stimuli (``[stimuli]`` with ``vary`` and ``levels``): the reference against
  its farthest level (the largest: levels are above the reference), by ``vary``'s
  threshold (``perception.compare_values``: periods 14 %, depths and clip levels 11 %).
  Constant stimuli measure a threshold, so levels under it are expected (answered
  correctly less often than at the threshold, the nearest near chance); only a design
  with none beyond it warns: its psychometric function stays below the threshold's point
  and cannot place it. A staircase has no fixed levels: only its scene is checked.
- listed stimuli (``[[stimulus]]``, or renderers crossed): every pair of stimuli from
  different scene files, their layers matched one to one
  (``perception.compare_scenes``); two renderings of one scene differ by their
  renderer, for which no threshold is published, and are not compared.
"""

from __future__ import annotations

from itertools import combinations

from frictex.app.experiment.protocol import Protocol
from frictex.rendering.perception import Finding, compare_scenes, compare_values, scene_findings
from frictex.textures.loader import load_scene


def protocol_findings(protocol: Protocol) -> list[Finding]:
    """The scenes' features and the pairs of stimuli below a threshold (module
    docstring), scenes first, in the protocol's order."""
    st = protocol.stimuli
    paths = list(dict.fromkeys([st.scene] if st.scene is not None and not st.listed
                               else [s.scene for s in st.listed]))
    scenes = {path: load_scene(path) for path in paths}
    out = [Finding(f.kind, f.where, f.value, f"{path.name}: {f.message}")
           for path, scene in scenes.items() for f in scene_findings(scene)]
    if st.vary is not None and st.levels:
        farthest = max(st.levels)  # every level is above the reference (protocol)
        found = compare_values(st.vary, st.reference, farthest,
                               f"stimuli {st.reference:g} and {farthest:g}")
        if found is not None:
            out.append(Finding(found.kind, found.where, found.value,
                               f"{found.message}; the farthest of {len(st.levels)} level"
                               f"{'s' * (len(st.levels) != 1)}: none reaches the threshold, "
                               f"and a design that measures it needs levels on both sides"))
    for a, b in combinations(st.listed, 2):
        if a.scene != b.scene:
            found = compare_scenes(scenes[a.scene], scenes[b.scene],
                                   f'stimuli "{a.name}" and "{b.name}"')
            out += [found] if found is not None else []
    return out
