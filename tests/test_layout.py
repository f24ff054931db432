"""The code's layout follows DESIGN.md's data flow; these are its rules, checked on the
imports every module makes (read from the source, nothing run):

- layers point one way: ``app`` -> ``rendering`` -> ``textures`` -> ``device``;
- nothing outside ``app/commands`` imports a command module;
- no import cycle between files (lazy imports inside functions count too);
- every list of names of an extension point derives from its registry
  (``device.registry``): no literal tuple, list, set or dict of two of its names, no
  profile name spelled outside ``device/profile.py``, argparse choices from the registry;
- ``device/`` starts no process of the app layer.

The registry checks import the registries to learn their names; the rest reads sources.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LAYERS = {"device": 0, "textures": 1, "rendering": 2, "app": 3}


def modules() -> dict[str, Path]:
    found = {}
    for package in LAYERS:
        for path in (ROOT / package).rglob("*.py"):
            if path.parts[len(ROOT.parts):][:2] == ("app", "api"):
                continue  # installed as the top package, frictex itself
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = "frictex." + ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            found[name] = path
    return found


def imports(mods: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the project's modules it imports (``from a import b`` counts a.b if it
    is a module, else a)."""
    edges = {}
    for name, path in mods.items():
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                for alias in node.names:
                    sub = f"{node.module}.{alias.name}"
                    targets.add(sub if sub in mods else node.module)
            elif isinstance(node, ast.Import):
                targets.update(a.name for a in node.names)
        edges[name] = {t for t in targets if t in mods and t != name}
    return edges


@pytest.fixture(scope="module")
def graph():
    return imports(modules())


def test_layers_point_one_way(graph):
    upward = [f"{m} imports {t}" for m, ts in graph.items() for t in ts
              if LAYERS[t.split(".")[1]] > LAYERS[m.split(".")[1]]]
    assert upward == []


def test_nothing_imports_the_commands(graph):
    offenders = [f"{m} imports {t}" for m, ts in graph.items() for t in ts
                 if t.startswith("frictex.app.commands") and not m.startswith("frictex.app.commands")]
    assert offenders == []


def test_no_import_cycle_between_files(graph):
    cycles = []
    state: dict[str, int] = {}  # 1 on the current path, 2 done

    def visit(module, path):
        state[module] = 1
        for target in sorted(graph[module]):
            if state.get(target) == 1:
                cycles.append(" -> ".join(path[path.index(target):] + [target]))
            elif target not in state:
                visit(target, path + [target])
        state[module] = 2

    for module in sorted(graph):
        if module not in state:
            visit(module, [module])
    assert cycles == []


def test_the_check_sees_the_imports_it_judges(graph):
    """Known edges are found (a checker that read nothing would pass everything)."""
    assert "frictex.device.link.protocol" in graph["frictex.device.link.host"]
    assert "frictex.rendering.pipeline" in graph["frictex.app.engine.replay"]
    assert "frictex.device.profile" in graph["frictex.textures.model"]


def _registries():
    from frictex.app.engine.clocks import CLOCKS
    from frictex.app.engine.sinks import SINKS
    from frictex.device.actuation.factory import ACTUATIONS
    from frictex.device.profile import PROFILES
    from frictex.rendering.renderers import LAYER_RENDERERS, RENDERERS
    return (RENDERERS, LAYER_RENDERERS, PROFILES, ACTUATIONS, CLOCKS, SINKS)


def _own_names(registry) -> set[str]:
    return {name for name in registry.names() if registry.origin(name) == "frictex"}


def _docstrings(tree) -> set[int]:
    """ids of the docstring nodes of a module, its classes and functions."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                found.add(id(body[0].value))
    return found


def _literal_strings(node) -> list[str]:
    """The string elements of a tuple, list or set display, or a dict display's keys."""
    items = node.keys if isinstance(node, ast.Dict) else getattr(node, "elts", [])
    return [e.value for e in items if isinstance(e, ast.Constant) and isinstance(e.value, str)]


def _trees():
    for name, path in modules().items():
        yield name, ast.parse(path.read_text(encoding="utf-8"))


#: modules that name some renderers on purpose, and why (not a list of the known ones)
NAMES_RENDERERS = {"frictex.app.measure.report_claims": "seed 003's claims compare the "
                                                        "renderers they name"}


