"""Protocol files: TOML, one experiment per file, checked once into :class:`Protocol`.

Grammar (format 1). Every key not marked *required* has the default shown; the full
table of keys, units and ranges is ``app/experiment/PROTOCOL_FORMAT.md``, generated from
the tables below.
::

    format = 1                  # required; the version of this grammar
    name = "..."                # default: the file name without .toml; names the study
    description = "..."
    method = "2afc"             # required: 2afc | staircase | same-different | magnitude
    seed = 12345                # trial order; default: drawn when a session starts (recorded)
    question = "..."            # what the participant is asked; default from the method
    repetitions = 10            # trials per level and order (see the methods below)
    practice = 0                # practice trials first (not analysed, not adapting)
    break_every = 0             # a break after every N main trials (0: none)

    [stimuli]                   # one scene with a parameter varied
    scene = "grating-5mm"       # required: a bundled scene or a path (relative to this file)
    vary = "period_mm"          # period_mm | depth | level (a clip's intensity); omit for
                                #   one stimulus per renderer in `renderers`
    layer = "lines"             # the layer varied; default: the first that has the parameter
    reference = 5.0             # required with `vary`: the standard stimulus (units of `vary`;
                                #   magnitude rates it as one of the stimuli)
    levels = [5.3, 5.6, 6.2]    # comparisons (2afc, same-different, magnitude), distinct,
                                #   none the reference; above it for 2afc (which asks for
                                #   the larger), either side for same-different; each
                                #   named apart from the others to 10 significant digits
    renderers = ["sho", "sht"]  # render the varied layer each of these ways: magnitude only,
                                #   crossed with the levels (seed 003's grating comparison)

    [[stimulus]]                # instead of [stimuli] (magnitude only): a list of scenes
    name = "..."                # required, unique
    scene = "grating-15mm"      # required
    renderer = "sht"            # optional: render every periodic layer this way

    [presentation]
    mode = "sequential"         # | side-by-side: two-interval trials in time or in space
    exploration = "fixed"       # | free: the participant answers when ready
    exploration_s = 3.0         # per stimulus: the time shown (fixed) or the most (free)
    show_scene = false          # true: the window shows the scene's picture while a stimulus
                                #   is explored (visuo-haptic); false: a uniform field

    [staircase]                 # method = "staircase" only
    rule = "1-up-2-down"        # | 1-up-3-down (Levitt 1971: 70.7 % and 79.4 % correct)
    start = 2.0                 # required: the first comparison's difference from the reference
    steps = [0.2, 0.1]          # step after 0, 1, ... reversals (the last one thereafter)
    scale = "log"               # log: steps in log10 units (x or / 10^step); linear: +- step
    reversals = 12              # stop after this many reversals ...
    max_trials = 100            # ... or this many trials
    threshold_reversals = 8     # the staircase's threshold: mean of the last N reversal levels
                                #   (their geometric mean on the log scale)
    min = ..., max = ...        # bounds of the difference (default: none); every difference
                                #   the steps can reach within max_trials (as if each trial
                                #   moved by the largest step) must be a valid stimulus,
                                #   above 0 (a linear scale needs min to stop short of 0)

    [scale]                     # method = "magnitude" only: the rating scale (integers;
                                #   at the window typed, then Enter, unless each value
                                #   has a key of its own, as 1-10 has)
    min = 1
    max = 10

    [analysis]
    function = "weibull"        # | logistic: the psychometric function fitted
    lapse_max = 0.06            # the lapse rate is fitted within [0, lapse_max]
    target = ...                # the threshold's proportion correct; default: 0.75 (2afc),
                                #   the rule's convergence point (staircase)
    bootstrap = 1000            # parametric bootstrap samples for the 95 % intervals; 0: no
                                #   intervals; at least 200 otherwise

Methods: ``2afc``: constant stimuli; each trial shows the reference and one comparison in
random order, counterbalanced (each level ``repetitions`` times in each order); correct
is choosing the comparison, guess rate 0.5. ``staircase``: the same two-interval trials
with the comparison's difference set by the rule: down a step after 2 (or 3) correct in a
row, up after an error; the order of the intervals is counterbalanced in pairs of trials.
``same-different``: pairs AB, BA, AA, BB (A the reference, B a level), ``repetitions``
of each; correct is "same" for AA and BB. ``magnitude``: one stimulus per trial, each
``repetitions`` times, rated on the scale. Trial order is shuffled from ``seed``.

Every problem in a file is reported as ``file:line: field: message``
(:class:`ProtocolError`, an ``InputError``); the line numbers come from the texture
loader's :class:`~frictex.textures.errors.Locator`, and the values are read by its reader,
so a protocol's numbers and strings are checked as a texture file's are.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, replace
from pathlib import Path

from frictex.app.experiment import PROTOCOLS_DIR
from frictex.device.errors import InputError
from frictex.device.safe_text import escape_path, quoted
from frictex.textures.errors import KeyPath, Locator, Problem
from frictex.textures.keys import RENDER_CHOICES
from frictex.textures.library import UnreadableText, read_utf8
from frictex.textures.schema import BAD as _BAD
from frictex.textures.schema import Choice, Flag, Int, Num, NumList, Reader, Text
from frictex.textures.toml_safe import parse_toml

#: the farthest a log staircase's level goes from its start (decades): within float64's
#: range whatever the steps and trials (its min and max clamp what is presented)
MAX_DECADES = 300.0

FORMAT_VERSION = 1
METHODS = ("2afc", "staircase", "same-different", "magnitude")
#: what a stimulus may vary (``stimuli.PARAMETERS`` says how each sets a layer)
VARIES = ("period_mm", "depth", "level")
#: the unit of each varied parameter, and so of results.csv's value and difference
VARY_UNITS = {"period_mm": "mm", "depth": "unitless (friction coefficient)",
              "level": "unitless (clip level, 0 to 1)"}
PRESENTATIONS = ("sequential", "side-by-side")
EXPLORATIONS = ("fixed", "free")
RULES = {"1-up-2-down": 2, "1-up-3-down": 3}
FUNCTIONS = ("weibull", "logistic")
#: the proportion correct a rule converges on: p^n = 1/2 (Levitt 1971)
RULE_TARGETS = {rule: 0.5 ** (1.0 / n) for rule, n in RULES.items()}
#: guess rate by method (chance performance), for the psychometric fit
GUESS_RATES = {"2afc": 0.5, "staircase": 0.5}
MAX_FILE_BYTES = 1 << 20
MAX_LEVELS = 100
MAX_STIMULI = 100
#: the largest difference a staircase may present (units of `vary`; as ``max``'s bound)
MAX_DIFFERENCE = 1e6
#: the fewest bootstrap samples that give a 95 % interval (its 2.5 % tails hold 5 each)
MIN_BOOTSTRAP = 200

#: what the participant is asked when the file gives no ``question``
QUESTIONS = {
    "2afc": "Which of the two felt {attribute}?",
    "staircase": "Which of the two felt {attribute}?",
    "same-different": "Did the two feel the same or different?",
    "magnitude": "How accurately did this reproduce what you saw? Rate it.",
}
#: the attribute a two-interval question names, by ``vary``
ATTRIBUTES = {"period_mm": "coarser (wider lines)", "depth": "stronger", "level": "stronger"}

NUMBER = Num("units of `vary`", ge=-1e6, le=1e6)
TOP = {"format": Int("format version"), "name": Text(None),
       "description": Text("", max_len=10_000, lines=True),
       "method": Choice(METHODS), "seed": Int("random seed", None, ge=0, le=2**63 - 1),
       "question": Text(None, max_len=500),
       "repetitions": Int("trials per level and order", 10, ge=1, le=1000),
       "practice": Int("trials", 0, ge=0, le=100),
       "break_every": Int("trials", 0, ge=0, le=10_000)}


@dataclass(frozen=True)
class Names:
    """A list of distinct names, each one of ``options``."""

    options: tuple[str, ...]
    default: tuple = ()

    def check(self, r: Reader, value, path: KeyPath):
        if not isinstance(value, list) or not value:
            return r.report(path, f"expected a list of names ({', '.join(self.options)})")
        out = [Choice(self.options).check(r, v, path + (i,)) for i, v in enumerate(value)]
        if _BAD in out:
            return _BAD
        if len(set(out)) != len(out):
            return r.report(path, "names one twice")
        return tuple(out)


STIMULI = {"scene": Text(max_len=1000), "vary": Choice(VARIES, None), "layer": Text(None),
           "reference": replace(NUMBER, default=None), "levels": NumList(NUMBER, default=()),
           "renderers": Names(RENDER_CHOICES)}
STIMULUS = {"name": Text(), "scene": Text(max_len=1000), "renderer": Choice(RENDER_CHOICES, None)}
PRESENTATION = {"mode": Choice(PRESENTATIONS, "sequential"),
                "exploration": Choice(EXPLORATIONS, "fixed"),
                "exploration_s": Num("s", 3.0, gt=0.0, le=600.0),
                "show_scene": Flag(False, "the scene's picture in the window while a stimulus is "
                                          "explored (visuo-haptic stimuli); false: a uniform "
                                          "field, so that only touch tells the stimuli apart")}
STAIRCASE = {"rule": Choice(tuple(RULES), "1-up-2-down"),
             "start": Num("units of `vary`", gt=0.0, le=1e6),
             "steps": NumList(Num("step (log10 units or units of `vary`)", gt=0.0, le=1e6),
                              default=(0.2, 0.1)),
             "scale": Choice(("log", "linear"), "log"),
             "reversals": Int("reversals", 12, ge=2, le=200),
             "max_trials": Int("trials", 100, ge=1, le=5000),
             "threshold_reversals": Int("reversals", 8, ge=1, le=200),
             "min": Num("units of `vary`", None, gt=0.0, le=MAX_DIFFERENCE),
             "max": Num("units of `vary`", None, gt=0.0, le=MAX_DIFFERENCE)}
SCALE = {"min": Int("rating", 1, ge=-1000, le=1000), "max": Int("rating", 10, ge=-1000, le=1000)}
ANALYSIS = {"function": Choice(FUNCTIONS, "weibull"),
            "lapse_max": Num("proportion", 0.06, ge=0.0, le=0.2),
            "target": Num("proportion correct", None, gt=0.5, lt=1.0),
            "bootstrap": Int(f"samples; 0: no intervals, else at least {MIN_BOOTSTRAP}", 1000,
                             ge=0, le=100_000)}
TABLES = ("stimuli", "stimulus", "presentation", "staircase", "scale", "analysis")


class ProtocolError(InputError):
    """A protocol file that cannot be used. ``problems`` lists every problem found;
    ``str()`` is one line: the first problem and how many more there are."""

    def __init__(self, problems: list[Problem] | str):
        self.problems = [] if isinstance(problems, str) else list(problems)
        if isinstance(problems, str):
            super().__init__(problems)
            return
        message = str(self.problems[0])
        more = len(self.problems) - 1
        if more:
            message += (f" (and {more} more problem{'s' if more > 1 else ''}; frictex "
                        f"experiment {escape_path(self.problems[0].file)} --check lists them all)")
        super().__init__(message)


@dataclass(frozen=True)
class Stimulus:
    """One stimulus: ``scene`` (a texture file) with ``value`` set on its ``vary`` layer
    (None: as the file has it) and rendered by ``renderer`` (None: as the file says).
    ``name`` is unique within the protocol and names the stimulus in the results."""

    name: str
    scene: Path
    value: float | None = None
    renderer: str | None = None


@dataclass(frozen=True)
class Stimuli:
    """``[stimuli]`` or ``[[stimulus]]``: where the stimuli come from.

    ``vary``/``layer``/``reference``/``levels``: the parametric form (``layer`` is the
    index of the varied layer in the base scene); ``listed``: the scenes of the
    ``[[stimulus]]`` form (or the renderers crossed with the levels)."""

    scene: Path | None
    vary: str | None = None
    layer: int | None = None
    reference: float | None = None
    levels: tuple[float, ...] = ()
    listed: tuple[Stimulus, ...] = ()


@dataclass(frozen=True)
class Presentation:
    mode: str = "sequential"
    exploration: str = "fixed"
    exploration_s: float = 3.0
    show_scene: bool = False


@dataclass(frozen=True)
class Staircase:
    rule: str
    start: float
    steps: tuple[float, ...]
    scale: str
    reversals: int
    max_trials: int
    threshold_reversals: int
    min: float | None
    max: float | None

    @property
    def down_after(self) -> int:
        """Correct answers in a row that take the difference down a step."""
        return RULES[self.rule]


@dataclass(frozen=True)
class Analysis:
    function: str = "weibull"
    lapse_max: float = 0.06
    target: float | None = None
    bootstrap: int = 1000


@dataclass(frozen=True)
class Protocol:
    """A checked protocol file (see the module docstring); ``text`` is the file as read,
    kept so that a session records exactly what it ran."""

    source: Path
    text: str
    name: str
    description: str
    method: str
    seed: int | None
    question: str
    repetitions: int
    practice: int
    break_every: int
    stimuli: Stimuli
    presentation: Presentation
    staircase: Staircase | None
    scale: tuple[int, int] | None
    analysis: Analysis

    @property
    def guess_rate(self) -> float | None:
        """Chance performance of the method's forced choice; None where none applies."""
        return GUESS_RATES.get(self.method)

    @property
    def target(self) -> float:
        """The proportion correct that defines the threshold (see ``[analysis] target``)."""
        if self.analysis.target is not None:
            return self.analysis.target
        if self.staircase is not None:
            return RULE_TARGETS[self.staircase.rule]
        return 0.75




