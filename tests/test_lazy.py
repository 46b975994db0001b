"""Public names imported on first use (nhham.lazy), on a package written here: nothing is
imported before a name is read, a name is resolved once, a module can be the value, and
unknown names are AttributeErrors as for any module."""

import importlib
import sys
import textwrap

import pytest


@pytest.fixture
def package(tmp_path, monkeypatch):
    root = tmp_path / "lazypkg"
    root.mkdir()
    (root / "__init__.py").write_text(textwrap.dedent('''
        from nhham.lazy import lazy_exports

        _LAZY = {"value": "one", "two": "two", "missing": "one"}
        __getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())
    '''))
    (root / "one.py").write_text("value = 41\n")
    (root / "two.py").write_text("other = 2\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield importlib.import_module("lazypkg")
    for name in ("lazypkg", "lazypkg.one", "lazypkg.two"):
        sys.modules.pop(name, None)


def test_a_name_is_imported_on_first_use_and_kept(package):
    assert "lazypkg.one" not in sys.modules and "value" not in vars(package)
    assert package.value == 41
    assert "lazypkg.one" in sys.modules and vars(package)["value"] == 41


def test_a_module_named_as_the_entry_is_the_value(package):
    assert package.two is sys.modules["lazypkg.two"] and package.two.other == 2


def test_unknown_names_and_names_a_module_does_not_define(package):
    with pytest.raises(AttributeError, match="module 'lazypkg' has no attribute 'nope'"):
        package.nope  # noqa: B018
    with pytest.raises(AttributeError, match=r"lazypkg.one does not define 'missing'"):
        package.missing  # noqa: B018
    assert not hasattr(package, "nope")
    assert {"value", "two", "missing"} <= set(dir(package))
