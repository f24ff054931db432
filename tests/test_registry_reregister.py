"""A module outside frictex (a notebook's ``__main__``) registers a name again to replace
its own entry, edited; never frictex's entry nor another module's or package's."""

import pytest

from frictex.device.registry import Expect, PluginError, Registry


def register_from(module: str):
    """``registry.register(name, entry)`` called from module ``module``."""
    return eval("lambda registry, name, entry: registry.register(name, entry)",
                {"__name__": module})


def registry_of_gadgets() -> Registry:
    return Registry("gadget", "frictex.test-gadgets-none", expect=Expect.factory("a gadget"))


def test_a_module_replaces_its_own_entry():
    registry, notebook = registry_of_gadgets(), register_from("__main__")
    notebook(registry, "wob", len)
    notebook(registry, "wob", abs)
    assert registry.get("wob") is abs and registry.origin("wob") == "__main__ (abs)"


def test_another_module_cannot_replace_it():
    registry = registry_of_gadgets()
    register_from("__main__")(registry, "wob", len)
    with pytest.raises(PluginError, match=r"^gadget 'wob' from other \(abs\) is already "
                                          r"registered by __main__ \(len\)$"):
        register_from("other")(registry, "wob", abs)
    assert registry.get("wob") is len


def test_a_module_cannot_replace_frictexs_own():
    registry = registry_of_gadgets()
    register_from("frictex.own")(registry, "wob", len)
    with pytest.raises(PluginError, match="already registered by frictex$"):
        register_from("__main__")(registry, "wob", abs)
    assert registry.get("wob") is len


def test_a_name_frictex_took_since_is_not_the_modules_any_more():
    registry, notebook = registry_of_gadgets(), register_from("__main__")
    notebook(registry, "wob", len)
    register_from("frictex.own")(registry, "wob", min)  # refused __main__'s, with a warning
    with pytest.raises(PluginError, match="already registered by frictex$"):
        notebook(registry, "wob", abs)
    assert registry.get("wob") is min
