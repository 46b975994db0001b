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