def test_no_literal_list_of_an_extension_points_names():
    """A tuple such as ("sho-held", "sho-predicted", "sht", "hybrid") is a copy of a
    registry that a plugin's names never reach. For the registries whose names are
    distinct words: the renderers, the device profiles and the actuations (the layer
    kinds are also layer types of the texture format; the sinks' and clocks' names, such
    as "link", are everyday words of the summaries)."""
    from frictex.device.actuation.factory import ACTUATIONS
    from frictex.device.profile import PROFILES
    from frictex.rendering.renderers import RENDERERS
    registries = [(r, _own_names(r)) for r in (RENDERERS, PROFILES, ACTUATIONS)]
    copies = []
    for module, tree in _trees():
        for node in ast.walk(tree):
            if not isinstance(node, (ast.Tuple, ast.List, ast.Set, ast.Dict)):
                continue
            strings = set(_literal_strings(node))
            for registry, names in registries:
                if len(strings & names) >= 2 and not (registry is RENDERERS
                                                      and module in NAMES_RENDERERS):
                    copies.append(f"{module}:{node.lineno}: {registry.kind} names "
                                  f"{sorted(strings & names)}")
    assert copies == []


def test_profile_names_are_spelled_only_in_the_profile_table():
    from frictex.device.profile import PROFILES
    names = _own_names(PROFILES)
    spelled = []
    for module, tree in _trees():
        if module == "frictex.device.profile":
            continue
        docs = _docstrings(tree)
        spelled += [f"{module}:{node.lineno}: {node.value!r}" for node in ast.walk(tree)
                    if isinstance(node, ast.Constant) and node.value in names
                    and id(node) not in docs]
    assert spelled == []


def test_choices_are_never_a_literal_list_of_registered_names():
    """argparse ``choices=`` of every command: a registry's names, not a copy of them."""
    names = set().union(*(_own_names(r) for r in _registries()))
    literal = []
    for module, tree in _trees():
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                for kw in node.keywords:
                    if kw.arg == "choices" and set(_literal_strings(kw.value)) & names:
                        literal.append(f"{module}:{node.lineno}")
    assert literal == []


def test_renderer_options_offer_exactly_the_registry():
    from frictex.app.commands import cli
    from frictex.rendering.renderers import render_modes
    import importlib
    parser, subparsers = cli.build_parser()
    offered = {}
    for name, (module, _) in cli.COMMANDS.items():
        importlib.import_module(module).add_arguments(subparsers[name])
        for action in subparsers[name]._actions:
            if action.dest == "renderer" and action.choices is not None:
                offered[name] = tuple(action.choices)
    assert {"replay", "demo"} <= set(offered)
    assert set(offered.values()) == {render_modes()}


def test_the_registry_checks_see_the_names_they_judge():
    """The checks above would pass everything if the registries were empty."""
    renderers, layer_kinds, profiles, actuations, clocks, sinks = map(_own_names, _registries())
    assert {"sho-held", "sht", "hybrid"} <= renderers and "clip" in layer_kinds
    assert {"plate-seed003", "ring-seed004"} <= profiles and "modal" in actuations
    assert "virtual" in clocks and "tables" in sinks
    tree = ast.parse('RENDERER_CYCLE = (None, "sho", "sht", "hybrid")')
    assert len(set(_literal_strings(tree.body[0].value)) & renderers) == 2


#: how a module could start the app layer in another process
APP_PROCESS = ("frictex.app", "app.commands", "-m frictex")


def test_device_starts_no_process_of_the_app_layer():
    """``device/`` never starts the command line (``python -m frictex.app...``): a
    simulated device runs in process; it may import nothing of ``app`` either (above)."""
    starts = []
    for module, tree in _trees():
        if not module.startswith("frictex.device"):
            continue
        for node in ast.walk(tree):
            strings = _literal_strings(node) if hasattr(node, "elts") else []
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                strings = [node.value]
            for text in strings:
                if any(marker in text for marker in APP_PROCESS):
                    starts.append(f"{module}:{getattr(node, 'lineno', '?')}: {text[:60]!r}")
            if strings and "-m" in strings and any(t.startswith("frictex") for t in strings):
                starts.append(f"{module}:{node.lineno}: {strings}")
    assert starts == []