def protocol_names() -> list[str]:
    """The bundled protocols' names, sorted."""
    return sorted(p.stem for p in PROTOCOLS_DIR.glob("*.toml"))


def names_a_path(name: str) -> bool:
    """Whether ``name`` is a file that exists (or a link, even a broken one) or holds a
    path separator: a path, never looked up as a bundled name."""
    path = Path(name)
    return path.exists() or path.is_symlink() or path.name != name


def bundled_protocol(name: str) -> Path | None:
    """The bundled protocol ``name`` names (``period-2afc`` or ``period-2afc.toml``), or
    None: when a file ``name`` exists (a path wins over a name, as for scenes), when it
    holds a path separator (a path, not a name) or when no bundled protocol has it."""
    if names_a_path(name):
        return None
    bundled = PROTOCOLS_DIR / (name if name.endswith(".toml") else f"{name}.toml")
    return bundled if bundled.is_file() else None


def unknown_name(name: str, names_by_kind: dict[str, list[str]]) -> str:
    """The one-line error for ``name``, neither a file nor a bundled name of the kinds
    searched (``names_by_kind``: "scene" or "protocol" -> its bundled names), with the
    closest name of any of them when one is close."""
    every = [n for names in names_by_kind.values() for n in names]
    close = difflib.get_close_matches(Path(name).stem, every, n=1, cutoff=0.5)
    hint = f"did you mean {close[0]}? " if close else ""
    where = {"scene": "frictex library lists the scenes",
             "protocol": f"the bundled protocols: {', '.join(protocol_names())}"}
    return (f"{escape_path(name)}: no such file, and no bundled {' or '.join(names_by_kind)} "
            f"of that name ({hint}{'; '.join(where[kind] for kind in names_by_kind)})")


