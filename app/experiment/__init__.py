"""Psychophysical experiments on friction displays: ``frictex experiment``.

One job per module:

- ``protocol``: the PROTOCOL.toml format, parsed and checked once into frozen dataclasses
  (line-located errors); ``protocol_doc`` writes its reference page, PROTOCOL_FORMAT.md.
- ``stimuli``: the scene each stimulus is (a bundled or given scene with a parameter
  set), as a checked ``Scene`` and as the TOML text a replay reads; ``toml_text`` writes it.
- ``scheduler``: the methods (constant stimuli, staircases, same-different, magnitude
  estimation) as pure trial logic with explicit state: responses in, next trial out.
- ``session``: the session folder (results table appended and fsynced per trial, per-trial
  traces and scenes), and resuming it.
- ``observer``: a simulated participant that feels the pipeline's friction target through
  a Weber fraction and a lapse rate.
- ``presenter``: the interface a presenter implements (``Presenter``: the headless
  simulated participant now, the demo window later) and what passes through it.
- ``runner``: drives a session through a presenter; the registry of participants.
- ``protocol_doc``: PROTOCOL_FORMAT.md from ``protocol``'s key tables.
- ``plot``: the analysis figure.
- ``psychometric``: maximum-likelihood psychometric functions and their bootstrap.
- ``analysis``: ``frictex experiment analyse``: sessions of a study, fitted and plotted.
"""

from pathlib import Path

#: the bundled protocols, ``NAME.toml``: given by name where a protocol file is asked for
PROTOCOLS_DIR = Path(__file__).resolve().parent / "protocols"
