"""The code's layout follows DESIGN.md's data flow; these are its rules, checked on the
imports every module makes (read from the source, nothing run):

- layers point one way: ``app`` -> ``rendering`` -> ``textures`` -> ``device``;
- nothing outside ``app/commands`` imports a command module;
- no import cycle between files (lazy imports inside functions count too).
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