def resolve_protocol(name_or_path: str) -> Path:
    """A protocol file: ``name_or_path`` if it exists or holds a path separator (a missing
    path is reported by :func:`check_protocol`), else the bundled protocol of that name
    (InputError when there is none)."""
    if names_a_path(name_or_path):
        return Path(name_or_path)
    bundled = bundled_protocol(name_or_path)
    if bundled is None:
        raise InputError(unknown_name(name_or_path, {"protocol": protocol_names()}))
    return bundled


def _scene_path(raw: str, base_dir: Path) -> Path:
    """A scene named in a protocol: a path relative to the protocol, else a bundled name
    (``textures.library.bundled_file``: never a file of that name in the current folder;
    a TextureError when neither exists). The path
    follows the rule of the files a texture file names (``textures.outside``): in the
    protocol's folder or below (no absolute path, no '..', no link leading out) unless
    ``--allow-outside`` lifts it, so that a stranger's protocol cannot make frictex read
    (and report on) any file of the machine."""
    from frictex.textures.errors import TextureError
    from frictex.textures.library import bundled_file
    from frictex.textures.outside import HOW, outside_allowed, leads_out
    local = base_dir / raw
    how = None if outside_allowed() else leads_out(base_dir, raw)
    if how is not None:
        raise TextureError(f"{quoted(raw)} {how}: a protocol names scenes in its own folder "
                           f"or below, or bundled ones ({HOW})")
    if local.exists() or local.is_symlink():
        return local
    if Path(raw).name != raw:
        raise TextureError(f"{escape_path(local)}: no such file")
    return bundled_file(raw, "scene")


