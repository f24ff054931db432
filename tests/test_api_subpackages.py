"""The four layers under ``frictex`` are reachable right after ``import frictex``, and
imported only when first used; a module inside one after its own import (the README's
``import frictex.textures.model``, then ``frictex.textures.model.RENDERERS``)."""

import re
import subprocess
import sys

import frictex

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


def test_what_the_module_docstring_says_works_right_after_import_does():
    said = re.search(r"\(``(frictex\.[\w.]+)`` right after ``import frictex``", frictex.__doc__)
    assert said, "the docstring names what works right after import frictex"
    done = run_python(f"import frictex\nprint(type({said[1]}).__name__)")
    assert done.returncode == 0, done.stderr


def test_the_module_inside_a_layer_works_after_its_own_import():
    done = run_python("import frictex.textures.model\n"
                      "print(type(frictex.textures.model.RENDERERS).__name__)")
    assert done.returncode == 0, done.stderr


def test_tab_completion_lists_the_layers():
    done = run_python("import sys, frictex\nnames = dir(frictex)\n"
                      "print(all(layer in names for layer in ('app', 'rendering', 'textures', "
                      "'device')), 'frictex.textures' in sys.modules)")
    assert done.stdout.split() == ["True", "False"]  # listed, not imported
