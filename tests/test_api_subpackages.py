"""The four layers under ``frictex`` are reachable right after ``import frictex`` (the
README's ``frictex.textures.model.RENDERERS``), and imported only when first used."""

import subprocess
import sys

import pytest


def run_python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)


@pytest.mark.parametrize("layer", ["app", "rendering", "textures", "device"])
def test_a_layer_is_imported_on_first_use(layer):
    done = run_python(f"import sys, frictex\n"
                      f"print('frictex.{layer}' in sys.modules)\n"
                      f"print(frictex.{layer} is sys.modules['frictex.{layer}'])")
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "True"]


def test_a_name_that_is_no_layer_is_still_an_attribute_error():
    done = run_python("import frictex\n"
                      "try:\n    frictex.texture\nexcept AttributeError as exc:\n    print(exc)")
    assert done.stdout.strip() == "module 'frictex' has no attribute 'texture'"