class _Check:
    """The reader, plus the checks that span keys."""

    def __init__(self, label: str):
        self.r = Reader(label, None)

    def report(self, path: KeyPath, message: str) -> object:
        return self.r.report(path, message)


def _renderers(c: _Check, renderers, method: str):
    """``[stimuli] renderers`` as read, or :data:`BAD` if the method does not cross them."""
    if renderers and renderers is not _BAD and method != "magnitude":
        return c.report(("stimuli", "renderers"), f"only method \"magnitude\" crosses "
                                                  f"renderers (this is {method})")
    return renderers


def _per_renderer(c: _Check, raw: dict, scene: Path, renderers: tuple) -> Stimuli | None:
    """``[stimuli]`` without ``vary``: the scene once per renderer."""
    if not renderers:
        c.report(("stimuli", "vary"), f"missing: one of {', '.join(VARIES)} (or list "
                                      f"`renderers` for a magnitude estimation)")
        return None
    for key in ("layer", "levels"):
        if raw.get(key) is not None:
            c.report(("stimuli", key), "given without `vary`")
    listed = tuple(Stimulus(f"{scene.stem}-{name}", scene, None, name) for name in renderers)
    return Stimuli(scene, listed=listed)


def _side_by_side_fits(c: _Check, doc: dict, method: str, base) -> bool:
    """Whether the base scene can be shown twice side by side, where the file asks for it."""
    from frictex.app.experiment import stimuli as S
    shown = doc.get("presentation")
    if method != "magnitude" and isinstance(shown, dict) and shown.get("mode") == "side-by-side":
        problem = S.side_by_side_problem(base.doc, base.doc)
        if problem:
            c.report(("presentation", "mode"), problem)
            return False
    return True


def _levels_fit(c: _Check, method: str, levels: tuple[float, ...]) -> bool:
    """Whether ``levels`` suit the method (a staircase's levels are reported, not fatal)."""
    if method == "staircase":
        if levels:
            c.report(("stimuli", "levels"), "not used by a staircase: [staircase] start and "
                                            "steps set the levels")
        return True
    if not levels:
        c.report(("stimuli", "levels"), f"missing (required for method \"{method}\"): the "
                                        f"comparison levels")
    elif len(levels) > MAX_LEVELS:
        c.report(("stimuli", "levels"), f"{len(levels)} levels; at most {MAX_LEVELS}")
    elif len(set(levels)) != len(levels):
        c.report(("stimuli", "levels"), "a level is given twice")
    else:
        return True
    return False


