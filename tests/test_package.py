"""The package's public surface: every exported name resolves, lazily."""

import subprocess
import sys

import nhham


def test_every_public_name_resolves():
    for name in nhham.__all__:
        assert getattr(nhham, name) is not None, name


def test_unknown_attribute_raises():
    import pytest

    with pytest.raises(AttributeError):
        nhham.no_such_thing


def test_classify_path_does_not_import_the_integrators():
    code = ("import sys, nhham; nhham.analyze_constraints; "
            "print('nhham.numerics.integrate' in sys.modules, 'scipy.integrate' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout
    assert out.split() == ["False", "False"]


def test_linearize_is_public():
    """nhham.linearize (a scene's [steady] motion) is ``nhham linearize``'s journey; the
    model-level function is nhham.numerics.linearization.linearize."""
    assert nhham.linearize.__module__ == "nhham.journeys.stability"
    assert nhham.linearize_scene.__module__ == "nhham.journeys.stability"
    for name in ("linearize", "linearize_scene", "Linearization", "sweep_steady", "Sweep",
                 "plot_root_locus", "dump_scene", "NumericModel"):
        assert name in nhham.__all__, name


def test_the_command_exports_nothing_to_the_library():
    """What a user does with a scene is a journey (nhham.journeys); nhham.cli only parses,
    calls it and prints: no public name comes from it."""
    from_cli = sorted(name for name, module in nhham._LAZY.items() if module.startswith("cli"))
    assert from_cli == []
    for name in ("classify", "classify_parametric", "derive", "compare", "linearize", "bench"):
        assert getattr(nhham, name).__module__.startswith("nhham.journeys."), name
