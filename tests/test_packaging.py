"""What the wheel installs: one package, frictex, with every module and data file the
repository's four layers hold; and the README's test command is what CI runs.

pyproject.toml lists the packages by hand (the four folders install under one name, which
setuptools' discovery cannot map), so these tests catch a new subpackage or data file that
the list and the globs miss. ``.ci/wheel-smoke`` then builds and installs the real wheel.
"""

from __future__ import annotations

import fnmatch
import re
import subprocess
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]

#: tracked files under the layers that are not installed, and why
NOT_INSTALLED = {
    "textures/library/make_raster_map.py": "the script that made raster-map.png",
    "device/firmware/.gitignore": "the firmware's build folder, for git",
}


def _folder(package: str) -> Path:
    """The repository folder a package is installed from (pyproject's package-dir)."""
    mapping = SETUPTOOLS["package-dir"]
    parts = package.split(".")
    for cut in range(len(parts), 0, -1):
        head = ".".join(parts[:cut])
        if head in mapping:
            return ROOT / mapping[head] / Path(*parts[cut:])
    raise AssertionError(f"{package} is not under any package-dir mapping")


def _tracked() -> list[str]:
    done = subprocess.run(["git", "ls-files", "app", "rendering", "textures", "device"],
                          cwd=ROOT, capture_output=True, text=True, check=True)
    return done.stdout.split()


def test_every_package_folder_is_listed_and_nothing_else():
    listed = set(SETUPTOOLS["packages"])
    found = {"frictex"}
    for layer in ("app", "rendering", "textures", "device"):
        for init in (ROOT / layer).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT)
            if rel.parts[:2] == ("app", "api"):
                continue  # installed as frictex itself
            found.add("frictex." + ".".join(rel.parts))
    assert sorted(found - listed) == [], "add these to pyproject.toml's packages"
    assert sorted(listed - found) == [], "these listed packages have no folder"
    assert all(_folder(p).is_dir() for p in listed)


def test_every_tracked_file_of_the_layers_is_installed():
    folders = {p: _folder(p).relative_to(ROOT).as_posix() for p in SETUPTOOLS["packages"]}
    data = SETUPTOOLS["package-data"]
    missing = []
    for path in _tracked():
        if path in NOT_INSTALLED:
            continue
        owner = max((p for p, f in folders.items() if path.startswith(f + "/")),
                    key=lambda p: len(folders[p]), default=None)
        assert owner is not None, path
        rel = path[len(folders[owner]) + 1:]
        if "/" not in rel and rel.endswith(".py"):
            continue  # a module of a listed package
        # package-data globs are relative to the package they are given for (or a parent)
        covered = any(fnmatch.fnmatch(path[len(folders[p]) + 1:], glob)
                      for p, globs in data.items() if path.startswith(folders[p] + "/")
                      for glob in globs)
        if not covered:
            missing.append(path)
    assert missing == [], "not in the wheel: add a package-data glob or say why not"


def test_the_readme_test_command_is_what_ci_runs():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Two commands for a fresh machine", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"^    (bash \.ci/setup.*)$", section, re.M)
    assert len(commands) >= 2
    main_job, tests = commands[0], commands[1]
    assert main_job == "bash .ci/setup && .venv/bin/frictex demo --headless-fallback"
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()[-1]
    assert ci == tests