#: why a level may not be the reference, by method (2afc's levels are above it)
LEVEL_IS_REFERENCE = {
    "same-different": "the reference itself: its 'different' pairs would be the same",
    "magnitude": "the reference, which is rated as one of the stimuli: a level given twice",
}


def _level_problem(method: str, level: float, reference: float) -> str | None:
    """Why ``level`` cannot be compared with ``reference`` by ``method``, or None: 2afc
    asks which of two is larger, so its levels lie above the reference; same-different
    (its d' per level is symmetric, ``same_different``) and magnitude take either side."""
    if method == "2afc" and not level > reference:
        return (f"{level:g} is not above the reference {reference:g}: 2afc asks which of the "
                f"two is larger")
    if level == reference and method in LEVEL_IS_REFERENCE:
        return f"{level:g} is {LEVEL_IS_REFERENCE[method]}"
    return None


def _names_fit(c: _Check, vary: str, reference: float, levels: tuple[float, ...]) -> bool:
    """Whether the reference and every level have stimulus names of their own
    (``stimuli.name_of`` keeps 10 significant digits: 0.3 and 0.3000000000001 would be
    one stimulus, played the same)."""
    from frictex.app.experiment.stimuli import name_of
    seen = {name_of(vary, reference, None): "the reference"}
    ok = True
    for i, level in enumerate(levels):
        name = name_of(vary, level, None)
        if level != reference and name in seen:  # the reference itself: _level_problem
            c.report(("stimuli", "levels", i), f"{level!r} is named {name}, as {seen[name]} "
                                               f"is: stimulus names keep 10 significant "
                                               f"digits; give values apart in those")
            ok = False
        seen.setdefault(name, f"level {level!r}")
    return ok


def _values_fit(c: _Check, base, vary: str, layer: int, method: str, reference: float,
                levels: tuple[float, ...]) -> bool:
    """Whether every level suits the method (:func:`_level_problem`) and has a name of
    its own (:func:`_names_fit`), and the reference and every level can be set on the
    varied layer (all problems reported)."""
    from frictex.app.experiment import stimuli as S
    ok = True
    for i, level in enumerate(levels):
        problem = _level_problem(method, level, reference)
        if problem is not None:
            c.report(("stimuli", "levels", i), problem)
            ok = False
    ok = _names_fit(c, vary, reference, levels) and ok
    for i, value in [(None, reference), *enumerate(levels)]:
        problem = S.value_problem(base, vary, layer, value)
        if problem:
            c.report(("stimuli", "reference" if i is None else "levels"), problem)
            ok = False
    return ok


def _parametric(c: _Check, doc: dict, method: str, base_dir: Path) -> Stimuli | None:
    """``[stimuli]``: one scene with a parameter varied, or crossed with renderers."""
    v = c.r.table(doc["stimuli"], ("stimuli",), STIMULI)
    if v is None:
        return None
    renderers = _renderers(c, v["renderers"], method)
    if _BAD in v.values() or renderers is _BAD:
        return None
    from frictex.app.experiment import stimuli as S
    try:
        scene = _scene_path(v["scene"], base_dir)
        base = S.load_base(scene)
    except InputError as exc:
        c.report(("stimuli", "scene"), str(exc))
        return None
    vary, levels, reference = v["vary"], tuple(v["levels"]), v["reference"]
    if vary is None:
        return _per_renderer(c, doc["stimuli"], scene, renderers)
    if not _side_by_side_fits(c, doc, method, base):
        return None
    layer = S.varied_layer(base, vary, v["layer"])
    if isinstance(layer, str):
        c.report(("stimuli", "layer" if v["layer"] is not None else "vary"), layer)
        return None
    if reference is None:
        c.report(("stimuli", "reference"), f"missing (required with vary = \"{vary}\"): the "
                                           f"standard stimulus's {vary}")
        return None
    if not (_levels_fit(c, method, levels)
            and _values_fit(c, base, vary, layer, method, reference, levels)):
        return None
    listed = ()
    if renderers:
        listed = tuple(Stimulus(S.name_of(vary, value, renderer), scene, value, renderer)
                       for renderer in renderers for value in (reference, *levels))
    return Stimuli(scene, vary, layer, reference, levels, listed)


