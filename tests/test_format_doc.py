"""textures/FORMAT.md is what the loader accepts: generated from its key tables, and equal."""

import tomllib
from pathlib import Path

from frictex.textures import format_doc
from frictex.textures import loader as L

PAGE = Path(__file__).resolve().parents[1] / "textures" / "FORMAT.md"
LIBRARY = Path(__file__).resolve().parents[1] / "textures" / "library"


def test_the_page_is_the_loaders_tables():
    assert PAGE.read_text(encoding="utf-8") == format_doc.render(), (
        "textures/FORMAT.md is stale: .venv/bin/python -m frictex.textures.format_doc > textures/FORMAT.md")


def test_every_layer_type_has_its_table():
    assert set(L.LAYER_KEYS) == set(L.LAYER_TYPES)


def test_every_key_of_the_bundled_scenes_is_on_the_page():
    """The bundled files use only documented keys (a key the loader read without a table
    entry would be missing from the page)."""
    page = PAGE.read_text(encoding="utf-8")
    for path in LIBRARY.glob("*.toml"):
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
        keys = set()

        def walk(value):
            if isinstance(value, dict):
                for key, inner in value.items():
                    keys.add(key)
                    walk(inner)
            elif isinstance(value, list):
                for inner in value:
                    walk(inner)
        walk(doc)
        tables = {"display", "device", "friction", "calibration", "structure", "driving",
                  "layer", "region", "visual"}
        missing = [k for k in keys - tables if f"| `{k}` |" not in page]
        assert missing == [], f"{path.name}: {missing}"