def _listed(c: _Check, doc: dict, method: str, base_dir: Path) -> Stimuli | None:
    raw = doc["stimulus"]
    if not isinstance(raw, list) or not all(isinstance(x, dict) for x in raw):
        c.report(("stimulus",), "expected [[stimulus]] tables (an array of tables)")
        return None
    if method != "magnitude":
        c.report(("stimulus",), f"[[stimulus]] lists are for method \"magnitude\"; {method} "
                                f"compares levels of one parameter: use [stimuli]")
        return None
    if not raw or len(raw) > MAX_STIMULI:
        c.report(("stimulus",), f"{len(raw)} stimuli; expected 1 to {MAX_STIMULI}")
        return None
    from frictex.app.experiment import stimuli as S
    out, names = [], set()
    for i, item in enumerate(raw):
        v = c.r.table(item, ("stimulus", i), STIMULUS)
        if v is None or _BAD in v.values():
            continue
        if v["name"] in names or not v["name"].strip() or not S.plain_name(v["name"]):
            c.report(("stimulus", i, "name"), f"{v['name']!r}: expected a unique name of "
                                              f"letters, digits, '.', '-', '_', '='")
            continue
        names.add(v["name"])
        try:
            scene = _scene_path(v["scene"], base_dir)
            S.load_base(scene)
        except InputError as exc:
            c.report(("stimulus", i, "scene"), str(exc))
            continue
        out.append(Stimulus(v["name"], scene, None, v["renderer"]))
    if len(out) != len(raw):
        return None
    return Stimuli(None, listed=tuple(out))


def check_staircase(c: _Check, doc: dict, method: str) -> Staircase | None | object:
    if method != "staircase":
        if "staircase" in doc:
            c.report(("staircase",), f"only for method \"staircase\" (this is {method})")
        return None
    if "staircase" not in doc:
        return c.report(("staircase",), "missing [staircase] table (start is required)")
    v = c.r.table(doc["staircase"], ("staircase",), STAIRCASE)
    if v is None or _BAD in v.values():
        return _BAD
    if v["threshold_reversals"] > v["reversals"]:
        value = (f"{v['threshold_reversals']} is" if "threshold_reversals" in doc["staircase"]
                 else f"not in the file (default {v['threshold_reversals']}), and")
        return c.report(("staircase", "threshold_reversals"),
                        f"{value} more than the {v['reversals']} reversals the staircase "
                        f"stops after; set it to {v['reversals']} or fewer")
    low, high = v["min"], v["max"]
    if low is not None and high is not None and not low < high:
        return c.report(("staircase", "min"), f"{low:g} is not below max {high:g}")
    if (low is not None and v["start"] < low) or (high is not None and v["start"] > high):
        return c.report(("staircase", "start"), f"{v['start']:g} is outside [min, max]")
    for step in v["steps"]:
        log = v["scale"] == "log"
        if (v["start"] * 10.0 ** step if log else v["start"] + step) == v["start"]:
            return c.report(("staircase", "steps"),
                            f"a step of {step:g}{' log10 units' if log else ''} leaves the "
                            f"start ({v['start']:g}) where it is in float64: the staircase "
                            f"would never move; give larger steps")
    return Staircase(v["rule"], v["start"], tuple(v["steps"]), v["scale"], v["reversals"],
                     v["max_trials"], v["threshold_reversals"], low, high)


def _read(c: _Check, path: Path) -> tuple[str | None, dict | None]:
    """The text of a protocol file and its TOML document; ``(text, None)`` with the
    problems in ``c`` when it cannot be read, is empty or is not TOML."""
    r = c.r
    try:
        text = read_utf8(path, MAX_FILE_BYTES)
    except UnreadableText as exc:
        r.problems.append(Problem(str(path), exc.line, "",
                                  f"{exc}; expected a protocol file (.toml)"))
        return None, None
    if not text.strip():
        c.report((), "is empty; expected a protocol file (format = 1, method, [stimuli])")
        return text, None
    doc = parse_toml(text, r)
    if doc is not None:
        r.locator = Locator(text)
    return text, doc


def _format_fits(c: _Check, fmt) -> bool:
    """Whether ``format`` is one this module reads (a bad value is reported already)."""
    if fmt is not _BAD and fmt != FORMAT_VERSION:
        c.report(("format",), f"{fmt} is not a protocol format this frictex reads "
                              f"(format = {FORMAT_VERSION})")
        return False
    return True


def check_scale(c: _Check, doc: dict, method: str) -> tuple[int, int] | None:
    """``[scale]``: (min, max) of a magnitude estimation's ratings; None for other methods
    or when it has a problem."""
    if method != "magnitude":
        if "scale" in doc:
            c.report(("scale",), f"only for method \"magnitude\" (this is {method})")
        return None
    v = c.r.table(doc.get("scale", {}), ("scale",), SCALE)
    if v is None or _BAD in v.values():
        return None
    if not v["min"] < v["max"]:
        c.report(("scale", "min"), f"{v['min']} is not below max {v['max']}")
    elif v["max"] - v["min"] > 1000:
        c.report(("scale", "max"), "a scale of more than 1000 steps")
    else:
        return (v["min"], v["max"])
    return None


def _target_fits(c: _Check, analysis: dict | None) -> None:
    """Report a threshold target the fit cannot reach: the fitted function tops out at
    1 - lapse_max (the default targets, 0.75 and a rule's, lie below its least, 0.8)."""
    if analysis is None or _BAD in analysis.values() or analysis["target"] is None:
        return
    top = 1.0 - analysis["lapse_max"]
    if not analysis["target"] < top:
        c.report(("analysis", "target"), f"{analysis['target']:g} is not below 1 - lapse_max "
                                         f"({top:g}): the fitted function never reaches it")


def check_method_fits(c: _Check, method: str, presentation: dict | None, analysis: dict | None):
    """Report presentation and analysis settings the method cannot use."""
    if presentation is not None and presentation["mode"] == "side-by-side" and method == "magnitude":
        c.report(("presentation", "mode"), "side-by-side needs two stimuli a trial; magnitude "
                                           "estimation shows one")
    if analysis is not None and analysis["target"] not in (None, _BAD) and method not in GUESS_RATES:
        c.report(("analysis", "target"), f"method \"{method}\" fits no psychometric function")
    _target_fits(c, analysis)
    if analysis is not None and analysis["bootstrap"] is not _BAD and (
            0 < analysis["bootstrap"] < MIN_BOOTSTRAP):
        c.report(("analysis", "bootstrap"), f"{analysis['bootstrap']} samples are too few for a "
                                            f"95 % interval: at least {MIN_BOOTSTRAP}, or 0 for "
                                            f"no intervals")


def _stimuli(c: _Check, doc: dict, method: str, base_dir: Path) -> Stimuli | None:
    """``[stimuli]`` or ``[[stimulus]]``, exactly one of them."""
    if ("stimuli" in doc) == ("stimulus" in doc):
        c.report(("stimuli",), "expected either [stimuli] (one scene, a parameter varied) or "
                               "[[stimulus]] tables (a list of scenes), and not both")
        return None
    if "stimuli" in doc:
        return _parametric(c, doc, method, base_dir)
    return _listed(c, doc, method, base_dir)


def fewest_trials(sc: Staircase, reversals: int) -> int:
    """The fewest main trials in which the staircase ``sc`` can reach ``reversals``
    reversals: its moves alternating, each after the first a reversal, the first an up
    step (one error) and every other move a down step (``down_after`` correct answers)."""
    moves = reversals + 1
    return (moves + 1) // 2 + (moves // 2) * sc.down_after


def staircase_warnings(sc: Staircase, stimuli: Stimuli | None = None) -> list[str]:
    """What may keep the staircase ``sc`` from a threshold, one line each: ``max_trials``
    fewer than :func:`fewest_trials` for its ``threshold_reversals`` (it stops before
    the reversals its threshold averages, whatever the answers), and, given the
    protocol's ``stimuli``, a floor its stimuli cannot show (:func:`unresolved_floor`)."""
    lines = [] if stimuli is None else [line for line in [unresolved_floor(sc, stimuli)] if line]
    needed = fewest_trials(sc, sc.threshold_reversals)
    if sc.max_trials >= needed:
        return lines
    return [f"staircase.max_trials: {sc.max_trials} trials cannot reach the "
            f"{sc.threshold_reversals} reversals its threshold averages ({sc.rule} needs at "
            f"least {needed}); the session would end without a reversal threshold"] + lines


def unresolved_floor(sc: Staircase, stimuli: Stimuli) -> str | None:
    """Why the staircase ``sc`` can present a comparison its stimulus name does not tell
    from the reference (a log staircase without ``min`` answered correctly halves its
    difference on and on: depth-staircase reaches 1.9e-13 by trial 121, both stimuli
    named depth=0.3), or None."""
    from frictex.app.experiment.stimuli import name_of
    low = reachable(sc)[0]
    reference = name_of(stimuli.vary, stimuli.reference, None)
    if sc.min is not None or name_of(stimuli.vary, stimuli.reference + low, None) != reference:
        return None
    return (f"staircase.min: none, and within {sc.max_trials} trials the difference can fall "
            f"to {low:.3g}, where the comparison is named as the reference ({reference}) and "
            f"no device plays them apart; give [staircase] min (the smallest difference "
            f"worth presenting)")


def reachable(sc: Staircase) -> tuple[float, float]:
    """The smallest and largest difference (units of ``vary``) the staircase ``sc`` can
    present within its ``max_trials`` main trials, bounded as if every trial moved by
    the largest step (down only after ``down_after`` correct answers), within ``min``
    and ``max``; the largest is at most :data:`MAX_DIFFERENCE`. On the linear scale
    without ``min`` the smallest can be 0 or below (no valid difference)."""
    step, ups, downs = max(sc.steps), sc.max_trials, sc.max_trials // sc.down_after
    if sc.scale == "log":
        high = sc.start * 10.0 ** min(step * ups, MAX_DECADES)
        low = sc.start * 10.0 ** -min(step * downs, MAX_DECADES)
    else:
        high = sc.start + step * ups
        low = sc.start - step * downs  # 0 or below without min: refused by _staircase_fits
    high = min(high, MAX_DIFFERENCE if sc.max is None else sc.max)
    return (low if sc.min is None else max(low, sc.min)), high


#: why a staircase's difference of 0 or below is no stimulus
NOT_ABOVE_ZERO = ("not above 0: the comparison would be the reference itself or on its "
                  "other side, and the staircase would sit at its floor")


def _staircase_fits(c: _Check, stimuli: Stimuli, staircase: Staircase) -> bool:
    """Whether a staircase varies a parameter and every difference it can reach
    (:func:`reachable`, from its start) can be set on the varied layer (problems
    reported): a level the varied field cannot take would stop the session midway."""
    if stimuli.vary is None:
        c.report(("stimuli", "vary"), "a staircase needs a parameter to vary")
        return False
    from frictex.app.experiment.stimuli import load_base, value_problem
    base = load_base(stimuli.scene)
    low, high = reachable(staircase)
    sc = staircase
    within = (f"within {sc.max_trials} trials (steps up to {max(sc.steps):g}"
              f"{' log10 units' if sc.scale == 'log' else ''})")
    for key, difference in (("start", sc.start), ("max" if sc.max == high else "steps", high),
                            ("min" if sc.min == low else "steps", low)):
        problem = (NOT_ABOVE_ZERO if difference <= 0.0 else
                   value_problem(base, stimuli.vary, stimuli.layer, stimuli.reference + difference))
        if problem is None:
            continue
        if key == "steps":
            bound = "max" if difference == high else "min"
            c.report(("staircase", key), f"the difference can reach {difference:g} {within}: "
                                         f"{problem}; bound it with [staircase] {bound} (or "
                                         f"fewer max_trials, smaller steps)")
        else:
            c.report(("staircase", key), f"a difference of {difference:g}: {problem}")
        return False
    return _differences_named(c, stimuli, sc)


def _differences_named(c: _Check, stimuli: Stimuli, sc: Staircase) -> bool:
    """Whether the staircase's ``start`` and ``min`` give comparisons named apart from
    the reference (``stimuli.name_of`` keeps 10 significant digits); without ``min``,
    :func:`unresolved_floor` warns of the floor the steps reach."""
    from frictex.app.experiment.stimuli import name_of
    reference = name_of(stimuli.vary, stimuli.reference, None)
    for key, difference in (("start", sc.start), ("min", sc.min)):
        if difference is not None and name_of(stimuli.vary, stimuli.reference + difference,
                                              None) == reference:
            c.report(("staircase", key), f"a difference of {difference:g}: the comparison is "
                                         f"named {reference}, as the reference is (stimulus "
                                         f"names keep 10 significant digits); give a larger "
                                         f"{key}")
            return False
    return True


def _by_line(problems: list[Problem]) -> list[Problem]:
    return sorted(problems, key=lambda p: p.line or 0)


def check_protocol(path: str | Path) -> tuple[Protocol | None, list[Problem]]:
    """Read and check a protocol file: ``(protocol, problems)``, the protocol None when
    there is any problem. Never raises for bad input."""
    path = Path(path)
    c = _Check(str(path))
    r = c.r
    text, doc = _read(c, path)
    if doc is None:
        return None, r.problems
    top = r.table(doc, (), TOP, tables=TABLES)
    if not _format_fits(c, top["format"]):
        return None, r.problems
    method = top["method"]
    if method is _BAD:
        return None, _by_line(r.problems)
    presentation = r.table(doc.get("presentation", {}), ("presentation",), PRESENTATION)
    analysis = r.table(doc.get("analysis", {}), ("analysis",), ANALYSIS)
    staircase = check_staircase(c, doc, method)
    scale = check_scale(c, doc, method)
    check_method_fits(c, method, presentation, analysis)
    stimuli = _stimuli(c, doc, method, path.parent)
    problems = _by_line(r.problems)
    if (problems or stimuli is None or presentation is None or analysis is None
            or staircase is _BAD or _BAD in top.values()):
        return None, problems
    if method == "staircase" and not _staircase_fits(c, stimuli, staircase):
        return None, r.problems
    question = top["question"]
    if question is None:
        question = QUESTIONS[method].format(attribute=ATTRIBUTES.get(stimuli.vary, "stronger"))
    return Protocol(source=path, text=text, name=top["name"] or path.stem,
                    description=top["description"], method=method, seed=top["seed"],
                    question=question, repetitions=top["repetitions"], practice=top["practice"],
                    break_every=top["break_every"], stimuli=stimuli,
                    presentation=Presentation(**presentation), staircase=staircase,
                    scale=scale, analysis=Analysis(**analysis)), []


def load_protocol(path: str | Path) -> Protocol:
    """The protocol in a file; :class:`ProtocolError` lists every problem."""
    protocol, problems = check_protocol(path)
    if protocol is None:
        raise ProtocolError(problems)
    return protocol
